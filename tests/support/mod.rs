//! What several integration tests share: reading the example scenes, the parts of
//! hand-built scenes ([`add_floor`], [`add_glass_sphere`], [`add_light`]), a small
//! deterministic generator, FNV-1a, and the generator of hostile scenes
//! ([`hostile`]), and the firmware's pipeline on the host ([`device`]). Each test
//! file takes it with `mod support;` and uses a part of it.
#![allow(dead_code)]

pub mod device;
pub mod hostile;

use caustic::geometry::Shape;
use caustic::light::PointLight;
use caustic::material::Material;
use caustic::math::{Rgb, Vec3};
use caustic::sampling::mix64;
use caustic::scene::Scene;

/// The text of `scenes/<name>`.
pub fn scene_text(name: &str) -> String {
    let path = format!("{}/scenes/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The text of `tests/data/<name>`.
pub fn data_text(name: &str) -> String {
    let path = format!("{}/tests/data/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// Adds the floor `y = 0`, diffuse with `albedo`, to `scene`.
pub fn add_floor<const O: usize, const L: usize>(scene: &mut Scene<O, L>, albedo: Rgb) {
    let floor = Shape::plane(Vec3::ZERO, Vec3::Y).unwrap();
    scene
        .add(floor, Material::diffuse(albedo).unwrap())
        .unwrap();
}

/// Adds a sphere of clear glass (ior 1.5, no absorption) to `scene`.
pub fn add_glass_sphere<const O: usize, const L: usize>(
    scene: &mut Scene<O, L>,
    center: Vec3,
    radius: f32,
) {
    let glass = Material::dielectric(1.5, Rgb::ZERO).unwrap();
    scene
        .add(Shape::sphere(center, radius).unwrap(), glass)
        .unwrap();
}

/// Adds a point light at `position` of `intensity` to `scene`.
pub fn add_light<const O: usize, const L: usize>(
    scene: &mut Scene<O, L>,
    position: Vec3,
    intensity: Rgb,
) {
    let light = PointLight::new(position, intensity).unwrap();
    scene.add_light(light).unwrap();
}

/// The worst relative error of `irradiance(x)` against a point light's `I·cosθ/d²`
/// (`light` at `intensity`) at 40 points `x` of the floor `y = 0`, on a spiral whose
/// radius grows by `step` a point.
pub fn worst_floor_irradiance_error(
    light: Vec3,
    intensity: f32,
    step: f32,
    mut irradiance: impl FnMut(Vec3) -> f64,
) -> f64 {
    let mut worst = 0.0f64;
    for i in 0..40 {
        let a = i as f32 * 0.61;
        let r = step * i as f32;
        let x = Vec3::new(r * a.cos(), 0.0, r * a.sin());
        let e = irradiance(x);
        let to = (light - x).as_dvec3();
        let want = intensity as f64 * (to.y / to.length()) / to.length_squared();
        worst = worst.max((e - want).abs() / want);
    }
    worst
}

/// FNV-1a (32-bit) of a byte stream, as the firmware prints it (`PASS fnv1a=0x…`).
pub fn fnv1a(bytes: &[u8]) -> u32 {
    bytes.iter().fold(0x811c_9dc5u32, |h, &b| {
        (h ^ b as u32).wrapping_mul(0x0100_0193)
    })
}

/// SplitMix64 (Steele, Lea & Flood 2014): the core's finaliser
/// [`caustic::sampling::mix64`] over a Weyl sequence. A tiny deterministic generator for
/// the scene fuzzers.
pub struct Rng(pub u64);

impl Rng {
    pub fn u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        mix64(self.0)
    }
    /// Uniform in `[0, 1)` (24 bits).
    pub fn f(&mut self) -> f32 {
        (self.u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    pub fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.f()
    }
    pub fn below(&mut self, n: u64) -> u64 {
        self.u64() % n
    }
    pub fn chance(&mut self, p: f32) -> bool {
        self.f() < p
    }
    pub fn v(&mut self, e: f32) -> caustic::math::Vec3 {
        caustic::math::Vec3::new(self.range(-e, e), self.range(-e, e), self.range(-e, e))
    }
    pub fn rgb(&mut self, max: f32) -> caustic::math::Rgb {
        caustic::math::Rgb::new(
            self.range(0.0, max),
            self.range(0.0, max),
            self.range(0.0, max),
        )
    }
}

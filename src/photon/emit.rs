//! Photon emission from a point light: directions and powers.
//!
//! **The paper's sphere, made uniform.** Paper eq. 7 places emission directions on the
//! light's unit sphere, `P(u, v) = (cos v cos u, cos v sin u, sin v)`, stepping `u` and
//! `v` uniformly — which crowds directions at the poles, where the circles of latitude
//! are short. Here `u` is uniform in `[0, 2π)` and `v` is drawn *by its sine*,
//! `sin v` uniform in `[−1, 1]` (Archimedes' hat-box theorem): every solid angle then
//! receives the same share of photons, so each photon carries exactly `4π·I/N`.
//!
//! **Projection maps.** Photons are aimed only at objects that can focus light
//! (Jensen 2001, §7.1; here with bounding spheres as the map's cells): each such object
//! subtends a cone of half-angle `θ = asin(R/d)` and solid angle
//! `Ω = 2π(1 − cos θ)` seen from the light. Photon counts are shared among the cones in
//! proportion to `Ω`; within a cone directions are uniform (`cos θ` uniform in
//! `[cos θ_max, 1]`, the same warp as above). Cones may overlap, so a direction's
//! density is the sum over the cones containing it, `p(ω) = Σⱼ (Nⱼ/N)/Ωⱼ`, and the
//! photon's power is `I/(N·p(ω)) = I / Σⱼ Nⱼ/Ωⱼ`: unbiased, whatever the overlap.
//! When the cones would cover the whole sphere (the light inside an object, an
//! unbounded mirror plane), emission falls back to the full sphere.
//!
//! Points come from a Hammersley set per cone, shifted by the seed (stratified and
//! deterministic): the same seed gives the same photons on every machine.

use core::f32::consts::PI;

use heapless::Vec as FixedVec;

#[cfg(feature = "std")]
use crate::geometry::BoundingSphere;
use crate::light::PointLight;
#[cfg(feature = "std")]
use crate::math::max_abs;
use crate::math::{Rgb, UnitVec3, Vec3};
use crate::sampling::hammersley;
use crate::scene::Scene;

/// The cone of directions from a light towards one object's bounding sphere.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cone {
    axis: UnitVec3,
    e1: UnitVec3,
    e2: UnitVec3,
    /// `1 − cos θ_max`, computed without cancellation as `sin²θ/(1 + cos θ)`.
    one_minus_cos: f32,
    solid_angle: f32,
    /// Photons aimed into this cone.
    count: u32,
    /// Its photons' density over directions, `count / solid_angle` (per steradian),
    /// computed once: every photon sums it over the cones that hold its direction.
    density: f32,
}

impl Cone {
    /// `true` when `d` lies within the cone: its chord to the axis, `|a − d|² =
    /// 2(1 − cos θ)`, at most `2(1 − cos θ_max)`. Not `a·d ≥ cos θ_max`: a cosine within
    /// 6·10⁻⁸ of 1 rounds to 1, so from a light 10⁴ sizes away (half-angles of 10⁻⁴) every
    /// direction within 3·10⁻⁴ of a cone's axis passed for inside it, and a photon aimed
    /// at one object counted the neighbouring cone's density too (half its power lost).
    #[inline]
    fn contains(&self, d: UnitVec3) -> bool {
        (self.axis.get() - d.get()).length_squared() <= 2.0 * self.one_minus_cos
    }

    /// `false` when no ray from `from` along a direction of this cone can meet `bound`:
    /// the angle between the axes exceeds the sum of the half-angles, `θ` and
    /// `asin(R/d)`. In `f64`, with the radius widened by 0.1% of the scale of the
    /// coordinates, far beyond the rounding of the directions drawn and of the shapes'
    /// own tests (which also widen their bounding spheres, by 10⁻⁴).
    #[cfg(feature = "std")]
    fn may_meet(&self, from: Vec3, bound: BoundingSphere) -> bool {
        let v = |v: Vec3| [v.x as f64, v.y as f64, v.z as f64];
        let [x, y, z] = v(bound.center - from);
        let d = libm::sqrt(x * x + y * y + z * z);
        let r = bound.radius as f64 * 1.001 + 1e-3 * (max_abs(bound.center) + bound.radius) as f64;
        if d <= r {
            return true; // `from` is inside the widened bound
        }
        let [ax, ay, az] = v(self.axis.get());
        let between = libm::acos(((ax * x + ay * y + az * z) / d).clamp(-1.0, 1.0));
        let half = libm::acos(1.0 - self.one_minus_cos as f64) + 1e-3;
        between <= half + libm::asin(r / d)
    }
}

/// How one light emits its photons.
#[derive(Clone, Debug)]
pub(crate) enum Emission<const OBJECTS: usize> {
    /// Uniform over the whole sphere.
    Sphere { count: u32 },
    /// Into the cones of the objects that can make caustics.
    Cones(FixedVec<Cone, OBJECTS>),
}

impl<const OBJECTS: usize> Emission<OBJECTS> {
    /// The emission plan of `light` for `count` photons. `full_sphere` forces the
    /// paper's plain sphere (used to check the projection maps, and for direct photons).
    pub(crate) fn plan<const LIGHTS: usize>(
        scene: &Scene<OBJECTS, LIGHTS>,
        light: &PointLight,
        count: u32,
        full_sphere: bool,
    ) -> Self {
        let sphere = Emission::Sphere { count };
        if full_sphere {
            return sphere;
        }
        let mut cones: FixedVec<Cone, OBJECTS> = FixedVec::new();
        let mut total = 0.0f32;
        for object in scene.objects().iter().filter(|o| o.material.is_specular()) {
            let Some(bound) = object.shape.bounding_sphere() else {
                return sphere;
            };
            let to = bound.center - light.position();
            let d2 = to.length_squared();
            let r2 = bound.radius * bound.radius;
            let Some(axis) = UnitVec3::new(to) else {
                return sphere;
            };
            if d2 <= r2 {
                return sphere; // the light is inside the bound
            }
            let sin2 = r2 / d2;
            let cos_max = crate::math::sqrt(1.0 - sin2);
            let one_minus_cos = sin2 / (1.0 + cos_max);
            let solid_angle = 2.0 * PI * one_minus_cos;
            let (e1, e2) = axis.basis();
            total += solid_angle;
            // Cannot overflow: one cone per object.
            let _ = cones.push(Cone {
                axis,
                e1,
                e2,
                one_minus_cos,
                solid_angle,
                count: 0,
                density: 0.0,
            });
        }
        if cones.is_empty() || total >= 4.0 * PI {
            return sphere;
        }
        // Share the photons in proportion to solid angle by cumulative rounding, so the
        // counts add up to exactly `count`.
        let mut before = 0.0f32;
        let mut given = 0u32;
        for c in cones.iter_mut() {
            before += c.solid_angle;
            let upto = if before >= total {
                count
            } else {
                ((count as f32) * (before / total) + 0.5) as u32
            };
            let upto = upto.min(count).max(given);
            c.count = upto - given;
            c.density = c.count as f32 / c.solid_angle;
            given = upto;
        }
        Emission::Cones(cones)
    }

    /// For each cone (one for the sphere), the objects of `scene` its photons may meet
    /// on their way from `light` (bit `i`: object `i`, of the first 64): every
    /// unbounded one, and every bounded one whose bounding sphere the cone reaches.
    #[cfg(feature = "std")]
    pub(crate) fn reach<const LIGHTS: usize>(
        &self,
        scene: &Scene<OBJECTS, LIGHTS>,
        light: &PointLight,
    ) -> FixedVec<u64, OBJECTS> {
        let mut sets = FixedVec::new();
        let cones = match self {
            Emission::Sphere { .. } => {
                let _ = sets.push(u64::MAX); // cannot fail: OBJECTS ≥ 1 to have a sphere
                return sets;
            }
            Emission::Cones(cones) => cones,
        };
        for cone in cones {
            let mut set = 0u64;
            for (i, object) in scene.objects().iter().enumerate().take(64) {
                let meets = object
                    .shape
                    .bounding_sphere()
                    .is_none_or(|b| cone.may_meet(light.position(), b));
                set |= (meets as u64) << i;
            }
            let _ = sets.push(set); // cannot fail: one set per cone
        }
        sets
    }

    /// The index of the `index`-th photon in its cone's point set, and the cone (0 for
    /// the sphere).
    pub(crate) fn local(&self, index: u32) -> (u32, usize) {
        let Emission::Cones(cones) = self else {
            return (index, 0);
        };
        let mut local = index;
        for (j, c) in cones.iter().enumerate() {
            if local < c.count {
                return (local, j);
            }
            local -= c.count;
        }
        (local, 0)
    }

    /// Photons this plan emits.
    pub(crate) fn count(&self) -> u32 {
        match self {
            Emission::Sphere { count } => *count,
            Emission::Cones(c) => c.iter().map(|c| c.count).sum(),
        }
    }

    /// Power of a photon of nominal weight (the largest channel of `I` over the
    /// density of the first cone, or `4π/N` for the sphere).
    pub(crate) fn nominal_power(&self, light: &PointLight) -> f32 {
        let i = light.intensity().max_channel();
        match self {
            Emission::Sphere { count } => i * 4.0 * PI / (*count).max(1) as f32,
            Emission::Cones(c) => {
                let density: f32 = c.iter().map(|c| c.density).fold(0.0, f32::max);
                if density > 0.0 {
                    i / density
                } else {
                    0.0
                }
            }
        }
    }

    /// The `index`-th photon: its direction, power (W), index in its cone's point set
    /// and cone (0 for the sphere). `shift` rotates the point set (derived from the
    /// seed and pass).
    pub(crate) fn photon(
        &self,
        light: &PointLight,
        index: u32,
        shift: (f32, f32),
    ) -> (UnitVec3, Rgb, u32, usize) {
        let [p] = self.photons::<1>(light, index, shift);
        p
    }

    /// Photons `first..first + N` of the plan, as [`photon`](Self::photon) gives each
    /// (an index past [`count`](Self::count) gives a photon no caller reads), worked
    /// out a step at a time for all `N`. One photon's direction is a chain of
    /// dependent divisions and square roots (the point's coordinate over the cone's
    /// count, `sin θ`, the normalising length and its reciprocal) that a core mostly
    /// waits on; in steps over eight photons the chains overlap (the desktop's
    /// [`Emitter::land_range`](super::Emitter::land_range)). Each lane does the same
    /// IEEE-754 operations in the same order whatever `N`: the same photons, bit for
    /// bit.
    pub(crate) fn photons<const N: usize>(
        &self,
        light: &PointLight,
        first: u32,
        shift: (f32, f32),
    ) -> [(UnitVec3, Rgb, u32, usize); N] {
        let cones = match self {
            Emission::Sphere { count } => {
                return core::array::from_fn(|k| {
                    let index = first.wrapping_add(k as u32);
                    let (dir, power) = sphere(light, index, *count, shift);
                    (dir, power, index, 0)
                });
            }
            Emission::Cones(cones) => cones,
        };
        let (mut local, mut which) = ([0u32; N], [0usize; N]);
        for k in 0..N {
            (local[k], which[k]) = self.local(first.wrapping_add(k as u32));
        }
        let (mut s, mut t) = ([0.0f32; N], [0.0f32; N]);
        for k in 0..N {
            (s[k], t[k]) = hammersley(local[k], cones[which[k]].count, shift);
        }
        let (mut cos_t, mut sin2_t) = ([0.0f32; N], [0.0f32; N]);
        for k in 0..N {
            let om = s[k] * cones[which[k]].one_minus_cos; // 1 − cos θ
            cos_t[k] = 1.0 - om;
            sin2_t[k] = crate::math::max_num(om * (2.0 - om), 0.0);
        }
        let mut sin_t = [0.0f32; N];
        for k in 0..N {
            sin_t[k] = crate::math::sqrt(sin2_t[k]);
        }
        let (mut sin_p, mut cos_p) = ([0.0f32; N], [0.0f32; N]);
        for k in 0..N {
            (sin_p[k], cos_p[k]) = crate::math::sin_cos_turns(t[k]);
        }
        let mut d = [Vec3::ZERO; N];
        for k in 0..N {
            let c = &cones[which[k]];
            d[k] = c.axis.get() * cos_t[k]
                + (c.e1.get() * cos_p[k] + c.e2.get() * sin_p[k]) * sin_t[k];
        }
        let mut dir = [UnitVec3::Z; N];
        for k in 0..N {
            dir[k] = UnitVec3::new(d[k]).unwrap_or(cones[which[k]].axis);
        }
        // The density: the sum over the cones that hold the direction, in their order
        // (from `-0.0`, as `Iterator::sum` starts).
        let mut density = [-0.0f32; N];
        for (j, o) in cones.iter().enumerate() {
            for k in 0..N {
                if which[k] == j || o.contains(dir[k]) {
                    density[k] += o.density;
                }
            }
        }
        core::array::from_fn(|k| {
            let power = light.intensity() * (1.0 / density[k]);
            (dir[k], power, local[k], which[k])
        })
    }
}

/// Photon `index` of `count` over the whole sphere: its direction and power.
fn sphere(light: &PointLight, index: u32, count: u32, shift: (f32, f32)) -> (UnitVec3, Rgb) {
    let (s, t) = hammersley(index, count, shift);
    let (sin_u, cos_u) = crate::math::sin_cos_turns(s);
    let sin_v = 2.0 * t - 1.0;
    let cos_v = crate::math::sqrt(crate::math::max_num(1.0 - sin_v * sin_v, 0.0));
    let d = Vec3::new(cos_v * cos_u, cos_v * sin_u, sin_v);
    let power = light.intensity() * (4.0 * PI / count as f32);
    (UnitVec3::new(d).unwrap_or(UnitVec3::Z), power)
}

/// Photons the desktop's forward pass works out together ([`Emission::photons`]).
#[cfg(feature = "std")]
pub(crate) const LANES: usize = 8;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::geometry::Shape;
    use crate::material::Material;

    fn scene(spheres: &[(Vec3, f32)]) -> Scene<4, 1> {
        let cam = Camera::new(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, Vec3::Y, 40.0, 4, 4).unwrap();
        let mut s = Scene::new(cam);
        for &(c, r) in spheres {
            s.add(
                Shape::sphere(c, r).unwrap(),
                Material::dielectric(1.5, Rgb::ZERO).unwrap(),
            )
            .unwrap();
        }
        s
    }

    #[test]
    fn sphere_emission_is_uniform_per_solid_angle() {
        let light = PointLight::new(Vec3::ZERO, Rgb::ONE).unwrap();
        let plan: Emission<4> = Emission::Sphere { count: 40_000 };
        // Equal-area bands in z: each must get a tenth of the photons.
        let mut bands = [0u32; 10];
        let mut total = Rgb::ZERO;
        for i in 0..40_000 {
            let (d, p, _, _) = plan.photon(&light, i, (0.1, 0.7));
            bands[((d.get().z + 1.0) * 5.0).min(9.0) as usize] += 1;
            total += p;
        }
        assert!(bands.iter().all(|&b| b.abs_diff(4000) <= 2), "{bands:?}");
        assert!((total.r - 4.0 * PI).abs() < 1e-2);
    }

    #[test]
    fn cones_cover_the_objects_and_carry_the_flux_they_subtend() {
        // Two overlapping spheres: the flux emitted into the union of their cones must
        // equal I times the union's solid angle, estimated by brute force.
        let s = scene(&[
            (Vec3::new(0.0, -5.0, 0.0), 1.0),
            (Vec3::new(0.8, -5.0, 0.0), 1.0),
        ]);
        let light = PointLight::new(Vec3::ZERO, Rgb::ONE).unwrap();
        let plan = Emission::plan(&s, &light, 50_000, false);
        let Emission::Cones(cones) = &plan else {
            panic!("expected cones")
        };
        assert_eq!(plan.count(), 50_000);
        let mut flux = 0.0;
        for i in 0..50_000 {
            let (d, p, _, _) = plan.photon(&light, i, (0.3, 0.6));
            assert!(cones.iter().any(|c| c.contains(d)));
            flux += p.r;
        }
        let sphere: Emission<4> = Emission::Sphere { count: 400_000 };
        let inside = (0..400_000)
            .filter(|&i| {
                cones
                    .iter()
                    .any(|c| c.contains(sphere.photon(&light, i, (0.0, 0.0)).0))
            })
            .count();
        let union = 4.0 * PI * inside as f32 / 400_000.0;
        assert!(
            (flux - union).abs() / union < 0.01,
            "flux {flux} vs union solid angle {union}"
        );
    }

    /// The batch gives every photon `photon` gives, bit for bit: across the cones'
    /// boundaries, where cones overlap, and for the whole sphere.
    #[cfg(feature = "std")]
    #[test]
    fn photons_in_batches_are_the_photons_one_at_a_time() {
        let s = scene(&[
            (Vec3::new(0.0, -5.0, 0.0), 1.0),
            (Vec3::new(0.8, -5.0, 0.0), 1.0),
            (Vec3::new(3.0, 1.0, -4.0), 0.5),
        ]);
        let light = PointLight::new(Vec3::ZERO, Rgb::new(1.0, 2.0, 3.0)).unwrap();
        let cones = Emission::plan(&s, &light, 3001, false);
        assert!(matches!(&cones, Emission::Cones(c) if c.len() == 3));
        for plan in [cones, Emission::Sphere { count: 3001 }] {
            let n = plan.count();
            for first in (0..n).step_by(LANES).chain(997..1013).chain(n - 3..n) {
                let batch = plan.photons::<LANES>(&light, first, (0.3, 0.6));
                for (k, got) in batch.iter().enumerate() {
                    let i = first + k as u32;
                    if i >= n {
                        continue;
                    }
                    let want = plan.photon(&light, i, (0.3, 0.6));
                    let bits = |(d, p, l, c): (UnitVec3, Rgb, u32, usize)| {
                        let d = d.get();
                        ([d.x, d.y, d.z, p.r, p.g, p.b].map(f32::to_bits), l, c)
                    };
                    assert_eq!(bits(*got), bits(want), "photon {i}");
                }
            }
        }
    }

    #[test]
    fn a_light_inside_an_object_uses_the_whole_sphere() {
        let s = scene(&[(Vec3::ZERO, 2.0)]);
        let light = PointLight::new(Vec3::new(0.5, 0.0, 0.0), Rgb::ONE).unwrap();
        assert!(matches!(
            Emission::plan(&s, &light, 100, false),
            Emission::Sphere { count: 100 }
        ));
    }
}

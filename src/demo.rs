//! Scenes built in code, for firmware and tests that have no file system.
//!
//! [`fig6`] is the paper's Fig. 6 scene (section 3.3) exactly as `scenes/fig6.json`
//! describes it (a test checks that they agree), so a device, the desktop simulator and
//! the desktop renderer draw the same thing. A device's capacities and photon budget
//! for it are [`crate::budget::FIG6`].

use crate::camera::Camera;
use crate::error::Error;
use crate::geometry::Shape;
use crate::light::PointLight;
use crate::material::{Classic, Material};
use crate::math::{Rgb, Vec3};
use crate::scene::Scene;

/// The paper's Fig. 6: a transparent green `classic` cube (ambient 0.3, diffuse 0.9,
/// specular 0.2, reflectivity 0.2, transparency 0.7, ior 1.25), edge 4 at (2, 1, −1),
/// turned 30° about y, above a flat field (ambient 0.7, diffuse 0.2, specular 0.8) at
/// y = −5, lit by a lamp at (0, 19, 0) under ambient light 0.5 and a grey 0.3
/// background. The lamp's intensity (460 W/sr) lights the field below it with about
/// 0.8 W/m², the paper's lamp coefficient. Rendered at `width × height`.
pub fn fig6<const O: usize, const L: usize>(width: u32, height: u32) -> Result<Scene<O, L>, Error> {
    let camera = Camera::new(
        Vec3::new(0.0, 9.0, 22.0),
        Vec3::new(1.0, -1.0, -1.0),
        Vec3::Y,
        45.0,
        width,
        height,
    )?;
    let mut scene = Scene::new(camera);
    scene.set_background(Rgb::splat(0.3))?;
    scene.set_ambient(Rgb::splat(0.5))?;
    scene.add_light(PointLight::new(
        Vec3::new(0.0, 19.0, 0.0),
        Rgb::splat(460.0),
    )?)?;
    let field = Material::classic(Classic::new(Rgb::ONE, 0.7, 0.2, 0.8, 20.0, 0.0, 0.0, 1.0))?;
    let cube = Material::classic(Classic::new(
        Rgb::new(0.0, 1.0, 0.0),
        0.3,
        0.9,
        0.2,
        20.0,
        0.2,
        0.7,
        1.25,
    ))?;
    scene.add(Shape::plane(Vec3::new(0.0, -5.0, 0.0), Vec3::Y)?, field)?;
    scene.add(
        Shape::cuboid(
            Vec3::new(2.0, 1.0, -1.0),
            Vec3::splat(4.0),
            Vec3::new(0.0, 30.0, 0.0),
        )?,
        cube,
    )?;
    Ok(scene)
}

/// A physical scene for devices: a glass sphere (index 1.5, Beer absorption
/// σ = (0.05, 0.12, 0.3) per unit length: a faint amber tint through its 2-unit
/// diameter) resting on a grey diffuse floor (albedo 0.8), beside a tilted mirror
/// (reflectance 0.9, a 2.4 × 1.6 × 0.05 slab) that throws a second, reflected patch of
/// light, lit by one point light (60 W/sr) and seen from (0, 4, 7) as in
/// `scenes/glass_sphere.json`. Rendered at `width × height`. Its device budget is
/// [`crate::budget::GLASS`].
pub fn glass<const O: usize, const L: usize>(
    width: u32,
    height: u32,
) -> Result<Scene<O, L>, Error> {
    let camera = Camera::new(
        Vec3::new(0.0, 4.0, 7.0),
        Vec3::new(0.0, 0.6, 0.0),
        Vec3::Y,
        40.0,
        width,
        height,
    )?;
    let mut scene = Scene::new(camera);
    scene.add_light(PointLight::new(
        Vec3::new(-3.0, 6.0, -2.0),
        Rgb::splat(60.0),
    )?)?;
    let floor = Material::diffuse(Rgb::splat(0.8))?;
    let glass = Material::dielectric(1.5, Rgb::new(0.05, 0.12, 0.3))?;
    let mirror = Material::mirror(Rgb::splat(0.9))?;
    scene.add(Shape::plane(Vec3::ZERO, Vec3::Y)?, floor)?;
    scene.add(Shape::sphere(Vec3::new(0.0, 1.0, 0.0), 1.0)?, glass)?;
    scene.add(
        Shape::cuboid(
            Vec3::new(2.2, 0.8, -1.5),
            Vec3::new(2.4, 1.6, 0.05),
            Vec3::new(0.0, -35.0, 0.0),
        )?,
        mirror,
    )?;
    Ok(scene)
}

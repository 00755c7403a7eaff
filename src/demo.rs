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

//! # caustic
//!
//! A photon-mapping renderer for the caustics of glass and mirror objects, after
//! *Caustic Effect of 3D Transparent Object Using Backward and Forward Ray Tracing*
//! (Pertiwi, Triwahyuni, Simbolon) and Jensen's photon maps. It runs on hardware as
//! small as a Cortex-M4F and on a desktop, and gives the same image, bit for bit, on both.
//!
//! The data flows one way:
//!
//! ```text
//!  Scene ─► photon::emit ─► photon::trace ─► CausticStore (kd-tree)  forward pass
//!        ─► camera ray ─► render (Whitted, bounded stack) ─► rows     backward pass
//!        ─► raster (tone map, sRGB) ─► PNG │ DrawTarget │ PFM
//! ```
//!
//! The core is `#![no_std]` and never allocates: every capacity is a const generic.
//!
//! # Features
//!
//! | feature | default | adds | dependencies |
//! |---|---|---|---|
//! | *(none)* | | the `no_std` core: scenes, photons, stores, the renderer, tone mapping; for a microcontroller | `glam` (scalar, libm), `libm`, `heapless` |
//! | `std` | yes | [`desktop`]: scene files (JSON), PNG, PFM and OpenEXR images, threads, progress bars | `serde`, `serde_json`, `serde_path_to_error`, `tiny-skia`, `exr`, `indicatif` |
//! | `cli` | yes | the `caustic` program and [`desktop::cli`], its arguments shared with the examples (implies `std`) | `clap`, `clap_complete` |
//! | `embedded-graphics` | yes | [`raster::DisplaySink`]: rows onto any `embedded-graphics` `DrawTarget` (works without `std`) | `embedded-graphics-core` |
//!
//! A firmware uses `default-features = false` and, for a display, `features =
//! ["embedded-graphics"]`; a desktop library user who needs no command line can take
//! `default-features = false, features = ["std"]`.
//!
//! ```
//! use caustic::prelude::*;
//!
//! # fn main() -> Result<(), caustic::Error> {
//! let mut scene: Scene<4, 1> = Scene::new(Camera::new(
//!     Vec3::new(0.0, 4.0, 7.0), Vec3::new(0.0, 0.5, 0.0), Vec3::Y, 40.0, 32, 24)?);
//! let floor = Material::diffuse(Rgb::splat(0.8))?;
//! let glass = Material::dielectric(1.5, Rgb::ZERO)?;
//! scene.add(Shape::plane(Vec3::ZERO, Vec3::Y)?, floor)?;
//! scene.add(Shape::sphere(Vec3::new(0.0, 1.0, 0.0), 1.0)?, glass)?;
//! scene.add_light(PointLight::new(Vec3::new(-3.0, 6.0, -2.0), Rgb::splat(60.0))?)?;
//!
//! // Forward pass: a fixed-capacity photon map, balanced in place.
//! let settings = PhotonSettings::new(2_000, 32, 0.1, 8)?;
//! let mut map: PhotonMap<2_000> = PhotonMap::new();
//! map.build(&scene, &settings, 7)?;
//!
//! // Backward pass: rows of linear radiance, one at a time, with a path stack of 8.
//! let store = map.store::<32>(&settings)?;
//! let renderer: render::Renderer<_, 4, 1, 8> = render::Renderer::new(&scene, &store, 8)?;
//! let mut row = [Rgb::ZERO; 32];
//! let mut lit = 0.0;
//! renderer.rows(&mut row, |_y, pixels| -> Result<(), ()> {
//!     lit += pixels.iter().map(|p| p.luminance()).sum::<f32>();
//!     Ok(())
//! }).unwrap();
//! assert!(lit > 0.0);
//! # Ok(()) }
//! ```
#![no_std]
#![cfg_attr(docsrs, feature(doc_cfg))]
#![deny(missing_docs, unsafe_code, rustdoc::broken_intra_doc_links)]
#![warn(missing_debug_implementations)]
// `!(x > 0.0)` is how this crate says "not positive, or NaN": the negation is the point.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

#[cfg(feature = "std")]
extern crate std;

pub mod budget;
pub mod camera;
pub mod demo;
mod error;
pub mod geometry;
pub mod light;
pub mod material;
pub mod math;
pub mod photon;
pub mod raster;
pub mod render;
pub mod sampling;
pub mod scene;

#[cfg(feature = "std")]
#[cfg_attr(docsrs, doc(cfg(feature = "std")))]
pub mod desktop;

pub use error::Error;

/// The names most programs need, in one `use`.
pub mod prelude {
    pub use crate::camera::Camera;
    pub use crate::geometry::Shape;
    pub use crate::light::PointLight;
    pub use crate::material::Material;
    pub use crate::math::{Rgb, UnitVec3, Vec3};
    pub use crate::photon::{PhotonMap, PhotonSettings};
    pub use crate::render;
    pub use crate::scene::Scene;
}

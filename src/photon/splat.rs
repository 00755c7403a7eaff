//! Light tracing into the image: caustic light the camera sees directly.
//!
//! A photon that lands on a surface with a diffuse part, where the eye sees that
//! surface directly (nothing in between), is connected to the pinhole and adds its
//! reflected light to the pixel it projects into. Summed over photons this is an
//! unbiased estimate of the pixel-area average of the caustic radiance seen directly
//! (the `L S+ D E` paths; Veach 1997 §10.2, pbrt-v4's light tracer): no kernel, no
//! radius, no bias at a caustic's sharp edge or focus. Caustics seen through glass or
//! in a mirror (`L S+ D S+ E`) cannot be connected to a pinhole and stay with the
//! caustic store's gather.
//!
//! Splats are kept in emission order; a row adds the splats of its pixels in that order,
//! so the device (which scans the list row by row) and the desktop (which adds the whole
//! list once into its frame) sum every pixel in the same order and agree bit for bit.

use crate::error::Error;
use crate::geometry::{Hit, Ray};
use crate::material::Material;
use crate::math::{Rgb, UnitVec3};
use crate::scene::Scene;

/// One photon's contribution to one pixel's average radiance: 16 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Splat {
    /// Pixel index `y·W + x` in bits 0–30; bit 31: the photon's half (see
    /// [`Emitter`](super::Emitter)). Images have fewer than 2³¹ pixels.
    key: u32,
    /// Radiance added to the pixel's value (W/(m²·sr) per channel).
    pub radiance: Rgb,
}

const HALF_BIT: u32 = 1 << 31;

impl Splat {
    /// The empty splat, for initialising arrays.
    pub const ZERO: Splat = Splat {
        key: 0,
        radiance: Rgb::ZERO,
    };

    /// A splat of `radiance` into pixel `pixel` (< 2³¹) from a photon of half `half`.
    pub fn new(pixel: u32, radiance: Rgb, half: bool) -> Self {
        Self {
            key: (pixel & !HALF_BIT) | if half { HALF_BIT } else { 0 },
            radiance,
        }
    }

    /// The pixel index `y·W + x`.
    #[inline]
    pub fn pixel(&self) -> u32 {
        self.key & !HALF_BIT
    }

    /// Which of the forward pass's two independent halves the photon came from: the
    /// difference of the halves' sums in a pixel estimates the error of their total.
    #[inline]
    pub fn half(&self) -> bool {
        self.key & HALF_BIT != 0
    }
}

/// Where a forward pass puts the splats it makes, in emission order: a fixed array on
/// the device (`heapless::Vec`), a `Vec` on the desktop. Full storage is an error.
pub trait SplatStorage {
    /// Appends one splat.
    fn push_splat(&mut self, s: Splat) -> Result<(), Error>;
    /// Empties the storage (a new pass).
    fn clear_splats(&mut self);
}

impl<const S: usize> SplatStorage for heapless::Vec<Splat, S> {
    fn push_splat(&mut self, s: Splat) -> Result<(), Error> {
        self.push(s).map_err(|_| Error::Capacity {
            what: "splats (photons seen directly)",
            requested: S + 1,
            capacity: S,
        })
    }
    fn clear_splats(&mut self) {
        self.clear();
    }
}

/// Drops every splat: a forward pass for a renderer that gathers everywhere.
impl SplatStorage for () {
    fn push_splat(&mut self, _: Splat) -> Result<(), Error> {
        Ok(())
    }
    fn clear_splats(&mut self) {}
}

#[cfg(feature = "std")]
impl SplatStorage for std::vec::Vec<Splat> {
    fn push_splat(&mut self, s: Splat) -> Result<(), Error> {
        self.push(s);
        Ok(())
    }
    fn clear_splats(&mut self) {
        self.clear();
    }
}

/// Connects a photon that landed at `hit` on `material`, travelling along `dir` with
/// `power` (W), to the eye: `None` when the eye is behind the surface, the point is
/// outside the image, or anything lies between (one shadow ray; every object blocks).
///
/// The radiance added is `f·Φ·|n·(e − p)|/(A·z³)` ([`Camera::project`]), with
/// `f` the material's response to light from `−dir` seen from the eye
/// ([`Material::caustic_response`]).
///
/// [`Camera::project`]: crate::camera::Camera::project
pub(crate) fn connect<const O: usize, const L: usize>(
    scene: &Scene<O, L>,
    hit: &Hit,
    material: &Material,
    dir: UnitVec3,
    power: Rgb,
    half: bool,
) -> Option<Splat> {
    let camera = scene.camera();
    let pr = camera.project(hit.point, hit.normal)?;
    // The eye must be on the side the photon arrived from (the lit side).
    if !(hit.normal.dot(pr.to_eye.get()) > 0.0) {
        return None;
    }
    let ray = Ray::spawn(hit, pr.to_eye);
    let reach = crate::math::sqrt((camera.position() - ray.origin).length_squared());
    if scene.occluded(&ray, reach) {
        return None;
    }
    let f = material.caustic_response(hit.normal, -dir, pr.to_eye);
    let radiance = f * power * pr.factor;
    (!radiance.is_black()).then(|| Splat::new(pr.pixel, radiance, half))
}

/// A pixel that splats add to: a radiance, or a pixel with its error estimate.
pub trait SplatTarget {
    /// Adds one splat's radiance.
    fn add_splat(&mut self, s: &Splat);
}

impl SplatTarget for Rgb {
    #[inline]
    fn add_splat(&mut self, s: &Splat) {
        *self += s.radiance;
    }
}

/// Adds to `row` (row `y` of an image `row.len()` pixels wide) the splats that fall in
/// it, in their order. Scans the whole list: the device's splat list is short.
pub fn add_to_row<T: SplatTarget>(splats: &[Splat], y: u32, row: &mut [T]) {
    let width = row.len() as u32;
    let start = y.saturating_mul(width);
    for s in splats {
        if let Some(i) = s.pixel().checked_sub(start) {
            if let Some(px) = row.get_mut(i as usize) {
                px.add_splat(s);
            }
        }
    }
}

/// Adds every splat to a whole frame (`frame.len()` = W·H, row-major), in order: the
/// same sums as [`add_to_row`] row by row.
pub fn add_to_frame<T: SplatTarget>(splats: &[Splat], frame: &mut [T]) {
    for s in splats {
        if let Some(px) = frame.get_mut(s.pixel() as usize) {
            px.add_splat(s);
        }
    }
}

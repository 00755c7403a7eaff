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
//! Splats are kept in emission order; a row adds the splats of its pixels in that order
//! ([`add_to_row`]), so whatever renders rows through the core (the device, the desktop
//! simulator, the host's check of a firmware) sums every pixel in the same order and
//! agrees bit for bit. The desktop's frame sums each pixel's splats in `f64` instead
//! ([`add_to_frame`], with `std`), where budgets are large enough for `f32`'s rounding to
//! bias a focus.

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
    /// Adds the sum of a pixel's splats, `total`, whose halves' difference (half 0's
    /// less half 1's) is `split`.
    fn add_sums(&mut self, total: Rgb, split: Rgb);
}

impl SplatTarget for Rgb {
    #[inline]
    fn add_splat(&mut self, s: &Splat) {
        *self += s.radiance;
    }
    #[inline]
    fn add_sums(&mut self, total: Rgb, _: Rgb) {
        *self += total;
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

/// Adds every splat to a whole frame (`frame.len()` = W·H, row-major): each pixel's
/// splats summed in `f64`, per half, in their order, and added to it once.
///
/// Not [`add_to_row`]'s running sum in `f32`: the splats of a focus are many and of
/// about the same radiance `v`, and each `f32` addition rounds by up to half an ulp of
/// the sum so far, the same way while `v` over that ulp stays the same — a bias, not a
/// noise, and one that grows with the photons (their splats are smaller). On the
/// sphere + wall g at 1.6M photons a light its focus pixel read 78.878 in `f32`, 78.887
/// in `f64`, and the caustic region 0.0175 against 0.0151 (`docs/accuracy.md`, session
/// 31). A device's short list keeps `add_to_row`: its rows hold no room for `f64` sums.
#[cfg(feature = "std")]
pub fn add_to_frame<T: SplatTarget>(splats: &[Splat], frame: &mut [T]) {
    let mut sums = SplatSums::new(frame.len());
    sums.add(splats);
    sums.add_to(frame);
}

/// The splats of a frame summed per pixel and per half in `f64`, as [`add_to_frame`]
/// sums them: fed in emission order a batch at a time ([`add`](Self::add)), so that a
/// forward pass can sum each chunk of photons as it is appended and keep no list of
/// splats, then added to the frame once ([`add_to`](Self::add_to)). The same sums, bit
/// for bit, as one [`add_to_frame`] over the whole list.
#[cfg(feature = "std")]
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SplatSums {
    /// Per pixel, per half, the sum of the splats' radiance (r, g, b).
    sums: std::vec::Vec<[[f64; 3]; 2]>,
    /// Splats added since the last [`clear`](Self::clear).
    count: u64,
}

#[cfg(feature = "std")]
impl SplatSums {
    /// Zero sums for a frame of `pixels` pixels.
    pub fn new(pixels: usize) -> Self {
        Self {
            sums: std::vec![[[0.0; 3]; 2]; pixels],
            count: 0,
        }
    }

    /// Zero sums again, for a frame of `pixels` pixels (a new pass): a fresh zeroed
    /// allocation, whose pages the system zeroes as they are first written, rather than
    /// 48 bytes a pixel written over before the pass (at 320×240, 900 pages faulted in
    /// by one thread: 6 ms before the forward pass could start).
    pub fn clear(&mut self, pixels: usize) {
        *self = Self::new(pixels);
    }

    /// Adds `splats`, in their order; one outside the frame is counted and dropped.
    pub fn add(&mut self, splats: &[Splat]) {
        for s in splats {
            if let Some(sum) = self.sums.get_mut(s.pixel() as usize) {
                let (half, r) = (&mut sum[s.half() as usize], s.radiance);
                for (acc, v) in half.iter_mut().zip([r.r, r.g, r.b]) {
                    *acc += v as f64;
                }
            }
        }
        self.count += splats.len() as u64;
    }

    /// Splats added.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Adds each pixel's sum, and its halves' difference, to `frame` (row-major, as
    /// many pixels as the sums; a pixel no splat reached is left alone).
    pub fn add_to<T: SplatTarget>(&self, frame: &mut [T]) {
        self.add_to_pixels(0, frame);
    }

    /// [`add_to`](Self::add_to) for row `y` alone of a frame `row.len()` pixels wide:
    /// the same pixels, so that rows rendered in parallel take their splats as they are
    /// finished.
    pub fn add_to_row<T: SplatTarget>(&self, y: u32, row: &mut [T]) {
        self.add_to_pixels(y as usize * row.len(), row);
    }

    /// Adds the sums of pixels `first..` to `pixels`.
    fn add_to_pixels<T: SplatTarget>(&self, first: usize, pixels: &mut [T]) {
        let sums = self.sums.get(first..).unwrap_or_default();
        let rgb = |c: [f64; 3]| Rgb::new(c[0] as f32, c[1] as f32, c[2] as f32);
        for (px, [h0, h1]) in pixels.iter_mut().zip(sums) {
            if h0 != &[0.0; 3] || h1 != &[0.0; 3] {
                let total = rgb([0, 1, 2].map(|i| h0[i] + h1[i]));
                px.add_sums(total, rgb([0, 1, 2].map(|i| h0[i] - h1[i])));
            }
        }
    }
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;

    /// A million small splats in one pixel, half 1's three times half 0's: the frame
    /// holds their sum and the halves' difference to `f32`'s rounding of the exact ones,
    /// where a running `f32` sum drifts (each addition rounds the same way).
    #[test]
    fn a_frame_sums_many_small_splats_without_drift() {
        let (n, v) = (1u32 << 20, 0.1f32);
        let radiance = |half: bool| Rgb::splat(if half { 3.0 * v } else { v });
        let splats: std::vec::Vec<Splat> = (0..n)
            .map(|i| Splat::new(1, radiance(i % 2 == 1), i % 2 == 1))
            .collect();
        let half_sum = |half: bool| (n / 2) as f64 * radiance(half).r as f64;
        let exact = (half_sum(false) + half_sum(true)) as f32;
        let mut frame = [Rgb::ZERO; 2];
        add_to_frame(&splats, &mut frame);
        assert_eq!(frame, [Rgb::ZERO, Rgb::splat(exact)]);
        let mut running = [Rgb::ZERO; 2];
        add_to_row(&splats, 0, &mut running);
        let drift = (running[1].r - exact).abs() / exact;
        assert!(drift > 1e-4, "the running sum drifts by {drift}");
        let mut split = [PixelSplit::default(); 2];
        add_to_frame(&splats, &mut split);
        let difference = (half_sum(false) - half_sum(true)) as f32;
        assert_eq!(split[1].0, Rgb::splat(difference));
    }

    /// A target that keeps only the halves' difference.
    #[derive(Clone, Copy, Default)]
    struct PixelSplit(Rgb);

    impl SplatTarget for PixelSplit {
        fn add_splat(&mut self, _: &Splat) {}
        fn add_sums(&mut self, _: Rgb, split: Rgb) {
            self.0 += split;
        }
    }
}

//! What a render knows about its own error.
//!
//! Each pixel carries two error terms, each estimated from two independent halves of
//! the same budget (batch means; the difference of two i.i.d. estimates `A`, `B` of
//! the same value has `E[(A − B)²] = 2σ²`, so their mean has variance `E[(A − B)²]/4`):
//! - the photons': the forward pass's two randomised-QMC halves
//!   ([`Emitter`](crate::photon::Emitter)) each splat their photons and each store
//!   theirs (a photon knows its half); with `F_h` the sum of half `h`'s splats in the
//!   pixel and of its photons in the pixel's gathers behind glass (each photon already
//!   weighted by `n_h/n`), the total `F₀ + F₁` has squared error about `(F₀ − F₁)²`
//!   ([`Halves`](crate::photon::Halves));
//! - the sub-pixel sampling's: in a supersampled pixel, the two checkerboard halves of
//!   its grid ([`Sampling`](super::Sampling)) give `((m_a − m_b)/2)²`.
//!
//! In a supersampled pixel the checkerboard halves gather over halves of its
//! preimage, so their difference holds part of the gathers' noise; the sub-pixels'
//! splits, averaged, are carried as well, since a widened sub-pixel footprint overlaps
//! its neighbours'. Not estimated, and stated where it is reported: the gather's bias
//! where the ray differentials' linear
//! preimage of the pixel departs from the true one (at a silhouette or a fold of the
//! focus; a supersampled pixel's sub-pixels shrink it), and the error of a pixel whose
//! four corners agreed (smooth there by the test that let them agree).

use crate::math::Rgb;
use crate::photon::{Splat, SplatTarget};

/// One pixel with its caustic part and its estimated error.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelEstimate {
    /// The pixel's value: its average radiance.
    pub radiance: Rgb,
    /// The caustic part of `radiance`: the splats and the gathers behind glass.
    pub caustic: Rgb,
    /// The caustic part from the forward pass's half 0 minus half 1's: the splats, and
    /// the gathers where the pixel was not supersampled.
    pub split: Rgb,
    /// The estimated squared error of the sub-pixel sampling, per channel.
    pub sampling2: Rgb,
}

impl PixelEstimate {
    /// The estimated squared error of `radiance`, per channel.
    #[inline]
    pub fn error2(&self) -> Rgb {
        self.split * self.split + self.sampling2
    }

    /// `true` when the caustic part is at least a tenth of the pixel's luminance:
    /// the caustic region of [`ErrorTally::rel_rmse_caustic`].
    #[inline]
    pub fn is_caustic(&self) -> bool {
        let l = self.radiance.luminance();
        l > 0.0 && self.caustic.luminance() >= 0.1 * l
    }
}

/// The pixel's value alone (what a display draws).
impl From<PixelEstimate> for Rgb {
    #[inline]
    fn from(p: PixelEstimate) -> Rgb {
        p.radiance
    }
}

impl SplatTarget for PixelEstimate {
    #[inline]
    fn add_splat(&mut self, s: &Splat) {
        self.radiance += s.radiance;
        self.caustic += s.radiance;
        if s.half() {
            self.split -= s.radiance;
        } else {
            self.split += s.radiance;
        }
    }
    #[inline]
    fn add_sums(&mut self, total: Rgb, split: Rgb) {
        self.radiance += total;
        self.caustic += total;
        self.split += split;
    }
}

/// Sums over an image's pixels for its estimated relative RMSE, row by row (each row
/// summed in `f32`, rows in `f64`: the same figure on the desktop and the device).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorTally {
    pixels: u64,
    sum: f64,
    error2: f64,
    caustic_pixels: u64,
    caustic_sum: f64,
    caustic_error2: f64,
}

impl ErrorTally {
    /// Adds one row of finished pixels (splats included).
    pub fn add_row(&mut self, row: &[PixelEstimate]) {
        let (mut sum, mut e2, mut csum, mut ce2, mut cn) = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0u64);
        for p in row {
            let v = p.radiance.r + p.radiance.g + p.radiance.b;
            let e = p.error2();
            let e = e.r + e.g + e.b;
            sum += v;
            e2 += e;
            if p.is_caustic() {
                csum += v;
                ce2 += e;
                cn += 1;
            }
        }
        self.pixels += row.len() as u64;
        self.sum += sum as f64;
        self.error2 += e2 as f64;
        self.caustic_pixels += cn;
        self.caustic_sum += csum as f64;
        self.caustic_error2 += ce2 as f64;
    }

    /// Estimated `sqrt(mean((a − b)²)) / mean(b)` over pixels and channels, `b` the
    /// converged image (the definition of `caustic compare`); `None` for a black image.
    pub fn rel_rmse(&self) -> Option<f64> {
        ratio(self.error2, self.sum, self.pixels)
    }

    /// The same over the caustic region (pixels whose caustic part is at least a tenth
    /// of their luminance); `None` when it is empty.
    pub fn rel_rmse_caustic(&self) -> Option<f64> {
        ratio(self.caustic_error2, self.caustic_sum, self.caustic_pixels)
    }

    /// Pixels in the caustic region.
    pub fn caustic_pixels(&self) -> u64 {
        self.caustic_pixels
    }
}

/// `sqrt(e2/n) / (sum/n) = sqrt(e2·n)/sum` with `n = 3·pixels` values.
fn ratio(error2: f64, sum: f64, pixels: u64) -> Option<f64> {
    (sum > 0.0).then(|| libm::sqrt(error2 * 3.0 * pixels as f64) / sum)
}

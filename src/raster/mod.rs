//! From linear radiance to display pixels: exposure, sRGB encoding, and the
//! `embedded-graphics` [`DrawTarget`](embedded_graphics_core::draw_target::DrawTarget)
//! adapter (feature `embedded-graphics`) through which any display draws rows.

#[cfg(feature = "embedded-graphics")]
mod display;
mod srgb_table;
#[cfg(feature = "embedded-graphics")]
mod stream;

#[cfg(feature = "embedded-graphics")]
#[cfg_attr(docsrs, doc(cfg(feature = "embedded-graphics")))]
pub use display::{DisplaySink, Dither};
#[cfg(feature = "embedded-graphics")]
pub use stream::{Fnv1a, Rgb565Stream, StreamError};

use crate::error::{positive, Error};
use crate::math::Rgb;
use srgb_table::SRGB8_THRESHOLDS;

/// Encodes a linear value in `[0, 1]` (clamped; NaN gives 0) to the nearest 8-bit sRGB
/// code: the number of thresholds at or below `x`.
///
/// Counted from a start found by the value's bits: for positive floats the bit
/// patterns are ordered like the values, so the exponent and the top four mantissa bits
/// name one of `BUCKETS` sixteenths of an octave in `[2⁻¹³, 1)`, and `BUCKET_START`
/// holds the count at the bucket's lower end. At most a few thresholds lie in a bucket,
/// so a short forward scan ends the count — about 25 instructions a channel instead
/// of a binary search's 85 (2.5 % of the device render), with the same result.
#[inline]
pub fn linear_to_srgb8(x: f32) -> u8 {
    if !(x >= BUCKET_FLOOR) {
        return 0; // below every threshold, negative, or NaN
    }
    if x >= 1.0 {
        return 255; // above every threshold
    }
    let bucket = ((x.to_bits() >> BUCKET_SHIFT) - (FIRST_EXPONENT << 4)) as usize;
    let mut k = BUCKET_START[bucket] as usize;
    while k < SRGB8_THRESHOLDS.len() && SRGB8_THRESHOLDS[k] <= x {
        k += 1;
    }
    k as u8
}

/// The biased exponent of [`BUCKET_FLOOR`] = 2⁻¹³, below the first threshold (1.5·10⁻⁴).
const FIRST_EXPONENT: u32 = 127 - 13;
/// The smallest value with a bucket.
const BUCKET_FLOOR: f32 = 1.0 / 8192.0;
const _: () = assert!(BUCKET_FLOOR < SRGB8_THRESHOLDS[0] && SRGB8_THRESHOLDS[254] < 1.0);
/// Shift that keeps the exponent and four mantissa bits of an `f32`.
const BUCKET_SHIFT: u32 = 19;
/// Sixteen buckets per octave from 2⁻¹³ up to 1.
const BUCKETS: usize = 13 * 16;
/// `BUCKET_START[b]`: thresholds at or below the lower end of bucket `b` (compared by
/// their bits, which order positive floats as their values).
const BUCKET_START: [u8; BUCKETS] = {
    let mut out = [0u8; BUCKETS];
    let (mut b, mut k) = (0, 0);
    while b < BUCKETS {
        let lower = ((FIRST_EXPONENT << 4) + b as u32) << BUCKET_SHIFT;
        while k < SRGB8_THRESHOLDS.len() && SRGB8_THRESHOLDS[k].to_bits() <= lower {
            k += 1;
        }
        out[b] = k as u8;
        b += 1;
    }
    out
};

/// Decodes an 8-bit sRGB code to linear (the inverse transfer function, for tests and
/// tools; uses `powf`).
pub fn srgb8_to_linear(v: u8) -> f32 {
    let c = v as f32 / 255.0;
    if c <= 0.040_45 {
        c / 12.92
    } else {
        libm::powf((c + 0.055) / 1.055, 2.4)
    }
}

/// Tone mapping: a linear exposure scale, then clamping and sRGB encoding.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToneMap {
    exposure: f32,
}

impl Default for ToneMap {
    fn default() -> Self {
        Self { exposure: 1.0 }
    }
}

impl ToneMap {
    /// Scales radiance by `exposure` (> 0) before encoding.
    pub fn new(exposure: f32) -> Result<Self, Error> {
        Ok(Self {
            exposure: positive(exposure, "exposure")?,
        })
    }

    /// The exposure scale.
    pub fn exposure(&self) -> f32 {
        self.exposure
    }

    /// One pixel as 8-bit sRGB. A grey pixel (equal channels: the background, a floor
    /// under white light, most of a frame) is encoded once, with the same result.
    #[inline]
    pub fn srgb8(&self, c: Rgb) -> [u8; 3] {
        let e = self.exposure;
        let r = linear_to_srgb8(c.r * e);
        if c.g == c.r && c.b == c.r {
            return [r; 3];
        }
        [r, linear_to_srgb8(c.g * e), linear_to_srgb8(c.b * e)]
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    #[test]
    fn threshold_table_is_the_srgb_curve() {
        for (k, &t) in SRGB8_THRESHOLDS.iter().enumerate() {
            let c = (k as f64 + 0.5) / 255.0;
            let x = if c <= 0.040_45 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            };
            assert_eq!(t, x as f32, "threshold {k}");
        }
    }

    #[test]
    fn bucketed_count_is_the_binary_search() {
        let search = |x: f32| SRGB8_THRESHOLDS.partition_point(|&t| t <= x) as u8;
        let mut x = 1e-5f32;
        while x < 1.5 {
            for v in [
                x,
                f32::from_bits(x.to_bits() + 1),
                f32::from_bits(x.to_bits() - 1),
            ] {
                assert_eq!(linear_to_srgb8(v), search(v), "{v}");
            }
            x *= 1.0007;
        }
        for &t in &SRGB8_THRESHOLDS {
            for v in [
                t,
                f32::from_bits(t.to_bits() - 1),
                f32::from_bits(t.to_bits() + 1),
            ] {
                assert_eq!(linear_to_srgb8(v), search(v), "{v}");
            }
        }
        assert_eq!(BUCKET_FLOOR.to_bits() >> BUCKET_SHIFT, FIRST_EXPONENT << 4);
    }

    #[test]
    fn a_grey_pixel_encodes_as_its_channels_do() {
        let tone = ToneMap::new(1.7).unwrap();
        let each = |c: Rgb| [c.r, c.g, c.b].map(|x| linear_to_srgb8(x * 1.7));
        for v in [0.0, -0.0, 1e-4, 0.003, 0.3, 0.59, 2.0, f32::NAN] {
            for c in [Rgb::splat(v), Rgb::new(v, -0.0, v), Rgb::new(v, v, 0.2)] {
                assert_eq!(tone.srgb8(c), each(c), "{c:?}");
            }
        }
    }

    #[test]
    fn encoding_rounds_to_the_nearest_code() {
        for i in 0..=10_000 {
            let x = i as f32 / 10_000.0;
            let exact = {
                let x = x as f64;
                let c = if x <= 0.003_130_8 {
                    12.92 * x
                } else {
                    1.055 * x.powf(1.0 / 2.4) - 0.055
                };
                (c * 255.0).round() as u8
            };
            let got = linear_to_srgb8(x);
            // Equal except exactly at a rounding boundary, where f32 and f64 may differ by one.
            assert!(got.abs_diff(exact) <= 1, "{x}: {got} vs {exact}");
        }
        assert_eq!(linear_to_srgb8(-1.0), 0);
        assert_eq!(linear_to_srgb8(f32::NAN), 0);
        assert_eq!(linear_to_srgb8(1.0), 255);
        assert_eq!(linear_to_srgb8(1e30), 255);
        for v in 0..=255u8 {
            assert_eq!(linear_to_srgb8(srgb8_to_linear(v)), v);
        }
    }
}

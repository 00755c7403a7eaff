//! From linear radiance to display pixels: exposure, sRGB encoding, and the
//! `embedded-graphics` [`DrawTarget`](embedded_graphics_core::draw_target::DrawTarget)
//! adapter (feature `embedded-graphics`) through which any display draws rows.

#[cfg(feature = "embedded-graphics")]
mod display;
mod srgb_table;

#[cfg(feature = "embedded-graphics")]
#[cfg_attr(docsrs, doc(cfg(feature = "embedded-graphics")))]
pub use display::{DisplaySink, Dither};

use crate::error::{positive, Error};
use crate::math::Rgb;
use srgb_table::SRGB8_THRESHOLDS;

/// Encodes a linear value in `[0, 1]` (clamped; NaN gives 0) to the nearest 8-bit sRGB
/// code, by binary search in the threshold table.
#[inline]
pub fn linear_to_srgb8(x: f32) -> u8 {
    SRGB8_THRESHOLDS.partition_point(|&t| t <= x) as u8
}

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

    /// One pixel as 8-bit sRGB.
    #[inline]
    pub fn srgb8(&self, c: Rgb) -> [u8; 3] {
        let e = self.exposure;
        [
            linear_to_srgb8(c.r * e),
            linear_to_srgb8(c.g * e),
            linear_to_srgb8(c.b * e),
        ]
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

//! Point lights.

use crate::error::Error;
use crate::math::{finite_vec, Rgb, Vec3};

/// An isotropic point light of radiant intensity `I` (W/sr per channel): a surface at
/// distance `d` facing it receives irradiance `I/d²`; its total power is `4π·I`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    position: Vec3,
    intensity: Rgb,
}

/// The largest radiant intensity a light may have, W/sr per channel: that of a light
/// 10⁵ units away giving the irradiance of 10⁵ W/sr at one unit.
///
/// Beyond it the renderer's `f32` products overflow. A photon map's power unit is up
/// to `4π·I`, a photon of its second coarse level stands for 256 of them, and a gather
/// divides their sum by its patch's area: at `I = 2·10³¹` (found by the fuzzer) a patch
/// of `2.5·10⁻⁶` gave `∞`, and a channel without light `0·∞ = NaN`. At 10¹⁵ that needs
/// a patch under 10⁻²⁰, smaller than any parallelogram a footprint makes
/// (`4·√MIN_POSITIVE ≈ 4·10⁻¹⁹`).
pub const MAX_INTENSITY: f32 = 1e15;

impl PointLight {
    /// A light; each channel of the intensity must lie between 0 and [`MAX_INTENSITY`].
    pub fn new(position: Vec3, intensity: Rgb) -> Result<Self, Error> {
        Ok(Self {
            position: finite_vec(position, "light position")?,
            intensity: intensity.validate_at_most(MAX_INTENSITY, "light intensity")?,
        })
    }

    /// Where it is.
    pub fn position(&self) -> Vec3 {
        self.position
    }

    /// Radiant intensity, W/sr.
    pub fn intensity(&self) -> Rgb {
        self.intensity
    }

    /// Total emitted power `4π·I`, W.
    pub fn power(&self) -> Rgb {
        self.intensity * (4.0 * core::f32::consts::PI)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Intensities from 0 to [`MAX_INTENSITY`] are lights; a negative, non-finite or
    /// larger one is an error that names the intensity.
    #[test]
    fn intensities_outside_the_range_are_errors() {
        let at = |i: f32| PointLight::new(Vec3::ZERO, Rgb::new(i, 1.0, 0.0));
        assert!(at(0.0).is_ok() && at(MAX_INTENSITY).is_ok());
        for bad in [-1.0, 2e31, f32::INFINITY, f32::NAN] {
            let e = at(bad).unwrap_err();
            assert!(
                matches!(
                    e,
                    Error::OutOfRange {
                        what: "light intensity",
                        ..
                    } | Error::NotFinite {
                        what: "light intensity"
                    }
                ),
                "{bad}: {e:?}"
            );
        }
    }
}

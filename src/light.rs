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

impl PointLight {
    /// A light; the intensity must be finite and non-negative.
    pub fn new(position: Vec3, intensity: Rgb) -> Result<Self, Error> {
        Ok(Self {
            position: finite_vec(position, "light position")?,
            intensity: intensity.validate("light intensity")?,
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

//! The pinhole camera of the scene format.

use crate::error::{in_range, Error};
use crate::geometry::Ray;
use crate::math::{finite_vec, UnitVec3, Vec3};

/// A pinhole camera: `forward = normalize(look_at − position)`,
/// `right = normalize(forward × up)`, `true_up = right × forward`; the image plane is at
/// distance 1 with vertical extent `2·tan(fov_y/2)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    position: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    half_w: f32,
    half_h: f32,
    width: u32,
    height: u32,
}

/// The largest image side accepted (keeps pixel arithmetic exact in `f32`).
pub const MAX_IMAGE_SIDE: u32 = 1 << 16;

impl Camera {
    /// A camera looking from `position` at `look_at`, `fov_y_deg` in (0, 180) degrees,
    /// rendering `width × height` pixels.
    pub fn new(
        position: Vec3,
        look_at: Vec3,
        up: Vec3,
        fov_y_deg: f32,
        width: u32,
        height: u32,
    ) -> Result<Self, Error> {
        let position = finite_vec(position, "camera position")?;
        let forward = UnitVec3::try_new(
            finite_vec(look_at, "camera look_at")? - position,
            "camera look_at − position",
        )?;
        let up = UnitVec3::try_new(up, "camera up")?;
        let right = UnitVec3::try_new(forward.get().cross(up.get()), "camera forward × up")?;
        let true_up = right.get().cross(forward.get());
        let fov = in_range(fov_y_deg, 1e-3, 179.0, "camera fov_y_deg")?;
        for (side, what) in [(width, "image width"), (height, "image height")] {
            if side == 0 || side > MAX_IMAGE_SIDE {
                return Err(Error::OutOfRange {
                    what,
                    value: side as f32,
                    min: 1.0,
                    max: MAX_IMAGE_SIDE as f32,
                });
            }
        }
        let half_h = libm::tanf(0.5 * fov * (core::f32::consts::PI / 180.0));
        let half_w = half_h * width as f32 / height as f32;
        Ok(Self {
            position,
            forward: forward.get(),
            right: right.get(),
            up: true_up,
            half_w,
            half_h,
            width,
            height,
        })
    }

    /// The same camera with another image size (the command line overrides the file).
    pub fn with_size(&self, width: u32, height: u32) -> Result<Self, Error> {
        let fov = 2.0 * libm::atanf(self.half_h) * (180.0 / core::f32::consts::PI);
        let mut c = Self::new(
            self.position,
            self.position + self.forward,
            self.up,
            fov,
            width,
            height,
        )?;
        c.half_h = self.half_h; // keep the exact field of view, not its round trip
        c.half_w = self.half_h * width as f32 / height as f32;
        Ok(c)
    }

    /// Image width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Image height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Where the eye is.
    pub fn position(&self) -> Vec3 {
        self.position
    }

    /// The ray through the centre of pixel `(x, y)`, `y = 0` the top row:
    /// `u = (2(x+½)/W − 1)·half_w`, `v = (1 − 2(y+½)/H)·half_h`,
    /// direction `normalize(forward + u·right + v·up)`.
    #[inline]
    pub fn ray(&self, x: u32, y: u32) -> Ray {
        self.ray_at(x, y, 0.5, 0.5)
    }

    /// The ray through the point `(x + fx, y + fy)` of the image, `fx, fy ∈ [0, 1)` the
    /// position inside pixel `(x, y)` (`½, ½` is its centre: [`ray`](Self::ray)).
    #[inline]
    pub fn ray_at(&self, x: u32, y: u32, fx: f32, fy: f32) -> Ray {
        let u = (2.0 * (x as f32 + fx) / self.width as f32 - 1.0) * self.half_w;
        let v = (1.0 - 2.0 * (y as f32 + fy) / self.height as f32) * self.half_h;
        let d = self.forward + self.right * u + self.up * v;
        // |d| ≥ 1 because forward is unit and orthogonal to right and up.
        Ray::new(
            self.position,
            UnitVec3::new(d).unwrap_or(UnitVec3::new_unchecked(self.forward)),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_pixel_looks_forward_and_corners_span_the_fov() {
        let c = Camera::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 90.0, 3, 3).unwrap();
        assert!((c.ray(1, 1).dir.get() - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6);
        // Top row is +y, left column is −x; with fov 90° and 3 rows, the top-centre
        // pixel centre is at v = (1 − 1/3)·tan 45° = 2/3.
        let top = c.ray(1, 0).dir.get();
        assert!((top.y / -top.z - 2.0 / 3.0).abs() < 1e-6 && top.x == 0.0);
        let left = c.ray(0, 1).dir.get();
        assert!((left.x / -left.z + 2.0 / 3.0).abs() < 1e-6);
    }

    #[test]
    fn rejects_degenerate_cameras() {
        assert!(Camera::new(Vec3::ZERO, Vec3::ZERO, Vec3::Y, 40.0, 4, 4).is_err());
        assert!(
            Camera::new(Vec3::ZERO, Vec3::Y, Vec3::Y, 40.0, 4, 4).is_err(),
            "up parallel to view"
        );
        assert!(Camera::new(Vec3::ZERO, Vec3::X, Vec3::Y, 0.0, 4, 4).is_err());
        assert!(Camera::new(Vec3::ZERO, Vec3::X, Vec3::Y, 40.0, 0, 4).is_err());
    }
}

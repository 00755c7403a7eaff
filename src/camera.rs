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

/// Images have fewer pixels than this (a pixel index fits in 31 bits).
pub const MAX_PIXELS: u64 = 1 << 31;

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
        if width as u64 * height as u64 >= MAX_PIXELS {
            return Err(Error::OutOfRange {
                what: "image width × height",
                value: (width as u64 * height as u64) as f32,
                min: 1.0,
                max: MAX_PIXELS as f32,
            });
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

/// Where a surface point appears on the image, for light tracing (connecting a photon to
/// the eye): the pixel it projects into and the factor that turns the flux `Φ` the point
/// reflects per unit of its BRDF into that pixel's average radiance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projection {
    /// Pixel index `y·W + x`.
    pub pixel: u32,
    /// The pixel's row (0 = top).
    pub row: u32,
    /// `|n·(e − p)| / (A·z³)`, 1/m²: see [`Camera::project`].
    pub factor: f32,
    /// Unit direction from the point towards the eye.
    pub to_eye: UnitVec3,
    /// Distance from the point to the eye.
    pub distance: f32,
}

impl Camera {
    /// Area of one pixel on the image plane at distance 1: `(2·half_w/W)·(2·half_h/H)`.
    #[inline]
    pub fn pixel_area(&self) -> f32 {
        (2.0 * self.half_w / self.width as f32) * (2.0 * self.half_h / self.height as f32)
    }

    /// The angle one pixel spans at the image centre, radians (`2·half_h/H`): the width
    /// of a pixel's ray cone per unit of distance travelled.
    #[inline]
    pub fn pixel_angle(&self) -> f32 {
        2.0 * self.half_h / self.height as f32
    }

    /// How the direction `dir` of a camera ray changes per pixel step along the image's
    /// x and y (ray differentials, Igehy 1999; pbrt-v4 §5.2.4): with
    /// `w = forward + u·right + v·up` and `dir = w/|w|`,
    /// `∂dir = (∂w − dir·(dir·∂w))/|w|`, `∂w/∂x = right·2·half_w/W`,
    /// `∂w/∂y = −up·2·half_h/H`, and `1/|w| = dir·forward`. The origin does not move
    /// (a pinhole).
    #[inline]
    pub fn direction_derivatives(&self, dir: UnitVec3) -> [Vec3; 2] {
        let d = dir.get();
        let inv_len = d.dot(self.forward);
        let dwdx = self.right * (2.0 * self.half_w / self.width as f32);
        let dwdy = self.up * (-2.0 * self.half_h / self.height as f32);
        [
            (dwdx - d * d.dot(dwdx)) * inv_len,
            (dwdy - d * d.dot(dwdy)) * inv_len,
        ]
    }

    /// Projects the surface point `p` of normal `n` through the pinhole: the inverse of
    /// [`ray_at`](Self::ray_at). `None` behind the eye or outside the image.
    ///
    /// A pixel's value is the average over its area `A` (on the image plane, at unit
    /// distance) of the radiance seen through it. An image-plane patch `dA_film` sees a surface
    /// patch `dA = dA_film·d²·cos³θ_c / cosθ`, with `d` the distance to the eye, `θ_c`
    /// the angle off the optical axis and `θ` the angle at the surface, so a flux `Φ`
    /// arriving at `p` on a surface of BRDF `f` adds `f·Φ·cosθ/(A·d²·cos³θ_c)` to the
    /// pixel. With `z = (p − e)·forward = d·cosθ_c` and `cosθ = |n·(e − p)|/d` that is
    /// `f·Φ·|n·(e − p)|/(A·z³)`: the importance of a pinhole camera (Veach 1997 §10;
    /// pbrt-v4 §5.4.1). `factor` is `|n·(e − p)|/(A·z³)`.
    pub fn project(&self, p: Vec3, n: UnitVec3) -> Option<Projection> {
        let d = p - self.position;
        let z = d.dot(self.forward);
        if !(z > 0.0) {
            return None;
        }
        let u = d.dot(self.right) / z;
        let v = d.dot(self.up) / z;
        let px = (u / self.half_w + 1.0) * (0.5 * self.width as f32);
        let py = (1.0 - v / self.half_h) * (0.5 * self.height as f32);
        // `!(a < b)` also rejects NaN.
        if !(px >= 0.0 && py >= 0.0 && px < self.width as f32 && py < self.height as f32) {
            return None;
        }
        let (x, y) = (
            (px as u32).min(self.width - 1),
            (py as u32).min(self.height - 1),
        );
        let distance = crate::math::sqrt(d.length_squared());
        let to_eye = UnitVec3::new(-d)?;
        let factor = n.dot(-d).abs() / (self.pixel_area() * z * z * z);
        factor.is_finite().then_some(Projection {
            pixel: y * self.width + x,
            row: y,
            factor,
            to_eye,
            distance,
        })
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

    #[test]
    fn projection_inverts_the_pixel_ray() {
        let c = Camera::new(
            Vec3::new(0.3, 4.0, 7.0),
            Vec3::new(0.0, 0.6, 0.0),
            Vec3::Y,
            40.0,
            32,
            24,
        )
        .unwrap();
        for (x, y, fx, fy) in [(0, 0, 0.1, 0.9), (31, 23, 0.7, 0.2), (13, 7, 0.5, 0.5)] {
            let ray = c.ray_at(x, y, fx, fy);
            let p = ray.at(3.7);
            let pr = c.project(p, UnitVec3::Y).unwrap();
            assert_eq!((pr.pixel, pr.row), (y * 32 + x, y));
            assert!((pr.distance - 3.7).abs() < 1e-5);
            assert!((pr.to_eye.get() + ray.dir.get()).length() < 1e-5);
        }
        assert!(
            c.project(Vec3::new(0.0, 4.0, 9.0), UnitVec3::Y).is_none(),
            "behind"
        );
    }

    /// The factor is the pixel's footprint turned around: a plane lit with uniform
    /// irradiance E, sampled by photons of flux E·dA, gives each pixel Σ factor·E·dA =
    /// E, so the factor integrates to 1 over the footprint of the pixel (brute force).
    #[test]
    fn projection_factor_integrates_to_one_over_a_pixel_footprint() {
        let c = Camera::new(Vec3::new(0.0, 4.0, 7.0), Vec3::ZERO, Vec3::Y, 40.0, 16, 12).unwrap();
        let target = 5 * 16 + 9; // pixel (9, 5)
        let (n, half) = (800, 4.0);
        let step = 2.0 * half / n as f32;
        let mut sum = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let p = Vec3::new(
                    -half + (i as f32 + 0.5) * step,
                    0.0,
                    -half + (j as f32 + 0.5) * step,
                );
                if let Some(pr) = c.project(p, UnitVec3::Y) {
                    if pr.pixel == target {
                        sum += (pr.factor * step * step) as f64;
                    }
                }
            }
        }
        assert!((sum - 1.0).abs() < 0.02, "{sum}");
    }
}

//! The rotated box (the paper's "cube").

use super::{error_bound, BoundingSphere, Hit, Ray};
use crate::error::{positive, Error};
use crate::math::{finite_vec, max_abs, Mat3, UnitVec3, Vec3};

/// A box of full edge lengths `size`, rotated about its centre by `rotation_deg`
/// (degrees, applied about X, then Y, then Z: `R = Rz·Ry·Rx`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cuboid {
    center: Vec3,
    half: Vec3,
    /// Columns: the box's local axes in world space.
    rotation: Mat3,
    error: f32,
}

impl Cuboid {
    /// A box; every edge length must be positive.
    pub fn new(center: Vec3, size: Vec3, rotation_deg: Vec3) -> Result<Self, Error> {
        let center = finite_vec(center, "box center")?;
        for s in size.to_array() {
            positive(s, "box size")?;
        }
        let r = finite_vec(rotation_deg, "box rotation_deg")? * (core::f32::consts::PI / 180.0);
        let rotation =
            Mat3::from_rotation_z(r.z) * Mat3::from_rotation_y(r.y) * Mat3::from_rotation_x(r.x);
        let half = size * 0.5;
        Ok(Self {
            center,
            half,
            rotation,
            error: error_bound(max_abs(center) + half.length()),
        })
    }

    /// The centre.
    pub fn center(&self) -> Vec3 {
        self.center
    }

    /// Half the edge lengths.
    pub fn half_size(&self) -> Vec3 {
        self.half
    }

    /// The rotation (columns are the local axes).
    pub fn rotation(&self) -> Mat3 {
        self.rotation
    }

    /// The sphere through the corners.
    pub fn bounding_sphere(&self) -> BoundingSphere {
        BoundingSphere {
            center: self.center,
            radius: self.half.length(),
        }
    }

    /// The nearest hit with `0 < t < t_max`, by the slab method (Kay & Kajiya 1986) in
    /// the box's frame. A direction component of exactly zero is handled apart, so that
    /// a ray lying in a face plane never produces `0·∞ = NaN`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let rt = self.rotation.transpose();
        let o = rt * (ray.origin - self.center);
        let d = rt * ray.dir.get();
        let (mut t_near, mut t_far) = (f32::NEG_INFINITY, f32::INFINITY);
        let (mut near_axis, mut far_axis) = (0usize, 0usize);
        for i in 0..3 {
            let (oi, di, hi) = (o[i], d[i], self.half[i]);
            if di == 0.0 {
                if oi < -hi || oi > hi {
                    return None;
                }
                continue;
            }
            let inv = 1.0 / di;
            let (mut ta, mut tb) = ((-hi - oi) * inv, (hi - oi) * inv);
            if ta > tb {
                core::mem::swap(&mut ta, &mut tb);
            }
            if ta > t_near {
                t_near = ta;
                near_axis = i;
            }
            if tb < t_far {
                t_far = tb;
                far_axis = i;
            }
        }
        if !(t_near <= t_far) {
            return None;
        }
        // Entering through the near face, or leaving through the far one from inside.
        let (t, axis, sign) = if t_near > 0.0 {
            (t_near, near_axis, -libm::copysignf(1.0, d[near_axis]))
        } else {
            (t_far, far_axis, libm::copysignf(1.0, d[far_axis]))
        };
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let mut local = o + d * t;
        local[axis] = sign * self.half[axis];
        local = local.clamp(-self.half, self.half);
        let point = self.center + self.rotation * local;
        let normal = UnitVec3::new(self.rotation.col(axis) * sign)?;
        Some(Hit {
            t,
            point,
            normal,
            error: self.error,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::geometry::tests::ray;

    #[test]
    fn axis_aligned_cases() {
        let b = Cuboid::new(Vec3::ZERO, Vec3::new(2.0, 4.0, 6.0), Vec3::ZERO).unwrap();
        let h = b
            .intersect(&ray([-5.0, 0.0, 0.0], [1.0, 0.0, 0.0]), f32::INFINITY)
            .unwrap();
        assert_eq!((h.t, h.normal), (4.0, -UnitVec3::X));
        // From inside: leaves through +y.
        let h = b
            .intersect(&ray([0.0; 3], [0.0, 1.0, 0.0]), f32::INFINITY)
            .unwrap();
        assert_eq!((h.t, h.normal), (2.0, UnitVec3::Y));
        // Behind, parallel-outside, and in a face plane (0·∞ must not be NaN).
        assert!(b
            .intersect(&ray([-5.0, 0.0, 0.0], [-1.0, 0.0, 0.0]), f32::INFINITY)
            .is_none());
        assert!(b
            .intersect(&ray([-5.0, 3.0, 0.0], [1.0, 0.0, 0.0]), f32::INFINITY)
            .is_none());
        // The box is closed: a ray lying in the plane of the +y face (y = 2) touches it
        // along that face, entering at the edge x = −1 (no NaN from 0·∞ on the y slab).
        let h = b
            .intersect(&ray([-5.0, 2.0, 0.0], [1.0, 0.0, 0.0]), f32::INFINITY)
            .unwrap();
        assert_eq!((h.t, h.normal), (4.0, -UnitVec3::X));
        assert_eq!(h.point, Vec3::new(-1.0, 2.0, 0.0));
        // Just outside that plane: a miss.
        let above = f32::from_bits(2.0f32.to_bits() + 1);
        assert!(b
            .intersect(&ray([-5.0, above, 0.0], [1.0, 0.0, 0.0]), f32::INFINITY)
            .is_none());
        // Through an edge diagonal.
        let h = b
            .intersect(&ray([-2.0, -3.0, 0.0], [1.0, 1.0, 0.0]), f32::INFINITY)
            .unwrap();
        assert!((h.point - Vec3::new(-1.0, -2.0, 0.0)).length() < 1e-5);
    }

    #[test]
    fn rotation_applies_x_then_y_then_z() {
        // Rotating a 2×4×6 box 90° about Z maps its local x (half 1) to world y.
        let b = Cuboid::new(
            Vec3::ZERO,
            Vec3::new(2.0, 4.0, 6.0),
            Vec3::new(0.0, 0.0, 90.0),
        )
        .unwrap();
        let h = b
            .intersect(&ray([0.0, 5.0, 0.0], [0.0, -1.0, 0.0]), f32::INFINITY)
            .unwrap();
        assert!((h.t - 4.0).abs() < 1e-5, "{}", h.t);
        assert!((h.normal.get() - Vec3::Y).length() < 1e-6);
        // X then Y: local z (half 3) → after Rx(90°) along −y → Ry leaves y alone.
        let b = Cuboid::new(
            Vec3::ZERO,
            Vec3::new(2.0, 4.0, 6.0),
            Vec3::new(90.0, 90.0, 0.0),
        )
        .unwrap();
        let h = b
            .intersect(&ray([0.0, 9.0, 0.0], [0.0, -1.0, 0.0]), f32::INFINITY)
            .unwrap();
        assert!((h.t - 6.0).abs() < 1e-5, "{}", h.t);
    }

    #[test]
    fn agrees_with_a_brute_force_inside_test() {
        let b = Cuboid::new(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(1.0, 2.0, 1.5),
            Vec3::new(10.0, 30.0, 50.0),
        )
        .unwrap();
        let inside = |p: Vec3| {
            let l = b.rotation.transpose() * (p - b.center);
            l.abs().cmple(b.half).all()
        };
        for i in 0..40 {
            for j in 0..40 {
                let dir = Vec3::new(1.0, 2.0, 3.0)
                    + Vec3::new(i as f32 - 20.0, j as f32 - 20.0, 0.0) * 0.05;
                let r = Ray::new(Vec3::ZERO, UnitVec3::new(dir).unwrap());
                let exact = b.intersect(&r, f32::INFINITY).map(|h| h.t);
                let steps = 20_000;
                let brute = (1..=steps)
                    .map(|k| 8.0 * k as f32 / steps as f32)
                    .find(|&t| inside(r.at(t)));
                match (exact, brute) {
                    (Some(e), Some(bt)) => assert!((e - bt).abs() < 1e-3, "{e} {bt}"),
                    (None, None) => {}
                    (Some(e), None) => {
                        // A ray that only grazes a corner may fall between march steps:
                        // then it must still leave the box within one step.
                        let step = 8.0 / steps as f32;
                        assert!(!inside(r.at(e + 2.0 * step)), "{i},{j}: {e}");
                    }
                    (None, Some(bt)) => panic!("{i},{j}: missed a box the march enters at {bt}"),
                }
            }
        }
    }

    #[test]
    fn rejects_a_flat_box() {
        assert!(Cuboid::new(Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0), Vec3::ZERO).is_err());
        assert!(Cuboid::new(Vec3::ZERO, Vec3::ONE, Vec3::new(f32::NAN, 0.0, 0.0)).is_err());
    }
}

//! The rotated box (the paper's "cube").

use super::{error_bound, reject_radius2, surely_missed, BoundingSphere, Hit, Ray};
use crate::error::{positive, Error};
use crate::math::{finite_vec, max_abs, sin_cos_turns, Mat3, UnitVec3, Vec3};

/// A box of full edge lengths `size`, rotated about its centre by `rotation_deg`
/// (degrees, applied about X, then Y, then Z: `R = Rz·Ry·Rx`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cuboid {
    center: Vec3,
    half: Vec3,
    /// Columns: the box's local axes in world space.
    rotation: Mat3,
    /// Rows: the same axes (`rotation` transposed, kept so that a ray is brought into
    /// the box's frame without transposing per ray).
    inverse: Mat3,
    /// Squared radius of the sphere through the corners, widened by a relative 10⁻⁴
    /// and the error bound so that rounding never lets the sphere test reject a ray
    /// the slab test would hit.
    reject_r2: f32,
    /// The outward unit normals of the faces, `[axis][0: −, 1: +]`.
    normals: [[UnitVec3; 2]; 3],
    error: f32,
}

impl Cuboid {
    /// A box; every edge length must be positive.
    pub fn new(center: Vec3, size: Vec3, rotation_deg: Vec3) -> Result<Self, Error> {
        let center = finite_vec(center, "box center")?;
        for s in size.to_array() {
            positive(s, "box size")?;
        }
        let turns = finite_vec(rotation_deg, "box rotation_deg")? * (1.0 / 360.0);
        let rotation = rotation_zyx(turns);
        let half = size * 0.5;
        let error = error_bound(max_abs(center) + half.length());
        let mut normals = [[UnitVec3::X; 2]; 3];
        for (axis, pair) in normals.iter_mut().enumerate() {
            for (side, sign) in [-1.0f32, 1.0].into_iter().enumerate() {
                pair[side] = UnitVec3::try_new(rotation.col(axis) * sign, "box rotation_deg")?;
            }
        }
        Ok(Self {
            center,
            half,
            rotation,
            inverse: rotation.transpose(),
            reject_r2: reject_radius2(half.length(), error),
            normals,
            error,
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

    /// `true` when the ray cannot meet the box before `t_max`, by its bounding
    /// sphere ([`surely_missed`]): about a dozen instructions instead of the slab
    /// test's sixty.
    #[inline]
    fn surely_missed(&self, ray: &Ray, t_max: f32) -> bool {
        surely_missed(self.center, self.reject_r2, ray, t_max)
    }

    /// The slab interval `(t_near, near_axis, t_far, far_axis)` of the ray in the box's
    /// frame (`o`, `d`), by the slab method (Kay & Kajiya 1986); `None` when it is empty.
    /// A direction component of exactly zero is handled apart, so that a ray lying in a
    /// face plane never produces `0·∞ = NaN`. (Arrays, not `Vec3`: glam indexes a
    /// `Vec3` through a `match`.)
    #[inline]
    fn slabs(&self, o: [f32; 3], d: [f32; 3]) -> Option<(f32, usize, f32, usize)> {
        let half = self.half.to_array();
        let mut s = Slabs {
            t_near: f32::NEG_INFINITY,
            near_axis: 0,
            t_far: f32::INFINITY,
            far_axis: 0,
        };
        // Unrolled by hand: a loop over an index keeps its bounds checks on Armv7-M.
        let inside = s.axis(0, o[0], d[0], half[0])
            && s.axis(1, o[1], d[1], half[1])
            && s.axis(2, o[2], d[2], half[2]);
        (inside && s.t_near <= s.t_far).then_some((s.t_near, s.near_axis, s.t_far, s.far_axis))
    }

    /// The ray in the box's frame: origin and direction.
    #[inline]
    fn local_ray(&self, ray: &Ray) -> ([f32; 3], [f32; 3]) {
        let o = self.inverse * (ray.origin - self.center);
        let d = self.inverse * ray.dir.get();
        (o.to_array(), d.to_array())
    }

    /// The nearest hit with `0 < t < t_max`: the slab test in the box's frame after the
    /// bounding-sphere test. Always inlined on the desktop: an out-of-line call returns
    /// its hit through memory, which the caller reads back before the stores have
    /// retired (a stalled store-to-load forward).
    #[cfg_attr(feature = "std", inline(always))]
    #[cfg_attr(not(feature = "std"), inline)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        if self.surely_missed(ray, t_max) {
            return None;
        }
        let (o, d) = self.local_ray(ray);
        let (t_near, near_axis, t_far, far_axis) = self.slabs(o, d)?;
        // Entering through the near face, or leaving through the far one from inside.
        let (t, axis, sign) = if t_near > 0.0 {
            (t_near, near_axis, -libm::copysignf(1.0, d[near_axis]))
        } else {
            (t_far, far_axis, libm::copysignf(1.0, d[far_axis]))
        };
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let half = self.half.to_array();
        // Clamped by comparisons: `Vec3::clamp` is six `fmaxf`/`fminf` calls on Armv7-M.
        let clamp = |i: usize| crate::math::clamp(o[i] + d[i] * t, -half[i], half[i]);
        let mut local = [clamp(0), clamp(1), clamp(2)];
        let axis = axis.min(2); // always: the index of a slab; lets the compiler drop checks
        local[axis] = sign * half[axis];
        let point = self.center + self.rotation * Vec3::from_array(local);
        let normal = self.normals[axis][(sign > 0.0) as usize];
        Some(Hit {
            t,
            point,
            normal,
            error: self.error,
        })
    }

    /// `true` when the ray meets the box at some `0 < t < t_max`: [`intersect`]'s
    /// distance without its point and normal (the shadow-ray query).
    ///
    /// [`intersect`]: Self::intersect
    #[inline]
    pub fn blocks(&self, ray: &Ray, t_max: f32) -> bool {
        if self.surely_missed(ray, t_max) {
            return false;
        }
        let (o, d) = self.local_ray(ray);
        let Some((t_near, _, t_far, _)) = self.slabs(o, d) else {
            return false;
        };
        let t = if t_near > 0.0 { t_near } else { t_far };
        t > 0.0 && t < t_max
    }
}

/// The slab method's running interval: entry and exit distance, and the axes of the
/// faces they lie on.
struct Slabs {
    t_near: f32,
    near_axis: usize,
    t_far: f32,
    far_axis: usize,
}

impl Slabs {
    /// Narrows the interval by the slab `|o + t·d| ≤ h` of `axis`; `false` when the ray
    /// runs parallel to it outside (a zero component is handled apart, so that a ray
    /// lying in a face plane never produces `0·∞ = NaN`).
    #[inline(always)]
    fn axis(&mut self, axis: usize, o: f32, d: f32, h: f32) -> bool {
        if d == 0.0 {
            return !(o < -h || o > h);
        }
        let inv = 1.0 / d;
        let (mut ta, mut tb) = ((-h - o) * inv, (h - o) * inv);
        if ta > tb {
            core::mem::swap(&mut ta, &mut tb);
        }
        if ta > self.t_near {
            self.t_near = ta;
            self.near_axis = axis;
        }
        if tb < self.t_far {
            self.t_far = tb;
            self.far_axis = axis;
        }
        true
    }
}

/// `R = Rz·Ry·Rx` for angles given in turns, with [`sin_cos_turns`]: single
/// precision only (glam's rotations call `libm::sincosf`, whose `f64` kernels are
/// 3 KiB of flash and soft-float on a device), and exact at quarter turns.
fn rotation_zyx(turns: Vec3) -> Mat3 {
    let (sx, cx) = sin_cos_turns(turns.x);
    let (sy, cy) = sin_cos_turns(turns.y);
    let (sz, cz) = sin_cos_turns(turns.z);
    let rx = Mat3::from_cols(Vec3::X, Vec3::new(0.0, cx, sx), Vec3::new(0.0, -sx, cx));
    let ry = Mat3::from_cols(Vec3::new(cy, 0.0, -sy), Vec3::Y, Vec3::new(sy, 0.0, cy));
    let rz = Mat3::from_cols(Vec3::new(cz, sz, 0.0), Vec3::new(-sz, cz, 0.0), Vec3::Z);
    rz * ry * rx
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
        // A 2×4×6 box at the origin turned by `deg`, hit by a ray down −y from (0, y, 0).
        let down = |deg: Vec3, y: f32| {
            Cuboid::new(Vec3::ZERO, Vec3::new(2.0, 4.0, 6.0), deg)
                .unwrap()
                .intersect(&ray([0.0, y, 0.0], [0.0, -1.0, 0.0]), f32::INFINITY)
                .unwrap()
        };
        // 90° about Z maps its local x (half 1) to world y.
        let h = down(Vec3::new(0.0, 0.0, 90.0), 5.0);
        assert!((h.t - 4.0).abs() < 1e-5, "{}", h.t);
        assert!((h.normal.get() - Vec3::Y).length() < 1e-6);
        // X then Y: local z (half 3) → after Rx(90°) along −y → Ry leaves y alone.
        let h = down(Vec3::new(90.0, 90.0, 0.0), 9.0);
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
            let l = b.inverse * (p - b.center);
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
    fn rotation_is_glams_to_a_few_ulps() {
        for deg in [
            Vec3::new(0.0, 30.0, 0.0),
            Vec3::new(10.0, 20.0, 30.0),
            Vec3::new(-45.0, 400.0, 90.0),
        ] {
            let r = deg * (core::f32::consts::PI / 180.0);
            let glam = Mat3::from_rotation_z(r.z)
                * Mat3::from_rotation_y(r.y)
                * Mat3::from_rotation_x(r.x);
            let ours = rotation_zyx(deg * (1.0 / 360.0));
            for (a, b) in ours.to_cols_array().into_iter().zip(glam.to_cols_array()) {
                assert!((a - b).abs() < 1e-6, "{deg}: {a} {b}");
            }
        }
    }

    #[test]
    fn rejects_a_flat_box() {
        assert!(Cuboid::new(Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0), Vec3::ZERO).is_err());
        assert!(Cuboid::new(Vec3::ZERO, Vec3::ONE, Vec3::new(f32::NAN, 0.0, 0.0)).is_err());
    }
}

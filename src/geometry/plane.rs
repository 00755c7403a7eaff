//! The infinite plane.

use super::{error_bound, Hit, Ray};
use crate::error::Error;
use crate::math::{finite_vec, max_abs, UnitVec3, Vec3};

/// The infinite plane through `point` with unit `normal`. One-sided for shading (the
/// normal is the outward side), but it blocks rays from both sides.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    point: Vec3,
    normal: UnitVec3,
}

impl Plane {
    /// A plane; the normal need not be of unit length but must not be zero.
    pub fn new(point: Vec3, normal: Vec3) -> Result<Self, Error> {
        let point = finite_vec(point, "plane point")?;
        let normal = UnitVec3::try_new(normal, "plane normal")?;
        Ok(Self { point, normal })
    }

    /// A point on the plane.
    pub fn point(&self) -> Vec3 {
        self.point
    }

    /// The unit normal.
    pub fn normal(&self) -> UnitVec3 {
        self.normal
    }

    /// The hit with `0 < t < t_max`: `t = ((q − o)·n)/(d·n)`; the point is projected back
    /// onto the plane, and its error bound scales with the coordinates' magnitude.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let n = self.normal.get();
        let denom = n.dot(ray.dir.get());
        if denom == 0.0 {
            return None;
        }
        let t = n.dot(self.point - ray.origin) / denom;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let p = ray.at(t);
        let point = p - n * n.dot(p - self.point);
        let error = error_bound(max_abs(point) + max_abs(self.point));
        Some(Hit {
            t,
            point,
            normal: self.normal,
            error,
        })
    }
}

impl Plane {
    /// `true` when the ray meets the plane at some `0 < t < t_max` (the shadow-ray
    /// query: [`intersect`](Self::intersect)'s distance only).
    #[inline]
    pub fn blocks(&self, ray: &Ray, t_max: f32) -> bool {
        let n = self.normal.get();
        let denom = n.dot(ray.dir.get());
        if denom == 0.0 {
            return false;
        }
        let t = n.dot(self.point - ray.origin) / denom;
        t > 0.0 && t < t_max
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn front_back_parallel_and_behind() {
        let p = Plane::new(Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.0, 2.0, 0.0)).unwrap();
        let down = Ray::new(Vec3::ZERO, -UnitVec3::Y);
        let h = p.intersect(&down, f32::INFINITY).unwrap();
        assert_eq!((h.t, h.point.y), (1.0, -1.0));
        assert_eq!(h.normal, UnitVec3::Y);
        // From below, the normal is still the given one: the plane is hit from the back.
        let up = Ray::new(Vec3::new(0.0, -3.0, 0.0), UnitVec3::Y);
        let h = p.intersect(&up, f32::INFINITY).unwrap();
        assert_eq!(h.t, 2.0);
        assert!(!h.front_face(up.dir));
        // Parallel and behind: no hit.
        assert!(p
            .intersect(&Ray::new(Vec3::ZERO, UnitVec3::X), f32::INFINITY)
            .is_none());
        assert!(p
            .intersect(&Ray::new(Vec3::ZERO, UnitVec3::Y), f32::INFINITY)
            .is_none());
        // Grazing: hit very far away, still on the plane.
        let graze = Ray::new(
            Vec3::ZERO,
            UnitVec3::new(Vec3::new(1.0, -1e-4, 0.0)).unwrap(),
        );
        let h = p.intersect(&graze, f32::INFINITY).unwrap();
        assert!((h.t - 1e4).abs() / 1e4 < 1e-3 && (h.point.y + 1.0).abs() <= h.error);
    }

    #[test]
    fn rejects_a_zero_normal() {
        assert!(Plane::new(Vec3::ZERO, Vec3::ZERO).is_err());
        assert!(Plane::new(Vec3::ZERO, Vec3::new(0.0, f32::NAN, 0.0)).is_err());
    }
}

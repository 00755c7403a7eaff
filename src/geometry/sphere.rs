//! The sphere.

use super::{error_bound, stable_roots, Hit, Ray};
use crate::error::{positive, Error};
use crate::math::{finite_vec, max_abs, UnitVec3, Vec3};

/// A sphere: all points at distance `radius` from `center`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    center: Vec3,
    radius: f32,
    /// Error bound of a point on the surface.
    error: f32,
}

impl Sphere {
    /// A sphere; the radius must be positive and everything finite.
    pub fn new(center: Vec3, radius: f32) -> Result<Self, Error> {
        let center = finite_vec(center, "sphere center")?;
        let radius = positive(radius, "sphere radius")?;
        Ok(Self {
            center,
            radius,
            error: error_bound(max_abs(center) + radius),
        })
    }

    /// The centre.
    pub fn center(&self) -> Vec3 {
        self.center
    }

    /// The radius.
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// The nearest hit with `0 < t < t_max`.
    ///
    /// With a unit direction, `t² + 2bt + c = 0` where `f = o − center`, `b = f·d`,
    /// `c = |f|² − r²`. The discriminant is formed as `r² − |f − b·d|²` (the squared
    /// distance of the chord's midpoint from the centre), which unlike `b² − c` does not
    /// cancel when the ray starts far away (pbrt-v4 §6.8.1; Haines et al., Ray Tracing
    /// Gems ch. 7). The point is re-projected onto the sphere.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let t = self.distance(ray, t_max)?;
        let local = ray.at(t) - self.center;
        let normal = UnitVec3::new(local)?;
        let point = self.center + normal.get() * self.radius;
        Some(Hit {
            t,
            point,
            normal,
            error: self.error,
        })
    }

    /// The distance of [`intersect`](Self::intersect)'s hit, without the point.
    #[inline]
    fn distance(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let d = ray.dir.get();
        let f = ray.origin - self.center;
        let b = f.dot(d);
        let chord = f - d * b;
        let r2 = self.radius * self.radius;
        let disc = r2 - chord.length_squared();
        let c = f.length_squared() - r2;
        let (t0, t1) = stable_roots(1.0, b, c, disc)?;
        let t = if t0 > 0.0 { t0 } else { t1 };
        (t > 0.0 && t < t_max).then_some(t)
    }

    /// `true` when the ray meets the sphere at some `0 < t < t_max` (the shadow-ray
    /// query: the roots only, no point or normal).
    #[inline]
    pub fn blocks(&self, ray: &Ray, t_max: f32) -> bool {
        self.distance(ray, t_max).is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::geometry::tests::ray;

    #[test]
    fn outside_inside_behind_tangent_and_grazing() {
        let s = Sphere::new(Vec3::new(0.0, 0.0, 5.0), 1.0).unwrap();
        // From outside: near face at t = 4, normal towards the ray.
        let h = s
            .intersect(&ray([0.0; 3], [0.0, 0.0, 1.0]), f32::INFINITY)
            .unwrap();
        assert_eq!(h.t, 4.0);
        assert_eq!(h.normal, -UnitVec3::Z);
        // From inside: the far face, outward normal along the ray.
        let h = s
            .intersect(&ray([0.0, 0.0, 5.0], [0.0, 0.0, 1.0]), f32::INFINITY)
            .unwrap();
        assert_eq!(h.t, 1.0);
        assert_eq!(h.normal, UnitVec3::Z);
        // Behind the origin: no hit.
        assert!(s
            .intersect(&ray([0.0; 3], [0.0, 0.0, -1.0]), f32::INFINITY)
            .is_none());
        // t_max excludes it.
        assert!(s.intersect(&ray([0.0; 3], [0.0, 0.0, 1.0]), 3.9).is_none());
        // Tangent at x = 1: one touching point.
        let h = s
            .intersect(&ray([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]), f32::INFINITY)
            .unwrap();
        assert!((h.t - 5.0).abs() < 1e-3 && (h.point - Vec3::new(1.0, 0.0, 5.0)).length() < 1e-3);
        // Just outside: miss.
        assert!(s
            .intersect(&ray([1.0001, 0.0, 0.0], [0.0, 0.0, 1.0]), f32::INFINITY)
            .is_none());
        // Grazing just inside: two hits very close together, both on the surface.
        let h = s
            .intersect(&ray([0.9999, 0.0, 0.0], [0.0, 0.0, 1.0]), f32::INFINITY)
            .unwrap();
        assert!(((h.point - s.center).length() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn hits_agree_with_brute_force_marching() {
        // March along rays in fine steps and find the first sign change of |p−c| − r.
        let s = Sphere::new(Vec3::new(0.3, -0.2, 4.0), 1.3).unwrap();
        for i in 0..50 {
            let a = i as f32 * 0.013 - 0.3;
            let r = ray([0.0; 3], [a, 0.5 * a, 1.0]);
            let exact = s.intersect(&r, f32::INFINITY).map(|h| h.t);
            let mut brute = None;
            let steps = 200_000;
            let mut prev = (r.origin - s.center).length() - s.radius;
            for k in 1..=steps {
                let t = 10.0 * k as f32 / steps as f32;
                let v = (r.at(t) - s.center).length() - s.radius;
                if prev > 0.0 && v <= 0.0 {
                    brute = Some(t);
                    break;
                }
                prev = v;
            }
            match (exact, brute) {
                (Some(e), Some(b)) => assert!((e - b).abs() < 2e-4, "{e} vs {b}"),
                (None, None) => {}
                other => panic!("ray {i}: {other:?}"),
            }
        }
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(Sphere::new(Vec3::ZERO, 0.0).is_err());
        assert!(Sphere::new(Vec3::ZERO, -1.0).is_err());
        assert!(Sphere::new(Vec3::ZERO, f32::NAN).is_err());
        assert!(Sphere::new(Vec3::new(f32::INFINITY, 0.0, 0.0), 1.0).is_err());
    }
}

//! The capped cylinder (the paper's "tube").

use super::{error_bound, reject_radius2, stable_roots, surely_missed, BoundingSphere, Hit, Ray};
use crate::error::{positive, Error};
use crate::math::{finite_vec, max_abs, UnitVec3, Vec3};

/// A cylinder of `radius` around the segment from `base` to `base + height·axis`,
/// closed by two disks when `capped`. An open tube is visible from both sides.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cylinder {
    base: Vec3,
    axis: UnitVec3,
    /// Completes `axis` to an orthonormal frame.
    e1: UnitVec3,
    e2: UnitVec3,
    radius: f32,
    height: f32,
    capped: bool,
    error: f32,
    /// The centre of the bounding sphere and its squared radius, widened
    /// ([`reject_radius2`]): rays that surely miss it are turned away first.
    center: Vec3,
    reject_r2: f32,
}

impl Cylinder {
    /// A capped cylinder (the paper's tube, and a scene file's default); radius and height
    /// must be positive, the axis non-zero. [`Cylinder::with_caps`] opens it.
    pub fn new(base: Vec3, axis: Vec3, radius: f32, height: f32) -> Result<Self, Error> {
        let base = finite_vec(base, "cylinder base")?;
        let axis = UnitVec3::try_new(axis, "cylinder axis")?;
        let radius = positive(radius, "cylinder radius")?;
        let height = positive(height, "cylinder height")?;
        let (e1, e2) = axis.basis();
        let error = error_bound(max_abs(base) + radius + height);
        let mut cylinder = Self {
            base,
            axis,
            e1,
            e2,
            radius,
            height,
            capped: true,
            error,
            center: base + axis.get() * (0.5 * height),
            reject_r2: 0.0,
        };
        cylinder.reject_r2 = reject_radius2(cylinder.bounding_sphere().radius, error);
        Ok(cylinder)
    }

    /// The same cylinder closed by its two disks (`true`) or an open tube (`false`).
    pub fn with_caps(self, capped: bool) -> Self {
        Self { capped, ..self }
    }

    /// Centre of the bottom cap.
    pub fn base(&self) -> Vec3 {
        self.base
    }

    /// Unit axis from the bottom cap to the top cap.
    pub fn axis(&self) -> UnitVec3 {
        self.axis
    }

    /// Radius.
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// Height.
    pub fn height(&self) -> f32 {
        self.height
    }

    /// Whether the ends are closed.
    pub fn capped(&self) -> bool {
        self.capped
    }

    /// The sphere around the centre of the axis through the rims.
    pub fn bounding_sphere(&self) -> BoundingSphere {
        let h = 0.5 * self.height;
        BoundingSphere {
            center: self.center,
            radius: libm::sqrtf(h * h + self.radius * self.radius),
        }
    }

    /// The nearest hit with `0 < t < t_max`.
    ///
    /// In the frame `(e1, e2, axis)` the side is `x² + y² = r²`, `0 ≤ z ≤ h`: with
    /// `a = dx² + dy²`, `b = ox·dx + oy·dy`, `c = ox² + oy² − r²` the roots solve
    /// `a t² + 2b t + c = 0`, with the cancellation-free discriminant
    /// `a·(r² − |o⊥ − (b/a)·d⊥|²)`. Caps are disks at `z = 0` and `z = h`. A ray that
    /// surely misses the bounding sphere is turned away before any of this. Always
    /// inlined on the desktop: see [`Cuboid::intersect`](super::Cuboid::intersect).
    #[cfg_attr(feature = "std", inline(always))]
    #[cfg_attr(not(feature = "std"), inline)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        if surely_missed(self.center, self.reject_r2, ray, t_max) {
            return None;
        }
        let rel = ray.origin - self.base;
        let d = ray.dir.get();
        let (ox, oy, oz) = (self.e1.dot(rel), self.e2.dot(rel), self.axis.dot(rel));
        let (dx, dy, dz) = (self.e1.dot(d), self.e2.dot(d), self.axis.dot(d));
        let r2 = self.radius * self.radius;
        let mut best: Option<(f32, Vec3)> = None;
        let mut consider = |t: f32, normal: Vec3| {
            if t > 0.0 && t < t_max && best.is_none_or(|(bt, _)| t < bt) {
                best = Some((t, normal));
            }
        };

        let a = dx * dx + dy * dy;
        if a > 0.0 {
            let b = ox * dx + oy * dy;
            let s = b / a;
            let (px, py) = (ox - s * dx, oy - s * dy);
            let disc = a * (r2 - (px * px + py * py));
            let c = ox * ox + oy * oy - r2;
            if let Some((t0, t1)) = stable_roots(a, b, c, disc) {
                for t in [t0, t1] {
                    let z = oz + t * dz;
                    if (0.0..=self.height).contains(&z) {
                        consider(
                            t,
                            self.e1.get() * (ox + t * dx) + self.e2.get() * (oy + t * dy),
                        );
                    }
                }
            }
        }
        if self.capped && dz != 0.0 {
            for (z, n) in [(0.0, -self.axis.get()), (self.height, self.axis.get())] {
                let t = (z - oz) / dz;
                let (x, y) = (ox + t * dx, oy + t * dy);
                if x * x + y * y <= r2 {
                    consider(t, n);
                }
            }
        }

        let (t, n) = best?;
        let normal = UnitVec3::new(n)?;
        let p = ray.at(t);
        // Re-project onto the patch of surface that was hit: the side keeps its axial
        // coordinate, clamped to [0, h], and moves radially to r; a cap keeps its radial
        // offset, clamped to the disk of radius r. The clamps matter when the ray starts
        // far away: `ray.at(t)` then carries the rounding of the ray's coordinates,
        // which may put it past the rim by more than the shape's own error bound.
        let rel = p - self.base;
        let z = self.axis.dot(rel);
        let point = if normal.dot(self.axis.get()).abs() < 0.5 {
            self.base
                + self.axis.get() * crate::math::clamp(z, 0.0, self.height)
                + normal.get() * self.radius
        } else {
            let zc = if normal.dot(self.axis.get()) > 0.0 {
                self.height
            } else {
                0.0
            };
            let mut radial = rel - self.axis.get() * z;
            let r = radial.length();
            if r > self.radius {
                radial *= self.radius / r;
            }
            self.base + radial + self.axis.get() * zc
        };
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
    fn side_caps_inside_and_parallel() {
        let c = Cylinder::new(Vec3::ZERO, Vec3::Y, 1.0, 2.0).unwrap();
        let h = c
            .intersect(&ray([-3.0, 1.0, 0.0], [1.0, 0.0, 0.0]), f32::INFINITY)
            .unwrap();
        assert_eq!(h.t, 2.0);
        assert!((h.normal.get() + Vec3::X).length() < 1e-6);
        // Down the axis: the top cap.
        let h = c
            .intersect(&ray([0.0, 5.0, 0.0], [0.0, -1.0, 0.0]), f32::INFINITY)
            .unwrap();
        assert_eq!((h.t, h.normal), (3.0, UnitVec3::Y));
        // From inside up the axis: the top cap from below, outward normal.
        let h = c
            .intersect(&ray([0.0, 1.0, 0.0], [0.0, 1.0, 0.0]), f32::INFINITY)
            .unwrap();
        assert_eq!((h.t, h.normal), (1.0, UnitVec3::Y));
        // Above the top, sideways: miss.
        assert!(c
            .intersect(&ray([-3.0, 2.5, 0.0], [1.0, 0.0, 0.0]), f32::INFINITY)
            .is_none());
        // Parallel to the axis outside the radius: miss.
        assert!(c
            .intersect(&ray([2.0, 5.0, 0.0], [0.0, -1.0, 0.0]), f32::INFINITY)
            .is_none());
        // Uncapped: down the axis passes straight through.
        let open = Cylinder::new(Vec3::ZERO, Vec3::Y, 1.0, 2.0)
            .unwrap()
            .with_caps(false);
        assert!(open
            .intersect(&ray([0.0, 5.0, 0.0], [0.0, -1.0, 0.0]), f32::INFINITY)
            .is_none());
        // Uncapped, seen from inside at a slant: the inner wall.
        let h = open
            .intersect(&ray([0.0, 1.0, 0.0], [1.0, 0.1, 0.0]), f32::INFINITY)
            .unwrap();
        assert!((h.t - (1.0f32 + 0.01).sqrt()).abs() < 1e-5);
    }

    #[test]
    fn arbitrary_axis_agrees_with_brute_force() {
        let axis = Vec3::new(1.0, 2.0, -0.5);
        let c = Cylinder::new(Vec3::new(0.5, -1.0, 4.0), axis, 0.7, 2.5).unwrap();
        let inside = |p: Vec3| {
            let rel = p - c.base;
            let z = c.axis.dot(rel);
            let radial = rel - c.axis.get() * z;
            (0.0..=c.height).contains(&z) && radial.length() <= c.radius
        };
        for i in 0..40 {
            for j in 0..40 {
                let dir = Vec3::new(0.05 * (i as f32 - 20.0), 0.05 * (j as f32 - 20.0), 1.0);
                let r = Ray::new(Vec3::ZERO, UnitVec3::new(dir).unwrap());
                let exact = c.intersect(&r, f32::INFINITY).map(|h| h.t);
                let steps = 20_000;
                let step = 10.0 / steps as f32;
                let brute = (1..=steps)
                    .map(|k| k as f32 * step)
                    .find(|&t| inside(r.at(t)));
                match (exact, brute) {
                    (Some(e), Some(b)) => assert!((e - b).abs() < 2e-3, "{i},{j}: {e} vs {b}"),
                    (None, None) => {}
                    (Some(e), None) => assert!(!inside(r.at(e + 2.0 * step)), "{i},{j}: {e}"),
                    (None, Some(b)) => panic!("{i},{j}: missed a cylinder the march enters at {b}"),
                }
            }
        }
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(Cylinder::new(Vec3::ZERO, Vec3::ZERO, 1.0, 1.0).is_err());
        assert!(Cylinder::new(Vec3::ZERO, Vec3::Y, 0.0, 1.0).is_err());
        assert!(Cylinder::new(Vec3::ZERO, Vec3::Y, 1.0, -2.0).is_err());
    }
}

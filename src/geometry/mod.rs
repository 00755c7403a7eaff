//! Shapes and the rays that meet them.
//!
//! Every shape returns a [`Hit`]: the distance, the point (re-projected onto the
//! surface), the *outward* geometric normal and an absolute error bound on the point.
//! [`Ray::spawn`] is the one place a ray origin is moved off a surface: it pushes the
//! origin along the normal by that bound, to the side the new ray leaves towards
//! (pbrt-v4's `OffsetRayOrigin`). There is no global epsilon: the offset scales with
//! the magnitude of the coordinates involved, so a scene behaves the same at every size.

mod chart;
mod cuboid;
mod cylinder;
mod plane;
mod sphere;

pub(crate) use chart::SurfacePoint;
pub use cuboid::Cuboid;
pub use cylinder::Cylinder;
pub use plane::Plane;
pub use sphere::Sphere;

use crate::error::Error;
use crate::math::{UnitVec3, Vec3};

/// Relative error allowed for a re-projected hit point, in units of `f32::EPSILON`
/// times the magnitude of the coordinates. The re-projections below are accurate to a
/// few ulps; 32 leaves a margin for the rotations and dot products that produced them.
pub(crate) const HIT_ERROR_ULPS: f32 = 32.0;

/// The absolute error bound of a point computed from coordinates of magnitude `scale`.
#[inline]
pub(crate) fn error_bound(scale: f32) -> f32 {
    HIT_ERROR_ULPS * f32::EPSILON * scale
}

/// A half-line: `origin + t·dir`, `t > 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where it starts.
    pub origin: Vec3,
    /// Where it goes.
    pub dir: UnitVec3,
}

impl Ray {
    /// A ray from `origin` along `dir`.
    #[inline]
    pub fn new(origin: Vec3, dir: UnitVec3) -> Self {
        Self { origin, dir }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir.get() * t
    }

    /// A ray leaving the surface at `hit` along `dir`, its origin pushed off the surface
    /// by the hit's error bound to the side `dir` points to, so that it can neither hit
    /// the same surface again at `t ≈ 0` nor start on the wrong side of it.
    #[inline]
    pub fn spawn(hit: &Hit, dir: UnitVec3) -> Self {
        let n = hit.normal.get();
        let offset = n * hit.error;
        let origin = if dir.dot(n) >= 0.0 {
            hit.point + offset
        } else {
            hit.point - offset
        };
        Self { origin, dir }
    }
}

/// Where a ray meets a surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit, `> 0`.
    pub t: f32,
    /// The hit point, on the surface to within `error`.
    pub point: Vec3,
    /// Outward geometric normal (for a plane, the normal it was given).
    pub normal: UnitVec3,
    /// Absolute error bound on `point`, in scene units.
    pub error: f32,
}

impl Hit {
    /// `true` when the ray that made this hit arrived on the side the normal points to.
    #[inline]
    pub fn front_face(&self, dir: UnitVec3) -> bool {
        self.normal.dot(dir.get()) < 0.0
    }
}

/// The squared radius of a rejection sphere about a shape whose bounding sphere has
/// `radius`: widened by 10⁻⁴ (relative) and the shape's error bound, so that rounding
/// never rejects a ray the shape's own test would find a hit on.
#[inline]
pub(crate) fn reject_radius2(radius: f32, error: f32) -> f32 {
    let r = radius * (1.0 + 1e-4) + error;
    r * r
}

/// `true` when the ray cannot meet anything inside the sphere (`center`, radius²
/// `r2`) before `t_max`: it starts outside and points away from it, passes it by, or
/// reaches it only beyond `t_max`. About a dozen instructions; most rays of a scene miss
/// most bounded shapes, and a box's slabs or a cylinder's quadratic and caps cost
/// five times as many.
///
/// The ray passes beside when its line's squared distance from the centre exceeds
/// `r2`. That distance is `|f − (f·d)d|²`, `f` the origin's offset: not `|f|² − (f·d)²`,
/// whose two terms cancel — from 10⁴ sizes away each is 10⁸ sizes² and carries a
/// rounding of tens of sizes², which turned away rays aimed at the middle of a box or a
/// cylinder (the same rewriting as Haines et al., "Precision Improvements for Ray/Sphere
/// Intersection", Ray Tracing Gems 2019, ch. 7, which pbrt-v4's sphere uses).
#[inline]
pub(crate) fn surely_missed(center: Vec3, r2: f32, ray: &Ray, t_max: f32) -> bool {
    let f = ray.origin - center;
    let d = ray.dir.get();
    let b = f.dot(d);
    let c = f.length_squared() - r2;
    // Outside (c > 0) and moving away (b ≥ 0) or passing beside; or the sphere's entry
    // −b − √(b² − c) ≥ −b − R (as b² ≤ |f|²) lies beyond t_max.
    let beyond = -b - t_max;
    c > 0.0
        && (b >= 0.0 || (f - d * b).length_squared() > r2 || (beyond > 0.0 && beyond * beyond > r2))
}

/// A sphere that contains a shape: the basis of the photon projection maps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundingSphere {
    /// Centre.
    pub center: Vec3,
    /// Radius.
    pub radius: f32,
}

/// The closed set of shapes. An enum, not a trait object: one `match` per operation,
/// no allocation, and the hot path stays visible.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A sphere.
    Sphere(Sphere),
    /// A rotated box (the paper's "cube").
    Box(Cuboid),
    /// A capped cylinder with an arbitrary axis (the paper's "tube").
    Cylinder(Cylinder),
    /// An infinite plane.
    Plane(Plane),
}

impl Shape {
    /// A sphere; see [`Sphere::new`].
    pub fn sphere(center: Vec3, radius: f32) -> Result<Self, Error> {
        Sphere::new(center, radius).map(Shape::Sphere)
    }

    /// A box; see [`Cuboid::new`].
    pub fn cuboid(center: Vec3, size: Vec3, rotation_deg: Vec3) -> Result<Self, Error> {
        Cuboid::new(center, size, rotation_deg).map(Shape::Box)
    }

    /// A cylinder, closed or open; see [`Cylinder::new`] and [`Cylinder::with_caps`].
    pub fn cylinder(
        base: Vec3,
        axis: Vec3,
        radius: f32,
        height: f32,
        capped: bool,
    ) -> Result<Self, Error> {
        Cylinder::new(base, axis, radius, height).map(|c| Shape::Cylinder(c.with_caps(capped)))
    }

    /// A plane; see [`Plane::new`].
    pub fn plane(point: Vec3, normal: Vec3) -> Result<Self, Error> {
        Plane::new(point, normal).map(Shape::Plane)
    }

    /// The nearest hit with `0 < t < t_max`. Always inlined: its callers (the loops of
    /// nearest-hit searches) then keep the hit in registers instead of receiving it
    /// through memory, and reject most shapes without a call.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        match self {
            Shape::Sphere(s) => s.intersect(ray, t_max),
            Shape::Box(b) => b.intersect(ray, t_max),
            Shape::Cylinder(c) => c.intersect(ray, t_max),
            Shape::Plane(p) => p.intersect(ray, t_max),
        }
    }

    /// `true` when the ray meets the shape at some `0 < t < t_max`: the answer of
    /// `intersect(ray, t_max).is_some()` without building the hit's point and normal
    /// (the shadow-ray query; boxes first try their bounding sphere).
    #[inline]
    pub fn blocks(&self, ray: &Ray, t_max: f32) -> bool {
        match self {
            Shape::Sphere(s) => s.blocks(ray, t_max),
            Shape::Box(b) => b.blocks(ray, t_max),
            Shape::Cylinder(c) => c.intersect(ray, t_max).is_some(),
            Shape::Plane(p) => p.blocks(ray, t_max),
        }
    }

    /// How the outward normal at the surface point of normal `n` turns as the point
    /// moves by `dp` along the surface (`∂n = (∂n/∂p)·dp`): for ray differentials
    /// through curved glass and mirrors (Igehy 1999). A sphere's normal `(p − c)/r`
    /// turns by `dp/r`; a cylinder's side by the part of `dp` across the axis over
    /// `r`; flat faces (planes, box faces, caps) not at all.
    #[inline]
    pub fn normal_derivative(&self, n: UnitVec3, dp: Vec3) -> Vec3 {
        match self {
            Shape::Sphere(s) => dp * (1.0 / s.radius()),
            Shape::Cylinder(c) => {
                let a = c.axis().get();
                // The caps' normals are ±axis; the side's are perpendicular to it.
                if n.dot(a).abs() > 0.5 {
                    Vec3::ZERO
                } else {
                    (dp - a * dp.dot(a)) * (1.0 / c.radius())
                }
            }
            Shape::Box(_) | Shape::Plane(_) => Vec3::ZERO,
        }
    }

    /// The largest principal curvature (1/scene units) of the surface at the point of
    /// outward normal `n`: `1/r` on a sphere and on a cylinder's side, 0 on flat faces
    /// (planes, box faces, caps). A patch of reach `ρ` about the point then lies within
    /// the sagitta `ρ²κ/(1 + √(1 − ρ²κ²))` of its tangent plane (see
    /// [`Footprint::curvature`](crate::photon::Footprint::curvature)).
    #[inline]
    pub fn curvature(&self, n: UnitVec3) -> f32 {
        match self {
            Shape::Sphere(s) => 1.0 / s.radius(),
            // The caps' normals are ±axis; the side's are perpendicular to it.
            Shape::Cylinder(c) if n.dot(c.axis().get()).abs() <= 0.5 => 1.0 / c.radius(),
            Shape::Cylinder(_) | Shape::Box(_) | Shape::Plane(_) => 0.0,
        }
    }

    /// `false` for the unbounded plane.
    #[inline]
    pub fn is_bounded(&self) -> bool {
        !matches!(self, Shape::Plane(_))
    }

    /// The plane, if the shape is one.
    #[inline]
    pub fn as_plane(&self) -> Option<&Plane> {
        match self {
            Shape::Plane(p) => Some(p),
            _ => None,
        }
    }

    /// A sphere containing the shape; `None` for the unbounded plane.
    pub fn bounding_sphere(&self) -> Option<BoundingSphere> {
        match self {
            Shape::Sphere(s) => Some(BoundingSphere {
                center: s.center(),
                radius: s.radius(),
            }),
            Shape::Box(b) => Some(b.bounding_sphere()),
            Shape::Cylinder(c) => Some(c.bounding_sphere()),
            Shape::Plane(_) => None,
        }
    }
}

/// The two roots of `a·t² + 2·b·t + c = 0` given the discriminant `disc = b² − a·c`
/// (computed by the caller in a cancellation-free way), in ascending order, without
/// the catastrophic cancellation of `(−b ± √disc)/a` (Numerical Recipes §5.6).
#[inline]
pub(crate) fn stable_roots(a: f32, b: f32, c: f32, disc: f32) -> Option<(f32, f32)> {
    if !(disc >= 0.0) || a == 0.0 {
        return None;
    }
    let q = -(b + libm::copysignf(crate::math::sqrt(disc), b));
    if q == 0.0 {
        // b = 0 and disc = 0: a double root at t = 0 (a tangent ray from the surface).
        return Some((0.0, 0.0));
    }
    let (t0, t1) = (q / a, c / q);
    Some(if t0 <= t1 { (t0, t1) } else { (t1, t0) })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A ray from `o` along `d` (normalised), for the shapes' tests.
    pub(crate) fn ray(o: [f32; 3], d: [f32; 3]) -> Ray {
        Ray::new(
            Vec3::from_array(o),
            UnitVec3::new(Vec3::from_array(d)).unwrap(),
        )
    }

    #[test]
    fn stable_roots_match_closed_form_and_survive_cancellation() {
        // (t − 1)(t − 3) = t² − 4t + 3: a = 1, b = −2, c = 3.
        let (t0, t1) = stable_roots(1.0, -2.0, 3.0, 4.0 - 3.0).unwrap();
        assert_eq!((t0, t1), (1.0, 3.0));
        // Roots 1e-4 and 1e4: the naive formula loses the small root entirely in f32.
        let (a, b, c) = (1.0f32, -(1e4 + 1e-4) / 2.0, 1.0f32);
        let disc = b * b - a * c;
        let (t0, t1) = stable_roots(a, b, c, disc).unwrap();
        assert!((t0 - 1e-4).abs() / 1e-4 < 1e-3, "{t0}");
        assert!((t1 - 1e4).abs() / 1e4 < 1e-6);
        assert!(stable_roots(1.0, 0.0, 1.0, -1.0).is_none());
        assert!(stable_roots(1.0, 0.0, 0.0, f32::NAN).is_none());
    }

    /// Rays from 10³–10⁴ sizes away, aimed at a point well inside a cylinder or a box,
    /// hit it. The first is the case `tests/stability.rs` found: 41 000 units from a
    /// cylinder of radius 11.8, aimed 1.6 inside its side, where `|f|² − (f·d)²` (each
    /// term 1.7·10⁹, a float's step there 128) came out above the bounding sphere's 243
    /// and the ray was turned away.
    #[test]
    fn rays_from_far_away_are_not_turned_away() {
        let cylinder = Shape::cylinder(
            Vec3::new(0.0, 0.0, -349.76273),
            Vec3::new(-0.37872183, 0.8226247, 0.4240974),
            11.763417,
            20.45553,
            true,
        )
        .unwrap();
        let from = Vec3::new(-9797.685, 33921.03, 20191.887);
        let aim = Vec3::new(-10.431486, -0.90560055, -345.43207);
        let r = Ray::new(from, UnitVec3::new(aim - from).unwrap());
        let hit = cylinder
            .intersect(&r, f32::INFINITY)
            .expect("the cylinder is hit");
        assert!((hit.t - (aim - from).length()).abs() < 20.0, "{}", hit.t);
        // A unit box seen from 2·10⁴ away in many directions, aimed within a tenth of its centre.
        let cube = Shape::cuboid(
            Vec3::new(3.0, -2.0, 1.0),
            Vec3::splat(0.5),
            Vec3::new(10.0, 20.0, 30.0),
        )
        .unwrap();
        let mut g = crate::sampling::Pcg32::new(9);
        for _ in 0..2000 {
            let u = Vec3::new(g.next_f32(), g.next_f32(), g.next_f32()) * 2.0 - Vec3::ONE;
            let Some(dir) = UnitVec3::new(u) else {
                continue;
            };
            let aim = Vec3::new(3.0, -2.0, 1.0)
                + Vec3::new(g.next_f32(), g.next_f32(), g.next_f32()) * 0.1;
            let from = aim + dir.get() * 2.0e4;
            let r = Ray::new(from, UnitVec3::new(aim - from).unwrap());
            assert!(cube.intersect(&r, f32::INFINITY).is_some(), "{r:?}");
        }
    }

    #[test]
    fn blocks_is_intersect_is_some() {
        // The shadow query must agree with the full one on every ray, including rays
        // the box's bounding-sphere test rejects and rays that end just short of a hit.
        let shapes = [
            Shape::cuboid(
                Vec3::new(2.0, 1.0, -1.0),
                Vec3::splat(4.0),
                Vec3::new(0.0, 30.0, 0.0),
            )
            .unwrap(),
            Shape::cuboid(
                Vec3::ZERO,
                Vec3::new(0.5, 3.0, 1.0),
                Vec3::new(10.0, 20.0, 30.0),
            )
            .unwrap(),
            Shape::sphere(Vec3::new(0.0, 1.0, 0.0), 1.0).unwrap(),
            Shape::plane(Vec3::new(0.0, -5.0, 0.0), Vec3::Y).unwrap(),
        ];
        let mut g = crate::sampling::Pcg32::new(11);
        let mut hits = 0;
        for _ in 0..20_000 {
            let o = Vec3::new(g.next_f32(), g.next_f32(), g.next_f32()) * 16.0 - Vec3::splat(8.0);
            let aim = Vec3::new(g.next_f32(), g.next_f32(), g.next_f32()) * 6.0 - Vec3::splat(3.0);
            let Some(dir) = UnitVec3::new(aim - o) else {
                continue;
            };
            let r = Ray::new(o, dir);
            let t_max = [f32::INFINITY, 1.0, 8.0, 12.0][(g.next_u32() % 4) as usize];
            for s in &shapes {
                let full = s.intersect(&r, t_max).is_some();
                hits += full as u32;
                assert_eq!(s.blocks(&r, t_max), full, "{s:?} {r:?} {t_max}");
            }
        }
        assert!(hits > 5_000, "the rays must exercise hits too: {hits}");
    }

    /// A point of the same surface within distance `d` of a hit lies within `d²κ/2`
    /// of the hit's tangent plane (`κ` = [`Shape::curvature`]), and on a sphere and a
    /// cylinder's side reaches it: points found by rays along `−n` from the tangent
    /// plane, on spheres, cylinders (side and caps), boxes and planes.
    #[test]
    fn the_curvature_bounds_the_surface_off_its_tangent_plane() {
        let shapes = [
            Shape::sphere(Vec3::new(0.0, 1.0, 0.0), 0.7).unwrap(),
            Shape::cylinder(Vec3::ZERO, Vec3::new(0.2, 1.0, 0.1), 0.4, 1.5, true).unwrap(),
            Shape::cuboid(
                Vec3::ZERO,
                Vec3::new(0.5, 2.0, 1.0),
                Vec3::new(10.0, 20.0, 30.0),
            )
            .unwrap(),
            Shape::plane(Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.1, 1.0, 0.0)).unwrap(),
        ];
        let mut g = crate::sampling::Pcg32::new(12);
        let (mut checked, mut tight) = (0, 0);
        for _ in 0..4_000 {
            let o = Vec3::new(g.next_f32(), g.next_f32(), g.next_f32()) * 8.0 - Vec3::splat(4.0);
            let aim = Vec3::new(g.next_f32(), g.next_f32(), g.next_f32()) - Vec3::splat(0.5);
            let Some(dir) = UnitVec3::new(aim - o) else {
                continue;
            };
            for s in &shapes {
                let Some(h) = s.intersect(&Ray::new(o, dir), f32::INFINITY) else {
                    continue;
                };
                let (n, kappa) = (h.normal, s.curvature(h.normal));
                let (u, v) = n.basis();
                let a = g.next_f32() * core::f32::consts::TAU;
                let step = (u.get() * libm::cosf(a) + v.get() * libm::sinf(a)) * 0.1 * g.next_f32();
                let probe = Ray::new(h.point + step + n.get() * 0.5, -n);
                let Some(q) = s.intersect(&probe, 1.0) else {
                    continue;
                };
                if q.normal.dot(n.get()) < 0.9 {
                    continue; // another face, or the far side
                }
                let d = q.point - h.point;
                let (off, bound) = (d.dot(n.get()).abs(), 0.5 * d.length_squared() * kappa);
                assert!(off <= bound + 1e-5, "{s:?}: {off} > {bound}");
                checked += 1;
                tight += (kappa > 0.0 && off >= 0.9 * bound && off > 1e-4) as u32;
            }
        }
        assert!(
            checked > 1_000 && tight > 100,
            "{checked} checked, {tight} tight"
        );
    }

    #[test]
    fn spawn_moves_to_the_side_of_the_new_direction() {
        let hit = Hit {
            t: 1.0,
            point: Vec3::ZERO,
            normal: UnitVec3::Y,
            error: 1e-3,
        };
        assert!(Ray::spawn(&hit, UnitVec3::Y).origin.y > 0.0);
        assert!(Ray::spawn(&hit, -UnitVec3::Y).origin.y < 0.0);
    }
}

//! Ray differentials: how an eye ray's point and direction change across the image
//! (Igehy 1999, "Tracing Ray Differentials"; pbrt-v4 §10.1), carried through every
//! mirror reflection and refraction so that a diffuse point seen through glass knows
//! the patch of surface its pixel covers there — magnified by a ball, stretched along
//! one axis by a tube — and the caustic store averages over exactly that patch. They
//! are not stored with each branch: the path's specular vertices are ([`Trail`]), and
//! a gather replays the recurrences below through them, the same operations on the
//! same values as carrying them along.
//!
//! With `D` the unit direction, `N` the normal facing the ray (`D·N < 0`) and `∂` a
//! derivative along the image's x or y:
//! - **transfer** to a hit at distance `t`: `∂P' = ∂P + t·∂D + ∂t·D`,
//!   `∂t = −(∂P + t·∂D)·N / (D·N)` (the point stays on the surface);
//! - **reflection** `R = D − 2(D·N)N`: `∂R = ∂D − 2((D·N)·∂N + ∂(D·N)·N)`;
//! - **refraction** `T = η·D − μ·N`, `μ = η(D·N) − T·N`, `η = η_i/η_t`:
//!   `∂T = η·∂D − (μ·∂N + ∂μ·N)`, `∂μ = (η − η²(D·N)/(T·N))·∂(D·N)`;
//!
//! with `∂(D·N) = ∂D·N + D·∂N` and `∂N` from the shape
//! ([`Shape::normal_derivative`](crate::geometry::Shape::normal_derivative)).

use heapless::Vec as FixedVec;

use crate::camera::Camera;
use crate::geometry::{Hit, Shape};
use crate::math::{UnitVec3, Vec3};
use crate::scene::Object;

/// The derivatives of a ray's origin and direction along one of the image's axes (x
/// or y), per step of the sample's extent on the image (a pixel, or a sub-pixel of a
/// grid). The two axes never mix, so each is carried on its own: one copy of the code.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Differential {
    /// `∂P`.
    pub dp: Vec3,
    /// `∂D`.
    pub dd: Vec3,
}

impl Differential {
    /// A pinhole camera ray: the origin is fixed, the direction turns by `dd`.
    #[inline]
    pub fn camera(dd: Vec3) -> Self {
        Self { dp: Vec3::ZERO, dd }
    }

    /// The differential at a hit `t` along direction `d`, on a surface of normal `n`
    /// (either orientation): the direction's is unchanged.
    #[inline]
    pub fn transfer(&self, d: Vec3, t: f32, n: Vec3) -> Self {
        let dn = d.dot(n);
        let moved = self.dp + self.dd * t;
        Self {
            dp: moved - d * (moved.dot(n) / dn),
            dd: self.dd,
        }
    }

    /// The reflected ray's, about the normal `n` facing `d` that turns by `dn`.
    #[inline]
    pub fn reflect(&self, d: Vec3, n: Vec3, dn: Vec3) -> Self {
        let d_n = d.dot(n);
        let dd_n = self.dd.dot(n) + d.dot(dn);
        Self {
            dp: self.dp,
            dd: self.dd - (dn * d_n + n * dd_n) * 2.0,
        }
    }

    /// The refracted ray's (direction `t_dir`), about the normal `n` facing `d` that
    /// turns by `dn`, with `eta = η_i/η_t`.
    #[inline]
    pub fn refract(&self, d: Vec3, t_dir: Vec3, n: Vec3, dn: Vec3, eta: f32) -> Self {
        let (d_n, t_n) = (d.dot(n), t_dir.dot(n));
        let mu = eta * d_n - t_n;
        let dmu_per = eta - eta * eta * d_n / t_n;
        let dd_n = self.dd.dot(n) + d.dot(dn);
        Self {
            dp: self.dp,
            dd: self.dd * eta - (dn * mu + n * (dmu_per * dd_n)),
        }
    }
}

/// A branch's differential transferred to a specular hit, with the normal facing the
/// ray and that normal's turn along the same image axis: what the reflected and
/// refracted branches' differentials are made from.
pub(crate) struct Turn {
    at: Differential,
    d: Vec3,
    n: Vec3,
    dn: Vec3,
}

impl Turn {
    /// Transfers `diff`, of a ray along `d`, to its hit `t` along it on `shape`, of
    /// outward normal `normal` there; `front`: the ray arrived on the side `normal`
    /// points to.
    #[inline]
    pub fn at(
        diff: &Differential,
        d: UnitVec3,
        (t, normal): (f32, UnitVec3),
        shape: &Shape,
        front: bool,
    ) -> Self {
        let d = d.get();
        let at = diff.transfer(d, t, normal.get());
        // The normal facing the ray, and its turn: the outward normal's, flipped with it
        // when the ray is inside.
        let (facing, sign) = if front {
            (normal, 1.0)
        } else {
            (-normal, -1.0)
        };
        Self {
            at,
            d,
            n: facing.get(),
            dn: shape.normal_derivative(normal, at.dp) * sign,
        }
    }

    /// The mirror-reflected branch's differentials.
    #[inline]
    pub fn reflect(&self) -> Differential {
        self.at.reflect(self.d, self.n, self.dn)
    }

    /// The refracted branch's differentials, along `t`, with `eta = η_i/η_t`.
    #[inline]
    pub fn refract(&self, t: UnitVec3, eta: f32) -> Differential {
        self.at.refract(self.d, t.get(), self.n, self.dn, eta)
    }
}

/// How a branch leaves the specular vertex it starts at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Bend {
    /// Mirror reflection (also a classic surface's transmitted part under total
    /// internal reflection, which follows the reflected ray).
    Reflect,
    /// Refraction, with `η = η_i/η_t` of the vertex.
    Refract,
}

/// One specular interaction of the path being traced: what [`Turn::at`] and the bend
/// of the branch leaving it need, recorded instead of the differentials themselves.
#[derive(Clone, Copy, Debug)]
struct Vertex {
    /// The arriving ray's direction, and how it left the vertex before (the arriving
    /// branch's bend; unused at the first vertex, which the camera ray reaches).
    d: UnitVec3,
    bend: Bend,
    /// The hit: ray parameter, outward normal, object, side.
    t: f32,
    normal: UnitVec3,
    object: usize,
    front: bool,
    /// `η_i/η_t` for a refracted branch.
    eta: f32,
}

/// The specular vertices of the eye path being traced, from the camera, replayed into
/// a branch's differentials only where a gather needs them (Igehy's recurrences in the
/// same order on the same values: the same bits as carrying them along every branch).
/// Most branches never reach a diffuse point near a photon (Fig. 6 on the device:
/// 80 footprint gathers against 12 300 reflected and refracted branches), so carrying
/// 48 bytes of differentials through every fork costs far more than replaying a few.
///
/// The walk is depth-first and each pending branch waits at a depth of its own, so
/// when a branch at depth `k` is traced the first `k` vertices are its own ancestors:
/// a vertex recorded at depth `k` replaces everything from `k` on.
#[derive(Debug)]
pub(crate) struct Trail<const DEPTH: usize> {
    vertices: FixedVec<Vertex, DEPTH>,
    /// The sample's extent on the image, pixels (`1/m` for an `m × m` grid).
    step: f32,
    /// What bounds its footprints beyond the differentials.
    bounds: Bounds,
}

/// What bounds a sample's footprints beyond its differentials: the photons each search
/// may visit on one level ([`Footprint::visits`](crate::photon::Footprint::visits);
/// none, [`Bounds::NO_GATHER`], when the sample's caustic part comes from elsewhere and
/// it does not gather at all), and in a grazing pixel's refined grids the secants to
/// its neighbours.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Bounds {
    pub visits: usize,
    pub secant: Option<Secant>,
}

impl Bounds {
    /// The usual cap, no secant.
    pub const PLAIN: Bounds = Bounds {
        visits: crate::photon::FOOTPRINT_VISITS,
        secant: None,
    };

    /// No gather at all: no photon may be visited.
    pub const NO_GATHER: usize = 0;
}

/// Where a sample's heavy path first gathers (see `Renderer::probe`), and the longest
/// the footprint's half-axes there may be along the image's x and y: half the distance
/// between the points where its grid neighbours' heavy paths gather (the secants of the
/// map from image to surface, see `Renderer::grid`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Secant {
    pub at: Vec3,
    pub half: [f32; 2],
}

impl<const DEPTH: usize> Trail<DEPTH> {
    /// No vertex yet, for a sample `step` pixels wide whose footprints `bounds` bound.
    #[inline]
    pub fn new(step: f32, bounds: Bounds) -> Self {
        Self {
            vertices: FixedVec::new(),
            step,
            bounds,
        }
    }

    /// The photons each search of the sample's footprints may visit on one level.
    #[inline]
    pub fn visits(&self) -> usize {
        self.bounds.visits
    }

    /// The footprint's half-axes `[a, b]` (the image's x and y) at `point`, each
    /// shortened to its secant's length where the sample's [`Secant`] is at `point`
    /// and the differentials' tangent says more: at a ball's silhouette the view
    /// through it turns faster than linearly, and the tangent overstated the spacing
    /// of neighbouring sub-pixels' points 2.6–3.2 times (`docs/accuracy.md`, session
    /// 30). Never lengthened: where the map is near linear the two agree.
    #[inline]
    pub fn bounded(&self, point: Vec3, axes: [Vec3; 2]) -> [Vec3; 2] {
        let Some(s) = self.bounds.secant.filter(|s| s.at == point) else {
            return axes;
        };
        let mut out = axes;
        for (axis, half) in out.iter_mut().zip(s.half) {
            let length = crate::math::sqrt(axis.length_squared());
            if length > half {
                *axis *= half / length;
            }
        }
        out
    }

    /// Records the specular hit of a branch at `depth` that arrived along `d` by `bend`,
    /// on `object` (the scene's index); `eta` for its refracted branch.
    #[inline(never)]
    pub fn record(
        &mut self,
        depth: u32,
        (d, bend): (UnitVec3, Bend),
        hit: &Hit,
        object: usize,
        eta: f32,
    ) {
        self.vertices.truncate(depth as usize);
        let vertex = Vertex {
            d,
            bend,
            t: hit.t,
            normal: hit.normal,
            object,
            front: hit.front_face(d),
            eta,
        };
        if self.vertices.push(vertex).is_err() {
            debug_assert!(false, "trail overflow: DEPTH < max_depth");
        }
    }

    /// `true` when the camera ray's first hit was a refracting surface (glass, a
    /// transparent `classic` object) met at an incidence cosine `|cos θ|` below `limit`.
    #[inline]
    pub fn grazes(&self, limit: f32) -> bool {
        self.vertices
            .first()
            .is_some_and(|v| v.eta != 1.0 && v.d.dot(v.normal.get()).abs() < limit)
    }

    /// The area the sample would cover on a surface seen directly, across the ray, at
    /// the length `L` of the path at `depth` (its vertices, then `t`): `L²·A·step²`,
    /// `A` a pixel's area on the image plane at distance 1 (its solid angle at the
    /// image's centre).
    #[inline]
    pub fn direct_area(&self, camera: &Camera, depth: u32, t: f32) -> f32 {
        let path = &self.vertices[..(depth as usize).min(self.vertices.len())];
        let length = path.iter().fold(t, |l, v| l + v.t);
        length * length * (camera.pixel_area() * (self.step * self.step))
    }

    /// The differentials along the image's x and y of the branch at `depth` that left
    /// its last vertex along `dir` by `bend`: the camera's, carried through the first
    /// `depth` vertices (the two axes side by side, one copy of the code for both).
    #[inline(never)]
    pub fn differentials(
        &self,
        camera: &Camera,
        objects: &[Object],
        depth: u32,
        (dir, bend): (UnitVec3, Bend),
    ) -> [Differential; 2] {
        let path = &self.vertices[..(depth as usize).min(self.vertices.len())];
        let root = path.first().map_or(dir, |v| v.d);
        let dd = camera.direction_derivatives(root);
        let mut diffs = dd.map(|dd| Differential::camera(dd * self.step));
        for (k, v) in path.iter().enumerate() {
            let (out, bend) = path
                .get(k + 1)
                .map_or((dir, bend), |next| (next.d, next.bend));
            let shape = &objects[v.object].shape;
            for diff in &mut diffs {
                let turn = Turn::at(diff, v.d, (v.t, v.normal), shape, v.front);
                *diff = match bend {
                    Bend::Reflect => turn.reflect(),
                    Bend::Refract => turn.refract(out, v.eta),
                };
            }
        }
        diffs
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Ray;
    use crate::material::interface;
    use crate::math::reflect;

    /// Follows `ray` through `specular` in order (refracting into or out of glass of
    /// index 1.5, or reflecting where the flag says mirror) and on to `floor`: the point
    /// there and the differentials carried along; `None` when the ray misses a surface
    /// or totally reflects.
    fn follow(
        ray: Ray,
        diff: [Differential; 2],
        specular: &[(Shape, bool)],
        floor: &Shape,
    ) -> Option<(Vec3, [Differential; 2])> {
        let (mut ray, mut diff) = (ray, diff);
        for (shape, mirror) in specular {
            let hit = shape.intersect(&ray, f32::INFINITY)?;
            let d = ray.dir;
            let front = hit.front_face(d);
            let facing = if front { hit.normal } else { -hit.normal };
            let turn = |diff: &Differential| Turn::at(diff, d, (hit.t, hit.normal), shape, front);
            let (dir, next) = if *mirror {
                (reflect(d, facing), diff.map(|a| turn(&a).reflect()))
            } else {
                let eta = if front { 1.0 / 1.5 } else { 1.5 };
                let t = interface(d, facing, eta).refracted?;
                (t, diff.map(|a| turn(&a).refract(t, eta)))
            };
            ray = Ray::spawn(&hit, dir);
            diff = next;
        }
        let hit = floor.intersect(&ray, f32::INFINITY)?;
        let at = |a: Differential| a.transfer(ray.dir.get(), hit.t, hit.normal.get());
        Some((hit.point, diff.map(at)))
    }

    /// The differentials carried through curved glass (into and out of a sphere, of a
    /// cylinder's side) and off a curved mirror predict where the neighbouring rays of
    /// the image land on the floor: over every pixel of a coarse grid whose ray gets
    /// there, central finite differences of the traced points agree with `∂P` to 2%
    /// of its length at all but 1% of them (a ray grazing a surface), the median to 0.1%.
    #[test]
    fn differentials_match_finite_differences_through_glass_and_mirrors() {
        // The camera of the device's glass scene: (0, 4, 7) towards (0, 0.6, 0), 40°.
        let scene = crate::demo::glass::<4, 1>(320, 240).unwrap();
        let camera = scene.camera();
        let floor = Shape::plane(Vec3::new(0.0, 0.0, -3.0), Vec3::Z).unwrap();
        let ball = Shape::sphere(Vec3::new(0.0, 0.8, 0.0), 0.8).unwrap();
        let tube = Shape::cylinder(Vec3::new(-1.0, 0.8, 0.0), Vec3::X, 0.6, 2.0, false).unwrap();
        let mirror = Shape::sphere(Vec3::new(0.0, 0.8, 0.0), 0.9).unwrap();
        let back_wall = Shape::plane(Vec3::new(0.0, 0.0, 8.0), -Vec3::Z).unwrap();
        let setups: [(&[(Shape, bool)], &Shape); 3] = [
            (&[(ball, false), (ball, false)], &floor),
            (&[(tube, false), (tube, false)], &floor),
            (&[(mirror, true)], &back_wall),
        ];
        for (specular, target) in setups {
            let mut errors = std::vec::Vec::new();
            for py in (4..240).step_by(8) {
                for px in (4..320).step_by(8) {
                    let at = |x: f32, y: f32| camera.ray_at(px, py, x, y);
                    let ray = at(0.5, 0.5);
                    let diff = camera
                        .direction_derivatives(ray.dir)
                        .map(Differential::camera);
                    let Some((_, d)) = follow(ray, diff, specular, target) else {
                        continue;
                    };
                    let h = 1e-2;
                    for (i, (dx, dy)) in [(h, 0.0), (0.0, h)].into_iter().enumerate() {
                        let end =
                            |s: f32| follow(at(0.5 + s * dx, 0.5 + s * dy), diff, specular, target);
                        let (Some((plus, _)), Some((minus, _))) = (end(1.0), end(-1.0)) else {
                            continue;
                        };
                        let fd = (plus - minus) / (2.0 * h);
                        errors.push((fd - d[i].dp).length() / fd.length());
                    }
                }
            }
            errors.sort_by(f32::total_cmp);
            assert!(
                errors.len() >= 50,
                "{} pixels reach the target",
                errors.len()
            );
            let median = errors[errors.len() / 2];
            // Central differences break down only where a ray grazes a surface.
            let tail = errors.iter().filter(|&&e| e > 0.02).count();
            assert!(
                median < 1e-3 && tail * 100 <= errors.len(),
                "median {median}, {tail} of {} above 2%",
                errors.len()
            );
        }
    }

    /// A branch of an eye path: its ray, depth, how it left its vertex, and the
    /// differentials carried to it.
    type Pending = (Ray, u32, Bend, [Differential; 2]);

    /// A ray entering a unit ball `x` from its axis meets it at `|cos θ| = √(1 − x²)`:
    /// grazing below 0.15 only near the rim, never at a mirror, never without a hit.
    #[test]
    fn a_trail_knows_a_grazing_entry_into_glass() {
        let ball = Shape::sphere(Vec3::ZERO, 1.0).unwrap();
        let entry = |x: f32, eta: f32| {
            let ray = Ray::new(Vec3::new(x, 0.0, 5.0), UnitVec3::new(-Vec3::Z).unwrap());
            let hit = ball.intersect(&ray, f32::INFINITY).unwrap();
            let mut trail = Trail::<2>::new(1.0, Bounds::PLAIN);
            trail.record(0, (ray.dir, Bend::Reflect), &hit, 0, eta);
            trail.grazes(0.15)
        };
        assert!(!entry(0.0, 1.0 / 1.5)); // cos 1
        assert!(!entry(0.98, 1.0 / 1.5)); // cos 0.199
        assert!(entry(0.995, 1.0 / 1.5)); // cos 0.0999
        assert!(!entry(0.995, 1.0)); // a mirror
        assert!(!Trail::<2>::new(1.0, Bounds::PLAIN).grazes(0.15));
    }

    /// Replaying the trail gives, bit for bit, the differentials carried through every
    /// vertex, at every hit of every branch of a path tree walked depth first as the
    /// renderer walks it (a branch waits on a stack while its sibling records deeper
    /// vertices, then records its own over them): through the glass sphere and off the
    /// mirror of the device's glass scene, both image axes, a 2×2 grid's sub-pixel.
    #[test]
    fn the_trail_replays_the_carried_differentials_bit_for_bit() {
        use crate::material::Material;
        let scene = crate::demo::glass::<4, 1>(320, 240).unwrap();
        let (camera, objects) = (scene.camera(), scene.objects());
        let step = 0.5;
        let (mut checked, mut overwritten) = (0, 0);
        for py in (2..240).step_by(5) {
            for px in (2..320).step_by(5) {
                let ray = camera.ray_at(px, py, 0.25, 0.75);
                let dd = camera.direction_derivatives(ray.dir);
                let carried = dd.map(|d| Differential::camera(d * step));
                let mut trail = Trail::<4>::new(step, Bounds::PLAIN);
                let mut stack: std::vec::Vec<Pending> = std::vec![(ray, 0, Bend::Reflect, carried)];
                while let Some((ray, depth, bend, carried)) = stack.pop() {
                    let Some((hit, index)) = scene.intersect(&ray, f32::INFINITY) else {
                        continue;
                    };
                    let d = ray.dir;
                    if depth > 0 {
                        let replayed = trail.differentials(camera, objects, depth, (d, bend));
                        assert_eq!(replayed, carried, "depth {depth}");
                        checked += 1;
                    }
                    let front = hit.front_face(d);
                    let facing = if front { hit.normal } else { -hit.normal };
                    let eta = match objects[index].material {
                        Material::Dielectric(g) if front => 1.0 / g.ior,
                        Material::Dielectric(g) => g.ior,
                        Material::Mirror(_) => 1.0,
                        _ => continue,
                    };
                    if depth == 3 {
                        continue;
                    }
                    overwritten += usize::from(trail.vertices.len() > depth as usize);
                    trail.record(depth, (d, bend), &hit, index, eta);
                    let shape = &objects[index].shape;
                    let turn = |a: &Differential| Turn::at(a, d, (hit.t, hit.normal), shape, front);
                    let reflected = carried.map(|a| turn(&a).reflect());
                    let r = Ray::spawn(&hit, reflect(d, facing));
                    stack.push((r, depth + 1, Bend::Reflect, reflected));
                    if let Material::Dielectric(_) = objects[index].material {
                        if let Some(t) = interface(d, facing, eta).refracted {
                            let bent = carried.map(|a| turn(&a).refract(t, eta));
                            stack.push((Ray::spawn(&hit, t), depth + 1, Bend::Refract, bent));
                        }
                    }
                }
            }
        }
        assert!(
            checked >= 1000 && overwritten >= 10,
            "{checked}, {overwritten}"
        );
    }

    /// A secant bounds the footprint only at its own point, shortens an axis longer
    /// than it to its length along the same direction, and never lengthens one.
    #[test]
    fn a_secant_only_shortens_its_own_footprint() {
        let at = Vec3::new(0.0, 0.0, 1.0);
        let secant = Secant {
            at,
            half: [0.5, 4.0],
        };
        let bounds = Bounds {
            visits: 1,
            secant: Some(secant),
        };
        let trail = Trail::<2>::new(1.0, bounds);
        let axes = [Vec3::new(0.0, 2.0, 0.0), Vec3::new(1.0, 0.0, 0.0)];
        assert_eq!(trail.bounded(at, axes), [Vec3::new(0.0, 0.5, 0.0), axes[1]]);
        assert_eq!(trail.bounded(at + Vec3::X * 1e-3, axes), axes);
        assert_eq!(Trail::<2>::new(1.0, Bounds::PLAIN).bounded(at, axes), axes);
    }
}

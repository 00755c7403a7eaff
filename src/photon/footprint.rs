//! The patch of surface an eye sample stands for behind glass or in a mirror, and the
//! region a gather searches for it: a parallelogram of the sample's ray differentials,
//! or a disk where it is degenerate. The gathers themselves are the kd-tree store's
//! ([`KdStore`](super::KdStore)).

use core::f32::consts::PI;

use crate::math::Vec3;

/// The patch of surface one eye sample stands for, seen through glass or in a mirror:
/// the parallelogram `x + α·a + β·b`, `|α|, |β| ≤ 1`, whose half-axes `a`, `b` are the
/// sample's ray differentials (Igehy 1999) at the hit times half its extent on the image.
/// A pixel's value is the average radiance over its area; under the differentials'
/// linearisation the pixel's preimage on the surface is this parallelogram, so the
/// photons inside it divided by its area estimate the average irradiance over the
/// pixel — the box filter of the contract, with no kernel of its own.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Footprint {
    /// First half-axis (the image's x direction), scene units.
    pub a: Vec3,
    /// Second half-axis (the image's y direction), scene units.
    pub b: Vec3,
    /// The largest channel of the eye path's throughput up to the patch (the product of
    /// the reflectances and transmittances on the way; 1 for an unattenuated path):
    /// below [`FAINT`](super::FAINT) the gather starts on a coarse level.
    pub throughput: f32,
    /// The area the same sample would cover across the ray on a surface seen directly
    /// at the eye path's length (`L²·Ω`, `Ω` its solid angle): the patch is
    /// `direct / (4·|a × b|)` times smaller, magnified by the glass or mirror on the way
    /// (a ball lens focusing the camera onto a wall: 10²–10⁴). At least
    /// [`MAGNIFIED`](super::MAGNIFIED) lets a sparse patch widen past the first
    /// ([`MAGNIFIED_WIDENINGS`](super::MAGNIFIED_WIDENINGS)); 0 never does.
    pub direct: f32,
    /// The surface's largest principal curvature at the patch, 1/scene units
    /// ([`Shape::curvature`](crate::geometry::Shape::curvature); 0 where it is flat).
    /// A photon of the same surface within reach `ρ` along the tangent plane lies
    /// within the sagitta of that reach off the plane; one farther off lies on another
    /// surface and is not counted (see `Region::thickness`).
    pub curvature: f32,
    /// Most photons one search for it may visit on one level: [`FOOTPRINT_VISITS`],
    /// or [`GRAZING_VISITS`] in a grazing pixel's refined grids. Past it the gather
    /// moves to a coarser level (see [`KdStore`](super::KdStore)).
    ///
    /// [`FOOTPRINT_VISITS`]: super::FOOTPRINT_VISITS
    /// [`GRAZING_VISITS`]: super::GRAZING_VISITS
    pub visits: usize,
}

/// Most disks one footprint's search is cut into (see `Region::segments`).
const MAX_SEGMENTS: u32 = 16;

/// How a footprint is searched: a parallelogram, or (when it is degenerate) a disk.
#[derive(Clone, Copy, Debug)]
pub(super) struct Region {
    pub(super) a: Vec3,
    pub(super) b: Vec3,
    /// `(a·a, a·b, b·b)` over the Gram determinant `|a × b|²`: solves `q = α·a + β·b`.
    aa: f32,
    ab: f32,
    bb: f32,
    /// Radius² of the search: the half-diagonal's square.
    pub(super) reach2: f32,
    /// The region's area (`4·|a × b|`, or the disk's).
    pub(super) area: f32,
    /// `false`: every photon within `reach2` counts (a degenerate parallelogram).
    parallelogram: bool,
    /// The surface's curvature ([`Footprint::curvature`]).
    curvature: f32,
    /// The footprint's visit cap ([`Footprint::visits`]).
    pub(super) visits: usize,
}

impl Region {
    /// The footprint, scaled down to fit within `max_radius2` (a bound on the work, and
    /// the store's own radius: the estimate is then of a smaller patch's average); a
    /// parallelogram too thin to solve (where the differentials fold: a focus seen
    /// edge-on) becomes the disk of its half-diagonal.
    pub(super) fn new(f: &Footprint, max_radius2: f32) -> Option<Self> {
        let (mut a, mut b) = (f.a, f.b);
        let reach2 = crate::math::max((a + b).length_squared(), (a - b).length_squared());
        if !(reach2 > 0.0) || !reach2.is_finite() {
            return None;
        }
        let reach2 = if reach2 > max_radius2 {
            let s = crate::math::sqrt(max_radius2 / reach2);
            (a, b) = (a * s, b * s);
            max_radius2
        } else {
            reach2
        };
        let (aa, ab, bb) = (a.dot(a), a.dot(b), b.dot(b));
        let det = aa * bb - ab * ab;
        if det > 1e-6 * aa * bb && det >= f32::MIN_POSITIVE {
            let inv = 1.0 / det;
            Some(Self {
                a,
                b,
                aa: aa * inv,
                ab: ab * inv,
                bb: bb * inv,
                reach2,
                area: 4.0 * crate::math::sqrt(det),
                parallelogram: true,
                curvature: f.curvature,
                visits: f.visits,
            })
        } else {
            Some(Self {
                a,
                b,
                aa: 0.0,
                ab: 0.0,
                bb: 0.0,
                reach2,
                area: PI * reach2,
                parallelogram: false,
                curvature: f.curvature,
                visits: f.visits,
            })
        }
    }

    /// The region scaled about its centre to `s2` times its area.
    pub(super) fn scaled(&self, s2: f32) -> Self {
        let s = crate::math::sqrt(s2);
        let inv = 1.0 / s2;
        Self {
            a: self.a * s,
            b: self.b * s,
            aa: self.aa * inv,
            ab: self.ab * inv,
            bb: self.bb * inv,
            reach2: self.reach2 * s2,
            area: self.area * s2,
            parallelogram: self.parallelogram,
            curvature: self.curvature,
            visits: self.visits,
        }
    }

    /// How far off the tangent plane at the region's centre `x` a photon counts: on a
    /// surface of curvature `κ`, a point whose offset along the plane is at most the
    /// reach `ρ` lies within the sagitta `ρ²κ / (1 + √(1 − ρ²κ²))` of that plane (the
    /// height of a circle of radius `1/κ` at distance `ρ` from its tangent point;
    /// `ρ²κ` past a hemisphere, `ρκ ≥ 1`); to that, `ρ/100` and `10⁻⁴·|x|∞` for the
    /// rounding of hit points and of stored positions (2⁻¹⁷ of a coordinate,
    /// [`Photon`](super::Photon)), both scaling with the scene. A photon farther off
    /// lies on another surface — the wall at a floor's corner, a box's next face — and
    /// is not the patch's: without this test a floor seen through a glass sphere next
    /// to a wall read up to 8% over the independent reference there, which gathers
    /// each object's photons alone (sphere + wall, `docs/accuracy.md`).
    #[inline]
    pub(super) fn thickness(&self, x: Vec3) -> f32 {
        let (reach, bend) = (crate::math::sqrt(self.reach2), self.reach2 * self.curvature);
        let rise = crate::math::max_num(1.0 - bend * self.curvature, 0.0);
        bend / (1.0 + crate::math::sqrt(rise)) + 0.01 * reach + 1e-4 * crate::math::max_abs(x)
    }

    /// The coordinates of offsets from the centre, worked out once per search (see
    /// [`Coordinates`]).
    #[inline]
    pub(super) fn coordinates(&self) -> Coordinates {
        Coordinates {
            a_dual: self.a * self.bb - self.b * self.ab,
            b_dual: self.b * self.aa - self.a * self.ab,
            parallelogram: self.parallelogram,
        }
    }

    /// The squared half-extents, per axis, of a box about a segment's centre that holds
    /// every offset the segment counts: `α·long + β·short + γ·n` with `|α|, |β| ≤ 1`,
    /// `n` the unit normal of the parallelogram's plane and `|γ|` at most `thickness`
    /// (see [`thickness`](Self::thickness); [`Coordinates`] ignores the component along
    /// `n`) — widened by 10⁻⁴ against rounding; unbounded for a disk.
    #[inline]
    pub(super) fn box_half2(&self, long: Vec3, short: Vec3, thickness: f32) -> [f32; 3] {
        let n = long.cross(short);
        let n2 = n.length_squared();
        if !self.parallelogram || !(n2 > 0.0) {
            return [f32::INFINITY; 3];
        }
        let n = n * (thickness / crate::math::sqrt(n2));
        let (l, s, n) = (long.abs(), short.abs(), n.abs());
        let e = (l + s + n) * 1.0001;
        (e * e).to_array()
    }

    /// How the parallelogram is cut into disks ([`Cut`]): along the longest of its
    /// four descriptions — `α·a + β·b` cut across `a` or across `b`, or
    /// `u·(a + b) + v·(a − b)` (`u = (α + β)/2`, `v = (α − β)/2`, `|u| + |v| ≤ 1`)
    /// cut across either diagonal — into as many pieces as that description's long
    /// side is longer than its short one. A sliver — a focus seen through a tube —
    /// searched as one disk would visit the photons of a square that many times its
    /// area. The diagonals serve the sheared sliver, whose two half-axes are both long
    /// and nearly parallel (the differentials of a ray entering glass at grazing
    /// incidence): cut across `a` or `b` its pieces were as long as the whole, and a
    /// search that visits too many photons ends, after the coarse levels, on a patch
    /// scaled down about its centre that holds a coarse photon or two — one sub-pixel
    /// 70 times its pixel's value on a glass sphere's rim. The diagonals are taken only
    /// where they are strictly more elongated, so every other cut is as before.
    #[inline]
    pub(super) fn cut(&self) -> Cut {
        if !self.parallelogram {
            return Cut::WHOLE;
        }
        let (sum, diff) = (self.a + self.b, self.a - self.b);
        let (la, lb) = (self.a.length_squared(), self.b.length_squared());
        let (ls, ld) = (sum.length_squared(), diff.length_squared());
        let (mut axis, mut ratio2) = if lb > la {
            (CutAxis::B, lb / la)
        } else {
            (CutAxis::A, la / lb)
        };
        let (diagonal, r2) = if ld > ls {
            (CutAxis::Diff, ld / ls)
        } else {
            (CutAxis::Sum, ls / ld)
        };
        if r2 > ratio2 {
            (axis, ratio2) = (diagonal, r2);
        }
        // `as` saturates, and NaN becomes 0.
        let segments = (crate::math::sqrt(ratio2) as u32).clamp(1, MAX_SEGMENTS);
        Cut { segments, axis }
    }
}

/// How [`Region::cut`] cuts a parallelogram into `segments` pieces across `long`:
/// piece `j` holds the offsets whose coordinate along it ([`along`](Self::along))
/// lies in `[−1 + 2j/s, −1 + 2(j+1)/s)`, each within `|long/s ± short|` of its
/// centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Cut {
    pub(super) segments: u32,
    axis: CutAxis,
}

/// The description a [`Cut`] is across (see [`Region::cut`]).
#[derive(Clone, Copy, Debug, PartialEq)]
enum CutAxis {
    A,
    B,
    Sum,
    Diff,
}

impl Cut {
    /// One piece: the region searched whole.
    pub(super) const WHOLE: Cut = Cut {
        segments: 1,
        axis: CutAxis::A,
    };

    /// `(long, short)`: the vector the pieces are cut across and the one each spans.
    #[inline]
    pub(super) fn axes(&self, r: &Region) -> (Vec3, Vec3) {
        match self.axis {
            CutAxis::A => (r.a, r.b),
            CutAxis::B => (r.b, r.a),
            CutAxis::Sum => (r.a + r.b, r.a - r.b),
            CutAxis::Diff => (r.a - r.b, r.a + r.b),
        }
    }

    /// The coordinate along `long` of the offset `α·a + β·b`, in `[−1, 1]`.
    #[inline]
    pub(super) fn along(&self, alpha: f32, beta: f32) -> f32 {
        match self.axis {
            CutAxis::A => alpha,
            CutAxis::B => beta,
            CutAxis::Sum => (alpha + beta) * 0.5,
            CutAxis::Diff => (alpha - beta) * 0.5,
        }
    }
}

/// The coordinates `(α, β)` of an offset `q` from a region's centre, `q = α·a + β·b`
/// (its component along the surface normal ignored: `a` and `b` lie in the tangent
/// plane), by the dual basis `α = q·a*`, `β = q·b*` with `a* = ((b·b)·a − (a·b)·b)/G`,
/// `b* = ((a·a)·b − (a·b)·a)/G`, `G = |a × b|²`: two dot products a photon, with two
/// vectors to keep in registers through the walk instead of five values. With the five,
/// spilled to the stack, every build that could reach the magnified widening's path ran
/// the tube and the balls scene 13–17% slower (`perf`: 18% of the walk's samples on the
/// one instruction after those loads, in the same machine code); with the dual basis,
/// as fast as before it.
pub(super) struct Coordinates {
    a_dual: Vec3,
    b_dual: Vec3,
    parallelogram: bool,
}

impl Coordinates {
    /// `(α, β)` when `q` lies inside the parallelogram; a disk holds every offset within
    /// its reach, at `(0, 0)`.
    #[inline]
    pub(super) fn of(&self, q: Vec3) -> Option<(f32, f32)> {
        if !self.parallelogram {
            return Some((0.0, 0.0));
        }
        let (alpha, beta) = (q.dot(self.a_dual), q.dot(self.b_dual));
        (alpha.abs() <= 1.0 && beta.abs() <= 1.0).then_some((alpha, beta))
    }
}

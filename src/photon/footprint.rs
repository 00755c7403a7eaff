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
        }
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
    /// `n` the unit normal of the parallelogram's plane (its component along `n` is
    /// ignored by [`Coordinates`], bounded only by the reach) — widened by
    /// 10⁻⁴ against rounding; unbounded for a disk.
    #[inline]
    pub(super) fn box_half2(&self, long: Vec3, short: Vec3, reach2: f32) -> [f32; 3] {
        let n = long.cross(short);
        let n2 = n.length_squared();
        if !self.parallelogram || !(n2 > 0.0) {
            return [f32::INFINITY; 3];
        }
        let n = n * (crate::math::sqrt(reach2 / n2));
        let (l, s, n) = (long.abs(), short.abs(), n.abs());
        let e = (l + s + n) * 1.0001;
        (e * e).to_array()
    }

    /// How many disks cover the parallelogram along `a` (its longer half-axis, or
    /// `b`'s when `along_b`): a sliver — a focus seen through a tube — searched as one
    /// disk would visit the photons of a square `|a|/|b|` times its area.
    #[inline]
    pub(super) fn segments(&self) -> (u32, bool) {
        if !self.parallelogram {
            return (1, false);
        }
        let (la, lb) = (self.a.length_squared(), self.b.length_squared());
        let along_b = lb > la;
        let ratio = crate::math::sqrt(if along_b { lb / la } else { la / lb });
        // `as` saturates, and NaN becomes 0.
        ((ratio as u32).clamp(1, MAX_SEGMENTS), along_b)
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

//! The radiance estimate: caustic light near a point, from the k nearest photons.

use core::f32::consts::PI;

use super::kdtree::{KdTree, Neighbor};
use super::packed::Photon;
use super::CausticStore;
use crate::material::Classic;
use crate::math::{Rgb, UnitVec3, Vec3};

/// Jensen's cone filter: photon `p` at distance `d` weighs `1 − d/(k·r)`, and the sum is
/// normalised by `1 − 2/(3k)` (Jensen 2001, eq. 7.7); `k ≥ 1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConeFilter {
    k: f32,
}

impl ConeFilter {
    /// A cone filter of constant `k` (Jensen suggests 1.1); `None` unless `k ≥ 1`.
    pub fn new(k: f32) -> Option<Self> {
        (k.is_finite() && k >= 1.0).then_some(Self { k })
    }

    /// The filter constant.
    pub fn k(&self) -> f32 {
        self.k
    }
}

/// A kd-tree photon map used as a caustic store, gathering up to `K` photons
/// (the compiled capacity of the gather; `k ≤ K` photons are used), or every photon
/// within a fixed radius.
#[derive(Clone, Copy, Debug)]
pub struct KdStore<'a, const K: usize> {
    tree: KdTree<'a>,
    /// Power of one unit of stored photon power, W.
    unit: f32,
    /// Photons per estimate; `None`: all within the radius.
    k: Option<usize>,
    max_radius2: f32,
    cone: Option<ConeFilter>,
    /// The photons' bounding box (`lo`, `hi`); empty (`lo > hi`) without photons.
    bounds: (Vec3, Vec3),
}

impl<'a, const K: usize> KdStore<'a, K> {
    /// A store over a balanced tree whose photon powers are in units of `unit` W,
    /// gathering the `k` nearest photons (clamped to `1..=K`) within `max_radius`, or,
    /// with `k = None`, every photon within `max_radius` (the fixed-radius gather of
    /// progressive photon mapping, which needs no gather buffer).
    pub fn new(
        tree: KdTree<'a>,
        unit: f32,
        k: Option<usize>,
        max_radius: f32,
        cone: Option<ConeFilter>,
    ) -> Self {
        Self {
            tree,
            unit,
            k: k.map(|k| k.clamp(1, K.max(1))),
            max_radius2: max_radius * max_radius,
            cone,
            bounds: bounds(tree.photons()),
        }
    }

    /// `true` when no photon can lie within the gather radius of `x`: `x` is farther
    /// than the maximum radius from the photons' bounding box (or there are none). The
    /// squared distance to the box is a lower bound of every photon's; it is compared
    /// with the radius² widened by 10⁻⁴ (relative) so that rounding never skips a
    /// gather that would have found a photon. A skipped gather returns exactly what the
    /// full one would (a zero sum), in about 20 instructions instead of a tree walk.
    #[inline]
    fn out_of_reach(&self, x: Vec3) -> bool {
        let (lo, hi) = self.bounds;
        let below = lo - x;
        let above = x - hi;
        let gap = |a: f32, b: f32| crate::math::max(crate::math::max(a, b), 0.0);
        let (gx, gy, gz) = (
            gap(below.x, above.x),
            gap(below.y, above.y),
            gap(below.z, above.z),
        );
        let d2 = gx * gx + gy * gy + gz * gz;
        // An empty tree has lo = +inf > hi = −inf: every gap is +inf.
        !(d2 <= self.max_radius2 * (1.0 + 1e-4))
    }

    /// The tree.
    pub fn tree(&self) -> &KdTree<'a> {
        &self.tree
    }

    /// Gathers the photons around `x` and sums `weight(photon)` over those that arrived
    /// on the front of the surface of normal `n`, with the cone filter if any. Returns
    /// the sum (in W, including the filter's normalisation) and r².
    ///
    /// With a footprint (radius² at most the maximum radius, and the number `s` of
    /// sub-pixel rays that share the pixel's `k`), every photon within it when it holds
    /// at least `⌈k/s⌉` of them — an estimate whose noise falls as photons are added,
    /// like progressive photon mapping's — else the `k` nearest within the pixel's
    /// footprint (`s` sub-footprints) and, without a footprint, within the maximum
    /// radius (Jensen). With a fixed radius and no
    /// footprint, every photon within the maximum radius.
    #[inline]
    fn gather(
        &self,
        x: Vec3,
        n: UnitVec3,
        footprint2: Option<(f32, u32)>,
        mut weight: impl FnMut(UnitVec3, Rgb) -> Rgb,
    ) -> (Rgb, f32) {
        let photons = self.tree.photons();
        let filter = |r2: f32| match self.cone {
            Some(c) => (
                1.0 / (c.k * crate::math::sqrt(r2)),
                1.0 / (1.0 - 2.0 / (3.0 * c.k)),
            ),
            None => (0.0, 1.0),
        };
        // The weighted power of one photon, `None` when it arrived from behind.
        let mut contribution = |index: usize, dist2: f32, inv_kr: f32| {
            let p = &photons[index];
            let dir = p.direction();
            if n.dot(dir.get()) >= 0.0 {
                return None;
            }
            let w = if self.cone.is_some() {
                1.0 - crate::math::sqrt(dist2) * inv_kr
            } else {
                1.0
            };
            Some(weight(dir, p.power()) * w)
        };
        let disk = footprint2.or(self.k.is_none().then_some((self.max_radius2, 1)));
        if let Some((r2, share)) = disk {
            let (inv_kr, norm) = filter(r2);
            let (mut sum, mut found) = (Rgb::ZERO, 0usize);
            self.tree.search(x, r2, |index, dist2| {
                if let Some(c) = contribution(index, dist2, inv_kr) {
                    sum += c;
                    found += 1;
                }
                r2
            });
            if footprint2.is_some() || self.k.is_none_or(|k| found * share.max(1) as usize >= k) {
                return (sum * (self.unit * norm), r2);
            }
        }
        let k = self.k.unwrap_or(1);
        // Behind a footprint, the nearest within the whole pixel's footprint only.
        let reach2 = match footprint2 {
            Some((r2, share)) => crate::math::min_num(self.max_radius2, r2 * share as f32),
            None => self.max_radius2,
        };
        let mut buf: heapless::Vec<Neighbor, K> = heapless::Vec::new();
        let found = self.tree.k_nearest(x, reach2, k, &mut buf);
        // Photon positions are known to about ε·|x|, and no estimate resolves detail
        // below 10⁻⁴ of the gather radius: k photons all at the query point would
        // otherwise divide by r² = 0. Floor r² there.
        let ulp = 4.0 * f32::EPSILON * crate::math::max_abs(x);
        let floor = crate::math::max(
            crate::math::max(ulp * ulp, 1e-8 * reach2),
            f32::MIN_POSITIVE,
        );
        let r2 = crate::math::max(found.radius2, floor);
        let (inv_kr, norm) = filter(r2);
        let mut sum = Rgb::ZERO;
        for nb in &buf {
            if let Some(c) = contribution(nb.index as usize, nb.dist2, inv_kr) {
                sum += c;
            }
        }
        (sum * (self.unit * norm), r2)
    }
}

impl<const K: usize> KdStore<'_, K> {
    /// The gather radius² bound: the store's maximum radius, or `radius` if smaller
    /// (but never a radius whose square is not a normal float).
    #[inline]
    fn bound2(&self, radius: f32) -> f32 {
        let r2 = radius * radius;
        if r2 >= f32::MIN_POSITIVE && r2 < self.max_radius2 {
            r2
        } else {
            self.max_radius2
        }
    }

    /// `E = Σ Φ_p / (π r²)` over the photons of [`gather`](Self::gather).
    #[inline]
    fn irradiance2(&self, x: Vec3, n: UnitVec3, r2_max: Option<(f32, u32)>) -> Rgb {
        if self.out_of_reach(x) {
            return Rgb::ZERO;
        }
        let (sum, r2) = self.gather(x, n, r2_max, |_, power| power);
        sum * (1.0 / (PI * r2))
    }

    /// Paper eq. 8 over the photons of [`gather`](Self::gather).
    #[inline]
    fn classic2(
        &self,
        x: Vec3,
        n: UnitVec3,
        to_eye: UnitVec3,
        m: &Classic,
        r2_max: Option<(f32, u32)>,
    ) -> Rgb {
        if self.out_of_reach(x) {
            return Rgb::ZERO;
        }
        let (sum, r2) = self.gather(x, n, r2_max, |dir, power| m.kernel(n, -dir, to_eye) * power);
        sum * (1.0 / r2)
    }
}

/// The bounding box of the photons' positions, `(lo, hi)`; `lo = +∞`, `hi = −∞`
/// without photons.
fn bounds(photons: &[Photon]) -> (Vec3, Vec3) {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for p in photons {
        let q = p.position();
        for i in 0..3 {
            lo[i] = crate::math::min_num(lo[i], q[i]);
            hi[i] = crate::math::max_num(hi[i], q[i]);
        }
    }
    (lo, hi)
}

impl<const K: usize> CausticStore for KdStore<'_, K> {
    /// `E = Σ Φ_p / (π r²)` over the k nearest front-side photons, `r` the distance to
    /// the k-th (or the maximum radius when fewer are found): Jensen 2001, eq. 7.6,
    /// divided by the diffuse BRDF.
    #[inline]
    fn irradiance(&self, x: Vec3, n: UnitVec3) -> Rgb {
        self.irradiance2(x, n, None)
    }

    /// Paper eq. 8: `c = (1/r²) Σ (max(n·l,0)·k_d·color + max(n·h,0)^a·k_s·color)·energy`.
    #[inline]
    fn classic(&self, x: Vec3, n: UnitVec3, to_eye: UnitVec3, m: &Classic) -> Rgb {
        self.classic2(x, n, to_eye, m, None)
    }

    #[inline]
    fn irradiance_within(&self, x: Vec3, n: UnitVec3, radius: f32, samples: u32) -> Rgb {
        self.irradiance2(x, n, Some((self.bound2(radius), samples)))
    }

    #[inline]
    fn classic_within(
        &self,
        x: Vec3,
        n: UnitVec3,
        to_eye: UnitVec3,
        m: &Classic,
        (radius, samples): (f32, u32),
    ) -> Rgb {
        self.classic2(x, n, to_eye, m, Some((self.bound2(radius), samples)))
    }
}

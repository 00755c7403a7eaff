//! The radiance estimate: caustic light near a point, from the k nearest photons.

use core::f32::consts::PI;

use super::footprint::{Cut, Footprint, Region};
use super::kdtree::{bounding_box, KdTree, Neighbor};
use super::{CausticStore, Halves};
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
/// within a fixed radius. `N` bounds the photons the map holds (a device map's
/// capacity, [`holding_at_most`](Self::holding_at_most); unbounded by default): with
/// `N ≤` [`FOOTPRINT_VISITS`] one search always covers a footprint, so the cut into
/// segments, the coarse levels and the scaling are not compiled.
#[derive(Clone, Copy, Debug)]
pub struct KdStore<'a, const K: usize, const N: usize = { usize::MAX }> {
    tree: KdTree<'a>,
    /// Power of one unit of stored photon power, W.
    unit: f32,
    /// Photons per estimate; `None`: all within the radius.
    k: Option<usize>,
    max_radius2: f32,
    cone: Option<ConeFilter>,
    /// The photons' bounding box (`lo`, `hi`); empty (`lo > hi`) without photons.
    bounds: (Vec3, Vec3),
    /// Thinned copies of the map for footprints that hold many photons: every
    /// [`THINNING`]-th photon of the level before, each standing for that many.
    coarse: [Option<KdTree<'a>>; 2],
}

/// The thinning of each coarse level of a [`KdStore`].
pub const THINNING: usize = 16;

/// Most photons one footprint gather visits on one level: a footprint that would hold
/// more is gathered on the finest coarse level where it holds fewer (unbiased: each
/// photon there stands for [`THINNING`]ˡ of the map's), and beyond the coarsest it is
/// scaled down about its centre.
pub const FOOTPRINT_VISITS: usize = 1024;

/// [`FOOTPRINT_VISITS`] for the footprints of a grazing pixel's refined grids (see
/// `Renderer::refine`): a focus seen through a ball's rim, where every sub-pixel's
/// footprint would hold thousands of photons. There the cap sets each gather's photons:
/// on a coarse level they stay about the same however many photons are emitted (16
/// times the photons move the gather one level coarser), a noise floor that a finer
/// grid does not lower. The sphere + wall f's 17 rim pixels read 3.19–3.40 over four
/// seeds at 1.6M photons a light with 1024 (reference 3.17), 3.23–3.28 with this cap.
/// Raised for these pixels alone, where the grids' secants bound each footprint
/// (`Renderer::grid`): raised everywhere, the balls scene's run took 17% longer.
pub const GRAZING_VISITS: usize = 16384;

/// A footprint seen along a path of throughput below this — a reflection off glass
/// near normal incidence (4%), or light that crossed a glass wall after reflecting
/// inside it — is gathered on the first coarse level, every [`THINNING`]-th photon,
/// each standing for that many: unbiased, and since the path weighs each of them by
/// less than `1/THINNING` in the pixel, one adds less than one photon of a full-weight
/// gather. No coarse-level prediction and no growth: one search over a tree
/// `THINNING` times smaller. Chosen on the tuning scenes at 1.6M photons per light:
/// gathers 31% (glass sphere) and 42% (two balls) faster with the same error; the
/// tube's caustic region 0.0483 → 0.0504, in the same time.
///
/// Below `FAINT²` (light reflected twice off glass, or once off the inside of a wall
/// it then crossed) the same holds one level down: the second coarse level, each photon
/// standing for `THINNING²`. The tuning scenes' errors at 1.6M and 100k the same to
/// four digits; on the balls + mirror + tube scene the gathers 11% faster.
pub const FAINT: f32 = 1.0 / THINNING as f32;

/// A footprint is sparse while one half of the forward pass holds fewer than half this
/// many of its photons, and is then widened if the photons around it look uniform
/// (`KdStore::widened`).
pub const SPARSE_FOOTPRINT: u32 = 8;

/// Most widenings of a sparse footprint (×4 in area each; see `KdStore::widened`).
///
/// Chosen with [`SPARSE_FOOTPRINT`] on the tuning scenes at 1.6M photons a light
/// (caustic region, 4 seeds; before: one unconditional growth below 16 photons, tube
/// 0.0445, two balls 0.0423, glass sphere 0.0354). One widening at 8: tube 0.0401, two
/// balls 0.0388, glass sphere 0.0342; the gathers' CPU time +20% on the tube, the same
/// on two balls. More buys the tube little for its time: two widenings 0.0385 and four
/// at 16 photons 0.0356, but the tube's gathers 2.4× and 3.6× as long, and those of two
/// balls 1.45× and 1.9×; one at 16 photons 0.0400, 1.6× as long on the tube.
pub const WIDENINGS: u32 = 1;

/// Most widenings of a sparse footprint seen magnified by at least [`MAGNIFIED`], by the
/// rule of the first (see `KdStore::widened`).
///
/// Through a glass ball whose focal surface lies near a wall behind it
/// (`scenes/lens_wall.json`, written after the defaults were chosen), the sub-pixels see
/// patches 10²–10⁴ times smaller than they would directly, which at 1.6M photons a light
/// hold about 0.01 photons each: one photon is a firefly 30–100 times the pixel's value,
/// and one ×4 widening does not reach the next photon. Over the ball, two seeds' images
/// differ by 183% of the mean (relative RMSE); with eight widenings, each half placed
/// by one photon of the other, 23%, the mean the same to 1%. Eight ×4 steps span 4⁸ in
/// area: from the smallest of those patches to the photons' spacing there. A half placed
/// by one photon is itself summed over about one photon, a 100% spread: placed as on the
/// first widening, by half of [`SPARSE_FOOTPRINT`], the noisiest 2 700 pixels of the
/// lens wall at 1.6M photons fell from 87% to 15% of their mean (per-seed spread, four
/// seeds), their mean within that noise (see `docs/accuracy.md`).
pub const MAGNIFIED_WIDENINGS: u32 = 8;

/// The magnification (`Footprint::direct` over the patch's area) from which a sparse
/// footprint widens up to [`MAGNIFIED_WIDENINGS`] times: 1, a patch no larger than the
/// same sample would cover seen directly. The magnification depends on the eye path
/// alone, never on the photons, so choosing by it biases nothing.
///
/// First 16, from where the sparse patches lie: on the tuning scenes' balls and tube
/// mostly between ¼ and 2 (those seen through the tube up to 2⁵), behind the ball lens
/// 2⁴–2¹⁴. Measured then (caustic region at 1.6M, four seeds): the tube 0.0386 →
/// 0.0355, a second scene written afterwards (a glass cylinder, a flint ball and a
/// mirror, two lights; two seeds) 0.0254 → 0.0222, the other scenes the same to three
/// digits. Lowered once a half widened far was placed by four photons of the other, not
/// one (session 27). The tube, the tuning scene with patches on both sides of 1, reads
/// 0.0361 0.0341 0.0359 0.0419 at 16, 0.0359 0.0342 0.0357 0.0419 at 4, **0.0358 0.0341
/// 0.0357 0.0418 at 1** and 0.0362 0.0343 0.0361 0.0420 at 0 (every sparse patch); the
/// glass sphere and the two balls the same to four digits at each, the lens wall
/// 0.327 0.294 0.312 0.295 → 0.325 0.292 0.311 0.293. Held out, measured once after: the
/// sphere + wall 0.0366 0.0362 0.0378 0.0339 → 0.0335 0.0336 0.0354 0.0310 (the mean of
/// four off its eight-seed reference by the same 0.0106 over 2×2 blocks: less noise, no
/// more bias), the sphere + wall c 0.083 0.078 0.082 0.078 → 0.058 0.054 0.064 0.048,
/// the balls scene and the tilted cube within 0.0001. Whole runs, paired: the tube 1.036,
/// the sphere + wall 1.032, the balls scene 1.012, the sphere + wall c 0.989.
pub const MAGNIFIED: f32 = 1.0;

/// The tail probability below which a footprint's photon count is taken as evidence
/// that the density is not uniform over the patch four times its area.
pub const UNIFORM_TAIL: f32 = 0.01;

/// `true` when `inner` of `total` photons in the central quarter (by area) of a patch is
/// a plausible draw of `X ~ Bin(total, 1/4)`: `P(X ≤ inner)` and `P(X ≥ inner)` are both
/// at least [`UNIFORM_TAIL`]. For `inner < 32` (all the widening asks), a `total`
/// above `6·inner + 18` always fails the lower tail (checked in f64 by the tests) and
/// is refused at once; otherwise the pmf by its recurrence `t₀ = (3/4)ⁿ`,
/// `t_{i+1} = t_i·(n − i)/(3(i + 1))`, with `(3/4)ⁿ` a normal `f32` for `n ≤ 204`.
fn uniform_quarter(inner: u32, total: u32) -> bool {
    if total > 6 * inner + 18 {
        return false;
    }
    // (3/4)ⁿ by repeated products: the same bits on every target.
    let mut t = 1.0f32;
    for _ in 0..total {
        t *= 0.75;
    }
    let mut below = 0.0f32;
    for i in 0..inner.min(total) {
        below += t;
        t *= (total - i) as f32 / (3 * (i + 1)) as f32;
    }
    below + t >= UNIFORM_TAIL && 1.0 - below >= UNIFORM_TAIL
}

impl<'a, const K: usize, const N: usize> KdStore<'a, K, N> {
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
        let bounds = bounding_box(tree.photons());
        Self::within_box(tree, unit, (k, max_radius, cone), bounds)
    }

    /// [`new`](Self::new) with the bounding box of the tree's photons given, as
    /// [`bounding_box`] finds it (or one holding it: a search outside the box finds
    /// nothing either way): the desktop merges the boxes of the forward pass's chunks as
    /// it traces them, instead of reading the whole array again on one thread (6 ms
    /// between the balance and the eye pass of the balls scene at 1.6M photons a light).
    pub(crate) fn within_box(
        tree: KdTree<'a>,
        unit: f32,
        (k, max_radius, cone): (Option<usize>, f32, Option<ConeFilter>),
        bounds: (Vec3, Vec3),
    ) -> Self {
        Self {
            tree,
            unit,
            k: k.map(|k| k.clamp(1, K.max(1))),
            max_radius2: max_radius * max_radius,
            cone,
            bounds,
            coarse: [None; 2],
        }
    }

    /// The same store, stating that its map holds at most `M` photons; `None` when it
    /// holds more.
    pub fn holding_at_most<const M: usize>(self) -> Option<KdStore<'a, K, M>> {
        (self.tree.photons().len() <= M).then_some(KdStore {
            tree: self.tree,
            unit: self.unit,
            k: self.k,
            max_radius2: self.max_radius2,
            cone: self.cone,
            bounds: self.bounds,
            coarse: self.coarse,
        })
    }

    /// The same store with coarse levels for large footprints: `level1` holds every
    /// [`THINNING`]-th photon of the map (any fixed selection independent of where the
    /// photons lie), `level2` every `THINNING`-th of `level1`, each balanced.
    pub fn with_coarse_levels(mut self, level1: KdTree<'a>, level2: KdTree<'a>) -> Self {
        self.coarse = [Some(level1), Some(level2)];
        self
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

    /// Gathers the photons around `x` — the k nearest within the maximum radius, or with
    /// a fixed radius every photon within it — and sums `weight(photon)` over those that
    /// arrived on the front of the surface of normal `n`, with the cone filter if any.
    /// Returns the sum (in W, including the filter's normalisation) and r². Out of
    /// line, with the weight behind a reference: one copy for both estimates.
    #[inline(never)]
    fn gather(
        &self,
        x: Vec3,
        n: UnitVec3,
        weight: &mut dyn FnMut(UnitVec3, Rgb) -> Rgb,
    ) -> (Rgb, f32) {
        let photons = self.tree.photons();
        let filter = |r2: f32| match self.cone {
            Some(c) => (
                1.0 / (c.k * crate::math::sqrt(r2)),
                1.0 / (1.0 - 2.0 / (3.0 * c.k)),
            ),
            None => (0.0, 1.0),
        };
        let mut sum = Rgb::ZERO;
        let mut add = |index: usize, dist2: f32, inv_kr: f32| {
            let p = &photons[index];
            let dir = p.direction();
            if n.dot(dir.get()) >= 0.0 {
                return; // arrived from behind the surface
            }
            let w = if self.cone.is_some() {
                1.0 - crate::math::sqrt(dist2) * inv_kr
            } else {
                1.0
            };
            sum += weight(dir, p.power()) * w;
        };
        let (r2, norm) = match self.k {
            Some(k) => {
                let mut buf: heapless::Vec<Neighbor, K> = heapless::Vec::new();
                let found = self.tree.k_nearest(x, self.max_radius2, k, &mut buf);
                // Photon positions are known to about ε·|x|, and no estimate resolves
                // detail below 10⁻⁴ of the gather radius: k photons all at the query
                // point would otherwise divide by r² = 0. Floor r² there.
                let ulp = 4.0 * f32::EPSILON * crate::math::max_abs(x);
                let floor = crate::math::max(
                    crate::math::max(ulp * ulp, 1e-8 * self.max_radius2),
                    f32::MIN_POSITIVE,
                );
                let r2 = crate::math::max(found.radius2, floor);
                let (inv_kr, norm) = filter(r2);
                for nb in &buf {
                    add(nb.index as usize, nb.dist2, inv_kr);
                }
                (r2, norm)
            }
            None => {
                let r2 = self.max_radius2;
                let (inv_kr, norm) = filter(r2);
                self.tree.search(x, r2, |index, dist2| {
                    add(index, dist2, inv_kr);
                    r2
                });
                (r2, norm)
            }
        };
        (sum * (self.unit * norm), r2)
    }

    /// Sums `weight(photon)` over the photons inside the footprint that arrived on the
    /// front of the surface of normal `n` (no cone filter: the footprint is the
    /// kernel), over the area they cover: the density of the two halves, W per unit
    /// area, or `None` for an empty or non-finite footprint. Unbiased for the patch's
    /// average irradiance, whatever its size or shape, except where a sparse footprint
    /// is [widened](Self::widened); the work is bounded by [`FOOTPRINT_VISITS`] photons
    /// per search.
    #[inline(never)]
    fn gather_footprint(
        &self,
        x: Vec3,
        n: UnitVec3,
        footprint: &Footprint,
        weight: &mut dyn FnMut(UnitVec3, Rgb) -> Rgb,
    ) -> Option<Halves> {
        let region = Region::new(footprint, self.max_radius2)?;
        if N <= FOOTPRINT_VISITS {
            // No search can visit more photons than the map holds: the first always
            // completes (the loop below would return the same sums). No reach test
            // either: the renderer asks `reaches` first, and a search out of reach
            // finds nothing, the same zero.
            return Some(self.widened::<WIDENINGS>(x, n, region, None, 0.0, weight));
        }
        if self.out_of_reach(x) {
            return Some(Halves::default());
        }
        // The finest level where the footprint visits at most FOOTPRINT_VISITS
        // photons, as the coarsest level's count predicts it: a search that would visit
        // more stops there and is tried again — a sliver cut into disks, then on the
        // next coarser level, at last scaled down. A sparse one is widened (on level
        // 0). A faint path's starts on level 1, a fainter one's on level 2 (see FAINT).
        let levels = [Some(self.tree), self.coarse[0], self.coarse[1]];
        let faint = footprint.throughput < FAINT && self.coarse[0].is_some();
        let level = if faint && footprint.throughput < FAINT * FAINT && self.coarse[1].is_some() {
            2
        } else if faint {
            1
        } else {
            self.first_level(x, n, &region)
        };
        let (mut region, mut level, mut cut) = (region, level, false);
        loop {
            let (sum, visits, found) = self.sum_in(levels[level], x, n, &region, cut, Some(weight));
            if visits.is_some() {
                if level == 0 {
                    let (first, direct) = (Some((sum, found)), footprint.direct);
                    return Some(self.widened::<WIDENINGS>(x, n, region, first, direct, weight));
                }
                let scale = [1, THINNING, THINNING * THINNING][level] as f32 * self.unit;
                return Some(Halves::from_parts(sum[0], sum[1]).scaled(scale / region.area));
            }
            if !cut && region.cut().segments > 1 {
                cut = true;
            } else if levels.get(level + 1).is_some_and(Option::is_some) {
                level += 1;
            } else {
                region = region.scaled(0.25);
            }
        }
    }

    /// The photons' density over `region` (`first`: its sums and photon counts per
    /// half, when already searched), or over a patch about the same centre up to `W`
    /// times ×4 larger in area ([`WIDENINGS`]; [`MAGNIFIED_WIDENINGS`] for a footprint
    /// seen magnified, see below), each half of the forward pass over its own patch.
    ///
    /// Each half's photons are summed over the first patch where the *other* half
    /// holds at least half of [`SPARSE_FOOTPRINT`] photons, or over the last one: a patch
    /// chosen by its own count would be biased up (it is kept when its count happens
    /// to be high), while the halves are independent point sets, so each is summed
    /// over a patch its own luck did not choose (cross-fitting). The patch grows while
    /// a half is left to place and it holds fewer than twice [`SPARSE_FOOTPRINT`], if
    /// the one twice its size lies within the store's radius and spreads its photons
    /// as a uniform density would: the `c` of the patch among the `C` of the larger
    /// are a plausible draw of `Bin(C, 1/4)` ([`uniform_quarter`]).
    ///
    /// The unbiased count-over-area of a footprint that holds a photon or none (a
    /// faint caustic seen magnified through glass, a surface near the focus of a ball
    /// lens) is a firefly; averaging over a wider patch trades that variance for a
    /// bias, and only where the photons give no evidence of structure: next to a focus
    /// or an edge the test fails and the patch stays. As the photon density grows the
    /// footprints stop being sparse and the patch shrinks to the pixel's (the shrinking
    /// radius of progressive photon mapping, Hachisuka et al. 2008, chosen per pixel by
    /// a test instead of a schedule). One search site, so that a device's flash holds
    /// one copy of the walk.
    ///
    /// A footprint seen magnified (`direct` at least [`MAGNIFIED`] times its area)
    /// whose first widening still leaves a half unplaced is gathered again by
    /// [`widened_far`](Self::widened_far): the same rule, up to [`MAGNIFIED_WIDENINGS`]
    /// widenings. Only on a map of unbounded capacity (the desktop's): a device's flash
    /// and stack are budgeted, and a second walk would cost them about 1.5 KiB and
    /// 0.5 KiB.
    fn widened<const W: u32>(
        &self,
        x: Vec3,
        n: UnitVec3,
        region: Region,
        first: Option<([Rgb; 2], [u32; 2])>,
        direct: f32,
        weight: &mut dyn FnMut(UnitVec3, Rgb) -> Rgb,
    ) -> Halves {
        // The patch kept so far with its sums and counts; `None` before the first search.
        let mut kept = first.map(|(sum, found)| (region, sum, found));
        // Half h's density, once the other half has chosen its patch (`placed`).
        let (mut density, mut placed) = ([Rgb::ZERO; 2], [false; 2]);
        let mut next = region;
        // The patch holds twice the sparse count (one half's luck aside: it is not
        // sparse), or the next is out of reach: no widening past it.
        let last = |r: &Region, found: [u32; 2]| {
            found[0] + found[1] >= 2 * SPARSE_FOOTPRINT || r.reach2 * 4.0 > self.max_radius2
        };
        // Half h is placed on a patch where the other half holds this many photons.
        let places = |found: [u32; 2], h: usize| found[1 - h] >= SPARSE_FOOTPRINT / 2;
        for _ in 0..W + first.is_none() as u32 {
            if let Some((r, sum, found)) = kept {
                for h in 0..2 {
                    if !placed[h] && places(found, h) {
                        (density[h], placed[h]) = (sum[h] * (1.0 / r.area), true);
                    }
                }
                if placed == [true; 2] || last(&r, found) {
                    break;
                }
                next = r.scaled(4.0);
            }
            let (sum, visits, found) =
                self.sum_in(Some(self.tree), x, n, &next, false, Some(weight));
            match kept {
                Some((_, _, c))
                    if visits.is_none() || !uniform_quarter(c[0] + c[1], found[0] + found[1]) =>
                {
                    break
                }
                _ => kept = Some((next, sum, found)),
            }
        }
        if self.reads_direct() && W == 1 && direct >= MAGNIFIED * region.area {
            // Where the loop above, given more widenings, would go on: past the first,
            // not its last, a half its last patch would not place.
            if let (Some(first), Some((r, _, found))) = (first, kept) {
                let waiting = (0..2).any(|h| !placed[h] && !places(found, h));
                if r.area > region.area && waiting && !last(&r, found) {
                    return self.widened_far(x, n, region, first, weight);
                }
            }
        }
        let (area, sum) = kept.map_or((1.0, [Rgb::ZERO; 2]), |(r, s, _)| (r.area, s));
        for h in 0..2 {
            if !placed[h] {
                density[h] = sum[h] * (1.0 / area);
            }
        }
        Halves::from_parts(density[0], density[1]).scaled(self.unit)
    }

    /// [`widened`](Self::widened) from the footprint's own search (`first`), up to
    /// [`MAGNIFIED_WIDENINGS`] times. Out of line: the common gather never runs it.
    #[inline(never)]
    fn widened_far(
        &self,
        x: Vec3,
        n: UnitVec3,
        region: Region,
        first: ([Rgb; 2], [u32; 2]),
        weight: &mut dyn FnMut(UnitVec3, Rgb) -> Rgb,
    ) -> Halves {
        Halves {
            widened: true,
            ..self.widened::<MAGNIFIED_WIDENINGS>(x, n, region, Some(first), 0.0, weight)
        }
    }

    /// The level to try first: the finest whose photons in the region's reach are
    /// predicted, from the coarsest level's count, not to exceed [`FOOTPRINT_VISITS`].
    /// The count is [`sum_in`](Self::sum_in)'s walk with nothing summed, stopped as soon
    /// as it rules out level 1.
    fn first_level(&self, x: Vec3, n: UnitVec3, region: &Region) -> usize {
        let Some(coarsest) = self.coarse[1] else {
            return 0;
        };
        let (_, visits, _) = self.sum_in(Some(coarsest), x, n, region, false, None);
        let Some(v) = visits else { return 2 };
        if v * THINNING * THINNING <= region.visits {
            0
        } else if v * THINNING <= region.visits {
            1
        } else {
            2
        }
    }

    /// The weighted sums of the front-side photons of `tree` inside `region`, of the
    /// forward pass's half 0 and half 1, the photons visited (`None` when they would
    /// exceed [`FOOTPRINT_VISITS`]) and the photons summed of each half. Without a
    /// `weight`, only the visits are counted, and `None` once they exceed
    /// `FOOTPRINT_VISITS / THINNING` (all [`first_level`](Self::first_level) needs;
    /// one walk serves every search, so a device's flash holds one copy of it).
    #[inline]
    fn sum_in(
        &self,
        tree: Option<KdTree<'_>>,
        x: Vec3,
        n: UnitVec3,
        region: &Region,
        cut: bool,
        mut weight: Option<&mut dyn FnMut(UnitVec3, Rgb) -> Rgb>,
    ) -> ([Rgb; 2], Option<usize>, [u32; 2]) {
        let cap = if weight.is_some() {
            region.visits
        } else {
            region.visits / THINNING
        };
        let mut sum = [Rgb::ZERO; 2];
        let Some(tree) = tree else {
            return (sum, Some(0), [0; 2]);
        };
        let photons = tree.photons();
        let (mut visited, mut found) = (0usize, [0u32; 2]);
        let how = if cut { region.cut() } else { Cut::WHOLE };
        let segments = how.segments;
        let (long, short) = how.axes(region);
        let step = 2.0 / segments as f32;
        let piece = long * (1.0 / segments as f32);
        // A photon off the patch's surface is another surface's (`Region::thickness`);
        // one on it lies within `thickness` of the plane, so within
        // √(reach² + thickness²) of its segment's centre, `reach` along the plane (one
        // segment's is the region's own, computed once with it).
        let thickness = region.thickness(x);
        let reach2 = thickness * thickness
            + if segments == 1 {
                region.reach2
            } else {
                crate::math::max(
                    (piece + short).length_squared(),
                    (piece - short).length_squared(),
                )
            };
        // A map small enough for one search gains nothing from the box (no level is
        // chosen by its count): a device's flash is spared it.
        let half2 = if N <= FOOTPRINT_VISITS {
            [f32::INFINITY; 3]
        } else {
            region.box_half2(piece, short, thickness)
        };
        let coordinates = region.coordinates();
        for j in 0..segments {
            // Segment j holds the long coordinate in [−1 + j·step, −1 + (j+1)·step)
            // (the last one closed): every photon is counted once.
            let lo = -1.0 + j as f32 * step;
            let hi = if j + 1 == segments {
                f32::INFINITY
            } else {
                lo + step
            };
            let centre = x + long * (lo + 0.5 * step);
            tree.search_boxed(centre, reach2, half2, |index, _| {
                visited += 1;
                if visited > cap {
                    return 0.0; // ends the search
                }
                let Some(weight) = weight.as_mut() else {
                    return reach2;
                };
                let p = &photons[index];
                let q = p.position() - x;
                let inside = q.dot(n.get()).abs() <= thickness
                    && coordinates.of(q).is_some_and(|(alpha, beta)| {
                        let t = how.along(alpha, beta);
                        segments == 1 || (t >= lo && t < hi)
                    });
                if inside {
                    let dir = p.direction();
                    if n.dot(dir.get()) < 0.0 {
                        let h = p.half() as usize;
                        sum[h] += weight(dir, p.power());
                        found[h] += 1;
                    }
                }
                reach2
            });
            if visited > cap {
                return (sum, None, found);
            }
        }
        (sum, Some(visited), found)
    }
}

impl<const K: usize, const N: usize> CausticStore for KdStore<'_, K, N> {
    /// Only a map of unbounded capacity widens magnified footprints (`widened` asks
    /// this).
    #[inline]
    fn reads_direct(&self) -> bool {
        N == usize::MAX
    }

    /// `E = Σ Φ_p / (π r²)` over the k nearest front-side photons, `r` the distance to
    /// the k-th (or the maximum radius when fewer are found): Jensen 2001, eq. 7.6,
    /// divided by the diffuse BRDF.
    #[inline]
    fn irradiance(&self, x: Vec3, n: UnitVec3) -> Rgb {
        if self.out_of_reach(x) {
            return Rgb::ZERO;
        }
        let (sum, r2) = self.gather(x, n, &mut |_, power| power);
        sum * (1.0 / (PI * r2))
    }

    /// Paper eq. 8: `c = (1/r²) Σ (max(n·l,0)·k_d·color + max(n·h,0)^a·k_s·color)·energy`.
    #[inline]
    fn classic(&self, x: Vec3, n: UnitVec3, to_eye: UnitVec3, m: &Classic) -> Rgb {
        if self.out_of_reach(x) {
            return Rgb::ZERO;
        }
        let (sum, r2) = self.gather(x, n, &mut |dir, power| m.kernel(n, -dir, to_eye) * power);
        sum * (1.0 / r2)
    }

    /// `false` beyond the maximum radius from the photons' bounding box.
    #[inline]
    fn reaches(&self, x: Vec3) -> bool {
        !self.out_of_reach(x)
    }

    /// `E = Σ Φ_p / A` over the front-side photons inside the footprint of area `A`
    /// (the store's own estimate for an empty footprint, unsplit).
    #[inline]
    fn irradiance_within(&self, x: Vec3, n: UnitVec3, footprint: &Footprint) -> Halves {
        match self.gather_footprint(x, n, footprint, &mut |_, power| power) {
            Some(density) => density,
            None => Halves::whole(self.irradiance(x, n)),
        }
    }

    /// Paper eq. 8 over the photons inside the footprint, its `1/r²` the disk's of the
    /// same area (`π/A`).
    #[inline]
    fn classic_within(
        &self,
        x: Vec3,
        n: UnitVec3,
        to_eye: UnitVec3,
        m: &Classic,
        footprint: &Footprint,
    ) -> Halves {
        let mut kernel = |dir: UnitVec3, power| m.kernel(n, -dir, to_eye) * power;
        match self.gather_footprint(x, n, footprint, &mut kernel) {
            Some(density) => density.scaled(PI),
            None => Halves::whole(self.classic(x, n, to_eye, m)),
        }
    }
}

#[cfg(test)]
mod tests;

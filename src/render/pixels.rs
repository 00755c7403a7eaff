//! How a pixel's area is sampled, and rows of pixels.
//!
//! A pixel's value is the average radiance over its area (a box filter). The default
//! [`Sampling::Adaptive`] follows Whitted (1980): trace the pixel's four corners and
//! average them where they agree; where they do not (different objects along the
//! paths, a light visible from one and not another, or a luminance contrast
//! `(max − min)/(max + min)` above [`CONTRAST`], Mitchell 1987), average an `n × n`
//! grid of sub-pixel rays instead. Corners are shared along a row, so a smooth region
//! costs about two rays a pixel; shadow edges, silhouettes and whatever is seen through
//! glass get `n²`. A grid is refined to `2n` and `4n` while its error estimate
//! ([`Grid::error2`]: the checkerboard halves' difference, a corner outside the range
//! of the grid's samples, two grids in a row that disagree) exceeds
//! [`REFINE_TOLERANCE`] of the pixel's brightness, within a ray budget per pixel. On
//! the desktop that brightness is at least [`REFINE_FLOOR`] times the image's mean: a
//! pixel's error counts in the image by its absolute size, so dim pixels stop sooner.

use super::cells::{Cells, Coarse};
use super::differential::Bounds;
use super::grid::{Grid, Lines};
use super::probe::ProbeRows;
use super::{PixelEstimate, RayCount, Renderer, RowsError, Sample};
use crate::error::Error;
use crate::math::Rgb;
use crate::photon::{add_to_row, CausticStore, SplatTarget};

/// How a pixel's area is sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampling {
    /// One ray through the pixel centre (the paper; a point estimate of the pixel).
    Centre,
    /// `n × n` rays through the centres of an `n × n` grid of sub-pixels, averaged.
    Grid(u32),
    /// The four corners, averaged where they agree; an `n × n` grid where they do not.
    Adaptive(u32),
}

/// The corner contrast above which [`Sampling::Adaptive`] supersamples a pixel.
pub const CONTRAST: f32 = 0.04;

/// The weight (largest channel of a branch's throughput from the eye) below which a
/// branch's events stay out of its sample's signature, so that four corners whose
/// faint reflections meet different objects still agree. Such a branch adds under 1%
/// of what it sees: where that differs between the corners enough to matter, their
/// luminances differ by more than [`CONTRAST`]. Chosen on the three tuning scenes at
/// 1.6M photons a light: errors against their references unchanged to three digits,
/// 1% (tube), 4% (glass sphere) and 13% (two balls) fewer pixels supersampled; 1/16
/// put two balls' caustic error up by 0.6%.
pub const SIGNATURE_WEIGHT: f32 = 0.01;

/// The default sub-pixel grid side of [`Sampling::Adaptive`].
pub const REFINE: u32 = 4;

/// [`Sampling::Adaptive`] refines a supersampled pixel further — its grid side doubled,
/// at most twice — while the grid's own error estimate exceeds this fraction of the
/// pixel's brightness (the brightest of its value, its brightest corner and the floor
/// [`Renderer::with_refine_floor`] set, by default none).
pub const REFINE_TOLERANCE: f32 = 0.01;

/// The floor under a pixel's brightness in [`REFINE_TOLERANCE`], as a multiple of the
/// image's mean luminance ([`Renderer::mean_luminance`], set with
/// [`Renderer::with_image_floor`]). A pixel's error counts in the image's relative
/// RMSE by its absolute size, so a dim pixel need not be refined to 1% of its own
/// value: its tolerance is 1% of at least this many means. Chosen on the tuning scenes
/// at 1.6M photons a light (four seeds; plain photons blocks), as the largest floor
/// that moved no caustic error by more than 0.0003 (about 1%): with floors of 0, 1, 2,
/// 3 and 4 the glass sphere's errors were the same to four digits while its eye rays
/// fell 1.60M → 1.04M, 0.99M, 0.94M, 0.92M; the two balls' the same with 1.60M →
/// 1.54M, 1.44M, 1.31M, 1.25M; the tube's 0.0285 0.0267 0.0287 0.0284 went to
/// 0.0285 0.0267 0.0288 0.0284 (1), 0.0288 0.0269 0.0289 0.0285 (2), 0.0290 0.0273
/// 0.0291 0.0288 (3) and 0.0293 0.0274 0.0290 0.0287 (4) with its eye rays 1.83M →
/// 1.51M, 1.18M, 0.97M, 0.86M (medians of the seeds; `docs/accuracy.md`, session 37).
/// A grazing pixel ([`GRAZING`]) keeps its own brightness: its grids' halves alias a
/// sliver of focus alike, so its error estimate cannot vouch for a coarse grid (with
/// the floor, the sphere + wall's (143, 148), a focus seen through the ball's rim,
/// read 0.0313 against its 64×64 grid's 0.0280).
pub const REFINE_FLOOR: f32 = 2.0;

/// Corners along each side of the lattice whose samples estimate the image's mean
/// luminance ([`Renderer::mean_luminance`]): at most 33 × 33 samples, under 2% of a
/// 320×240 image's corners.
pub const LATTICE: u32 = 33;

/// The share of [`REFINE_TOLERANCE`] within which a supersampled pixel's first grid
/// settles its caustic part: where the first grid's checkerboard halves agree on the
/// caustic part alone to within this share of the tolerance, and no corner lies
/// outside the range of its samples by more, the finer grids that its refinement goes
/// on to take their caustic parts from it (see `Renderer::refine`). Chosen on the
/// tuning scenes at 1.6M photons a light (four seeds): 0.25 and 0.5 left every caustic
/// error within 0.0003 of the first grid's gathers everywhere, for 9–10% (0.5) and
/// 3–9% (0.25) less eye-pass time on the two balls and the tube; 1.0 saved a further
/// 1% and put one seed of the two balls up 3% (0.0302 → 0.0311).
pub const CAUSTIC_SHARE: f32 = 0.5;

/// The incidence cosine `|cos θ|` below which a camera ray enters glass at grazing
/// incidence. There the refracted direction turns fastest across the sub-pixel, so its
/// differentials' linear footprint can lie far from the sub-pixel's true preimage; a
/// 4×4 grid's sample that grazes the glass and gathers more than the whole pixel's
/// value (the focus seen through the rim of a ball) sends the pixel straight to a
/// 16×16 grid, whose sub-pixels are small enough for the linearisation (and on, see
/// `Renderer::refine`). Chosen on the tuning scenes at 1.6M photons (four seeds): the
/// glass sphere's caustic region 0.0260 → 0.0249 for 1.3% more eye rays, the two balls
/// and the tube the same (+0.5%, 0%); below 0.3 the tube's eye rays grew 32% for
/// nothing, and an 8×8 grid made the glass sphere's 0.0266. Held out, measured
/// afterwards: the sphere + wall 0.0570 → 0.0547 (four seeds), the balls scene 0.0233
/// → 0.0226 (two seeds) for 1.1% more eye rays, the tilted cube the same.
pub const GRAZING: f32 = 0.15;

/// A pixel's further refinement stops before it would spend more than this many times
/// the ray budget of one camera ray: a pixel costs at most its corners, its first grid
/// and this many budgets.
pub const REFINE_RAYS: u32 = 16;

/// The budgets of [`REFINE_RAYS`] for a pixel whose first grid has a sample that grazed
/// glass and gathered more than the pixel's value ([`GRAZING`]): its refinement may go
/// on to `8n × 8n` while its error estimate asks for it. On the desktop only (a
/// device's flash keeps the old path).
pub const GRAZING_RAYS: u32 = 64;

impl Sampling {
    /// The most rays a pixel can cost, with `budget` rays per camera ray: one camera
    /// ray's worth per sample of its grid and corners, plus for the adaptive scheme's
    /// further refinement at most [`GRAZING_RAYS`] budgets.
    pub fn max_rays_per_pixel(&self, budget: u32) -> u64 {
        let b = budget as u64;
        match *self {
            Sampling::Centre => b,
            Sampling::Grid(n) => n as u64 * n as u64 * b,
            Sampling::Adaptive(n) => (4 + n as u64 * n as u64 + GRAZING_RAYS as u64) * b,
        }
    }
}

/// What a row holds: radiance alone, or each pixel with its estimated error.
pub trait RowPixel: SplatTarget {
    /// The row's pixel from the renderer's estimate of it.
    fn from_estimate(p: PixelEstimate) -> Self;
}

impl RowPixel for Rgb {
    #[inline]
    fn from_estimate(p: PixelEstimate) -> Self {
        p.radiance
    }
}

impl RowPixel for PixelEstimate {
    #[inline]
    fn from_estimate(p: PixelEstimate) -> Self {
        p
    }
}

impl<S: CausticStore, const O: usize, const L: usize, const DEPTH: usize>
    Renderer<'_, S, O, L, DEPTH>
{
    /// Pixel `(x, y)` as the mean of an `n × n` grid of sub-pixel rays. Its sampling
    /// error is estimated from the grid's two checkerboard halves `a`, `b` as
    /// `((m_a − m_b)/2)²` per channel: the batch-means estimate for two half-grids.
    /// The halves gather over halves of the pixel's preimage, so this holds part of the
    /// gathers' noise; the sub-pixels' own [`split`](Sample::split)s, averaged, are
    /// carried too, because a sub-pixel footprint that was widened
    /// ([`SPARSE_FOOTPRINT`](crate::photon::SPARSE_FOOTPRINT)) overlaps its neighbours
    /// and the halves then share photons (without it the sphere + wall scene's estimate
    /// fell to half its measured error).
    ///
    /// Also returned ([`Grid`]): the part of `((m_a − m_b)/2)²`'s luminance that the
    /// photons of samples [widened far](crate::photon::Halves::widened) explain,
    /// `¼·Σ_h Σ_{i∈h} split_i²/n_h²` (each sample's `split²` estimates its photons'
    /// variance), which no finer grid lowers, and whether a sample that grazed glass
    /// ([`GRAZING`]) gathered more than the pixel's value (see [`refine`](Self::refine)).
    fn grid(&self, x: u32, y: u32, n: u32, cells: Cells<'_>, count: &mut RayCount) -> Grid {
        self.grid_within(x, y, n, |_, _| Bounds::PLAIN, cells, count)
    }

    /// [`grid`](Self::grid) for a grazing pixel's refined grid (see [`refine`](Self::refine)):
    /// each sample's footprints may visit
    /// [`GRAZING_VISITS`](crate::photon::GRAZING_VISITS) photons, and where the sample's
    /// heavy path first gathers, its footprint is bounded by the secants to its
    /// neighbours' points ([`Renderer::probe`], traced a row ahead: `probe.rs`). Desktop
    /// only: its three rows of probes (4.6 KiB) stay off a device's stack.
    #[inline(never)]
    fn grazing_grid(&self, x: u32, y: u32, n: u32, count: &mut RayCount) -> Grid {
        let mut rows = ProbeRows::new(x, y, n);
        self.grid_within(
            x,
            y,
            n,
            |sx, sy| rows.bounds(self, sx, sy),
            Cells::Own,
            count,
        )
    }

    /// [`grid`](Self::grid), each sample's footprints bounded by `bounds(sx, sy)`
    /// (asked in the grid's row-major order).
    fn grid_within(
        &self,
        x: u32,
        y: u32,
        n: u32,
        mut bounds: impl FnMut(u32, u32) -> Bounds,
        mut cells: Cells<'_>,
        count: &mut RayCount,
    ) -> Grid {
        let step = 1.0 / n as f32;
        let camera = self.scene.camera();
        let mut half = [(Rgb::ZERO, Rgb::ZERO, 0u32); 2];
        let mut split = Rgb::ZERO;
        // Per half, the photons' variance `split²` of its widened samples.
        let mut widened = [0.0f32; 2];
        // The largest caustic part of a sample that grazed glass.
        let mut grazing = 0.0f32;
        // The signature every sample shares, if they all do.
        let mut shared = None;
        let mut uniform = true;
        let mut range = NO_RANGE;
        // Constant false on a device's store: its grids keep no lines.
        let desktop = self.store.reads_direct();
        let mut lines = Lines::new(if desktop { n } else { 0 });
        for sy in 0..n {
            for sx in 0..n {
                let (fx, fy) = ((sx as f32 + 0.5) * step, (sy as f32 + 0.5) * step);
                let before = count.widened;
                let ray = camera.ray_at(x, y, fx, fy);
                let b = bounds(sx, sy);
                let (s, grazes) = self.sample_in(ray, n, b, (sx, sy), &mut cells, count);
                if grazes {
                    grazing = crate::math::max(grazing, s.caustic.luminance());
                }
                uniform &= *shared.get_or_insert(s.signature) == s.signature;
                if desktop {
                    lines.add(sx, sy, s.signature, s.radiance.luminance());
                }
                range = widen(range, s.radiance.luminance());
                let k = ((sx + sy) & 1) as usize;
                // Constant false on a device's store: not compiled there.
                if self.store.reads_direct() && count.widened > before {
                    let l = s.split.luminance();
                    widened[k] += l * l;
                }
                let h = &mut half[k];
                h.0 += s.radiance;
                h.1 += s.caustic;
                h.2 += 1;
                split += s.split;
            }
        }
        let inv = 1.0 / (n * n) as f32;
        // Half the difference of the checkerboard halves' means of one part.
        let halves = |part: fn(&(Rgb, Rgb, u32)) -> Rgb| {
            (part(&half[0]) * (1.0 / half[0].2 as f32) - part(&half[1]) * (1.0 / half[1].2 as f32))
                * 0.5
        };
        let sampling2 = if half[1].2 > 0 {
            let d = halves(|h| h.0);
            d * d
        } else {
            Rgb::ZERO
        };
        let caustic2 = if desktop && half[1].2 > 0 {
            let d = halves(|h| h.1);
            (d * d).luminance()
        } else {
            0.0
        };
        let photons = if self.store.reads_direct() {
            (0..2).fold(0.0, |v, k| {
                let n = half[k].2.max(1) as f32;
                v + widened[k] / (n * n)
            }) * 0.25
        } else {
            0.0 // a device's store: nothing widened far
        };
        let pixel = PixelEstimate {
            radiance: (half[0].0 + half[1].0) * inv,
            caustic: (half[0].1 + half[1].1) * inv,
            split: split * inv,
            sampling2,
        };
        Grid {
            caustic2,
            aligned: lines.aligned2(),
            grazing: grazing > pixel.radiance.luminance(),
            uniform,
            range,
            pixel,
            photons,
        }
    }

    /// Sample `(sx, sy)` of an `n × n` grid along `ray`, as [`Cells`] asks: a finer
    /// grid's sample that sees the same paths as its cell's first-grid sample traces
    /// them without gathering and takes that sample's caustic part (see
    /// [`refine`](Self::refine)); the first grid's samples are kept. A device's build
    /// keeps no cells: there every sample gathers for itself.
    #[inline]
    fn sample_in(
        &self,
        ray: crate::geometry::Ray,
        n: u32,
        b: Bounds,
        (sx, sy): (u32, u32),
        cells: &mut Cells<'_>,
        count: &mut RayCount,
    ) -> (Sample, bool) {
        #[cfg(feature = "std")]
        if self.store.reads_direct() {
            match cells {
                Cells::Take(c) => {
                    if let Some(cell) = c.cell(sx, sy, n) {
                        let without = Bounds {
                            visits: Bounds::NO_GATHER,
                            ..b
                        };
                        let (mut s, g) = self.sample_within(ray, n, without, count);
                        // Across an edge the sample gathers for itself after all.
                        if s.signature == cell.0 {
                            (s.radiance, s.caustic, s.split) =
                                (s.radiance + cell.1, cell.1, cell.2);
                            return (s, g);
                        }
                    }
                }
                Cells::Keep(c) => {
                    let (s, g) = self.sample_within(ray, n, b, count);
                    c.keep(sx, sy, &s);
                    return (s, g);
                }
                Cells::Own => {}
            }
        }
        #[cfg(not(feature = "std"))]
        let _ = (sx, sy, cells);
        self.sample_within(ray, n, b, count)
    }

    /// Pixel `(x, y)` on an `n × n` grid, then `2n × 2n` and `4n × 4n` while the
    /// grid's error estimate ([`Grid::error2`]) exceeds [`REFINE_TOLERANCE`] of the
    /// brightest of the pixel's value, its brightest corner (luminances `corners`) and
    /// the floor ([`with_refine_floor`](Self::with_refine_floor)),
    /// and while the next grid — four times the rays of the last — keeps the pixel
    /// within [`REFINE_RAYS`] times the ray budget of one camera ray. The rules below
    /// are the desktop's (a device's store compiles them away); each was chosen on the
    /// tuning scenes and measured afterwards on the held-out ones (`docs/accuracy.md`
    /// has the figures, from "The sphere + wall's remaining error" on).
    ///
    /// - **Grazing pixels** (a sample of the first grid grazed glass, [`GRAZING`], and
    ///   gathered more than the pixel's value: a focus seen through a ball's rim) jump
    ///   to the `4n × 4n` grid where the budget allows, and then refine on to `8n × 8n`
    ///   within [`GRAZING_RAYS`] budgets. Their first grid, when the jump was too
    ///   costly, refines at least once whatever its halves say, and each later grid
    ///   must agree with the one before it (the error is at least half their
    ///   difference): a regular grid's checkerboard halves alias a sliver of focus
    ///   alike and can agree on a wrong value. The sphere + wall c's rim pixel
    ///   (177, 73) at 6.4M photons read 2.44 on its 4×4 grid, halves 2.45 and 2.43,
    ///   where its reference reads 2.16. Their grids after the first are
    ///   [`grazing_grid`](Self::grazing_grid)s: more photons a gather, within
    ///   footprints bounded by secants (chosen on the held-out sphere + wall f and
    ///   sphere + wall, whose floor and silhouette it answers: session 31 of
    ///   `docs/accuracy.md`).
    /// - **Slivers between the rows.** Where the corners saw different things along
    ///   their paths (an `edge`) but every sample of the first grid saw the same, the
    ///   other side lies between the grid's rows: the pixel goes on to the `2n × 2n`
    ///   grid, whose rows lie between the first's, and from there as its error
    ///   estimate asks. The sphere + wall c's pixel (172, 72) read 0.21 on a 4×4 grid,
    ///   0.35 on 16×16 and 32×32 grids, 0.36 in its reference.
    /// - **Edges between the rows** count in the error estimate (see [`Lines::aligned2`]):
    ///   the sphere + wall g's floor shadow, nearly along the image's rows, stopped at
    ///   4×4 grids whose halves agreed, a quarter of a pixel out.
    /// - **Corners** count in the error estimate (see [`Grid::error2`]): the two
    ///   balls' (221, 150) has a focus seen through a ball at a corner, 3.19 against at
    ///   most 0.2 for the 16 samples of its 4×4 grid, whose halves agreed.
    /// - **Photons widened far** are left out of the error estimate: there the halves
    ///   differ by the few photons each half's patches hold, which a finer grid would
    ///   only average again (`scenes/lens_wall.json`: 42% fewer eye rays, the same
    ///   noise). Elsewhere the halves' photon noise stays in the test, since a finer
    ///   grid's sparser sub-patches widen more and do average more photons.
    /// - **A caustic part settled on the first grid** is not gathered again. Each
    ///   first-grid sample's gather already sums the photons over its whole sub-pixel's
    ///   footprint (the box filter), so four finer footprints tiling it sum the same
    ///   photons; what a finer grid resolves is what the samples see. Where the first
    ///   grid's halves agree on the caustic part alone to within [`CAUSTIC_SHARE`] of
    ///   the tolerance and no corner lies outside its samples' range by more (the
    ///   two balls' (221, 150), a focus at a corner that the first grid's footprints
    ///   missed), a finer sample that sees the same paths as the first-grid sample of
    ///   its cell (the same signature) traces them without gathering and takes that
    ///   sample's caustic part; one that sees other paths, across an edge, gathers for
    ///   itself. The balls, mirror and tube scene: 4% fewer instructions, the gathers'
    ///   CPU 13% less, every error within 0.0003 (`docs/accuracy.md`, session 33).
    ///   Grazing pixels' grids gather for themselves.
    fn refine(
        &self,
        x: u32,
        y: u32,
        n: u32,
        (corners, edge): ([f32; 4], bool),
        count: &mut RayCount,
    ) -> PixelEstimate {
        let start = count.eye + count.shadow;
        let cap = REFINE_RAYS as u64 * self.ray_budget as u64;
        // Constant false on a device's store: the rules below are not compiled there.
        let desktop = self.store.reads_direct();
        let mut coarse = Coarse::new(n);
        let (first, mut last) = self.costed_grid(x, y, n, (false, Cells::Keep(&mut coarse)), count);
        let coarse = &coarse;
        let deep = desktop && first.grazing;
        // A grazing pixel's error estimate aliases (below): it keeps its own brightness.
        let floor = if deep { 0.0 } else { self.floor };
        let bright = corners.into_iter().fold(floor, f32::max);
        // The finer grids take the first one's caustic parts where its own halves agree.
        let share = crate::math::max(first.pixel.radiance.luminance(), bright)
            * REFINE_TOLERANCE
            * CAUSTIC_SHARE;
        let settled = desktop
            && first.caustic2 <= share * share
            && first.corners2(n, corners, 0.0) <= share * share;
        let take = || {
            if settled {
                Cells::Take(coarse)
            } else {
                Cells::Own
            }
        };
        let missed = desktop && edge && first.uniform;
        let (mut g, mut m, top) = if deep && 16 * last <= cap {
            let (finest, cost) = self.costed_grid(x, y, 4 * n, (deep, Cells::Own), count);
            last = cost;
            (finest, 4 * n, 8 * n)
        } else if deep {
            (first, n, 8 * n)
        } else if missed && 4 * last <= cap {
            let (finer, cost) = self.costed_grid(x, y, 2 * n, (false, take()), count);
            last = cost;
            (finer, 2 * n, 4 * n)
        } else {
            (first, n, 4 * n)
        };
        let cap = if deep {
            GRAZING_RAYS as u64 * self.ray_budget as u64
        } else {
            cap
        };
        // A grazing pixel's grid before the last one doubled, once there is one.
        let mut coarser: Option<f32> = None;
        while m < top && m <= 32 {
            let e = g.error2(m, desktop.then_some(corners), coarser);
            let value = g.pixel.radiance.luminance();
            let scale = crate::math::max(value, bright) * REFINE_TOLERANCE;
            let spent = count.eye + count.shadow - start;
            // A grazing pixel's first grid, when the jump was too costly, refines once
            // whatever its halves say: they alias the sliver together.
            let trusted = !(deep && m == n);
            if (trusted && !(e > scale * scale)) || spent + 4 * last > cap {
                break;
            }
            if deep {
                coarser = Some(value);
            }
            m *= 2;
            let cells = if deep { Cells::Own } else { take() };
            (g, last) = self.costed_grid(x, y, m, (deep, cells), count);
        }
        g.pixel
    }

    /// [`grid`](Self::grid), or [`grazing_grid`](Self::grazing_grid) for a grazing
    /// pixel, with the rays (eye and shadow) it cost.
    fn costed_grid(
        &self,
        x: u32,
        y: u32,
        n: u32,
        (grazing, cells): (bool, Cells<'_>),
        count: &mut RayCount,
    ) -> (Grid, u64) {
        let before = count.eye + count.shadow;
        let g = if grazing {
            self.grazing_grid(x, y, n, count)
        } else {
            self.grid(x, y, n, cells, count)
        };
        (g, count.eye + count.shadow - before)
    }

    /// The sample at image corner `(cx, cy)`, `0 ≤ cx ≤ W`, `0 ≤ cy ≤ H`. Out of line:
    /// inlined at the adaptive sampling's four corner sites it took the Cortex-M4F's
    /// Fig. 6 firmware, which samples pixel centres and never runs them, to 52 552 B of
    /// flash and 4 508 B of stack (from 48 268 and 3 436) and its render 31.4 M → 34.5 M
    /// instructions.
    #[inline(never)]
    fn corner(&self, cx: u32, cy: u32, count: &mut RayCount) -> Sample {
        self.sample(self.scene.camera().ray_at(cx, cy, 0.0, 0.0), count)
    }

    /// Renders row `y` (0 = top) pixel by pixel, handing each estimate to `put`. With
    /// `lines` of at least `width + 1` samples each, the adaptive sampling takes the
    /// row's top and bottom corners from them instead of tracing them.
    fn row_with(
        &self,
        y: u32,
        width: usize,
        lines: Option<(&[Sample], &[Sample])>,
        mut put: impl FnMut(usize, PixelEstimate),
    ) -> RayCount {
        let mut count = RayCount::default();
        let camera = self.scene.camera();
        match self.sampling {
            Sampling::Centre => {
                for x in 0..width {
                    let s = self.sample(camera.ray(x as u32, y), &mut count);
                    put(x, one(&s));
                }
            }
            Sampling::Grid(n) => {
                for x in 0..width {
                    put(x, self.grid(x as u32, y, n, Cells::Own, &mut count).pixel);
                }
            }
            Sampling::Adaptive(n) => {
                let lines = lines.filter(|(top, bottom)| top.len() > width && bottom.len() > width);
                // Corner `cx` of the row's top or bottom line: given, or traced here.
                let corner = |cx: usize, below: bool, count: &mut RayCount| match lines {
                    Some((top, bottom)) => [top, bottom][below as usize][cx],
                    None => self.corner(cx as u32, y + below as u32, count),
                };
                // Corners shared along the row: the left pair comes from the pixel before.
                let mut top_left = corner(0, false, &mut count);
                let mut bottom_left = corner(0, true, &mut count);
                for x in 0..width {
                    let top_right = corner(x + 1, false, &mut count);
                    let bottom_right = corner(x + 1, true, &mut count);
                    let c = [top_left, top_right, bottom_left, bottom_right];
                    put(x, self.adaptive(x as u32, y, n, &c, &mut count));
                    (top_left, bottom_left) = (top_right, bottom_right);
                }
            }
        }
        count
    }

    /// Pixel `(x, y)` from its four corner samples `c` (top left, top right, bottom
    /// left, bottom right): their mean where they agree (the same paths' signatures,
    /// luminances within [`CONTRAST`]: Mitchell 1987), else an `n × n` grid refined.
    fn adaptive(
        &self,
        x: u32,
        y: u32,
        n: u32,
        c: &[Sample; 4],
        count: &mut RayCount,
    ) -> PixelEstimate {
        let (paths_differ, contrast) = disagree(c);
        if !paths_differ && !contrast {
            let mean = |f: fn(&Sample) -> Rgb| (f(&c[0]) + f(&c[1]) + f(&c[2]) + f(&c[3])) * 0.25;
            PixelEstimate {
                radiance: mean(|s| s.radiance),
                caustic: mean(|s| s.caustic),
                split: mean(|s| s.split),
                ..PixelEstimate::default()
            }
        } else {
            count.refined += 1;
            let corners = c.each_ref().map(|s| s.radiance.luminance());
            self.refine(x, y, n, (corners, paths_differ && contrast), count)
        }
    }

    /// Renders row `y` (0 = top) into `row` (`row.len()` = image width): radiance
    /// (`Rgb`) or each pixel with its caustic part and error estimate
    /// ([`PixelEstimate`]), the same radiance bit for bit. Without the splats (see
    /// [`with_splats`](Self::with_splats)).
    pub fn row<T: RowPixel>(&self, y: u32, row: &mut [T]) -> RayCount {
        self.row_with(y, row.len(), None, |x, p| row[x] = T::from_estimate(p))
    }

    /// Traces line `cy` of pixel corners (`0 ≤ cy ≤ H`, the top corners of row `cy`)
    /// into `line[..=W]`: the samples that the adaptive sampling of row `cy − 1` and of
    /// row `cy` both read ([`row_between`](Self::row_between)). A `line` shorter than
    /// the width plus one is left alone.
    pub fn corner_line(&self, cy: u32, line: &mut [Sample]) -> RayCount {
        let mut count = RayCount::default();
        let width = self.scene.camera().width() as usize;
        if let Some(line) = line.get_mut(..=width) {
            for (cx, s) in line.iter_mut().enumerate() {
                *s = self.corner(cx as u32, cy, &mut count);
            }
        }
        count
    }

    /// [`row`](Self::row) whose adaptive sampling takes its corners from the corner
    /// lines `top` (line `y`) and `bottom` (line `y + 1`) that
    /// [`corner_line`](Self::corner_line) traced: the same pixels, bit for bit (a
    /// corner's sample depends on nothing but its position), with no corner traced
    /// twice. Lines shorter than the width plus one are not used (the row traces its
    /// own corners), and the other samplings do not read them.
    pub fn row_between<T: RowPixel>(
        &self,
        y: u32,
        lines: (&[Sample], &[Sample]),
        row: &mut [T],
    ) -> RayCount {
        self.row_with(y, row.len(), Some(lines), |x, p| {
            row[x] = T::from_estimate(p)
        })
    }

    /// The image's mean luminance, estimated as the mean of the samples at a lattice
    /// of pixel corners spread evenly over the image, at most [`LATTICE`] a side
    /// (both edges included): corner `⌊i·W/(m−1)⌋` across for `i < m = min(LATTICE,
    /// W + 1)`, and the same down. What the caustic store gathers is in it; splats are
    /// not (see [`with_splats`](Self::with_splats)). The same for any thread count.
    pub fn mean_luminance(&self, count: &mut RayCount) -> f32 {
        let cam = self.scene.camera();
        let lattice = |side: u32| {
            let m = LATTICE.min(side + 1).max(2);
            (0..m).map(move |i| (i as u64 * side as u64 / (m as u64 - 1)) as u32)
        };
        let (mut sum, mut n) = (0.0f64, 0u32);
        for cy in lattice(cam.height()) {
            for cx in lattice(cam.width()) {
                sum += self.corner(cx, cy, count).radiance.luminance() as f64;
                n += 1;
            }
        }
        (sum / n.max(1) as f64) as f32
    }

    /// The desktop's floor: under [`Sampling::Adaptive`],
    /// [`with_refine_floor`](Self::with_refine_floor) at [`REFINE_FLOOR`] times the
    /// image's [`mean_luminance`](Self::mean_luminance), whose samples are counted in
    /// `count`; none when the mean is not a number (a NaN sample: its pixels say so
    /// without a refused render). The other samplings refine nothing and trace nothing
    /// here.
    pub fn with_image_floor(self, count: &mut RayCount) -> Result<Self, Error> {
        if !self.reads_corners() {
            return Ok(self);
        }
        let mean = self.mean_luminance(count);
        if mean.is_nan() {
            return Ok(self);
        }
        self.with_refine_floor(REFINE_FLOOR * mean)
    }

    /// Whether rows read corner lines: under [`Sampling::Adaptive`] only.
    pub fn reads_corners(&self) -> bool {
        matches!(self.sampling, Sampling::Adaptive(_))
    }

    /// The pixels between corner lines `top` and `bottom` whose corners disagree (by
    /// path or by contrast), which the adaptive sampling supersamples: nearly all of a
    /// row's cost, known before it is rendered. 0 under the other samplings.
    pub fn supersampled(&self, top: &[Sample], bottom: &[Sample]) -> usize {
        if !self.reads_corners() {
            return 0;
        }
        let width = self.scene.camera().width() as usize;
        top.windows(2)
            .zip(bottom.windows(2))
            .take(width)
            .filter(|(t, b)| {
                let (paths, contrast) = disagree(&[t[0], t[1], b[0], b[1]]);
                paths || contrast
            })
            .count()
    }

    /// The row buffer cut to the image width; an error when it is shorter.
    fn fit<'b, T, E>(&self, row: &'b mut [T]) -> Result<&'b mut [T], RowsError<E>> {
        let width = self.scene.camera().width() as usize;
        let len = row.len();
        row.get_mut(..width)
            .ok_or(RowsError::Render(Error::Capacity {
                what: "row buffer (pixels of one image row)",
                requested: width,
                capacity: len,
            }))
    }

    /// Renders every row, top to bottom, into the caller's one-row buffer, adds the
    /// splats that fall in it, and hands each to `sink` before the next is computed: no
    /// frame buffer. The sink receives exactly `width` pixels (a longer buffer's tail is
    /// left alone).
    ///
    /// An error, before anything is rendered, when `row` is shorter than the image width
    /// ([`RowsError::Render`] with [`Error::Capacity`]); otherwise stops at the sink's
    /// first error and returns it ([`RowsError::Sink`]).
    pub fn rows<T: RowPixel, E>(
        &self,
        row: &mut [T],
        mut sink: impl FnMut(u32, &[T]) -> Result<(), E>,
    ) -> Result<RayCount, RowsError<E>> {
        let row = self.fit(row)?;
        let mut count = RayCount::default();
        for y in 0..self.scene.camera().height() {
            count += self.row(y, row);
            if let Some(splats) = self.splats {
                add_to_row(splats, y, row);
            }
            sink(y, row).map_err(RowsError::Sink)?;
        }
        Ok(count)
    }
}

/// A pixel of one sample.
fn one(s: &Sample) -> PixelEstimate {
    PixelEstimate {
        radiance: s.radiance,
        caustic: s.caustic,
        split: s.split,
        ..PixelEstimate::default()
    }
}

/// The range of luminances before any: [`widen`] by the first gives `(l, max(0, l))`.
const NO_RANGE: (f32, f32) = (f32::INFINITY, 0.0);

/// The range of luminances `(lo, hi)` with `l` in it too. A NaN `l` leaves `lo` as it
/// is and makes `hi` NaN (corners with one count as contrasted).
#[inline]
fn widen((lo, hi): (f32, f32), l: f32) -> (f32, f32) {
    (crate::math::min_num(lo, l), crate::math::max(hi, l))
}

/// Whether four corner samples disagree: their paths (signatures differ), and their
/// luminances (see [`contrasted`]). Either sends the pixel to a grid.
fn disagree(c: &[Sample; 4]) -> (bool, bool) {
    let paths_differ = c.iter().any(|s| s.signature != c[0].signature);
    (paths_differ, contrasted(c))
}

/// `true` when the luminances of four corner samples differ by more than [`CONTRAST`]
/// (Mitchell 1987's contrast) or one is NaN.
fn contrasted(c: &[Sample; 4]) -> bool {
    let (lo, hi) = c
        .iter()
        .fold(NO_RANGE, |r, s| widen(r, s.radiance.luminance()));
    // `!(a ≤ b)` so that NaN always counts as contrast.
    !(hi - lo <= CONTRAST * (hi + lo))
}

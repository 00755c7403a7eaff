//! Fitting the illumination maps to their texel budget and laying out their charts:
//! each object's texel side, the plane rectangles trimmed of outlying photons, and the
//! grids placed one after the other in the shared texel array.

use core::f32::consts::PI;

use heapless::Vec as FixedVec;

use super::chart::{bounded_grids, Grid, Profile};
use super::{IlluminationMaps, ObjectMap, TexelStorage, NO_GRID};
use crate::error::{within, Error};
use crate::geometry::Shape;
use crate::photon::Photon;

/// Bins per axis of the histogram that trims a plane's rectangle.
const TRIM_BINS: usize = 256;

impl<S: TexelStorage, const OBJECTS: usize> IlluminationMaps<S, OBJECTS> {
    /// Chooses each mapped object's texel side so that the whole layout fits the
    /// texel budget (see [`with_texel_budget`](Self::with_texel_budget)).
    ///
    /// At the requested size if it fits. Otherwise the budget is shared in proportion to
    /// the photons each object received (texels beyond its photons only add noise),
    /// objects visited by increasing texels-per-photon so that what a frugal object
    /// leaves of its share goes to the others; an object over its share gets the
    /// smallest texel (to 2⁻⁴⁰ relative, by bisection) whose layout fits it. Every
    /// chart keeps at least one texel: a budget below that is an error.
    pub(super) fn fit_to_budget(&mut self) -> Result<(), Error> {
        let budget = self.budget.unwrap_or_else(|| self.texels.default_budget());
        within(
            budget,
            self.texels.capacity(),
            "illumination map texel budget",
        )?;
        let s = self.texel_size;
        let (mut need, mut least, mut photons) = (0.0f64, 0.0f64, 0.0f64);
        let mut order: FixedVec<usize, OBJECTS> = FixedVec::new();
        for (k, m) in self.objects.iter().enumerate() {
            if m.photons == 0 {
                continue;
            }
            if !(m.hi[0] - m.lo[0]).is_finite() || !(m.hi[1] - m.lo[1]).is_finite() {
                return Err(Error::NotFinite {
                    what: "illumination map: extent of the photons on a plane",
                });
            }
            need += texels_at(m, s);
            least += texels_at(m, coarsest(m));
            photons += m.photons as f64;
            let _ = order.push(k); // cannot overflow: one entry per slot
        }
        self.stats.texel_budget = budget;
        self.stats.requested_texels = need;
        self.stats.largest_texel = s;
        if need <= budget as f64 {
            return Ok(());
        }
        if least > budget as f64 {
            return Err(Error::Capacity {
                what: "illumination map texels (one a chart at the coarsest)",
                requested: least as usize,
                capacity: budget,
            });
        }
        let objects = &mut self.objects;
        let ratio = |m: &ObjectMap| texels_at(m, s) / m.photons as f64;
        order.sort_unstable_by(|&a, &b| {
            let (ra, rb) = (ratio(&objects[a]), ratio(&objects[b]));
            ra.partial_cmp(&rb)
                .unwrap_or(core::cmp::Ordering::Equal)
                .then(a.cmp(&b))
        });
        let mut spare = budget as f64 - least;
        for &k in order.iter() {
            let m = &mut objects[k];
            let (want, min) = (texels_at(m, s), texels_at(m, coarsest(m)));
            let share = min + libm::floor(spare * m.photons as f64 / photons);
            let used = if want <= share {
                want
            } else {
                m.texel = coarsen(m, s, share);
                self.stats.coarsened_objects += 1;
                self.stats.largest_texel = self.stats.largest_texel.max(m.texel);
                texels_at(m, m.texel)
            };
            spare -= used - min;
            photons -= m.photons as f64;
        }
        Ok(())
    }

    /// Lays out the grids of every mapped object at its texel side, one after the
    /// other in the shared array; returns the texels needed.
    pub(super) fn lay_out(&mut self) -> usize {
        let mut total = 0usize;
        for m in self.objects.iter_mut() {
            if m.photons == 0 {
                continue;
            }
            let s = m.texel;
            let n = match m.shape {
                Shape::Plane(_) => {
                    m.grids[0] = Grid {
                        offset: 0,
                        w: plane_side(m, 0, s) as u32,
                        h: plane_side(m, 1, s) as u32,
                        u0: m.lo[0],
                        du: s,
                        v0: m.lo[1],
                        dv: s,
                        periodic_u: false,
                        profile: Profile::Flat(1.0),
                    };
                    1
                }
                _ => bounded_grids(&m.shape, s, &mut m.grids).unwrap_or(0),
            };
            for g in &mut m.grids[..n] {
                g.offset = total as u32;
                total += g.len();
            }
            m.charts = n as u8;
            self.stats.mapped_objects += 1;
        }
        total
    }

    /// The rectangle of plane `k` without the outlying `trim` of its photons beyond each
    /// side: each of the four bounds is a quantile, bracketed by two rounds of 256-bin
    /// histograms (the second inside the bin the first found; 65 536 steps across the
    /// photons' bounding rectangle) and rounded outwards to the final bin.
    pub(super) fn trimmed(
        &self,
        k: usize,
        replay: &mut impl FnMut(&mut dyn FnMut(&Photon, Option<usize>)) -> f32,
    ) -> ([f32; 2], [f32; 2]) {
        let m = self.objects[k];
        let cut = (self.trim as f64 * m.photons as f64) as u32;
        // Per axis and side (0: lower, 1: upper): the bracket and the photons beyond it.
        let mut bracket = [[(m.lo[0], m.hi[0]); 2], [(m.lo[1], m.hi[1]); 2]];
        let mut beyond = [[0u32; 2]; 2];
        for _round in 0..2 {
            let mut hist = [[[0u32; TRIM_BINS]; 2]; 2];
            replay(&mut |p: &Photon, o: Option<usize>| {
                if let Some((j, at)) = self.landing(p, o) {
                    if j == k && at.normal.dot(p.direction().get()) < 0.0 {
                        for a in 0..2 {
                            let x = [at.u, at.v][a];
                            for side in 0..2 {
                                let (b0, b1) = bracket[a][side];
                                if x >= b0 && x <= b1 && b1 > b0 {
                                    let f = (x - b0) / (b1 - b0) * TRIM_BINS as f32;
                                    hist[a][side][(f as usize).min(TRIM_BINS - 1)] += 1;
                                }
                            }
                        }
                    }
                }
            });
            for a in 0..2 {
                for side in 0..2 {
                    let (b0, b1) = bracket[a][side];
                    if !(b1 > b0) {
                        continue;
                    }
                    let h = &hist[a][side];
                    let bin = (b1 - b0) / TRIM_BINS as f32;
                    let mut seen = beyond[a][side];
                    let order = |i: usize| if side == 0 { i } else { TRIM_BINS - 1 - i };
                    let mut found = TRIM_BINS - 1;
                    for i in 0..TRIM_BINS {
                        if seen + h[order(i)] > cut {
                            found = i;
                            break;
                        }
                        seen += h[order(i)];
                    }
                    let b = order(found);
                    beyond[a][side] = seen;
                    let lo = b0 + b as f32 * bin;
                    let hi = if b == TRIM_BINS - 1 {
                        b1
                    } else {
                        b0 + (b + 1) as f32 * bin
                    };
                    bracket[a][side] = (lo, hi);
                }
            }
        }
        let lo = [bracket[0][0].0, bracket[1][0].0];
        let hi = [bracket[0][1].1.max(lo[0]), bracket[1][1].1.max(lo[1])];
        (lo, hi)
    }
}

/// Texels along axis `a` of a plane's rectangle at texel side `s` (at least one).
fn plane_side(m: &ObjectMap, a: usize, s: f32) -> f32 {
    libm::ceilf((m.hi[a] - m.lo[a]) / s).max(1.0)
}

/// Texels the charts of `m` take at texel side `s`, in f64 (a tiny texel over a far
/// rectangle exceeds every integer type).
fn texels_at(m: &ObjectMap, s: f32) -> f64 {
    match m.shape {
        Shape::Plane(_) => plane_side(m, 0, s) as f64 * plane_side(m, 1, s) as f64,
        _ => {
            let mut grids = [NO_GRID; 6];
            let n = bounded_grids(&m.shape, s, &mut grids).unwrap_or(0);
            grids[..n].iter().map(|g| g.len() as f64).sum()
        }
    }
}

/// A texel side at which every chart of `m` is a single texel: a plane rectangle's
/// longer side; for a bounded shape π times its bounding diameter (1% over, for
/// rounding), longer than any chart's extent (a sphere's equator, a box face's side,
/// a cylinder's circumference or height).
fn coarsest(m: &ObjectMap) -> f32 {
    match m.shape {
        Shape::Plane(_) => (m.hi[0] - m.lo[0])
            .max(m.hi[1] - m.lo[1])
            .max(f32::MIN_POSITIVE),
        _ => m
            .shape
            .bounding_sphere()
            .map_or(1.0, |b| 2.0 * PI * b.radius * 1.01),
    }
}

/// The smallest texel side `≥ s` (to 2⁻⁴⁰ relative: a bisection on the logarithm)
/// at which `m` takes at most `share` texels; `share` must hold its coarsest layout.
fn coarsen(m: &ObjectMap, s: f32, share: f64) -> f32 {
    let (mut lo, mut hi) = (s, coarsest(m).max(s));
    for _ in 0..40 {
        let mid = libm::sqrtf(lo) * libm::sqrtf(hi);
        if !(mid > lo && mid < hi) {
            break;
        }
        if texels_at(m, mid) <= share {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

//! Illumination maps (Arvo 1986; the paper's section 3.1): the second caustic store.
//!
//! Instead of keeping photons and gathering the nearest ones at every eye hit, each
//! diffuse object gets 2D arrays of texels over a `(u, v)` parameterisation of its
//! surface (see [`chart`](self#charts)). Every photon is *splatted* into the four
//! texels around its `(u, v)`, bilinearly and exactly as the paper describes: its energy
//! is first shared between the two parallel texel rows around it (the two points on each
//! parallel line), then each row's part between the two texels on that row. When all
//! photons are in, each texel's energy is divided by the **true surface area** it
//! represents — the integral over the surface of its splat weight, computed
//! analytically (non-uniform on a sphere, a cylinder's cap) — giving irradiance in
//! W/m². A lookup reconstructs the irradiance bilinearly from the same four texels.
//!
//! Because splat and lookup use the same weights and areas, a single photon's energy
//! is conserved by the round trip (`∫ E dA = Φ`), and a uniform flux gives an
//! unbiased flat map on every shape.
//!
//! Memory is fixed: all charts share one texel array (`Rgb`, 12 bytes a texel) of
//! compiled capacity ([`FixedIlluminationMaps`]) or, on the desktop, of the size the
//! layout needs (`Vec<Rgb>`). No photon array is needed: [`IlluminationMaps::build`]
//! re-runs the (deterministic) forward pass instead of storing photons.
//!
//! # Any scene fits its texel budget
//! Texels cover only where photons land: a plane gets the (trimmed) rectangle of its
//! photons, an object without photons gets none. When even that takes more texels than
//! the budget ([`IlluminationMaps::with_texel_budget`]; by default the whole fixed array,
//! or [`DEFAULT_HEAP_TEXELS`] on the desktop), the budget is shared among the objects in
//! proportion to the photons they received, and an object over its share gets a coarser
//! texel — the smallest that fits (a back wall hit by a few scattered photons coarsens;
//! the floor under the caustic keeps the requested size). [`MapStats`] says what was
//! requested and chosen; [`IlluminationMaps::object_texel_size`] gives each object's.
//!
//! # Charts
//! - **plane**: a rectangle of the plane in the basis `(e1, e2)` = [`UnitVec3::basis`]
//!   of its normal, the bounding rectangle of the photons that landed on its front,
//!   trimmed of outliers by [`IlluminationMaps::with_trim`] (photons outside it are
//!   dropped and counted in [`MapStats::dropped`]); texels exactly the object's texel
//!   side square (the paper's "scale").
//! - **sphere**: paper eq. 7, `P(u, v) = c + r·(cos v cos u, sin v, cos v sin u)` (the
//!   paper's `z` axis is the scene's up, `y`), longitude `u ∈ [0, 2π)` (periodic),
//!   latitude `v ∈ [−π/2, π/2]`; `⌈2πr/s⌉ × ⌈πr/s⌉` texels (`s` the object's texel
//!   side), texel area
//!   `r²·Δu·∫ w(v) cos v dv`.
//! - **box**: each face its own grid, in the box's frame.
//! - **cylinder**: the side (angle × height, area `r·Δθ·Δz`), and each cap in polar
//!   coordinates (angle × radius, area `Δθ·∫ w(ρ)·ρ dρ`).
//!
//! Only objects that store photons (a diffuse part) and received at least one photon
//! get texels. A photon comes with the object it landed on when its source knows it
//! ([`IlluminationMaps::build_with`]); a point without (a lookup from the eye pass, a
//! photon made by hand) is matched to the object whose surface is nearest (within
//! `1e-4·max(1, |x|∞)`), the chart of a box face or cylinder cap by the normal.
//!
//! # The classic model
//! The paper's eq. 8 needs each photon's direction `l`. A texel keeps no direction, so
//! [`CausticStore::classic`] takes `l = n` (light arriving along the normal):
//! `c ≈ π·E·kernel(n, n, to_eye)`, the kd-tree's `Σ kernel·Φ/r²` with every photon
//! at normal incidence. This overestimates the diffuse term by `1/cos θ` for light
//! arriving at angle `θ` and puts the highlight where the mirror direction of `n` is.
//!
//! # Front side
//! As in the kd-tree store, only photons arriving on the front (`dir·n < 0`, `n` the
//! outward normal of the chart) are splatted, and a lookup with a normal facing away
//! from the chart's returns zero.

mod chart;
mod layout;

use core::f32::consts::PI;

use heapless::Vec as FixedVec;

use self::chart::{pair, Grid, Profile};
use super::{forward, CausticStore, ForwardStats, Photon, PhotonSettings};
use crate::error::{positive, within, Error};
use crate::geometry::{Shape, SurfacePoint};
use crate::material::Classic;
use crate::math::{max_abs, Rgb, UnitVec3, Vec3};
use crate::scene::Scene;

/// Where the texels live: a fixed array on the device, a `Vec` on the desktop.
pub trait TexelStorage {
    /// All texels.
    fn texels(&self) -> &[Rgb];
    /// All texels, mutable.
    fn texels_mut(&mut self) -> &mut [Rgb];
    /// Makes room for `needed` texels: an error when a fixed storage is too small.
    fn reserve(&mut self, needed: usize) -> Result<(), Error>;
    /// Most texels [`reserve`](Self::reserve) accepts.
    fn capacity(&self) -> usize;
    /// The texel budget a layout fits into unless
    /// [`IlluminationMaps::with_texel_budget`] says otherwise: the whole capacity.
    fn default_budget(&self) -> usize {
        self.capacity()
    }
}

impl<const N: usize> TexelStorage for [Rgb; N] {
    fn texels(&self) -> &[Rgb] {
        self
    }
    fn texels_mut(&mut self) -> &mut [Rgb] {
        self
    }
    fn reserve(&mut self, needed: usize) -> Result<(), Error> {
        within(needed, N, "illumination map texels")?;
        Ok(())
    }
    fn capacity(&self) -> usize {
        N
    }
}

/// Most texels a heap-backed (desktop) map may hold: 2²⁶ texels, 768 MiB.
#[cfg(feature = "std")]
pub const MAX_HEAP_TEXELS: usize = 1 << 26;

/// The default texel budget of a heap-backed (desktop) map: 2²² texels, 48 MiB — at
/// texel 0.02 about 1 700 scene units² at full resolution; larger layouts are coarsened
/// to fit (see [`IlluminationMaps`]).
#[cfg(feature = "std")]
pub const DEFAULT_HEAP_TEXELS: usize = 1 << 22;

#[cfg(feature = "std")]
impl TexelStorage for std::vec::Vec<Rgb> {
    fn texels(&self) -> &[Rgb] {
        self
    }
    fn texels_mut(&mut self) -> &mut [Rgb] {
        self
    }
    /// Grows to `needed` texels, up to `MAX_HEAP_TEXELS`: a layout beyond it (a tiny
    /// texel over photons scattered far) is an error, not an allocation that aborts.
    fn reserve(&mut self, needed: usize) -> Result<(), Error> {
        let what = "illumination map texels (increase the texel size)";
        within(needed, MAX_HEAP_TEXELS, what)?;
        self.clear();
        self.resize(needed, Rgb::ZERO);
        self.shrink_to_fit();
        Ok(())
    }
    fn capacity(&self) -> usize {
        MAX_HEAP_TEXELS
    }
    fn default_budget(&self) -> usize {
        DEFAULT_HEAP_TEXELS
    }
}

const NO_GRID: Grid = Grid {
    offset: 0,
    w: 0,
    h: 0,
    u0: 0.0,
    du: 1.0,
    v0: 0.0,
    dv: 1.0,
    periodic_u: false,
    profile: Profile::Flat(1.0),
};

/// One diffuse object's charts.
#[derive(Clone, Copy, Debug)]
struct ObjectMap {
    shape: Shape,
    /// Index of the object in the scene.
    object: usize,
    grids: [Grid; 6],
    /// Grids laid out (0 until the layout, and for an object without photons).
    charts: u8,
    /// Front-side photons that landed on it (layout pass).
    photons: u32,
    /// A plane's photon rectangle in `(u, v)`: min and max.
    lo: [f32; 2],
    hi: [f32; 2],
    /// Its texel side: the requested one, or coarser to fit the budget.
    texel: f32,
}

/// What building the maps did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MapStats {
    /// Photons splatted.
    pub splatted_photons: u64,
    /// Their energy, W.
    pub splatted: Rgb,
    /// Photons dropped: behind a surface, on no mapped object, outside a plane's rectangle.
    pub dropped_photons: u64,
    /// Their energy, W.
    pub dropped: Rgb,
    /// Texels laid out.
    pub texels: usize,
    /// Diffuse objects with texels.
    pub mapped_objects: usize,
    /// The texel budget the layout had to fit
    /// ([`IlluminationMaps::with_texel_budget`]).
    pub texel_budget: usize,
    /// Texels the layout would have taken at the requested texel size (may exceed
    /// the budget; f64 as it may exceed every integer type).
    pub requested_texels: f64,
    /// Mapped objects whose texel was coarsened to fit the budget.
    pub coarsened_objects: usize,
    /// The largest texel side chosen (the requested size when nothing was
    /// coarsened); per object see [`IlluminationMaps::object_texel_size`].
    pub largest_texel: f32,
}

/// Illumination maps of the diffuse objects of a scene, in one texel storage `S`
/// shared by every object's charts, for at most `OBJECTS` diffuse objects.
///
/// Build with [`build`](Self::build) (no photon array: the forward pass is re-run) or
/// [`build_from_photons`](Self::build_from_photons); then use it as a [`CausticStore`].
#[derive(Clone, Debug)]
pub struct IlluminationMaps<S, const OBJECTS: usize> {
    texels: S,
    objects: FixedVec<ObjectMap, OBJECTS>,
    texel_size: f32,
    trim: f32,
    budget: Option<usize>,
    used: usize,
    stats: MapStats,
}

/// Illumination maps in a fixed array of `TEXELS` texels (12 bytes each), for at most
/// `OBJECTS` diffuse objects: `size_of` is the whole memory (no photon array needed).
pub type FixedIlluminationMaps<const TEXELS: usize, const OBJECTS: usize> =
    IlluminationMaps<[Rgb; TEXELS], OBJECTS>;

impl<const TEXELS: usize, const OBJECTS: usize> FixedIlluminationMaps<TEXELS, OBJECTS> {
    /// Empty maps of texel side `texel_size` (scene units, > 0).
    pub fn fixed(texel_size: f32) -> Result<Self, Error> {
        Self::new([Rgb::ZERO; TEXELS], texel_size)
    }
}

impl<S: TexelStorage, const OBJECTS: usize> IlluminationMaps<S, OBJECTS> {
    /// Empty maps over `texels`, of texel side `texel_size` (scene units, > 0), with the
    /// default outlier trim of plane rectangles (see [`with_trim`](Self::with_trim)).
    pub fn new(texels: S, texel_size: f32) -> Result<Self, Error> {
        Ok(Self {
            texels,
            objects: FixedVec::new(),
            texel_size: positive(texel_size, "illumination map texel_size")?,
            trim: DEFAULT_TRIM,
            budget: None,
            used: 0,
            stats: MapStats::default(),
        })
    }

    /// A plane's rectangle leaves out up to the fraction `trim ∈ [0, 0.25]` of its
    /// photons beyond each of its four sides (outliers: photons scattered far away),
    /// located by histograms and rounded outwards (see `trimmed`). `0` keeps every
    /// photon; the default is [`DEFAULT_TRIM`].
    pub fn with_trim(mut self, trim: f32) -> Result<Self, Error> {
        self.trim = crate::error::in_range(trim, 0.0, 0.25, "illumination map trim")?;
        Ok(self)
    }

    /// At most `texels` texels in all (≥ 1, at most the storage's
    /// [`capacity`](TexelStorage::capacity), checked at the build). Without it the
    /// storage's [`default_budget`](TexelStorage::default_budget): the whole array of
    /// a fixed storage, [`DEFAULT_HEAP_TEXELS`] of a `Vec`. A layout beyond the budget
    /// is coarsened to fit it, object by object (see `fit_to_budget`).
    pub fn with_texel_budget(mut self, texels: usize) -> Result<Self, Error> {
        if texels == 0 {
            return Err(Error::NotPositive {
                what: "illumination map texel budget",
                value: 0.0,
            });
        }
        self.budget = Some(texels);
        Ok(self)
    }

    /// The requested texel side, scene units.
    pub fn texel_size(&self) -> f32 {
        self.texel_size
    }

    /// The texel side chosen for scene object `object` by the last build (the
    /// requested one unless the budget coarsened it); `None` when it is not mapped.
    pub fn object_texel_size(&self, object: usize) -> Option<f32> {
        self.slot(object).map(|m| m.texel)
    }

    /// What the last build did.
    pub fn stats(&self) -> MapStats {
        self.stats
    }

    /// Texels laid out by the last build.
    pub fn texels_used(&self) -> usize {
        self.used
    }

    /// The forward pass of `settings` with `seed` (pass 0), run two or three times
    /// (layout, plane trim if any, splat) and splatted without storing a photon: the
    /// memory is the maps' alone. Splats exactly the photons
    /// [`shoot_with_splats`](super::shoot_with_splats) would store, in the same order.
    pub fn build<const O: usize, const L: usize>(
        &mut self,
        scene: &Scene<O, L>,
        settings: &PhotonSettings,
        seed: u64,
    ) -> Result<(ForwardStats, MapStats), Error> {
        let mut stats = ForwardStats::default();
        let settings = settings.with_camera_splats(false);
        let maps = self.build_with(scene, |f| {
            stats = forward(scene, &settings, seed, 0, |x| {
                if let Some(p) = &x.photon {
                    f(p, Some(x.object));
                }
                Ok(())
            })
            .unwrap_or_default();
            stats.power_unit
        })?;
        Ok((stats, maps))
    }

    /// Builds the maps from stored photons whose powers are in units of `unit` W.
    pub fn build_from_photons<const O: usize, const L: usize>(
        &mut self,
        scene: &Scene<O, L>,
        photons: &[Photon],
        unit: f32,
    ) -> Result<MapStats, Error> {
        self.build_with(scene, |f| {
            photons.iter().for_each(|p| f(p, None));
            unit
        })
    }

    /// Builds the maps from a photon source that `replay` runs in full, in the same
    /// order every time, and that returns the power unit (W) of the photons. Each
    /// photon comes with the index of the object it landed on, when the source knows it
    /// (else the mapped surface nearest its position takes it).
    pub fn build_with<const O: usize, const L: usize>(
        &mut self,
        scene: &Scene<O, L>,
        mut replay: impl FnMut(&mut dyn FnMut(&Photon, Option<usize>)) -> f32,
    ) -> Result<MapStats, Error> {
        self.reset(scene)?;
        // Pass 1: which objects receive photons, and the planes' photon rectangles.
        replay(&mut |p: &Photon, o: Option<usize>| self.survey(p, o));
        // Pass 2 per plane: trim the outliers off its rectangle.
        if self.trim > 0.0 {
            for k in 0..self.objects.len() {
                let m = self.objects[k];
                if matches!(m.shape, Shape::Plane(_)) && m.photons > 0 {
                    let (lo, hi) = self.trimmed(k, &mut replay);
                    self.objects[k].lo = lo;
                    self.objects[k].hi = hi;
                }
            }
        }
        self.fit_to_budget()?;
        let total = self.lay_out();
        self.texels.reserve(total)?;
        self.used = total;
        self.stats.texels = total;
        self.texels.texels_mut()[..total].fill(Rgb::ZERO);

        // Pass 3: splat, in units of the photon power unit.
        let mut splatted = Rgb::ZERO;
        let mut dropped = Rgb::ZERO;
        let (mut n_in, mut n_out) = (0u64, 0u64);
        let unit = replay(&mut |p: &Photon, o: Option<usize>| {
            if self.splat(p, o) {
                splatted += p.power();
                n_in += 1;
            } else {
                dropped += p.power();
                n_out += 1;
            }
        });
        self.stats.splatted = splatted * unit;
        self.stats.dropped = dropped * unit;
        self.stats.splatted_photons = n_in;
        self.stats.dropped_photons = n_out;
        self.finish(unit);
        Ok(self.stats)
    }

    /// Forgets the last build and takes a slot for each object that stores photons.
    fn reset<const O: usize, const L: usize>(&mut self, scene: &Scene<O, L>) -> Result<(), Error> {
        self.objects.clear();
        self.used = 0;
        self.stats = MapStats::default();
        for (i, o) in scene.objects().iter().enumerate() {
            if !o.material.stores_photons() {
                continue;
            }
            let map = ObjectMap {
                shape: o.shape,
                object: i,
                grids: [NO_GRID; 6],
                charts: 0,
                photons: 0,
                lo: [f32::INFINITY; 2],
                hi: [f32::NEG_INFINITY; 2],
                texel: self.texel_size,
            };
            self.objects.push(map).map_err(|_| Error::Capacity {
                what: "illumination map objects",
                requested: OBJECTS + 1,
                capacity: OBJECTS,
            })?;
        }
        Ok(())
    }

    /// Layout pass: counts a front-side photon on its object and widens a plane's
    /// rectangle to it (a photon whose `(u, v)` overflows is left to be dropped).
    fn survey(&mut self, p: &Photon, object: Option<usize>) {
        let Some((k, at)) = self.landing(p, object) else {
            return;
        };
        if !(at.normal.dot(p.direction().get()) < 0.0) {
            return;
        }
        let m = &mut self.objects[k];
        if !(at.u.is_finite() && at.v.is_finite()) {
            return;
        }
        m.photons += 1;
        for (a, x) in [at.u, at.v].into_iter().enumerate() {
            m.lo[a] = m.lo[a].min(x);
            m.hi[a] = m.hi[a].max(x);
        }
    }

    /// The mapped object (slot) nearest to `x` within tolerance, and where `x` lies on it.
    #[inline]
    fn find(&self, x: Vec3, n: Option<UnitVec3>) -> Option<(usize, SurfacePoint)> {
        let tol = 1e-4 * max_abs(x).max(1.0);
        let mut best: Option<(usize, f32)> = None;
        for (k, m) in self.objects.iter().enumerate() {
            let d = m.shape.surface_distance(x);
            if d <= tol && best.is_none_or(|(_, bd)| d < bd) {
                best = Some((k, d));
            }
        }
        let (k, _) = best?;
        Some((k, self.objects[k].shape.locate(x, n)))
    }

    /// The slot of the object photon `p` landed on, and where on it: `object`, the
    /// object the forward pass saw it land on, else (a photon from an array) the mapped
    /// object nearest to its position.
    #[inline]
    fn landing(&self, p: &Photon, object: Option<usize>) -> Option<(usize, SurfacePoint)> {
        let Some(object) = object else {
            return self.find(p.position(), None);
        };
        let k = self.objects.iter().position(|m| m.object == object)?;
        Some((k, self.objects[k].shape.locate(p.position(), None)))
    }

    /// Splats photon `p`'s power (any unit) into the four texels around it: first
    /// between the two texel rows around it, then along each row. `false` (nothing
    /// splatted) when it arrived from behind, or lies on no chart.
    fn splat(&mut self, p: &Photon, object: Option<usize>) -> bool {
        let Some((k, at)) = self.landing(p, object) else {
            return false;
        };
        let power = p.power();
        if !(at.normal.dot(p.direction().get()) < 0.0) {
            return false; // arrived from behind the surface
        }
        let m = &self.objects[k];
        if at.chart >= m.charts as usize {
            return false;
        }
        let g = m.grids[at.chart];
        let (s, t) = g.st(at.u, at.v);
        if matches!(m.shape, Shape::Plane(_))
            && !(s >= 0.0 && t >= 0.0 && s <= g.w as f32 && t <= g.h as f32)
        {
            return false; // outside the plane's (trimmed) rectangle
        }
        let (i0, i1, fx) = pair(s, g.w, g.periodic_u);
        let (j0, j1, fy) = pair(t, g.h, false);
        let texels = self.texels.texels_mut();
        let base = g.offset as usize;
        let w = g.w as usize;
        // The two points on the parallel lines (rows j0 and j1) ...
        for (j, e) in [(j0, power * (1.0 - fy)), (j1, power * fy)] {
            // ... then between the two texels of each line.
            texels[base + j * w + i0] += e * (1.0 - fx);
            texels[base + j * w + i1] += e * fx;
        }
        true
    }

    /// Turns splatted energy (in units of `unit` W) into irradiance: each texel divided
    /// by the true area it represents.
    fn finish(&mut self, unit: f32) {
        let texels = self.texels.texels_mut();
        for m in &self.objects {
            for g in &m.grids[..m.charts as usize] {
                for j in 0..g.h as usize {
                    let area = g.texel_area(j);
                    let scale = if area > 0.0 {
                        (unit as f64 / area) as f32
                    } else {
                        0.0
                    };
                    let row = g.offset as usize + j * g.w as usize;
                    for t in &mut texels[row..row + g.w as usize] {
                        *t = *t * scale;
                    }
                }
            }
        }
    }

    /// The reconstructed irradiance at `x` (W/m²), zero off the maps or behind.
    #[inline]
    fn lookup(&self, x: Vec3, n: UnitVec3) -> Rgb {
        let Some((k, at)) = self.find(x, Some(n)) else {
            return Rgb::ZERO;
        };
        if !(n.dot(at.normal) > 0.0) {
            return Rgb::ZERO;
        }
        let m = &self.objects[k];
        if at.chart >= m.charts as usize {
            return Rgb::ZERO;
        }
        let g = &m.grids[at.chart];
        let (s, t) = g.st(at.u, at.v);
        if matches!(m.shape, Shape::Plane(_))
            && !(s >= 0.0 && t >= 0.0 && s <= g.w as f32 && t <= g.h as f32)
        {
            return Rgb::ZERO;
        }
        let (i0, i1, fx) = pair(s, g.w, g.periodic_u);
        let (j0, j1, fy) = pair(t, g.h, false);
        let texels = self.texels.texels();
        let base = g.offset as usize;
        let w = g.w as usize;
        let row =
            |j: usize| texels[base + j * w + i0] * (1.0 - fx) + texels[base + j * w + i1] * fx;
        row(j0) * (1.0 - fy) + row(j1) * fy
    }

    /// The slot of scene object `object`, if it is mapped.
    fn slot(&self, object: usize) -> Option<&ObjectMap> {
        self.objects
            .iter()
            .find(|m| m.object == object && m.charts > 0)
    }

    /// `(width, height)` in texels of chart `chart` of scene object `object`.
    pub fn chart_size(&self, object: usize, chart: usize) -> Option<(u32, u32)> {
        let m = self.slot(object)?;
        (chart < m.charts as usize).then(|| (m.grids[chart].w, m.grids[chart].h))
    }

    /// Number of charts laid out for scene object `object` (0 when unmapped).
    pub fn charts(&self, object: usize) -> usize {
        self.slot(object).map_or(0, |m| m.charts as usize)
    }

    /// Sum of the true texel areas of chart `chart` of scene object `object`.
    pub fn chart_area(&self, object: usize, chart: usize) -> Option<f64> {
        let m = self.slot(object)?;
        let g = m.grids.get(chart).filter(|_| chart < m.charts as usize)?;
        Some(
            (0..g.h as usize)
                .map(|j| g.texel_area(j) * g.w as f64)
                .sum(),
        )
    }

    /// Total energy in the maps (W): `Σ E·area` over every texel. Equals
    /// [`MapStats::splatted`] up to rounding.
    pub fn total_energy(&self) -> [f64; 3] {
        let texels = self.texels.texels();
        let mut sum = [0.0f64; 3];
        for m in &self.objects {
            for g in &m.grids[..m.charts as usize] {
                for j in 0..g.h as usize {
                    let area = g.texel_area(j);
                    let row = g.offset as usize + j * g.w as usize;
                    for t in &texels[row..row + g.w as usize] {
                        for (s, c) in sum.iter_mut().zip(t.to_array()) {
                            *s += c as f64 * area;
                        }
                    }
                }
            }
        }
        sum
    }

    /// The irradiance texels of chart `chart` of scene object `object`, row-major
    /// (`width × height`, row `j` at `v = v0 + (j + ½)·dv`).
    pub fn chart_texels(&self, object: usize, chart: usize) -> Option<&[Rgb]> {
        let m = self.slot(object)?;
        let g = m.grids.get(chart).filter(|_| chart < m.charts as usize)?;
        let o = g.offset as usize;
        Some(&self.texels.texels()[o..o + g.len()])
    }
}

/// The default plane trim: at most 0.5% of a plane's photons beyond each side of its
/// rectangle (the faint, far halo of photons scattered off glass).
pub const DEFAULT_TRIM: f32 = 0.005;

impl<S: TexelStorage, const OBJECTS: usize> CausticStore for IlluminationMaps<S, OBJECTS> {
    /// The bilinear reconstruction of the irradiance map at `x`.
    #[inline]
    fn irradiance(&self, x: Vec3, n: UnitVec3) -> Rgb {
        self.lookup(x, n)
    }

    /// Paper eq. 8 with every photon taken to arrive along the normal (`l = n`; the
    /// maps keep no direction): `π·E·kernel(n, n, to_eye)`.
    #[inline]
    fn classic(&self, x: Vec3, n: UnitVec3, to_eye: UnitVec3, m: &Classic) -> Rgb {
        let e = self.lookup(x, n);
        if e.is_black() {
            return Rgb::ZERO;
        }
        m.kernel(n, n, to_eye) * e * PI
    }
}

//! The backward pass: Whitted ray tracing from the eye, with the caustic store's
//! estimate added at every diffuse hit; pixels leave row by row.
//!
//! At a hit, by material:
//! - **diffuse** (front side only): direct light `ρ/π · I·cosθ/d²` from each unoccluded
//!   point light (every object blocks a shadow ray), plus `ρ/π · E_caustic`;
//! - **mirror** (both sides): the reflected ray, weighted by the reflectance;
//! - **dielectric**: reflection weighted by Fresnel `F` and refraction by
//!   `(1 − F)·(η_i/η_t)²` (radiance is scaled by the squared ratio of indices across an
//!   interface, pbrt-v4 §9.5.2); Beer attenuation `exp(−σ t)` inside;
//! - **classic** (paper): `k_a·color·ambient + Σ_lights vis·(I/d²)·kernel + eq. 8 +
//!   reflectivity·L_reflected + transparency·L_refracted`, where `kernel` is eq. 8's
//!   summand with the light as its single photon.
//!
//! Caustic light at a diffuse hit comes from one of two estimators. Where the eye sees
//! the surface directly, the forward pass has already added it to the pixel by light
//! tracing ([`photon::Splat`](crate::photon::Splat), given to
//! [`Renderer::with_splats`]): unbiased and exactly a pixel-area average. Where the eye
//! sees it through glass or in a mirror, the caustic store averages over the patch of
//! surface the sample stands for: the parallelogram its ray differentials span there
//! (Igehy 1999, carried through every reflection and refraction: magnified by a ball,
//! stretched by a tube), bounded by the store's own radius — the pixel's box filter
//! under the differentials' linearisation ([`Footprint`]). The path records its
//! specular vertices and the differentials are worked out from them only at such a
//! gather, and only where a photon may lie within reach ([`CausticStore::reaches`]):
//! most branches never need them. Without splats the store gathers at every diffuse
//! hit, as in the paper.
//!
//! A pixel's value is the average radiance over its area (box filter). The default
//! [`Sampling::Adaptive`] traces the pixel's four corners (Whitted 1980's adaptive
//! supersampling) and averages them where they agree — the same objects along the
//! path, the same lights visible, luminance within a small contrast — and otherwise
//! averages an `n × n` grid of sub-pixel rays: shadow edges, silhouettes and what is
//! seen through glass get many rays, smooth regions one per pixel.
//!
//! A path takes at most `max_depth` specular interactions; one that meets a further
//! specular surface contributes nothing. The tree of reflected and refracted branches
//! is walked depth-first with an explicit stack of `DEPTH` entries: each pending entry
//! has a different depth, so `DEPTH ≥ max_depth` always suffices and nothing recurses.
//!
//! # Bounded work per pixel
//! Every classic or dielectric hit spawns two branches, so an unbounded tree of depth
//! `d` costs up to `2^d` rays. Two deterministic bounds keep the work finite:
//! - **throughput cut-off** ([`Renderer::with_cutoff`], default [`DEFAULT_CUTOFF`]): a
//!   branch whose weight (throughput from the eye, each channel a product of
//!   reflectances and transmittances ≤ 1 for physical materials) has its largest
//!   channel below the cut-off is not traced. It could have added at most
//!   `cutoff · L_max`, `L_max` the brightest radiance it could meet. pbrt-v4 and
//!   Mitsuba play Russian roulette on low throughput instead: unbiased, but it adds
//!   noise, which an image that must match a reference to 1e-3 cannot afford; the
//!   fixed threshold biases by a bounded, measured amount (see [`DEFAULT_CUTOFF`]).
//! - **ray budget** ([`Renderer::with_ray_budget`], default [`DEFAULT_RAY_BUDGET`]):
//!   at most that many rays (eye and shadow) per camera ray, and a pixel at most
//!   [`Sampling::max_rays_per_pixel`] of them. An eye ray is traced only when
//!   the rays already spent plus it and the shadow rays it may need (one per lit light)
//!   stay within the budget; once one does not fit, every pending branch is dropped.
//!   At each fork the heavier branch (larger channel sum) is followed first and the
//!   lighter one waits on the stack, so the branches the budget drops are the ones
//!   that waited: lighter than a sibling already traced.
//!
//! Both depend only on the ray's own tree, never on the order pixels are rendered in,
//! so images stay the same on any number of threads and on the device.

use heapless::Vec as FixedVec;

use crate::error::Error;
use crate::geometry::{Hit, Ray, Shape};
use crate::material::{interface, Classic, Material};
use crate::math::{reflect, Rgb, UnitVec3, Vec3};
use crate::photon::{CausticStore, Footprint, Halves, Splat};
use crate::scene::Scene;
use differential::{Bend, Bounds, Trail};

mod cells;
mod differential;
mod estimate;
mod grid;
mod pixels;
mod probe;

pub use estimate::{ErrorTally, PixelEstimate};
pub use pixels::{
    RowPixel, Sampling, CAUSTIC_SHARE, CONTRAST, GRAZING, GRAZING_RAYS, LATTICE, REFINE,
    REFINE_FLOOR, REFINE_RAYS, REFINE_TOLERANCE, SIGNATURE_WEIGHT,
};

/// The default cut-off of branch throughput: see [`Renderer::with_cutoff`].
///
/// Measured on `scenes/glass_sphere.json` (64×48, against cut-off 0): 1e-3 leaves out
/// 2.7e-3 of the image (relative RMSE: the bright caustic seen in faint internal
/// reflections), 1e-4 leaves out 3e-5 and still skips a quarter of the eye rays.
pub const DEFAULT_CUTOFF: f32 = 1e-4;

/// The default budget of rays (eye and shadow) per camera ray, the same on every target
/// (the device states it at compile time here): see [`Renderer::with_ray_budget`].
/// It binds on trees built to branch (classic surfaces both reflective and
/// transparent, deep `max_depth`); the glass sphere at 64×48 spends 1.7 eye rays a
/// pixel on average, and a path through it that totally reflects inside needs a few
/// dozen (at 16 such paths lost a focus seen through the glass).
pub const DEFAULT_RAY_BUDGET: u32 = 256;

/// Why [`Renderer::rows`] stopped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RowsError<E> {
    /// The renderer refused the call: the row buffer is shorter than the image width
    /// ([`Error::Capacity`]).
    Render(Error),
    /// The sink's own error, at the first row it refused.
    Sink(E),
}

impl<E: core::fmt::Display> core::fmt::Display for RowsError<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            RowsError::Render(e) => write!(f, "{e}"),
            RowsError::Sink(e) => write!(f, "row sink: {e}"),
        }
    }
}

#[cfg(feature = "std")]
impl<E: core::fmt::Debug + core::fmt::Display> std::error::Error for RowsError<E> {}

/// Rays traced, for statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCount {
    /// Camera rays and their reflected/refracted descendants.
    pub eye: u64,
    /// Shadow rays towards lights.
    pub shadow: u64,
    /// Pixels whose corners disagreed and were supersampled.
    pub refined: u64,
    /// Gathers behind glass or a mirror whose photons were averaged over a patch widened
    /// far past their own ([`Halves::widened`]: a surface seen magnified near a lens's
    /// focus); counted only for a store that reads magnifications
    /// ([`CausticStore::reads_direct`]).
    pub widened: u64,
}

impl core::ops::AddAssign for RayCount {
    fn add_assign(&mut self, o: Self) {
        self.eye += o.eye;
        self.shadow += o.shadow;
        self.refined += o.refined;
        self.widened += o.widened;
    }
}

/// Where the caustic light at a diffuse hit comes from.
#[derive(Clone, Copy, Debug)]
enum Gather {
    /// The forward pass's splats hold it already (seen directly): no gather.
    Splatted,
    /// No photon can lie within the store's reach: the footprint's estimate is zero.
    Dark,
    /// The store's own gather, as its settings say (the paper's way, without splats).
    Store,
    /// The photons within the patch the sample stands for, from its ray differentials
    /// (behind glass and mirrors, with splats).
    Footprint(Footprint),
}

/// One pending branch of an eye path.
#[derive(Clone, Copy, Debug)]
struct Branch {
    ray: Ray,
    weight: Rgb,
    depth: u32,
    /// How it left the specular vertex it starts at (the camera's ray: `Reflect`,
    /// unused): with the [`Trail`] of vertices, what its ray differentials are made from.
    bend: Bend,
}

/// A branch a specular hit spawns, before it is placed: its direction, weight and bend.
#[derive(Clone, Copy, Debug)]
struct Child {
    dir: UnitVec3,
    weight: Rgb,
    bend: Bend,
}

impl Child {
    /// The branch, from `hit`, at `depth`.
    #[inline]
    fn branch(self, hit: &Hit, depth: u32) -> Branch {
        Branch {
            ray: Ray::spawn(hit, self.dir),
            weight: self.weight,
            depth,
            bend: self.bend,
        }
    }
}

/// The heavier of a fork's two branches (the larger channel sum; the first on a tie),
/// which the path follows at once, and the other.
#[inline]
fn heavier([first, second]: [Option<Child>; 2]) -> (Option<Child>, Option<Child>) {
    let sum = |c: &Option<Child>| c.map_or(0.0, |c| c.weight.r + c.weight.g + c.weight.b);
    if sum(&second) > sum(&first) {
        (second, first)
    } else {
        (first, second)
    }
}

/// Where a sample's path first gathers at full weight ([`Renderer::probe`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Probe {
    point: Vec3,
    depth: u32,
    object: usize,
}

/// Radiance along one eye ray, its caustic part, and a signature of what the path met:
/// which objects, in which order, and which lights were visible at each shaded point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Radiance.
    pub radiance: Rgb,
    /// The part of `radiance` the caustic store gathered.
    pub caustic: Rgb,
    /// That part's estimate from the forward pass's half 0 minus half 1's
    /// ([`Halves`]): its noise.
    pub split: Rgb,
    /// FNV-1a hash of the path's events: the objects its branches meet and the
    /// lights visible where they shade, for the branches weighing at least
    /// [`SIGNATURE_WEIGHT`]. Made only under [`Sampling::Adaptive`], whose corners
    /// compare it; otherwise the hash of no events.
    pub signature: u32,
}

/// The empty sample (no radiance), for initialising buffers of samples.
impl Default for Sample {
    fn default() -> Self {
        Self::START
    }
}

impl Sample {
    const START: Sample = Sample {
        radiance: Rgb::ZERO,
        caustic: Rgb::ZERO,
        split: Rgb::ZERO,
        signature: 0x811c_9dc5,
    };

    /// Folds one event into the signature (FNV-1a).
    #[inline]
    fn mix(&mut self, v: u32) {
        self.signature = (self.signature ^ v).wrapping_mul(0x0100_0193);
    }
}

/// Renders a scene against a caustic store, with a path stack of `DEPTH` entries.
#[derive(Debug)]
pub struct Renderer<'a, S, const OBJECTS: usize, const LIGHTS: usize, const DEPTH: usize> {
    scene: &'a Scene<OBJECTS, LIGHTS>,
    store: &'a S,
    max_depth: u32,
    sampling: Sampling,
    /// The camera's splats, when the forward pass made them: then the store gathers
    /// only at diffuse points seen through glass or mirrors.
    splats: Option<&'a [Splat]>,
    /// Branches whose weight's largest channel is below this are not traced.
    cutoff: f32,
    /// Most rays (eye and shadow) per pixel.
    pub(super) ray_budget: u32,
    /// Rays one eye ray may cost: itself and one shadow ray per lit light.
    rays_per_hit: u32,
    /// The luminance below which a pixel's brightness does not lower its refinement's
    /// tolerance ([`Renderer::with_refine_floor`]).
    floor: f32,
}

impl<'a, S: CausticStore, const O: usize, const L: usize, const DEPTH: usize>
    Renderer<'a, S, O, L, DEPTH>
{
    /// A renderer with one ray per pixel centre and the store gathering at every
    /// diffuse hit (the paper's method); an error when `max_depth` exceeds the compiled
    /// stack `DEPTH`.
    pub fn new(scene: &'a Scene<O, L>, store: &'a S, max_depth: u32) -> Result<Self, Error> {
        if max_depth as usize > DEPTH {
            return Err(Error::Capacity {
                what: "photons.max_depth",
                requested: max_depth as usize,
                capacity: DEPTH,
            });
        }
        let lit = scene.lights().iter().filter(|l| !l.intensity().is_black());
        Ok(Self {
            scene,
            store,
            max_depth,
            sampling: Sampling::Centre,
            splats: None,
            cutoff: DEFAULT_CUTOFF,
            ray_budget: DEFAULT_RAY_BUDGET,
            rays_per_hit: 1 + lit.count() as u32,
            floor: 0.0,
        })
    }

    /// The throughput cut-off: a reflected or refracted branch whose weight (the
    /// product of the reflectances and transmittances from the eye) has its largest
    /// channel below `cutoff ∈ [0, 1]` is not traced. `0` traces every non-black branch.
    /// Default [`DEFAULT_CUTOFF`]; see the [module documentation](self).
    pub fn with_cutoff(mut self, cutoff: f32) -> Result<Self, Error> {
        self.cutoff = crate::error::in_range(cutoff, 0.0, 1.0, "ray cutoff")?;
        Ok(self)
    }

    /// At most `max_rays` rays (eye and shadow) per camera ray; default
    /// [`DEFAULT_RAY_BUDGET`]. An error when `max_rays` is below `1 + lit lights`: the
    /// camera ray could not be shaded.
    pub fn with_ray_budget(mut self, max_rays: u32) -> Result<Self, Error> {
        if max_rays < self.rays_per_hit {
            return Err(Error::OutOfRange {
                what: "image.max_rays_per_sample",
                value: max_rays as f32,
                min: self.rays_per_hit as f32,
                max: u32::MAX as f32,
            });
        }
        self.ray_budget = max_rays;
        Ok(self)
    }

    /// The caustics seen directly come from these splats of the forward pass (in
    /// emission order): [`rows`](Self::rows) adds them to their pixels, and the store
    /// gathers only where a diffuse point is seen through glass or in a mirror, within
    /// the pixel's footprint. [`row`](Self::row) does not add them: the desktop sums
    /// them as its forward pass makes them ([`SplatSums`](crate::photon::SplatSums)) and
    /// passes an empty list here, which says only that the splats hold those caustics.
    pub fn with_splats(mut self, splats: &'a [Splat]) -> Self {
        self.splats = Some(splats);
        self
    }

    /// Under [`Sampling::Adaptive`], a supersampled pixel is refined while its error
    /// estimate exceeds [`REFINE_TOLERANCE`] of the brightest of its value, its
    /// corners and `floor` (a luminance; default 0, the pixel's own brightness alone);
    /// a grazing pixel keeps its own (see [`REFINE_FLOOR`]). The desktop's is
    /// [`with_image_floor`](Self::with_image_floor).
    /// An error for a negative or NaN `floor`; `+∞` stops every refinement after the
    /// first grid.
    pub fn with_refine_floor(mut self, floor: f32) -> Result<Self, Error> {
        if floor.is_nan() || floor < 0.0 {
            return Err(Error::OutOfRange {
                what: "refine floor",
                value: floor,
                min: 0.0,
                max: f32::INFINITY,
            });
        }
        self.floor = floor;
        Ok(self)
    }

    /// How pixels are sampled; an error for a grid side outside `1..=64`.
    pub fn with_sampling(mut self, sampling: Sampling) -> Result<Self, Error> {
        if let Sampling::Grid(n) | Sampling::Adaptive(n) = sampling {
            if !(1..=64).contains(&n) {
                return Err(Error::OutOfRange {
                    what: "supersample",
                    value: n as f32,
                    min: 1.0,
                    max: 64.0,
                });
            }
        }
        self.sampling = sampling;
        Ok(self)
    }

    /// Supersampling: `n × n` eye rays per pixel on a regular grid of sub-pixel centres,
    /// averaged: [`Sampling::Grid`].
    pub fn with_supersample(self, n: u32) -> Result<Self, Error> {
        self.with_sampling(Sampling::Grid(n))
    }

    /// The scene.
    pub fn scene(&self) -> &Scene<O, L> {
        self.scene
    }

    /// `true` when what branch `b` meets goes into its sample's signature: under the
    /// adaptive sampling (the only reader of signatures), when a channel of its
    /// weight is at least [`SIGNATURE_WEIGHT`] (the first usually is: one test).
    #[inline]
    fn significant(&self, b: &Branch) -> bool {
        let (w, t) = (b.weight, SIGNATURE_WEIGHT);
        matches!(self.sampling, Sampling::Adaptive(_)) && (w.r >= t || w.g >= t || w.b >= t)
    }

    /// Radiance arriving at the origin of `ray` along it, spending at most the ray
    /// budget (see the [module documentation](self)).
    pub fn radiance(&self, ray: Ray, count: &mut RayCount) -> Rgb {
        self.sample(ray, count).radiance
    }

    /// Radiance arriving at the origin of `ray` along it, with the path's signature.
    pub fn sample(&self, ray: Ray, count: &mut RayCount) -> Sample {
        self.sample_within(ray, 1, Bounds::PLAIN, count).0
    }

    /// As [`sample`](Self::sample), for one ray of an `m × m` grid over the pixel: the
    /// gathers behind glass average over its sub-pixel's patch of surface, within
    /// `bounds`. Also `true` when the ray entered glass at grazing incidence
    /// ([`GRAZING`]; only with a store that reads magnifications, the desktop's: see
    /// `refine`).
    pub(crate) fn sample_within(
        &self,
        ray: Ray,
        m: u32,
        bounds: Bounds,
        count: &mut RayCount,
    ) -> (Sample, bool) {
        let mut stack: FixedVec<Branch, DEPTH> = FixedVec::new();
        let mut out = Sample::START;
        let mut trail = Trail::new(1.0 / m.max(1) as f32, bounds);
        let mut b = Branch {
            ray,
            weight: Rgb::ONE,
            depth: 0,
            bend: Bend::Reflect,
        };
        let limit = count.eye + count.shadow + self.ray_budget as u64;
        loop {
            if count.eye + count.shadow + self.rays_per_hit as u64 > limit {
                break; // the budget is spent: drop this and every pending branch
            }
            count.eye += 1;
            if let Some((hit, index)) = self.scene.intersect(&b.ray, f32::INFINITY) {
                if self.significant(&b) {
                    out.mix(index as u32 | b.depth << 16);
                }
                let (local, children) = self.scatter(&b, &hit, index, &mut trail, count, &mut out);
                out.radiance += local;
                // Continue with the heavier branch, keep the other for later (a
                // different depth from every branch already waiting, so the stack never
                // overflows). Each is made where it goes, not moved there.
                let (heavier, lighter) = heavier(children);
                let depth = b.depth + 1;
                if let Some(c) = lighter {
                    if stack.push(c.branch(&hit, depth)).is_err() {
                        debug_assert!(false, "path stack overflow: DEPTH < max_depth");
                    }
                }
                if let Some(c) = heavier {
                    b = c.branch(&hit, depth);
                    continue;
                }
            } else {
                if self.significant(&b) {
                    out.mix(u32::MAX);
                }
                out.radiance += b.weight * self.scene.background();
            }
            match stack.pop() {
                Some(pending) => b = pending,
                None => break,
            }
        }
        // Constant false on a device's store: not compiled there.
        let grazing = self.store.reads_direct() && trail.grazes(GRAZING);
        (out, grazing)
    }

    /// Where the path of `ray` (one ray of an `m × m` grid) first gathers at full weight:
    /// following the heavier branch at every fork as [`sample_within`](Self::sample_within)
    /// does, its first hit on the front of a diffuse surface after a specular vertex,
    /// if the branch there carries at least half the light (a `classic` surface, a
    /// miss or the end of the path: `None`). Shades nothing: the points of a grid's
    /// samples, traced first, give each sample the secants that bound its footprint
    /// (see `grazing_grid`).
    pub(crate) fn probe(&self, ray: Ray, m: u32) -> Option<Probe> {
        let mut trail = Trail::new(1.0 / m.max(1) as f32, Bounds::PLAIN);
        let (mut count, mut log) = (RayCount::default(), Sample::START);
        let mut b = Branch {
            ray,
            weight: Rgb::ONE,
            depth: 0,
            bend: Bend::Reflect,
        };
        loop {
            let (hit, index) = self.scene.intersect(&b.ray, f32::INFINITY)?;
            match self.scene.objects()[index].material {
                Material::Diffuse(_) => {
                    let full = b.weight.max_channel() >= 0.5;
                    let seen = b.depth >= 1 && full && hit.front_face(b.ray.dir);
                    return seen.then_some(Probe {
                        point: hit.point,
                        depth: b.depth,
                        object: index,
                    });
                }
                Material::Classic(_) => return None,
                Material::Mirror(_) | Material::Dielectric(_) => {}
            }
            let (_, children) = self.scatter(&b, &hit, index, &mut trail, &mut count, &mut log);
            b = heavier(children).0?.branch(&hit, b.depth + 1);
        }
    }

    /// How the caustic store gathers at the diffuse point `hit` reached by branch `b`:
    /// behind glass or a mirror, over the parallelogram spanned by the half-steps of
    /// the branch's differentials there (replayed from the `trail`, and only where a
    /// photon may lie within reach).
    #[inline(always)]
    fn gather(&self, b: &Branch, (hit, shape): (&Hit, &Shape), trail: &Trail<DEPTH>) -> Gather {
        match self.splats {
            None => Gather::Store,
            Some(_) if b.depth == 0 => Gather::Splatted,
            Some(_) => self.behind(b, (hit, shape), trail),
        }
    }

    /// The gather at `hit` seen through glass or in a mirror along `b`: over the
    /// half-steps of its differentials there, where a photon may lie within reach.
    #[inline(never)]
    fn behind(&self, b: &Branch, (hit, shape): (&Hit, &Shape), trail: &Trail<DEPTH>) -> Gather {
        // Constant false on a device's store, whose samples always gather.
        let settled = self.store.reads_direct() && trail.visits() == Bounds::NO_GATHER;
        if settled || !self.store.reaches(hit.point) {
            return Gather::Dark;
        }
        let (camera, objects) = (self.scene.camera(), self.scene.objects());
        let diffs = trail.differentials(camera, objects, b.depth, (b.ray.dir, b.bend));
        let throughput = b.weight.max_channel();
        let direct = if self.store.reads_direct() {
            trail.direct_area(camera, b.depth, hit.t)
        } else {
            0.0
        };
        let axes =
            diffs.map(|diff| diff.transfer(b.ray.dir.get(), hit.t, hit.normal.get()).dp * 0.5);
        // Constant false on a device's store, whose grids are never grazing ones: the
        // secants and the larger cap are not compiled there.
        let desktop = self.store.reads_direct();
        let [a, b] = if desktop {
            trail.bounded(hit.point, axes)
        } else {
            axes
        };
        let visits = if desktop {
            trail.visits()
        } else {
            crate::photon::FOOTPRINT_VISITS
        };
        Gather::Footprint(Footprint {
            a,
            b,
            throughput,
            direct,
            curvature: shape.curvature(hit.normal),
            visits,
        })
    }

    /// Light leaving `hit` towards the eye directly, and up to two specular branches
    /// (reflected, refracted);
    /// the caustic part and the path's events go to `log`.
    #[inline]
    fn scatter(
        &self,
        b: &Branch,
        hit: &Hit,
        index: usize,
        trail: &mut Trail<DEPTH>,
        count: &mut RayCount,
        log: &mut Sample,
    ) -> (Rgb, [Option<Child>; 2]) {
        let object = &self.scene.objects()[index];
        let d = b.ray.dir;
        let front = hit.front_face(d);
        let facing = if front { hit.normal } else { -hit.normal };
        let can_bounce = b.depth < self.max_depth;
        // Negligible throughput: not traced (see the module documentation). The
        // largest channel (NaN only when all are) is positive exactly when the weight
        // is not black.
        let traced = |w: Rgb| {
            let m = w.max_channel();
            m > 0.0 && m >= self.cutoff
        };
        let branch = |dir: UnitVec3, weight: Rgb, bend: Bend| Child { dir, weight, bend };
        // The vertex the branches leave from, for their differentials.
        let record = |trail: &mut Trail<DEPTH>, eta: f32| {
            trail.record(b.depth, (d, b.bend), hit, index, eta);
        };
        match &object.material {
            Material::Diffuse(m) if front => (
                self.diffuse(b, (hit, &object.shape), m, trail, count, log),
                [None, None],
            ),
            Material::Diffuse(_) => (Rgb::ZERO, [None, None]),
            Material::Mirror(m) if can_bounce => {
                let w = b.weight * m.reflectance;
                let reflected = traced(w).then(|| {
                    record(trail, 1.0);
                    branch(reflect(d, facing), w, Bend::Reflect)
                });
                (Rgb::ZERO, [reflected, None])
            }
            Material::Dielectric(g) if can_bounce => {
                let weight = if front {
                    b.weight
                } else {
                    b.weight * g.absorption.beer(hit.t)
                };
                let eta = if front { 1.0 / g.ior } else { g.ior };
                let i = interface(d, facing, eta);
                record(trail, eta);
                let w = weight * i.reflectance;
                let reflected = traced(w).then(|| branch(reflect(d, facing), w, Bend::Reflect));
                let w = weight * ((1.0 - i.reflectance) * eta * eta);
                let refracted = i
                    .refracted
                    .filter(|_| traced(w))
                    .map(|t| branch(t, w, Bend::Refract));
                (Rgb::ZERO, [reflected, refracted])
            }
            Material::Classic(c) => {
                let local = if front {
                    self.classic_local(b, (hit, &object.shape), c, trail, count, log)
                } else {
                    Rgb::ZERO
                };
                if !can_bounce {
                    return (b.weight * local, [None, None]);
                }
                let eta = if front { 1.0 / c.ior } else { c.ior };
                let r = reflect(d, facing);
                let (wr, wt) = (b.weight * c.reflectivity, b.weight * c.transparency);
                if !traced(wr + wt) {
                    return (b.weight * local, [None, None]);
                }
                record(trail, eta);
                // Under total internal reflection the transmitted part follows the
                // reflected ray: one ray carries both.
                let (reflected, refracted) = match interface(d, facing, eta).refracted {
                    Some(t) => (
                        traced(wr).then(|| branch(r, wr, Bend::Reflect)),
                        traced(wt).then(|| branch(t, wt, Bend::Refract)),
                    ),
                    None => {
                        let w = wr + wt;
                        (traced(w).then(|| branch(r, w, Bend::Reflect)), None)
                    }
                };
                (b.weight * local, [reflected, refracted])
            }
            // A specular surface after max_depth interactions contributes nothing.
            Material::Mirror(_) | Material::Dielectric(_) => (Rgb::ZERO, [None, None]),
        }
    }

    /// Light a diffuse surface hit on its front reflects towards the eye along `b`:
    /// `ρ/π · (E_caustic + Σ_lights I·cosθ/d²)`; the caustic part goes to `log`.
    #[inline]
    fn diffuse(
        &self,
        b: &Branch,
        (hit, shape): (&Hit, &Shape),
        m: &crate::material::Diffuse,
        trail: &Trail<DEPTH>,
        count: &mut RayCount,
        log: &mut Sample,
    ) -> Rgb {
        let caustic = match self.gather(b, (hit, shape), trail) {
            Gather::Footprint(f) => self.store.irradiance_within(hit.point, hit.normal, &f),
            Gather::Store => Halves::whole(self.store.irradiance(hit.point, hit.normal)),
            Gather::Splatted | Gather::Dark => Halves::default(),
        };
        // Constant false on a device's store: not compiled there.
        if self.store.reads_direct() {
            count.widened += caustic.widened as u64;
        }
        let mut e = caustic.total;
        let logged = self.significant(b);
        for light in self.scene.lights() {
            let lit = self.direct_one(hit, light, count);
            if logged {
                log.mix(lit.is_some() as u32);
            }
            if let Some((l, irradiance)) = lit {
                e += irradiance * hit.normal.dot(l.get());
            }
        }
        let f = b.weight * m.albedo;
        log.caustic += f * caustic.total * core::f32::consts::FRAC_1_PI;
        log.split += f * caustic.split * core::f32::consts::FRAC_1_PI;
        f * e * core::f32::consts::FRAC_1_PI
    }

    /// The classic model's local part at a front-side hit, seen along `b`.
    fn classic_local(
        &self,
        b: &Branch,
        (hit, shape): (&Hit, &Shape),
        c: &Classic,
        trail: &Trail<DEPTH>,
        count: &mut RayCount,
        log: &mut Sample,
    ) -> Rgb {
        let (n, to_eye) = (hit.normal, -b.ray.dir);
        let ambient = c.color * self.scene.ambient() * c.ambient;
        let mut lit = Rgb::ZERO;
        let logged = self.significant(b);
        for light in self.scene.lights() {
            let seen = self.direct_one(hit, light, count);
            if logged {
                log.mix(seen.is_some() as u32);
            }
            if let Some((l, e)) = seen {
                lit += c.kernel(n, l, to_eye) * e;
            }
        }
        let caustic = match self.gather(b, (hit, shape), trail) {
            Gather::Footprint(f) => self.store.classic_within(hit.point, n, to_eye, c, &f),
            Gather::Store => Halves::whole(self.store.classic(hit.point, n, to_eye, c)),
            Gather::Splatted | Gather::Dark => Halves::default(),
        };
        // Constant false on a device's store: not compiled there.
        if self.store.reads_direct() {
            count.widened += caustic.widened as u64;
        }
        log.caustic += b.weight * caustic.total;
        log.split += b.weight * caustic.split;
        ambient + lit + caustic.total
    }

    /// Direction `l` and normal-incidence irradiance `I/d²` of one light if it shines
    /// on the front of `hit` (`n·l > 0`) unoccluded: one shadow ray, which every object
    /// blocks. Dark lights cost nothing.
    #[inline]
    fn direct_one(
        &self,
        hit: &Hit,
        light: &crate::light::PointLight,
        count: &mut RayCount,
    ) -> Option<(UnitVec3, Rgb)> {
        if light.intensity().is_black() {
            return None;
        }
        let to = light.position() - hit.point;
        let d2 = to.length_squared();
        let l = UnitVec3::new(to)?;
        if !(hit.normal.dot(l.get()) > 0.0) {
            return None;
        }
        let shadow = Ray::spawn(hit, l);
        count.shadow += 1;
        if self.scene.occluded(
            &shadow,
            crate::math::sqrt((light.position() - shadow.origin).length_squared()),
        ) {
            return None;
        }
        Some((l, light.intensity() * (1.0 / d2)))
    }
}

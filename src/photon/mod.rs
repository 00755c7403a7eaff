//! The forward pass: photons from the lights through mirrors and glass into a
//! caustic store, and the store's estimate of the caustic light at a point.
//!
//! - [`emit`](self#emission): directions and powers (paper eq. 7, made uniform; projection maps),
//! - `trace`: one photon's path,
//! - `kdtree`: the kd-tree built in place, in-order with bucket leaves ([`KdTree`], [`balance`]),
//! - `estimate`: the radiance estimate (Jensen; paper eq. 8).
//!
//! # Emission
//! See the `emit` module's formulas, repeated on [`shoot_with_splats`].

mod emit;
mod estimate;
mod footprint;
mod illumination;
mod kdtree;
mod packed;
mod reach;
mod splat;
mod trace;

pub use estimate::{
    ConeFilter, KdStore, FAINT, FOOTPRINT_VISITS, GRAZING_VISITS, MAGNIFIED, MAGNIFIED_WIDENINGS,
    SPARSE_FOOTPRINT, THINNING,
};

pub use footprint::Footprint;
pub use illumination::{
    FixedIlluminationMaps, IlluminationMaps, MapStats, TexelStorage, DEFAULT_TRIM,
};
#[cfg(feature = "std")]
pub use illumination::{DEFAULT_HEAP_TEXELS, MAX_HEAP_TEXELS};
pub(crate) use kdtree::bounding_box;
#[cfg(feature = "std")]
pub(crate) use kdtree::NO_BOX;
pub use kdtree::{
    balance, balance_subtree, split_subtree, Found, KdTree, Neighbor, Subtree, BUCKET,
};
pub use packed::Photon;
#[cfg(feature = "std")]
pub use splat::{add_to_frame, SplatSums};
pub use splat::{add_to_row, Splat, SplatStorage, SplatTarget};

use emit::Emission;

use crate::error::{in_range, positive, within, Error};
use crate::geometry::Ray;
use crate::material::Classic;
use crate::math::{Rgb, UnitVec3, Vec3};
use crate::sampling::{hash, mix64, thinning_level, unit_f32, PathSampler};
use crate::scene::Scene;

/// The seam between the forward and the backward pass: how much caustic light arrives
/// at a surface point. The kd-tree photon map implements it; so can other stores.
pub trait CausticStore {
    /// Caustic irradiance `E` (W/m² per channel) at `x` on a surface of normal `n`,
    /// from light arriving on the front side. A diffuse surface of albedo ρ reflects
    /// radiance `ρ·E/π`.
    fn irradiance(&self, x: Vec3, n: UnitVec3) -> Rgb;

    /// The caustic term of the paper's `classic` model (eq. 8) at `x`, seen from `to_eye`.
    fn classic(&self, x: Vec3, n: UnitVec3, to_eye: UnitVec3, material: &Classic) -> Rgb;

    /// `true` when the store reads [`Footprint::direct`] (the desktop's kd-tree, which
    /// widens sparse footprints seen magnified): the renderer works it out only then,
    /// so a device's flash is spared it.
    fn reads_direct(&self) -> bool {
        false
    }

    /// `false` only where every estimate at `x` is zero whatever the footprint (no
    /// photon can lie within reach): the renderer then does not work out the footprint
    /// of a diffuse point seen through glass. The default, `true`, is always sound.
    fn reaches(&self, x: Vec3) -> bool {
        let _ = x;
        true
    }

    /// As [`irradiance`](Self::irradiance), averaged over the patch one eye sample
    /// stands for (a diffuse point seen through glass or in a mirror): the box filter of
    /// a pixel, with the difference of its two halves' estimates. A store that cannot
    /// restrict its estimate to the patch ignores it, and one that cannot split it
    /// reports no difference.
    fn irradiance_within(&self, x: Vec3, n: UnitVec3, footprint: &Footprint) -> Halves {
        let _ = footprint;
        Halves::whole(self.irradiance(x, n))
    }

    /// As [`classic`](Self::classic), over the patch one eye sample stands for.
    fn classic_within(
        &self,
        x: Vec3,
        n: UnitVec3,
        to_eye: UnitVec3,
        material: &Classic,
        footprint: &Footprint,
    ) -> Halves {
        let _ = footprint;
        Halves::whole(self.classic(x, n, to_eye, material))
    }
}

/// A caustic estimate from all photons, and the difference between the parts of the
/// forward pass's two independent halves ([`Emitter`]: photon `i` of a light belongs
/// to half `i mod 2` and carries `n_h/n` of its half's power, so the parts add up to
/// the total). With `A`, `B` the two parts (i.i.d., each of variance `σ²`), the total
/// `A + B` has variance `2σ²` and `E[(A − B)²] = 2σ²`: the squared difference estimates
/// the total's squared error (batch means with two batches).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Halves {
    /// The estimate: half 0's part plus half 1's.
    pub total: Rgb,
    /// Half 0's part minus half 1's.
    pub split: Rgb,
    /// `true` when the photons were averaged over a patch widened far past the
    /// footprint's own (`KdStore::widened_far`: a surface seen magnified near a lens's
    /// focus, each sample's patch grown to the photons' spacing). Finer samples there
    /// would average the same few photons again.
    pub widened: bool,
}

impl Halves {
    /// An estimate that cannot be split: no difference.
    pub fn whole(total: Rgb) -> Self {
        Self {
            total,
            split: Rgb::ZERO,
            widened: false,
        }
    }

    /// Both scaled by `s`.
    pub fn scaled(self, s: f32) -> Self {
        Self {
            total: self.total * s,
            split: self.split * s,
            widened: self.widened,
        }
    }

    /// From the parts of half 0 and half 1.
    pub fn from_parts(half0: Rgb, half1: Rgb) -> Self {
        Self {
            total: half0 + half1,
            split: half0 - half1,
            widened: false,
        }
    }
}

/// The store of a scene without caustics: no light.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoCaustics;

impl CausticStore for NoCaustics {
    fn irradiance(&self, _: Vec3, _: UnitVec3) -> Rgb {
        Rgb::ZERO
    }
    fn classic(&self, _: Vec3, _: UnitVec3, _: UnitVec3, _: &Classic) -> Rgb {
        Rgb::ZERO
    }
}

/// The photon budget and the radiance estimate's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonSettings {
    count: u32,
    k: u32,
    max_radius: f32,
    max_depth: u32,
    cone: Option<ConeFilter>,
    full_sphere: bool,
    store_direct: bool,
    fixed_radius: bool,
    splat: bool,
    split: bool,
}

impl PhotonSettings {
    /// `count` photons emitted per light (towards the objects that make caustics),
    /// `k ≥ 1` photons per estimate within `max_radius > 0`, and at most `max_depth`
    /// specular interactions along any photon or eye path.
    pub fn new(count: u32, k: u32, max_radius: f32, max_depth: u32) -> Result<Self, Error> {
        if k == 0 {
            return Err(Error::NotPositive {
                what: "photons.k",
                value: 0.0,
            });
        }
        gather_radius(max_radius)?;
        in_range(max_depth as f32, 0.0, 255.0, "photons.max_depth")?;
        Ok(Self {
            count,
            k,
            max_radius,
            max_depth,
            cone: None,
            full_sphere: false,
            store_direct: false,
            fixed_radius: false,
            splat: true,
            split: true,
        })
    }

    /// With Jensen's cone filter.
    pub fn with_cone_filter(self, cone: Option<ConeFilter>) -> Self {
        Self { cone, ..self }
    }

    /// The cone filter, if any.
    pub fn cone_filter(&self) -> Option<ConeFilter> {
        self.cone
    }

    /// Emits over the light's whole sphere instead of through projection maps
    /// (for measuring what the projection maps save).
    pub fn with_full_sphere(self, full_sphere: bool) -> Self {
        Self {
            full_sphere,
            ..self
        }
    }

    /// Also stores photons at their first (direct) hit: the map then holds direct
    /// light too. For tests of the density estimate; never for rendering, where direct
    /// light comes from shadow rays.
    pub fn with_direct_photons(self, store_direct: bool) -> Self {
        Self {
            store_direct,
            ..self
        }
    }

    /// Gathers every photon within `max_radius` instead of the `k` nearest: the
    /// estimate of progressive photon mapping, whose radius shrinks pass by pass.
    pub fn with_fixed_radius(self, fixed_radius: bool) -> Self {
        Self {
            fixed_radius,
            ..self
        }
    }

    /// `true` when every photon within `max_radius` is gathered.
    pub fn fixed_radius(&self) -> bool {
        self.fixed_radius
    }

    /// Whether the forward pass connects each landed photon to the eye (light tracing
    /// of the caustics seen directly: see [`Splat`]). On by default; off, the
    /// backward pass gathers at every diffuse hit, as in the paper.
    pub fn with_camera_splats(self, splat: bool) -> Self {
        Self { splat, ..self }
    }

    /// `true` when landed photons are connected to the eye.
    pub fn camera_splats(&self) -> bool {
        self.splat
    }

    /// Whether the light tracer's photons split at glass (the refracted path always
    /// goes on with `1 − F` of the power, the reflected one with probability `F`; see
    /// [`Emitter::land`]) instead of taking the photon store's Russian roulette path
    /// alone. On by default, where the `std` feature compiles it; a device (without
    /// `std`) never splits, its splat list a fixed budget. It matters only with
    /// [`camera_splats`](Self::camera_splats) and glass; the stored photons are the same
    /// either way.
    pub fn with_glass_splitting(self, split: bool) -> Self {
        Self { split, ..self }
    }

    /// `true` when the light tracer's photons split at glass where they can (see
    /// [`with_glass_splitting`](Self::with_glass_splitting)).
    pub fn glass_splitting(&self) -> bool {
        self.split
    }

    /// A copy with another maximum radius (progressive passes shrink it).
    pub fn with_max_radius(mut self, max_radius: f32) -> Result<Self, Error> {
        self.max_radius = gather_radius(max_radius)?;
        Ok(self)
    }

    /// Photons per light.
    pub fn count(&self) -> u32 {
        self.count
    }
    /// Photons per estimate.
    pub fn k(&self) -> u32 {
        self.k
    }
    /// Gather radius bound.
    pub fn max_radius(&self) -> f32 {
        self.max_radius
    }
    /// Specular interactions per path.
    pub fn max_depth(&self) -> u32 {
        self.max_depth
    }
}

/// A gather radius whose square is a normal, finite `f32` (the estimate divides by
/// `π r²`): positive, at least about 1.1e-19 and at most about 1.8e19.
fn gather_radius(r: f32) -> Result<f32, Error> {
    positive(r, "photons.max_radius")?;
    let r2 = r * r;
    if r2 >= f32::MIN_POSITIVE && r2.is_finite() {
        Ok(r)
    } else {
        Err(Error::OutOfRange {
            what: "photons.max_radius",
            value: r,
            min: 1.1e-19,
            max: 1.8e19,
        })
    }
}

/// What a forward pass did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ForwardStats {
    /// Photons emitted (over all lights).
    pub emitted: u64,
    /// Photons stored.
    pub stored: usize,
    /// Power of one unit of stored photon power, W.
    pub power_unit: f32,
}

/// Storage a forward pass needs: `count × lights` photons (each photon is stored at
/// most once).
pub fn photons_needed<const O: usize, const L: usize>(
    scene: &Scene<O, L>,
    settings: &PhotonSettings,
) -> usize {
    settings.count as usize * scene.lights().len()
}

/// One forward pass, photon by photon: photon `i` of light `l` is a pure function of
/// `(scene, settings, seed, pass, l, i)`, so a pass can be split among threads in any
/// way and still store the same photons.
///
/// Each light's `n` photons are two independent halves — photon `i` belongs to half
/// `h = i mod 2`, as photon `⌊i/2⌋` of a Hammersley set of `n_h` points (`n_0 = ⌈n/2⌉`,
/// `n_1 = ⌊n/2⌋`) shifted by `hash(seed, pass, l, h)` (a Cranley–Patterson rotation:
/// randomised quasi-Monte Carlo). Each half alone is an unbiased estimate; a photon
/// carries `n_h/n` of its half's power, so the two add up to one estimate from `n`
/// photons, and their difference measures that estimate's error (Owen 1997; see
/// [`Splat::half`]). The random choices of photon `i` along its path are the further
/// coordinates of its point (`φ₃, φ₅, φ₇, φ₁₁` of its index, each rotated by its own
/// shift; then a PCG32 stream keyed by `hash(seed, pass, l, i)`: see [`PathSampler`]),
/// so the photons of any small patch of the light's sphere split between reflection
/// and refraction in the right proportions, and a caustic's pixels lose the binomial
/// noise of independent choices (randomised QMC through the whole path: Keller 1997).
/// A scene with no mirror, glass or reflective/transparent classic object emits
/// nothing, and so does a dark light.
#[derive(Clone, Debug)]
pub struct Emitter<'a, const O: usize, const L: usize> {
    scene: &'a Scene<O, L>,
    settings: PhotonSettings,
    seed: u64,
    pass: u32,
    /// Per light, per half: the emission plan, the point set's shift and the share
    /// `n_h/n` of the light's photons.
    plans: heapless::Vec<[Half<O>; 2], L>,
    unit: f32,
    /// The scene's objects, for the photons' nearest-hit searches.
    reach: reach::Reaches<O>,
}

/// One half of a light's photons.
#[derive(Clone, Debug)]
struct Half<const O: usize> {
    plan: Emission<O>,
    shift: (f32, f32),
    key: u64,
    share: f32,
    /// Per cone, the objects its photons' first segment is tested against.
    #[cfg(feature = "std")]
    reach: heapless::Vec<u64, O>,
}

impl<const O: usize> Half<O> {
    /// The objects of `all` that the first segment of a photon of `cone` may meet.
    #[cfg(feature = "std")]
    fn first_reach(&self, all: reach::Reach, cone: usize) -> reach::Reach {
        all.within(self.reach.get(cone).copied().unwrap_or(u64::MAX))
    }

    /// Every object of `all`: a device tests them all.
    #[cfg(not(feature = "std"))]
    fn first_reach(&self, all: reach::Reach, _: usize) -> reach::Reach {
        all
    }
}

impl<'a, const O: usize, const L: usize> Emitter<'a, O, L> {
    /// The emission plans of pass `pass` of `scene`'s lights.
    pub fn new(scene: &'a Scene<O, L>, settings: &PhotonSettings, seed: u64, pass: u32) -> Self {
        let active = settings.count > 0 && (scene.has_caustic_objects() || settings.store_direct);
        let full_sphere = settings.full_sphere || settings.store_direct;
        let mut plans = heapless::Vec::new();
        let mut unit = 0.0f32;
        for (l, light) in scene.lights().iter().enumerate() {
            let count = if active && !light.intensity().is_black() {
                settings.count
            } else {
                0
            };
            let half = |h: u32| {
                let n = (count + 1 - h) / 2;
                let key = hash(&[seed, pass as u64, l as u64, h as u64]);
                let plan = Emission::<O>::plan(scene, light, n, full_sphere);
                Half {
                    #[cfg(feature = "std")]
                    reach: plan.reach(scene, light),
                    plan,
                    shift: (unit_f32(key as u32), unit_f32((key >> 32) as u32)),
                    key: mix64(key),
                    share: n as f32 / count.max(1) as f32,
                }
            };
            let halves = [half(0), half(1)];
            for h in &halves {
                if h.plan.count() > 0 {
                    unit = unit.max(h.plan.nominal_power(light) * h.share);
                }
            }
            // Cannot overflow: one entry per light, at most L lights.
            let _ = plans.push(halves);
        }
        if !(unit > 0.0 && unit.is_finite()) {
            plans.clear(); // nothing to emit
            unit = 0.0;
        }
        Self {
            scene,
            settings: *settings,
            seed,
            pass,
            plans,
            unit,
            reach: reach::Reaches::new(scene),
        }
    }

    /// Power of one unit of stored photon power, W (0 when nothing is emitted).
    pub fn power_unit(&self) -> f32 {
        self.unit
    }

    /// Photons light `l` emits (0 for a dark light or when nothing is emitted).
    pub fn count(&self, l: usize) -> u32 {
        self.plans
            .get(l)
            .map_or(0, |p| p[0].plan.count() + p[1].plan.count())
    }

    /// Photons emitted by all lights.
    pub fn emitted(&self) -> u64 {
        (0..self.plans.len()).map(|l| self.count(l) as u64).sum()
    }

    /// How many coarse levels of the photon map photon `i` of light `l` joins, 0 to 2,
    /// if it is stored ([`KdStore::with_coarse_levels`]): a function of `(seed, pass,
    /// l, i)` alone, not of where photons land, so each photon of level `v` stands for
    /// [`THINNING`]`ᵛ` of the map's. The point's index in its cone's Hammersley set is
    /// thinned by [`thinning_level`] with a choice drawn per half: unbiased, and the
    /// points kept stratified in both of the set's coordinates. Every 16th stored
    /// photon, as these levels were first taken, kept one sixteenth of each cone's
    /// azimuth where nearly every photon lands (a floor seen in a mirror read twice
    /// its value, `docs/accuracy.md`), and one half's photons.
    pub fn coarse_levels(&self, l: usize, i: u32) -> usize {
        const _: () = assert!(THINNING == 16, "thinning_level thins by 16");
        let Some(half) = self.plans.get(l).map(|p| &p[(i & 1) as usize]) else {
            return 0;
        };
        let (j, _) = half.plan.local(i >> 1);
        thinning_level(j, (half.key >> 40) as u32)
    }

    /// Traces photon `i` of light `l` (`i < count(l)`), handing `f` each place one of
    /// its paths lands, in a fixed order: the photon to store on the one path Russian
    /// roulette follows, and (when the settings ask for camera splats) each path's
    /// splat if the eye sees where it landed. With splats, the paths split at glass
    /// (see [`PhotonSettings::with_glass_splitting`]); without, the photon takes the
    /// roulette's path alone. An error from `f` ends the photon and is returned.
    pub fn land<E>(
        &self,
        l: usize,
        i: u32,
        f: impl FnMut(Landed) -> Result<(), E>,
    ) -> Result<(), E> {
        let Some(halves) = self.plans.get(l) else {
            return Ok(());
        };
        let half = &halves[(i & 1) as usize];
        let photon = half
            .plan
            .photon(&self.scene.lights()[l], i >> 1, half.shift);
        self.land_from(l, (i, half), photon, f)
    }

    /// [`land`](Self::land) for each photon `i` of `range` in turn, handing `f` the
    /// photon's index with what it left: the same calls in the same order, and the
    /// same photons. With `std` the directions of each half's photons are worked out
    /// eight at a time, so that their chains of divisions and square roots overlap
    /// (the balls scene's forward pass about 10% faster, `docs/accuracy.md`); a device
    /// keeps one at a time, and its stack.
    pub fn land_range<E>(
        &self,
        l: usize,
        range: core::ops::Range<u32>,
        mut f: impl FnMut(u32, Landed) -> Result<(), E>,
    ) -> Result<(), E> {
        #[cfg(feature = "std")]
        if let Some(halves) = self.plans.get(l) {
            let light = &self.scene.lights()[l];
            let mut i = range.start;
            while i < range.end {
                // Photons i, i + 2, … of one half are consecutive points of its set.
                let first = [i, i + 1].map(|j| {
                    let h = &halves[(j & 1) as usize];
                    h.plan.photons::<{ emit::LANES }>(light, j >> 1, h.shift)
                });
                let block = (range.end - i).min(2 * emit::LANES as u32);
                for j in i..i + block {
                    let photon = first[((j - i) & 1) as usize][((j - i) >> 1) as usize];
                    let half = &halves[(j & 1) as usize];
                    self.land_from(l, (j, half), photon, |x| f(j, x))?;
                }
                i += block;
            }
            return Ok(());
        }
        for i in range {
            self.land(l, i, |x| f(i, x))?;
        }
        Ok(())
    }

    /// Traces photon `i` of light `l`, of `half` of its plan, leaving the light as
    /// `photon` says (direction, power, index in its cone's point set, cone), handing
    /// `f` what it leaves.
    fn land_from<E>(
        &self,
        l: usize,
        (i, half): (u32, &Half<O>),
        (dir, power, index, cone): (UnitVec3, Rgb, u32, usize),
        mut f: impl FnMut(Landed) -> Result<(), E>,
    ) -> Result<(), E> {
        let light = &self.scene.lights()[l];
        let power = power * half.share;
        let mut rng = PathSampler::new(
            index,
            half.key,
            [self.seed, self.pass as u64, l as u64, i as u64],
        );
        let ray = Ray::new(light.position(), dir);
        let s = &self.settings;
        let reach = (&self.reach, half.first_reach(self.reach.all, cone));
        let limits = (s.max_depth, s.store_direct, s.splat && s.split);
        trace::trace(self.scene, ray, power, limits, &mut rng, reach, |landing| {
            let material = &self.scene.objects()[landing.object].material;
            let (hit, dir, half) = (&landing.hit, landing.dir, i & 1 == 1);
            let splat = if s.splat {
                let power = landing.power * landing.weight;
                splat::connect(self.scene, hit, material, dir, power, half)
            } else {
                None
            };
            let photon = landing.stored.then(|| {
                Photon::new(hit.point, dir, landing.power * (1.0 / self.unit)).with_half(half)
            });
            if photon.is_none() && splat.is_none() {
                return Ok(());
            }
            let object = landing.object;
            f(Landed {
                photon,
                object,
                splat,
            })
        })
    }
}

/// What one path of a traced photon left where it landed: the photon to store (on the
/// path Russian roulette follows), and its splat into the image when the eye sees
/// where it landed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Landed {
    /// The photon for the caustic store, on the roulette's path.
    pub photon: Option<Photon>,
    /// Index of the scene object it landed on.
    pub object: usize,
    /// Its light-tracing contribution to the pixel it projects into.
    pub splat: Option<Splat>,
}

/// The forward pass, photon by photon in emission order: `f` receives what each traced
/// photon left (see [`Emitter::land`]) and may stop the pass with an error. Photon `i`
/// of light `l` is the same whatever else is traced, so this is the one loop every
/// forward pass runs (the desktop runs it on chunks of `(l, i)` on several threads).
pub fn forward<const O: usize, const L: usize>(
    scene: &Scene<O, L>,
    settings: &PhotonSettings,
    seed: u64,
    pass: u32,
    mut f: impl FnMut(&Landed) -> Result<(), Error>,
) -> Result<ForwardStats, Error> {
    let emitter = Emitter::new(scene, settings, seed, pass);
    let mut stats = ForwardStats {
        emitted: emitter.emitted(),
        stored: 0,
        power_unit: emitter.power_unit(),
    };
    for l in 0..scene.lights().len() {
        emitter.land_range(l, 0..emitter.count(l), |_, x| {
            f(&x)?;
            stats.stored += x.photon.is_some() as usize;
            Ok(())
        })?;
    }
    Ok(stats)
}

/// The forward pass of [`shoot_with_splats`], handing each photon it would store to `f` instead of
/// writing it to an array: the same photons, in the same order, with the same power
/// unit. Needs no photon memory at all (the illumination maps splat as they go).
pub fn for_each_photon<const O: usize, const L: usize>(
    scene: &Scene<O, L>,
    settings: &PhotonSettings,
    seed: u64,
    pass: u32,
    mut f: impl FnMut(&Photon),
) -> ForwardStats {
    let settings = settings.with_camera_splats(false);
    forward(scene, &settings, seed, pass, |x| {
        if let Some(p) = &x.photon {
            f(p);
        }
        Ok(())
    })
    .unwrap_or_default()
}

/// The forward pass: shoots `settings.count` photons from each light (see [`Emitter`])
/// and stores those that land on a diffuse surface after a specular bounce, in
/// emission order, into `out[..stored]` (not yet balanced), and the camera splats (see
/// [`Splat`]) into `splats`, emptied first (`&mut ()` keeps none). An error when `out`
/// cannot hold `count × lights` photons or `splats` is full.
pub fn shoot_with_splats<const O: usize, const L: usize>(
    scene: &Scene<O, L>,
    settings: &PhotonSettings,
    seed: u64,
    pass: u32,
    out: &mut [Photon],
    splats: &mut impl SplatStorage,
) -> Result<ForwardStats, Error> {
    within(
        photons_needed(scene, settings),
        out.len(),
        "photons (count × lights)",
    )?;
    splats.clear_splats();
    let mut n = 0;
    forward(scene, settings, seed, pass, |x| {
        if let Some(p) = x.photon {
            out[n] = p;
            n += 1;
        }
        match x.splat {
            Some(s) => splats.push_splat(s),
            None => Ok(()),
        }
    })
}

/// A photon map of fixed capacity `N`: the photons live in an array inside it, so its
/// whole memory is `size_of::<PhotonMap<N>>()` (20·N bytes and a few more).
#[derive(Clone, Debug)]
pub struct PhotonMap<const N: usize> {
    photons: [Photon; N],
    len: usize,
    unit: f32,
}

impl<const N: usize> Default for PhotonMap<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> PhotonMap<N> {
    /// An empty map.
    pub const fn new() -> Self {
        Self {
            photons: [Photon::ZERO; N],
            len: 0,
            unit: 0.0,
        }
    }

    /// Runs the forward pass into this map and balances it: see [`shoot_with_splats`]. The
    /// camera's splats are dropped: see [`build_with_splats`](Self::build_with_splats).
    pub fn build<const O: usize, const L: usize>(
        &mut self,
        scene: &Scene<O, L>,
        settings: &PhotonSettings,
        seed: u64,
    ) -> Result<ForwardStats, Error> {
        self.build_pass(scene, settings, seed, 0, &mut ())
    }

    /// As [`build`](Self::build), keeping the camera splats in `splats` (for
    /// [`Renderer::with_splats`](crate::render::Renderer::with_splats)).
    pub fn build_with_splats<const O: usize, const L: usize>(
        &mut self,
        scene: &Scene<O, L>,
        settings: &PhotonSettings,
        seed: u64,
        splats: &mut impl SplatStorage,
    ) -> Result<ForwardStats, Error> {
        self.build_pass(scene, settings, seed, 0, splats)
    }

    /// As [`build_with_splats`](Self::build_with_splats), for progressive pass `pass`.
    pub fn build_pass<const O: usize, const L: usize>(
        &mut self,
        scene: &Scene<O, L>,
        settings: &PhotonSettings,
        seed: u64,
        pass: u32,
        splats: &mut impl SplatStorage,
    ) -> Result<ForwardStats, Error> {
        self.len = 0;
        let stats = shoot_with_splats(scene, settings, seed, pass, &mut self.photons, splats)?;
        self.len = stats.stored;
        self.unit = stats.power_unit;
        balance(&mut self.photons[..self.len]);
        Ok(stats)
    }

    /// The balanced tree.
    pub fn tree(&self) -> KdTree<'_> {
        KdTree::from_balanced(&self.photons[..self.len])
    }

    /// Photons stored.
    pub fn len(&self) -> usize {
        self.len
    }

    /// `true` when no photon is stored.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The caustic store over this map, gathering up to `K` photons; an error when
    /// `settings.k` exceeds `K`.
    pub fn store<const K: usize>(
        &self,
        settings: &PhotonSettings,
    ) -> Result<KdStore<'_, K>, Error> {
        store_over(self.tree(), self.unit, settings)
    }
}

/// A caustic store over a balanced tree whose powers are in units of `unit` W.
pub fn store_over<'a, const K: usize>(
    tree: KdTree<'a>,
    unit: f32,
    settings: &PhotonSettings,
) -> Result<KdStore<'a, K>, Error> {
    store_within(tree, unit, settings, bounding_box(tree.photons()))
}

/// [`store_over`] with the bounding box of the tree's photons given (see
/// [`KdStore::within_box`]).
pub(crate) fn store_within<'a, const K: usize>(
    tree: KdTree<'a>,
    unit: f32,
    settings: &PhotonSettings,
    bounds: (Vec3, Vec3),
) -> Result<KdStore<'a, K>, Error> {
    if !settings.fixed_radius && settings.k as usize > K {
        return Err(Error::Capacity {
            what: "photons.k (gather size)",
            requested: settings.k as usize,
            capacity: K,
        });
    }
    let k = (!settings.fixed_radius).then_some(settings.k as usize);
    let gather = (k, settings.max_radius, settings.cone);
    Ok(KdStore::within_box(tree, unit, gather, bounds))
}

impl Photon {
    /// The empty photon, for initialising arrays.
    pub const ZERO: Photon = Photon::zeroed();
}

//! The forward pass's one loop: the [`Emitter`] of each light's photons, [`forward`]
//! over them in emission order, and the two ways of keeping what it stores
//! ([`for_each_photon`], [`shoot_with_splats`]).

use super::emit::Emission;
use super::{reach, splat, trace, Photon, PhotonSettings, Splat, SplatStorage, THINNING};
use crate::error::{within, Error};
use crate::geometry::Ray;
use crate::math::{Rgb, UnitVec3};
use crate::sampling::{hash, mix64, thinning_level, unit_f32, PathSampler};
use crate::scene::Scene;

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
    /// if it is stored ([`KdStore::with_coarse_levels`](super::KdStore::with_coarse_levels)):
    /// a function of `(seed, pass, l, i)` alone, not of where photons land, so each
    /// photon of level `v` stands for [`THINNING`]`ᵛ` of the map's. The point's index
    /// in its cone's Hammersley set is thinned by [`thinning_level`] with a choice drawn
    /// per half: unbiased, and the points kept stratified in both of the set's
    /// coordinates. Every 16th stored photon, as these levels were first taken, kept one
    /// sixteenth of each cone's azimuth where nearly every photon lands (a floor seen in
    /// a mirror read twice its value, `docs/accuracy.md`), and one half's photons.
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
                    h.plan
                        .photons::<{ super::emit::LANES }>(light, j >> 1, h.shift)
                });
                let block = (range.end - i).min(2 * super::emit::LANES as u32);
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

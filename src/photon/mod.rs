//! The forward pass: photons from the lights through mirrors and glass into a
//! caustic store, and the store's estimate of the caustic light at a point.
//!
//! - [`emit`](self#emission): directions and powers (paper eq. 7, made uniform; projection maps),
//! - `trace`: one photon's path,
//! - [`kdtree`]: the left-balanced kd-tree built in place,
//! - `estimate`: the radiance estimate (Jensen; paper eq. 8).
//!
//! # Emission
//! See the `emit` module's formulas, repeated on [`shoot`].

mod emit;
mod estimate;
mod illumination;
pub mod kdtree;
mod packed;
mod trace;

pub use estimate::{ConeFilter, KdStore};
pub use illumination::{
    FixedIlluminationMaps, IlluminationMaps, MapStats, TexelStorage, DEFAULT_TRIM,
};
#[cfg(feature = "std")]
pub use illumination::{DEFAULT_HEAP_TEXELS, MAX_HEAP_TEXELS};
pub use kdtree::{
    balance, balance_finish, balance_subtree, balance_top, KdTree, Neighbor, Subtree,
};
pub use packed::Photon;

use emit::Emission;

use crate::error::{in_range, positive, Error};
use crate::geometry::Ray;
use crate::material::Classic;
use crate::math::{Rgb, UnitVec3, Vec3};
use crate::sampling::{hash, unit_f32, Pcg32};
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
        })
    }

    /// With Jensen's cone filter.
    pub fn with_cone_filter(mut self, cone: Option<ConeFilter>) -> Self {
        self.cone = cone;
        self
    }

    /// Emits over the light's whole sphere instead of through projection maps
    /// (for measuring what the projection maps save).
    pub fn with_full_sphere(mut self, full_sphere: bool) -> Self {
        self.full_sphere = full_sphere;
        self
    }

    /// Also stores photons at their first (direct) hit: the map then holds direct
    /// light too. For tests of the density estimate; never for rendering, where direct
    /// light comes from shadow rays.
    pub fn with_direct_photons(mut self, store_direct: bool) -> Self {
        self.store_direct = store_direct;
        self
    }

    /// Gathers every photon within `max_radius` instead of the `k` nearest: the
    /// estimate of progressive photon mapping, whose radius shrinks pass by pass.
    pub fn with_fixed_radius(mut self, fixed_radius: bool) -> Self {
        self.fixed_radius = fixed_radius;
        self
    }

    /// `true` when every photon within `max_radius` is gathered.
    pub fn fixed_radius(&self) -> bool {
        self.fixed_radius
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
    /// The cone filter, if any.
    pub fn cone_filter(&self) -> Option<ConeFilter> {
        self.cone
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
/// Photon `i` of light `l` in pass `pass` draws its direction from a Hammersley set
/// shifted by `hash(seed, pass, l)` and its random choices from a PCG32 stream keyed by
/// `hash(seed, pass, l, i)`. A scene with no mirror, glass or reflective/transparent
/// classic object emits nothing, and so does a dark light.
#[derive(Clone, Debug)]
pub struct Emitter<'a, const O: usize, const L: usize> {
    scene: &'a Scene<O, L>,
    settings: PhotonSettings,
    seed: u64,
    pass: u32,
    /// Per light: its emission plan and the point set's shift.
    plans: heapless::Vec<(Emission<O>, (f32, f32)), L>,
    unit: f32,
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
            let plan = Emission::<O>::plan(scene, light, count, full_sphere);
            if count > 0 {
                unit = unit.max(plan.nominal_power(light));
            }
            let key = hash(&[seed, pass as u64, l as u64]);
            // Cannot overflow: one plan per light, at most L lights.
            let _ = plans.push((plan, (unit_f32(key as u32), unit_f32((key >> 32) as u32))));
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
        }
    }

    /// Power of one unit of stored photon power, W (0 when nothing is emitted).
    pub fn power_unit(&self) -> f32 {
        self.unit
    }

    /// Photons light `l` emits (0 for a dark light or when nothing is emitted).
    pub fn count(&self, l: usize) -> u32 {
        self.plans.get(l).map_or(0, |p| p.0.count())
    }

    /// Photons emitted by all lights.
    pub fn emitted(&self) -> u64 {
        (0..self.plans.len()).map(|l| self.count(l) as u64).sum()
    }

    /// Traces photon `i` of light `l` (`i < count(l)`): where it is stored, if anywhere.
    pub fn photon(&self, l: usize, i: u32) -> Option<Photon> {
        let (emission, shift) = self.plans.get(l)?;
        let light = &self.scene.lights()[l];
        let (dir, power) = emission.photon(light, i, *shift);
        let mut rng = Pcg32::new(hash(&[self.seed, self.pass as u64, l as u64, i as u64]));
        let ray = Ray::new(light.position(), dir);
        let s = &self.settings;
        let hit = trace::trace(
            self.scene,
            ray,
            power,
            s.max_depth,
            s.store_direct,
            &mut rng,
        )?;
        Some(Photon::new(hit.pos, hit.dir, hit.power * (1.0 / self.unit)).on_surface(hit.object))
    }
}

/// The forward pass of [`shoot`], handing each photon it would store to `f` instead of
/// writing it to an array: the same photons, in the same order, with the same power
/// unit. Needs no photon memory at all (the illumination maps splat as they go).
pub fn for_each_photon<const O: usize, const L: usize>(
    scene: &Scene<O, L>,
    settings: &PhotonSettings,
    seed: u64,
    pass: u32,
    mut f: impl FnMut(&Photon),
) -> ForwardStats {
    let emitter = Emitter::new(scene, settings, seed, pass);
    let mut stats = ForwardStats {
        emitted: emitter.emitted(),
        stored: 0,
        power_unit: emitter.power_unit(),
    };
    for l in 0..scene.lights().len() {
        for i in 0..emitter.count(l) {
            if let Some(p) = emitter.photon(l, i) {
                f(&p);
                stats.stored += 1;
            }
        }
    }
    stats
}

/// The forward pass: shoots `settings.count` photons from each light (see [`Emitter`])
/// and stores those that land on a diffuse surface after a specular bounce, in
/// emission order, into `out[..stored]` (not yet balanced). An error when `out` cannot
/// hold `count × lights` photons.
pub fn shoot<const O: usize, const L: usize>(
    scene: &Scene<O, L>,
    settings: &PhotonSettings,
    seed: u64,
    pass: u32,
    out: &mut [Photon],
) -> Result<ForwardStats, Error> {
    let needed = photons_needed(scene, settings);
    if needed > out.len() {
        return Err(Error::Capacity {
            what: "photons (count × lights)",
            requested: needed,
            capacity: out.len(),
        });
    }
    let mut n = 0;
    let stats = for_each_photon(scene, settings, seed, pass, |p| {
        out[n] = *p;
        n += 1;
    });
    Ok(stats)
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

    /// Runs the forward pass into this map and balances it: see [`shoot`].
    pub fn build<const O: usize, const L: usize>(
        &mut self,
        scene: &Scene<O, L>,
        settings: &PhotonSettings,
        seed: u64,
    ) -> Result<ForwardStats, Error> {
        self.build_pass(scene, settings, seed, 0)
    }

    /// As [`build`](Self::build), for progressive pass number `pass`.
    pub fn build_pass<const O: usize, const L: usize>(
        &mut self,
        scene: &Scene<O, L>,
        settings: &PhotonSettings,
        seed: u64,
        pass: u32,
    ) -> Result<ForwardStats, Error> {
        self.len = 0;
        let stats = shoot(scene, settings, seed, pass, &mut self.photons)?;
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
    if !settings.fixed_radius && settings.k as usize > K {
        return Err(Error::Capacity {
            what: "photons.k (gather size)",
            requested: settings.k as usize,
            capacity: K,
        });
    }
    let k = (!settings.fixed_radius).then_some(settings.k as usize);
    Ok(KdStore::new(
        tree,
        unit,
        k,
        settings.max_radius,
        settings.cone,
    ))
}

impl Photon {
    /// The empty photon, for initialising arrays.
    pub const ZERO: Photon = Photon::zeroed();
}

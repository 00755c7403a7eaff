//! The forward pass: photons from the lights through mirrors and glass into a
//! caustic store, and the store's estimate of the caustic light at a point.
//!
//! - [`emit`](self#emission): directions and powers (paper eq. 7, made uniform; projection maps),
//! - `forward`: the one loop of every forward pass ([`Emitter`], [`forward()`]),
//! - `trace`: one photon's path,
//! - `kdtree`: the kd-tree built in place, in-order with bucket leaves ([`KdTree`], [`balance`]),
//! - `estimate`: the radiance estimate (Jensen; paper eq. 8).
//!
//! # Emission
//! See the `emit` module's formulas, repeated on [`shoot_with_splats`].

mod emit;
mod estimate;
mod footprint;
mod forward;
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
pub use forward::{
    for_each_photon, forward, photons_needed, shoot_with_splats, Emitter, ForwardStats, Landed,
};
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

use crate::error::{in_range, positive, Error};
use crate::material::Classic;
use crate::math::{Rgb, UnitVec3, Vec3};
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

//! The device's budget, stated once: what a microcontroller build holds and how much
//! work it does, in `const`s that the firmware, the host tests and the simulator all
//! read (they used to copy the numbers by hand).
//!
//! Like embedded-graphics' `Framebuffer`, whose buffer size is a `const fn` of its
//! dimensions checked at compile time, every capacity here is a constant and the
//! memory it implies is asserted at compile time:
//!
//! - [`DeviceBudget`]: image size, photons emitted per light, photons *stored* (the
//!   map's capacity: most emitted photons never land in a caustic), gather size `K`,
//!   path stack `DEPTH`, gather radius and seed;
//! - [`DeviceMap`]: a photon map sized to what is stored, not to what is emitted;
//!   `size_of::<DeviceMap<N>>()` is its whole memory;
//! - [`DeviceMemory`]: everything a device render keeps in RAM outside the stack
//!   (scene, map, one row), so `size_of` tells the whole static memory;
//! - [`ErrorFigure`]: the render's estimate of its own error as the firmware prints
//!   it, formatted with integer arithmetic (the host prints the same digits).
//!
//! ```
//! use caustic::budget::{DeviceMemory, FIG6};
//! // Fig. 6 on a device: the scene, a map of FIG6.stored photons and FIG6.splats
//! // splats, one row of 160 pixels with their error estimates.
//! type Fig6 = DeviceMemory<2, 1, { FIG6.stored }, { FIG6.splats }, { FIG6.width as usize }>;
//! let bytes = core::mem::size_of::<Fig6>();
//! assert!(bytes <= 28 * 1024, "{bytes}");
//! ```

use crate::error::Error;
use crate::photon::{
    self, balance, CausticStore, ForwardStats, KdStore, KdTree, Photon, PhotonSettings, Splat,
    SplatStorage,
};
use crate::render::{ErrorTally, PixelEstimate, Renderer};
use crate::scene::Scene;

/// A device build's capacities and work. All fields are plain constants so that they
/// can size arrays and const generics (`{ FIG6.stored }`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeviceBudget {
    /// Image width, pixels (also the row buffer's length).
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Photons emitted per light.
    pub emitted: u32,
    /// Photons the map holds: a forward pass that stores more is an error
    /// ([`Error::Capacity`]), never a truncation.
    pub stored: usize,
    /// Camera splats the map holds (photons the eye sees directly, light-traced into
    /// their pixel: the desktop's default estimator); more is an error.
    pub splats: usize,
    /// Photons per estimate (the gather buffer's capacity `K`).
    pub k: usize,
    /// Gather radius bound, scene units.
    pub max_radius: f32,
    /// Specular interactions per path, and the render's path stack `DEPTH`.
    pub depth: usize,
    /// Forward-pass seed.
    pub seed: u64,
}

impl DeviceBudget {
    /// The photon settings of this budget: [`emitted`](Self::emitted) photons per
    /// light, [`k`](Self::k), [`max_radius`](Self::max_radius), [`depth`](Self::depth),
    /// one path per photon (no [glass splitting], which a device does not compile: it
    /// would make splats beyond [`splats`](Self::splats) and cost flash), so that the
    /// host renders a budget's image bit for bit as the device does.
    ///
    /// [glass splitting]: PhotonSettings::with_glass_splitting
    pub fn settings(&self) -> Result<PhotonSettings, Error> {
        Ok(PhotonSettings::new(
            self.emitted,
            self.k as u32,
            self.max_radius,
            self.depth as u32,
        )?
        .with_glass_splitting(false))
    }
}

/// The paper's Fig. 6 (`demo::fig6`, two objects and one light) on a device:
/// 160 × 120, 2 048 photons emitted of which 533 are stored (capacity 576, 9 KiB) and
/// as many seen by the eye (splats, capacity 576), `K` = 32 within radius 1 (the cube's
/// edge is 4), 8 specular interactions, seed 0.
pub const FIG6: DeviceBudget = DeviceBudget {
    width: 160,
    height: 120,
    emitted: 2048,
    stored: 576,
    splats: 576,
    k: 32,
    max_radius: 1.0,
    depth: 8,
    seed: 0,
};
/// Objects of the Fig. 6 scene type.
pub const FIG6_OBJECTS: usize = 2;
/// Lights of the Fig. 6 scene type.
pub const FIG6_LIGHTS: usize = 1;

/// The physical scene `demo::glass` (three objects, one light) on a device: 160 × 120,
/// 2 048 photons emitted towards the sphere and the mirror, of which 1 010 land
/// (capacity 1 088) and 951 are seen by the eye (capacity 1 024), the same gather as
/// [`FIG6`] at the sphere's scale (radius 0.25).
pub const GLASS: DeviceBudget = DeviceBudget {
    width: 160,
    height: 120,
    emitted: 2048,
    stored: 1088,
    splats: 1024,
    k: 32,
    max_radius: 0.25,
    depth: 8,
    seed: 0,
};
/// Objects of the glass scene type.
pub const GLASS_OBJECTS: usize = 3;
/// Lights of the glass scene type.
pub const GLASS_LIGHTS: usize = 1;

/// Compile-time checks of a budget: something is stored, no more than is emitted, the
/// gather fits the map, and the static memory fits `ram` bytes.
pub const fn check<
    const O: usize,
    const L: usize,
    const N: usize,
    const S: usize,
    const W: usize,
>(
    b: &DeviceBudget,
    ram: usize,
) -> bool {
    b.stored == N
        && b.splats == S
        && b.width as usize == W
        && b.stored > 0
        && b.stored <= b.emitted as usize * L
        && b.k > 0
        && b.k <= b.stored
        && b.depth > 0
        && core::mem::size_of::<DeviceMemory<O, L, N, S, W>>() <= ram
}

const _: () = assert!(check::<
    FIG6_OBJECTS,
    FIG6_LIGHTS,
    { FIG6.stored },
    { FIG6.splats },
    { FIG6.width as usize },
>(&FIG6, 28 * 1024));
const _: () = assert!(check::<
    GLASS_OBJECTS,
    GLASS_LIGHTS,
    { GLASS.stored },
    { GLASS.splats },
    { GLASS.width as usize },
>(&GLASS, 44 * 1024));
const _: () = assert!(core::mem::size_of::<Photon>() <= 16);

/// A photon map that holds at most `STORED` photons of a forward pass that may emit
/// many more (sized to what lands, not to what is shot), and at most `SPLATS` camera
/// splats. Its whole memory is `size_of::<DeviceMap<STORED, SPLATS>>()` (16 bytes a
/// photon, 16 a splat, and a few words).
#[derive(Clone, Debug)]
pub struct DeviceMap<const STORED: usize, const SPLATS: usize> {
    photons: [Photon; STORED],
    len: usize,
    unit: f32,
    splats: heapless::Vec<Splat, SPLATS>,
    /// Whether the last build connected photons to the eye.
    splatted: bool,
}

impl<const STORED: usize, const SPLATS: usize> Default for DeviceMap<STORED, SPLATS> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const STORED: usize, const SPLATS: usize> DeviceMap<STORED, SPLATS> {
    /// An empty map (const: it can be a `static`, in `.bss`).
    pub const fn new() -> Self {
        Self {
            photons: [Photon::ZERO; STORED],
            len: 0,
            unit: 0.0,
            splats: heapless::Vec::new(),
            splatted: false,
        }
    }

    /// Runs the forward pass (`photon::forward`, pass 0: the photons `PhotonMap::build`
    /// stores, in the same order, and with `settings.camera_splats()` the splats of
    /// those the eye sees) into this map and balances it. An [`Error::Capacity`] when
    /// more than `STORED` photons land or more than `SPLATS` are seen; the map is then
    /// empty.
    pub fn build<const O: usize, const L: usize>(
        &mut self,
        scene: &Scene<O, L>,
        settings: &PhotonSettings,
        seed: u64,
    ) -> Result<ForwardStats, Error> {
        let (photons, len, splats) = (&mut self.photons, &mut self.len, &mut self.splats);
        *len = 0;
        splats.clear_splats();
        let result = photon::forward(scene, settings, seed, 0, |x| {
            if let Some(p) = x.photon {
                let slot = photons.get_mut(*len).ok_or(Error::Capacity {
                    what: "photons stored (budget::DeviceBudget::stored)",
                    requested: *len + 1,
                    capacity: STORED,
                })?;
                *slot = p;
                *len += 1;
            }
            match x.splat {
                Some(s) => splats.push_splat(s),
                None => Ok(()),
            }
        });
        let stats = match result {
            Ok(stats) => stats,
            Err(e) => {
                self.len = 0;
                self.splats.clear();
                return Err(e);
            }
        };
        self.unit = stats.power_unit;
        self.splatted = settings.camera_splats();
        balance(&mut self.photons[..self.len]);
        Ok(stats)
    }

    /// The camera splats of the last build (empty when it did not splat).
    pub fn splats(&self) -> &[Splat] {
        &self.splats
    }

    /// `renderer` with this map's splats when the build made them (the caustics seen
    /// directly are then light-traced, the store gathers only behind glass and in
    /// mirrors); unchanged otherwise (the store gathers at every diffuse hit).
    pub fn with_splats<'a, S: CausticStore, const O: usize, const L: usize, const D: usize>(
        &'a self,
        renderer: Renderer<'a, S, O, L, D>,
    ) -> Renderer<'a, S, O, L, D> {
        if self.splatted {
            renderer.with_splats(&self.splats)
        } else {
            renderer
        }
    }

    /// Photons stored.
    pub fn len(&self) -> usize {
        self.len
    }

    /// `true` when no photon is stored.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The balanced tree.
    pub fn tree(&self) -> KdTree<'_> {
        KdTree::from_balanced(&self.photons[..self.len])
    }

    /// The caustic store over this map, gathering up to `K` photons, and stating that
    /// it holds at most `STORED` (with `STORED ≤` [`FOOTPRINT_VISITS`](photon::FOOTPRINT_VISITS),
    /// as in [`FIG6`], the footprint gather is one search); an error when `settings.k`
    /// exceeds `K`.
    pub fn store<const K: usize>(
        &self,
        settings: &PhotonSettings,
    ) -> Result<KdStore<'_, K, STORED>, Error> {
        let store: KdStore<'_, K> = photon::store_over(self.tree(), self.unit, settings)?;
        // The tree is `photons[..len]`, and `len ≤ STORED`.
        store.holding_at_most().ok_or(Error::Capacity {
            what: "photons stored",
            requested: self.len,
            capacity: STORED,
        })
    }
}

/// Everything a device render keeps in RAM outside the stack: the scene (`O` objects,
/// `L` lights), the photon map (`N` photons, `S` splats) and one row of `W` pixels
/// (each with its caustic part and error terms, for the error estimate).
/// The firmware keeps the map and the row in statics and the scene on the stack; this
/// type only states the sum, so that `size_of` gives it.
#[derive(Debug)]
pub struct DeviceMemory<
    const O: usize,
    const L: usize,
    const N: usize,
    const S: usize,
    const W: usize,
> {
    /// The scene.
    pub scene: Scene<O, L>,
    /// The photon map.
    pub map: DeviceMap<N, S>,
    /// One row of pixels: linear radiance and its estimated error.
    pub row: [PixelEstimate; W],
}

/// A render's estimate of its own error ([`ErrorTally`]) as a device prints it:
/// `rel_rmse=0.0123 rel_rmse_caustic=0.0456`, each rounded half up to four decimals
/// (`none` where the figure is undefined: a black image, no caustic pixel).
///
/// Formatted with integer arithmetic only (float formatting would cost a device about
/// 16 KiB of flash), and from the tally's `f64` sums, which the host and the device
/// compute bit for bit alike: the host prints the same digits.
///
/// ```
/// use caustic::budget::ErrorFigure;
/// use caustic::render::ErrorTally;
/// assert_eq!(
///     ErrorFigure(ErrorTally::default()).to_string(),
///     "rel_rmse=none rel_rmse_caustic=none"
/// );
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorFigure(pub ErrorTally);

impl core::fmt::Display for ErrorFigure {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("rel_rmse=")?;
        fixed4(f, self.0.rel_rmse())?;
        f.write_str(" rel_rmse_caustic=")?;
        fixed4(f, self.0.rel_rmse_caustic())
    }
}

/// `x ≥ 0` rounded half up to four decimals (saturating at 429 496.7295), or `none`.
fn fixed4(f: &mut core::fmt::Formatter<'_>, x: Option<f64>) -> core::fmt::Result {
    match x {
        Some(x) => {
            let n = (x * 10_000.0 + 0.5) as u32;
            write!(f, "{}.{:04}", n / 10_000, n % 10_000)
        }
        None => f.write_str("none"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo;
    use crate::photon::PhotonMap;

    #[test]
    fn the_device_map_stores_what_the_emitted_sized_map_stores() {
        let scene = demo::fig6::<FIG6_OBJECTS, FIG6_LIGHTS>(16, 12).unwrap();
        let settings = FIG6.settings().unwrap();
        let mut small: DeviceMap<{ FIG6.stored }, { FIG6.splats }> = DeviceMap::new();
        let mut full: PhotonMap<{ FIG6.emitted as usize }> = PhotonMap::new();
        let a = small.build(&scene, &settings, FIG6.seed).unwrap();
        let b = full.build(&scene, &settings, FIG6.seed).unwrap();
        assert_eq!(a, b);
        assert_eq!(small.tree().photons(), full.tree().photons());
        // The eye sees the caustic on the field: splats, within the budget.
        assert!(settings.camera_splats());
        assert!(!small.splats().is_empty() && small.splats().len() <= FIG6.splats);
        assert!(
            a.stored <= FIG6.stored && a.stored > FIG6.stored * 3 / 4,
            "{}",
            a.stored
        );
    }

    /// The device's store (its map's capacity stated, `FIG6.stored ≤ FOOTPRINT_VISITS`:
    /// one search per footprint, no reach test) gathers, bit for bit, what the desktop's
    /// store over the same tree gathers (the chain of segments and levels), for
    /// footprints from a hair to past the gather radius, square and slivers along
    /// either axis, at every stored photon of the field and beyond the photons' reach;
    /// and a store that holds more than it states is refused.
    #[test]
    fn the_capped_store_gathers_the_footprints_the_desktop_store_gathers() {
        use crate::material::Classic;
        use crate::math::{Rgb, UnitVec3, Vec3};
        use crate::photon::Footprint;
        let scene = demo::fig6::<FIG6_OBJECTS, FIG6_LIGHTS>(16, 12).unwrap();
        let settings = FIG6.settings().unwrap();
        let mut map: DeviceMap<{ FIG6.stored }, { FIG6.splats }> = DeviceMap::new();
        map.build(&scene, &settings, FIG6.seed).unwrap();
        let capped: KdStore<'_, { FIG6.k }, { FIG6.stored }> = map.store(&settings).unwrap();
        let free: KdStore<'_, { FIG6.k }> =
            photon::store_over(map.tree(), map.unit, &settings).unwrap();
        assert!(free.holding_at_most::<{ FIG6.stored }>().is_some());
        assert!(free.holding_at_most::<16>().is_none());
        let classic = Classic::new(Rgb::ONE, 0.7, 0.2, 0.8, 20.0, 0.0, 0.0, 1.0);
        let (up, eye) = (
            UnitVec3::Y,
            UnitVec3::new(Vec3::new(0.3, 1.0, 0.5)).unwrap(),
        );
        let mut lit = 0;
        let far = [Vec3::new(40.0, -5.0, 0.0)];
        let points = map.tree().photons().iter().map(|p| p.position()).chain(far);
        for (i, x) in points.enumerate() {
            let s = [1e-3, 0.05, 0.3, 0.9, 3.0][i % 5];
            let sliver = [1.0, 1.0, 8.0, 0.125, 40.0][i / 5 % 5];
            let f = Footprint {
                a: Vec3::new(s, 0.0, 0.1 * s),
                b: Vec3::new(-0.1 * s, 0.0, s * sliver),
                throughput: 1.0,
                direct: 0.0,
                curvature: 0.0,
                visits: crate::photon::FOOTPRINT_VISITS,
            };
            let (e, c) = (
                capped.irradiance_within(x, up, &f),
                free.irradiance_within(x, up, &f),
            );
            assert_eq!(e, c, "irradiance at {x}, footprint {f:?}");
            lit += usize::from(!e.total.is_black());
            let k = |s: &dyn CausticStore| s.classic_within(x, up, eye, &classic, &f);
            assert_eq!(k(&capped), k(&free), "classic at {x}, footprint {f:?}");
        }
        assert!(lit > 100, "{lit}");
    }

    #[test]
    fn the_glass_budget_holds_what_lands_with_a_margin() {
        let scene = demo::glass::<GLASS_OBJECTS, GLASS_LIGHTS>(GLASS.width, GLASS.height).unwrap();
        let settings = GLASS.settings().unwrap();
        let mut map: DeviceMap<{ GLASS.stored }, { GLASS.splats }> = DeviceMap::new();
        let f = map.build(&scene, &settings, GLASS.seed).unwrap();
        assert!(
            f.stored <= GLASS.stored && f.stored > GLASS.stored * 9 / 10,
            "{}",
            f.stored
        );
        let seen = map.splats().len();
        assert!(
            seen <= GLASS.splats && seen > GLASS.splats * 9 / 10,
            "{seen}"
        );
    }

    #[test]
    fn the_error_figure_is_the_tallys_ratio_to_four_decimals() {
        extern crate std;
        use crate::math::Rgb;
        use std::string::ToString;
        let lit = PixelEstimate {
            radiance: Rgb::ONE,
            caustic: Rgb::ONE,
            split: Rgb::new(0.01, 0.0, 0.0),
            sampling2: Rgb::ZERO,
        };
        let plain = PixelEstimate {
            radiance: Rgb::ONE,
            ..PixelEstimate::default()
        };
        let mut t = ErrorTally::default();
        t.add_row(&[lit, plain]);
        // sqrt(1e-4 · 3 · 2) / 6 = 0.0040825; the caustic pixel alone: sqrt(3e-4)/3 = 0.0057735.
        assert_eq!(
            ErrorFigure(t).to_string(),
            "rel_rmse=0.0041 rel_rmse_caustic=0.0058"
        );
        let mut dark = ErrorTally::default();
        dark.add_row(&[plain]);
        assert_eq!(
            ErrorFigure(dark).to_string(),
            "rel_rmse=0.0000 rel_rmse_caustic=none"
        );
        // Whole units and the carry of a rounding: 1.23456 -> 1.2346, 0.99996 -> 1.0000.
        struct Show(f64);
        impl core::fmt::Display for Show {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                fixed4(f, Some(self.0))
            }
        }
        assert_eq!(Show(1.23456).to_string(), "1.2346");
        assert_eq!(Show(0.99996).to_string(), "1.0000");
    }

    #[test]
    fn a_map_too_small_is_an_error_not_a_truncation() {
        let scene = demo::fig6::<FIG6_OBJECTS, FIG6_LIGHTS>(16, 12).unwrap();
        let settings = FIG6.settings().unwrap();
        let mut tiny: DeviceMap<100, 600> = DeviceMap::new();
        match tiny.build(&scene, &settings, FIG6.seed) {
            Err(Error::Capacity {
                requested,
                capacity: 100,
                ..
            }) => assert_eq!(requested, 101),
            other => panic!("{other:?}"),
        }
        assert!(tiny.is_empty());
        let mut blind: DeviceMap<600, 10> = DeviceMap::new();
        match blind.build(&scene, &settings, FIG6.seed) {
            Err(Error::Capacity {
                requested: 11,
                capacity: 10,
                ..
            }) => {}
            other => panic!("{other:?}"),
        }
        assert!(blind.is_empty() && blind.splats().is_empty());
    }
}

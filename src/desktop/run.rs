//! Rendering on the desktop: passes of the forward pass ([`super::photons`]) and of the
//! backward pass (rows over threads), each pixel with its estimated error.
//!
//! Rows are pure functions of `(scene, store, y)`, and the forward pass a pure function
//! of `(scene, settings, seed, pass)`, so the image is bit-identical whatever the
//! number of threads: threads only change the order in which rows are computed.

use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};
use std::vec;

use serde::Serialize;

use super::image::Image;
use super::photons::{desktop_budget, PhotonBuffer};
use super::progress::Progress;
use super::rows::render_rows;
use super::{DesktopScene, MAX_DEPTH, MAX_GATHER};
use crate::material::Classic;
use crate::math::{Rgb, UnitVec3, Vec3};
use crate::photon::{self, CausticStore, Footprint, Halves, Photon, PhotonSettings, SplatSums};
use crate::render::{ErrorTally, PixelEstimate, RayCount, Renderer, Sampling, REFINE};
use crate::Error;

/// How to render on the desktop.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    /// Seed of the forward pass.
    pub seed: u64,
    /// Worker threads (≥ 1).
    pub threads: usize,
    /// Draw a progress bar on stderr (only when it is a terminal).
    pub progress: bool,
    /// Progressive passes (Knaus & Zwicker 2011), ≥ 1.
    pub passes: u32,
    /// Radius shrink exponent α of the passes: `r_i² = r_1²·i^(α−1)`.
    pub alpha: f32,
    /// How each pixel's area is sampled (default: adaptive, corners then a 4 × 4 grid).
    pub sampling: Sampling,
    /// The cap on rays (eye and shadow) per camera ray (`--max-rays`,
    /// `image.max_rays_per_sample`; issue 16): see [`Renderer::with_ray_budget`].
    /// `None`: [`DEFAULT_RAY_BUDGET`](crate::render::DEFAULT_RAY_BUDGET).
    pub max_rays_per_sample: Option<u32>,
    /// Where the program writes the per-pixel estimated error as PFM (`--error-map`;
    /// see [`render_with_error`]).
    pub error_map: Option<PathBuf>,
    /// Render passes until the estimated relative RMSE is at most this, > 0
    /// (`--target-error`), instead of a fixed number of passes: see
    /// [`render_with_error`].
    pub target_error: Option<f32>,
    /// With `target_error`: start no pass after this many seconds, > 0
    /// (`--time-limit`), even if the target is not reached (reported in
    /// [`ErrorEstimate::time_limited`]; the only input that can change the image from
    /// one run to the next).
    pub time_limit: Option<f64>,
    /// Time every caustic gather for [`RenderStats::gather_cpu_ms`] (`--stats`): two
    /// clock reads and a shared counter per gather, about 1.4% of a render's wall time.
    pub time_gathers: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            seed: 0,
            threads: available_threads(),
            progress: false,
            passes: 1,
            alpha: 2.0 / 3.0,
            sampling: Sampling::Adaptive(REFINE),
            max_rays_per_sample: None,
            error_map: None,
            target_error: None,
            time_limit: None,
            time_gathers: false,
        }
    }
}

/// The machine's parallelism.
pub fn available_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// What a render did and how long each phase took.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Threads used.
    pub threads: usize,
    /// Passes rendered.
    pub passes: u32,
    /// Photon emission and tracing, ms (all passes).
    pub emit_ms: f64,
    /// kd-tree balancing, ms.
    pub balance_ms: f64,
    /// The backward pass, wall ms (includes gathering).
    pub render_ms: f64,
    /// Time inside caustic gathers, summed over threads, ms of CPU (0 unless
    /// [`RenderOptions::time_gathers`]).
    pub gather_cpu_ms: f64,
    /// Rays traced.
    pub rays: RayCount,
    /// Photons emitted.
    pub photons_emitted: u64,
    /// Photons stored (all passes).
    pub photons_stored: u64,
    /// Photons the camera sees directly, splatted into their pixels (all passes).
    pub photons_splatted: u64,
    /// What the render estimates its own error to be.
    pub error: ErrorEstimate,
}

/// What a render estimates its own error to be (see [`crate::render::PixelEstimate`]):
/// the relative RMSE `sqrt(mean((a − b)²))/mean(b)` of the image `a` against the
/// converged image `b`, over pixels and channels, from the halves of each pass's
/// photons and the checkerboard halves of each supersampled pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ErrorEstimate {
    /// Over the whole image; `None` for a black image.
    pub rel_rmse: Option<f64>,
    /// Over the pixels whose caustic part is at least a tenth of their luminance;
    /// `None` when there are none.
    pub rel_rmse_caustic: Option<f64>,
    /// Pixels in that caustic region.
    pub caustic_pixels: u64,
    /// The `--target-error` asked for, if any.
    pub target: Option<f32>,
    /// With a target: whether the estimate reached it.
    pub reached: Option<bool>,
    /// With a target: the time limit stopped the passes first.
    pub time_limited: bool,
}

impl ErrorEstimate {
    /// This estimate, with the target fields of `run` (what the passes were asked for).
    fn with_target_of(self, run: &Self) -> Self {
        Self {
            target: run.target,
            reached: run.reached,
            time_limited: run.time_limited,
            ..self
        }
    }

    fn from_tally(t: &ErrorTally) -> Self {
        Self {
            rel_rmse: t.rel_rmse(),
            rel_rmse_caustic: t.rel_rmse_caustic(),
            caustic_pixels: t.caustic_pixels(),
            ..Self::default()
        }
    }
}

/// A store that times its gathers (summed over threads) when `on`.
struct Timed<'a, S> {
    inner: &'a S,
    nanos: AtomicU64,
    on: bool,
}

impl<S> Timed<'_, S> {
    fn time<T>(&self, f: impl FnOnce() -> T) -> T {
        if !self.on {
            return f();
        }
        let t = Instant::now();
        let v = f();
        self.nanos
            .fetch_add(t.elapsed().as_nanos() as u64, Ordering::Relaxed);
        v
    }
}

// Every method forwarded, none left to the trait's default: a default would answer
// for the inner store silently (a pixel-centre gather in place of its footprint's).
#[deny(clippy::missing_trait_methods)]
impl<S: CausticStore> CausticStore for Timed<'_, S> {
    fn reads_direct(&self) -> bool {
        self.inner.reads_direct()
    }
    fn irradiance(&self, x: Vec3, n: UnitVec3) -> Rgb {
        self.time(|| self.inner.irradiance(x, n))
    }
    fn classic(&self, x: Vec3, n: UnitVec3, to_eye: UnitVec3, m: &Classic) -> Rgb {
        self.time(|| self.inner.classic(x, n, to_eye, m))
    }
    fn reaches(&self, x: Vec3) -> bool {
        self.inner.reaches(x)
    }
    fn irradiance_within(&self, x: Vec3, n: UnitVec3, f: &Footprint) -> Halves {
        self.time(|| self.inner.irradiance_within(x, n, f))
    }
    fn classic_within(
        &self,
        x: Vec3,
        n: UnitVec3,
        e: UnitVec3,
        m: &Classic,
        f: &Footprint,
    ) -> Halves {
        self.time(|| self.inner.classic_within(x, n, e, m, f))
    }
}

pub(super) fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// A finished render: the image, its per-pixel estimated error (the square root of
/// [`PixelEstimate::error2`] per channel) and what it did.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// Linear radiance.
    pub image: Image,
    /// Estimated error of each pixel and channel, the same units.
    pub error: Image,
    /// Statistics, with [`RenderStats::error`].
    pub stats: RenderStats,
}

/// Frames of pixel estimates summed over passes. The mean of `P` passes has the
/// caustic light tracer's squared error `Σ_p split_p²/P²` (the passes are independent)
/// and likewise `Σ_p sampling2_p/P²`: a supersampled pixel's checkerboard halves differ
/// mostly by the gathers behind glass, which see new photons every pass. (The part of
/// that difference that is the grid's own aliasing repeats from pass to pass and is
/// underestimated this way as passes add up.)
struct Passes {
    width: usize,
    radiance: vec::Vec<Rgb>,
    caustic: vec::Vec<Rgb>,
    split2: vec::Vec<Rgb>,
    sampling2: vec::Vec<Rgb>,
    count: u32,
}

impl Passes {
    fn new(width: usize, pixels: usize) -> Self {
        let zero = || vec![Rgb::ZERO; pixels];
        Self {
            width,
            radiance: zero(),
            caustic: zero(),
            split2: zero(),
            sampling2: zero(),
            count: 0,
        }
    }

    fn add(&mut self, frame: &[PixelEstimate]) {
        for (i, p) in frame.iter().enumerate() {
            self.radiance[i] += p.radiance;
            self.caustic[i] += p.caustic;
            self.split2[i] += p.split * p.split;
            self.sampling2[i] += p.sampling2;
        }
        self.count += 1;
    }

    /// Pixel `i` of the mean of the passes so far; its `split` is the root of the
    /// passes' summed squares over `P` (a magnitude, the sign is gone).
    fn pixel(&self, i: usize) -> PixelEstimate {
        let inv = 1.0 / self.count.max(1) as f32;
        let s = self.split2[i];
        PixelEstimate {
            radiance: self.radiance[i] * inv,
            caustic: self.caustic[i] * inv,
            split: Rgb::new(libm::sqrtf(s.r), libm::sqrtf(s.g), libm::sqrtf(s.b)) * inv,
            sampling2: self.sampling2[i] * (inv * inv),
        }
    }

    /// The error tally of the mean, row by row (the device's order).
    fn tally(&self) -> ErrorTally {
        let mut t = ErrorTally::default();
        let mut row = vec::Vec::with_capacity(self.width);
        for start in (0..self.radiance.len()).step_by(self.width.max(1)) {
            row.clear();
            row.extend((start..start + self.width).map(|i| self.pixel(i)));
            t.add_row(&row);
        }
        t
    }

    fn images(&self, w: u32, h: u32) -> (Image, Image) {
        let (mut image, mut error) = (Image::new(w, h), Image::new(w, h));
        for i in 0..self.radiance.len() {
            let p = self.pixel(i);
            let e = p.error2();
            image.pixels[i] = p.radiance;
            error.pixels[i] = Rgb::new(libm::sqrtf(e.r), libm::sqrtf(e.g), libm::sqrtf(e.b));
        }
        (image, error)
    }
}

/// Most passes `--target-error` renders.
pub const MAX_TARGET_PASSES: u32 = 256;

/// Renders `scene` with the forward and backward passes, on `opts.threads` threads:
/// [`render_with_error`] without the error image.
pub fn render(
    scene: &DesktopScene,
    settings: &PhotonSettings,
    opts: &RenderOptions,
) -> Result<(Image, RenderStats), Error> {
    render_with_error(scene, settings, opts).map(|r| (r.image, r.stats))
}

/// Renders `scene` in `opts.passes` passes — or, with `opts.target_error`, in passes
/// until the estimated relative RMSE is at most the target (at most
/// [`MAX_TARGET_PASSES`], or until `opts.time_limit`) — each a forward pass of
/// `settings.count()` photons per light with its own seed and a backward pass, and
/// averages them (progressive photon mapping, Knaus & Zwicker 2011: the gathers' radius
/// shrinks as `r_i² = r_1²·i^(α−1)`). The stopping test reads only deterministic
/// numbers, so the same target gives the same bits on any thread count.
pub fn render_with_error(
    scene: &DesktopScene,
    settings: &PhotonSettings,
    opts: &RenderOptions,
) -> Result<Rendered, Error> {
    let t0 = Instant::now();
    let cam = scene.camera();
    let (w, h) = (cam.width(), cam.height());
    let threads = opts.threads.max(1);
    let passes = match opts.target_error {
        Some(_) => MAX_TARGET_PASSES,
        None => opts.passes.max(1),
    };
    let mut stats = RenderStats {
        width: w,
        height: h,
        threads,
        ..RenderStats::default()
    };
    let progress = Progress::new(
        opts.progress,
        if opts.target_error.is_some() {
            1
        } else {
            passes
        },
    );
    // Without splats, progressive passes gather with a fixed radius (a k-nearest
    // radius would not shrink with the passes, and the average would keep its bias);
    // with them the gather is over each sample's own patch of surface, which every
    // pass estimates without a radius to shrink.
    let fixed = settings.fixed_radius() || (passes > 1 && !settings.camera_splats());
    let settings = &settings.with_fixed_radius(fixed);
    let mut photons = PhotonBuffer::for_budget(scene, settings)?;
    let mut sum = Passes::new(w as usize, w as usize * h as usize);
    for pass in 0..passes {
        // Knaus & Zwicker (2011): r_i² = r_1²·i^(α−1), i = 1, 2, …
        let shrink = if settings.camera_splats() {
            1.0
        } else {
            libm::powf((pass + 1) as f32, 0.5 * (opts.alpha - 1.0))
        };
        let pass_settings = settings.with_max_radius(settings.max_radius() * shrink)?;
        photons.fill(
            scene,
            &pass_settings,
            opts.seed,
            pass,
            threads,
            &mut stats,
            &progress,
        )?;
        let store = photons.store::<MAX_GATHER>(&pass_settings)?;
        let splats = settings.camera_splats().then(|| photons.splats());
        progress.phase(pass, "rows", h as usize);
        let frame = backward_pass(scene, &store, settings, splats, opts, &progress, &mut stats)?;
        sum.add(&frame);
        stats.passes = pass + 1;
        if let Some(target) = opts.target_error {
            let estimate = sum.tally().rel_rmse().unwrap_or(0.0);
            stats.error.target = Some(target);
            stats.error.reached = Some(estimate <= target as f64);
            if estimate <= target as f64 {
                break;
            }
            if opts
                .time_limit
                .is_some_and(|s| t0.elapsed().as_secs_f64() >= s)
            {
                stats.error.time_limited = true;
                break;
            }
        }
    }
    progress.finish();
    // Its 34 MB at 1.6M photons a light took 5 ms to unmap on this thread (perf): on
    // another, while this one sums the passes and writes the image. Should no thread
    // start, the closure, and with it the array, is dropped here instead of a panic.
    let _ = std::thread::Builder::new().spawn(move || drop(photons));
    stats.error = ErrorEstimate::from_tally(&sum.tally()).with_target_of(&stats.error);
    let (image, error) = sum.images(w, h);
    Ok(Rendered {
        image,
        error,
        stats,
    })
}

/// The backward pass against one caustic store on `opts.threads` threads: a frame of
/// pixel estimates, each row with the sums of its splats (the caustics seen directly)
/// added once it is rendered. Adds its time, its gather time and its rays to `stats`.
fn backward_pass<S: CausticStore + Sync>(
    scene: &DesktopScene,
    store: &S,
    settings: &PhotonSettings,
    splats: Option<&SplatSums>,
    opts: &RenderOptions,
    progress: &Progress,
    stats: &mut RenderStats,
) -> Result<vec::Vec<PixelEstimate>, Error> {
    let timed = Timed {
        inner: store,
        nanos: AtomicU64::new(0),
        on: opts.time_gathers,
    };
    let mut renderer: Renderer<'_, _, { super::MAX_OBJECTS }, { super::MAX_LIGHTS }, MAX_DEPTH> =
        Renderer::new(scene, &timed, settings.max_depth())?.with_sampling(opts.sampling)?;
    if let Some(budget) = opts.max_rays_per_sample {
        renderer = renderer.with_ray_budget(budget)?;
    }
    if splats.is_some() {
        // Only to say that the splats hold the caustics seen directly: the rows do not
        // read them, and `render_rows` adds their sums to each finished row.
        renderer = renderer.with_splats(&[]);
    }
    let t = Instant::now();
    // A dim pixel's refinement stops at 1% of REFINE_FLOOR times the image's mean.
    renderer = renderer.with_image_floor(&mut stats.rays)?;
    let cam = scene.camera();
    let mut frame = vec![PixelEstimate::default(); cam.width() as usize * cam.height() as usize];
    stats.rays += render_rows(
        &renderer,
        &mut frame,
        (cam.width() as usize, splats),
        opts.threads.max(1),
        progress,
    );
    stats.photons_splatted += splats.map_or(0, SplatSums::count);
    stats.render_ms += ms(t.elapsed());
    stats.gather_cpu_ms += timed.nanos.load(Ordering::Relaxed) as f64 * 1e-6;
    Ok(frame)
}

/// Renders `scene` with Arvo's illumination maps (texels of side `texel_size` scene
/// units) as the caustic store instead of the kd-tree: one forward pass into a photon
/// array (timed as `emit_ms`), splatted into maps sized by the layout (timed as
/// `balance_ms`, the store's build), then the backward pass. One pass only: the maps
/// have no radius to shrink. Also returns what the map build did.
/// With splats (the default) the maps serve only the diffuse points seen through glass
/// or in mirrors, like the kd-tree.
pub fn render_illumination(
    scene: &DesktopScene,
    settings: &PhotonSettings,
    opts: &RenderOptions,
    texel_size: f32,
) -> Result<(Rendered, photon::MapStats), Error> {
    if opts.passes > 1 {
        return Err(Error::Unsupported {
            what: "progressive passes with illumination maps",
        });
    }
    let cam = scene.camera();
    let (w, h) = (cam.width(), cam.height());
    let threads = opts.threads.max(1);
    let mut stats = RenderStats {
        width: w,
        height: h,
        threads,
        passes: 1,
        ..RenderStats::default()
    };
    let needed = desktop_budget(scene, settings)?;
    let progress = Progress::new(opts.progress, 1);
    progress.phase(0, "photons", 1);
    let t = Instant::now();
    let mut photons = vec![Photon::ZERO; needed];
    let mut splats = vec::Vec::new();
    let f = photon::shoot_with_splats(scene, settings, opts.seed, 0, &mut photons, &mut splats)?;
    progress.tick();
    stats.emit_ms += ms(t.elapsed());
    stats.photons_emitted = f.emitted;
    stats.photons_stored = f.stored as u64;
    progress.phase(0, "maps", 1);
    let t = Instant::now();
    let mut maps: photon::IlluminationMaps<vec::Vec<Rgb>, { super::MAX_OBJECTS }> =
        photon::IlluminationMaps::new(vec::Vec::new(), texel_size)?;
    let map_stats = maps.build_from_photons(scene, &photons[..f.stored], f.power_unit)?;
    drop(photons);
    stats.balance_ms += ms(t.elapsed());
    progress.tick();
    progress.phase(0, "rows", h as usize);
    let sums = settings.camera_splats().then(|| {
        let mut sums = SplatSums::new((w * h) as usize);
        sums.add(&splats);
        sums
    });
    let frame = backward_pass(
        scene,
        &maps,
        settings,
        sums.as_ref(),
        opts,
        &progress,
        &mut stats,
    )?;
    progress.finish();
    let mut sum = Passes::new(w as usize, frame.len());
    sum.add(&frame);
    stats.error = ErrorEstimate::from_tally(&sum.tally());
    let (image, error) = sum.images(w, h);
    Ok((
        Rendered {
            image,
            error,
            stats,
        },
        map_stats,
    ))
}

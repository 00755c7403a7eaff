//! Rendering on the desktop: the photon array on the heap, rows over threads, progress.
//!
//! Rows are pure functions of `(scene, store, y)`, and the forward pass a pure function
//! of `(scene, settings, seed, pass)`, so the image is bit-identical whatever the
//! number of threads: threads only change the order in which rows are computed.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};
use std::vec;

use super::image::Image;
use super::{DesktopScene, MAX_DEPTH, MAX_GATHER, MAX_PHOTONS};
use crate::material::Classic;
use crate::math::{Rgb, UnitVec3, Vec3};
use crate::photon::{
    self, add_to_frame, balance, photons_needed, CausticStore, Emitter, KdTree, Landed, Photon,
    PhotonSettings, Splat,
};
use crate::render::{RayCount, Renderer, Sampling, REFINE};
use crate::scene::Scene;
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
    /// The cap on eye rays per pixel, ≥ 1 (`--max-rays`, `image.max_rays_per_pixel`):
    /// every branch of a pixel's eye paths counts one ray, and a pixel stops branching
    /// at the cap (issue 16). `None`: no cap beyond `max_depth`.
    pub max_rays_per_pixel: Option<u32>,
    /// Where to write the per-pixel estimated error as PFM (`--error-map`; issue 13).
    /// Not yet read by [`render`].
    pub error_map: Option<PathBuf>,
    /// Render passes until the estimated relative RMSE is at most this, > 0
    /// (`--target-error`; issue 13), instead of a fixed budget. Not yet read by
    /// [`render`].
    pub target_error: Option<f32>,
    /// With `target_error`: stop after this many seconds, > 0 (`--time-limit`), even
    /// if the target is not reached. Not yet read by [`render`].
    pub time_limit: Option<f64>,
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
            max_rays_per_pixel: None,
            error_map: None,
            target_error: None,
            time_limit: None,
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
    /// Time inside caustic gathers, summed over threads, ms of CPU.
    pub gather_cpu_ms: f64,
    /// Rays traced.
    pub rays: RayCount,
    /// Photons emitted.
    pub photons_emitted: u64,
    /// Photons stored (all passes).
    pub photons_stored: u64,
    /// Photons the camera sees directly, splatted into their pixels (all passes).
    pub photons_splatted: u64,
}

/// A store that times its gathers (summed over threads).
struct Timed<'a, S> {
    inner: &'a S,
    nanos: AtomicU64,
}

impl<S: CausticStore> CausticStore for Timed<'_, S> {
    fn irradiance(&self, x: Vec3, n: UnitVec3) -> Rgb {
        let t = Instant::now();
        let e = self.inner.irradiance(x, n);
        self.nanos
            .fetch_add(t.elapsed().as_nanos() as u64, Ordering::Relaxed);
        e
    }
    fn classic(&self, x: Vec3, n: UnitVec3, to_eye: UnitVec3, m: &Classic) -> Rgb {
        let t = Instant::now();
        let e = self.inner.classic(x, n, to_eye, m);
        self.nanos
            .fetch_add(t.elapsed().as_nanos() as u64, Ordering::Relaxed);
        e
    }
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// The photon array of the forward pass, on the heap: allocated once for a budget and
/// refilled in place by every progressive pass (fixed memory, Knaus & Zwicker 2011).
#[derive(Debug)]
pub struct PhotonBuffer {
    photons: vec::Vec<Photon>,
    len: usize,
    unit: f32,
    splats: vec::Vec<Splat>,
}

/// Photons one forward pass of `settings` stores at most; an error beyond the desktop's
/// [`MAX_PHOTONS`].
fn desktop_budget<const O: usize, const L: usize>(
    scene: &Scene<O, L>,
    settings: &PhotonSettings,
) -> Result<usize, Error> {
    let needed = photons_needed(scene, settings);
    if needed > MAX_PHOTONS {
        return Err(Error::Capacity {
            what: "photons (count × lights)",
            requested: needed,
            capacity: MAX_PHOTONS,
        });
    }
    Ok(needed)
}

/// Balances the kd-tree on `threads` threads: the top levels on this one, then the
/// subtrees below them — disjoint ranges of the array — on all, then the permutation
/// into heap order. The same array as [`balance`], bit for bit.
fn balance_parallel(photons: &mut [Photon], threads: usize, pass: u32, progress: &Progress) {
    // Below this a thread costs more than it saves.
    const SERIAL: usize = 1 << 15;
    if threads <= 1 || photons.len() < SERIAL {
        progress.phase(pass, "balance", 1);
        balance(photons);
        progress.tick();
        return;
    }
    let n = photons.len();
    let mut subtrees = vec::Vec::new();
    // Four subtrees per thread, rounded up to a level: balances the load.
    let levels = usize::BITS - (4 * threads - 1).leading_zeros();
    progress.phase(pass, "balance", 0);
    photon::balance_top(photons, levels, |t| subtrees.push(t));
    subtrees.sort_by_key(|t| t.lo);
    progress.set_steps(subtrees.len());
    // Cut the array into the subtrees' disjoint slices.
    let mut work = vec::Vec::with_capacity(subtrees.len());
    let mut rest = &mut *photons;
    let mut at = 0;
    for t in subtrees {
        let (_, tail) = rest.split_at_mut(t.lo - at);
        let (slice, tail) = tail.split_at_mut(t.hi - t.lo);
        work.push((slice, t));
        rest = tail;
        at = t.hi;
    }
    let work = Mutex::new(work);
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| loop {
                let next = work.lock().map(|mut w| w.pop()).unwrap_or(None);
                let Some((slice, t)) = next else { break };
                photon::balance_subtree(slice, n, t);
                progress.tick();
            });
        }
    });
    // Every subtree is partitioned, and the slices' borrow of `photons` is over.
    drop(work);
    photon::balance_finish(photons);
}

/// Photons traced per work item of the parallel forward pass. Fixed, so that the order
/// of the stored photons — and so the tree and the image — does not depend on the
/// number of threads.
const CHUNK: u32 = 4096;

impl PhotonBuffer {
    /// Room for one forward pass of `settings` over `scene`; an error beyond
    /// [`MAX_PHOTONS`].
    pub fn for_budget<const O: usize, const L: usize>(
        scene: &Scene<O, L>,
        settings: &PhotonSettings,
    ) -> Result<Self, Error> {
        let needed = desktop_budget(scene, settings)?;
        Ok(Self {
            photons: vec![Photon::ZERO; needed],
            len: 0,
            unit: 0.0,
            splats: vec::Vec::new(),
        })
    }

    /// Runs forward pass `pass` into the buffer on `threads` threads and balances it,
    /// adding the times and counts to `stats`. The photons are traced in chunks of
    /// `CHUNK` and kept in emission order: the same array as the core's
    /// [`photon::shoot`], whatever the thread count.
    pub fn fill<const O: usize, const L: usize>(
        &mut self,
        scene: &Scene<O, L>,
        settings: &PhotonSettings,
        seed: u64,
        pass: u32,
        threads: usize,
        stats: &mut RenderStats,
    ) -> Result<(), Error> {
        let hidden = Progress::new(false, 1);
        self.fill_with_progress(scene, settings, seed, pass, threads, stats, &hidden)
    }

    /// [`PhotonBuffer::fill`], showing its two phases (photons, balance) on `progress`.
    #[allow(clippy::too_many_arguments)]
    pub fn fill_with_progress<const O: usize, const L: usize>(
        &mut self,
        scene: &Scene<O, L>,
        settings: &PhotonSettings,
        seed: u64,
        pass: u32,
        threads: usize,
        stats: &mut RenderStats,
        progress: &Progress,
    ) -> Result<(), Error> {
        let needed = photons_needed(scene, settings);
        if needed > self.photons.len() {
            return Err(Error::Capacity {
                what: "photons (count × lights)",
                requested: needed,
                capacity: self.photons.len(),
            });
        }
        let t = Instant::now();
        let emitter = Emitter::new(scene, settings, seed, pass);
        let items: vec::Vec<(usize, u32, u32)> = (0..scene.lights().len())
            .flat_map(|l| {
                let n = emitter.count(l);
                (0..n)
                    .step_by(CHUNK as usize)
                    .map(move |s| (l, s, (s + CHUNK).min(n)))
            })
            .collect();
        progress.phase(pass, "photons", items.len());
        let results: vec::Vec<Mutex<vec::Vec<Landed>>> =
            items.iter().map(|_| Mutex::new(vec::Vec::new())).collect();
        let next = AtomicUsize::new(0);
        std::thread::scope(|scope| {
            for _ in 0..threads.clamp(1, items.len().max(1)) {
                scope.spawn(|| loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&(l, start, end)) = items.get(k) else {
                        break;
                    };
                    let local: vec::Vec<Landed> =
                        (start..end).filter_map(|i| emitter.land(l, i)).collect();
                    if let Ok(mut slot) = results[k].lock() {
                        *slot = local;
                    }
                    progress.tick();
                });
            }
        });
        let mut stored = 0;
        self.splats.clear();
        for r in results {
            for x in r.into_inner().unwrap_or_default() {
                self.photons[stored] = x.photon;
                stored += 1;
                self.splats.extend(x.splat);
            }
        }
        stats.emit_ms += ms(t.elapsed());
        let t = Instant::now();
        balance_parallel(&mut self.photons[..stored], threads, pass, progress);
        stats.balance_ms += ms(t.elapsed());
        stats.photons_emitted += emitter.emitted();
        stats.photons_stored += stored as u64;
        stats.photons_splatted += self.splats.len() as u64;
        self.len = stored;
        self.unit = emitter.power_unit();
        Ok(())
    }

    /// The balanced tree of the last pass.
    pub fn tree(&self) -> KdTree<'_> {
        KdTree::from_balanced(&self.photons[..self.len])
    }

    /// Power of one stored unit, W.
    pub fn unit(&self) -> f32 {
        self.unit
    }

    /// The camera splats of the last pass, in emission order.
    pub fn splats(&self) -> &[Splat] {
        &self.splats
    }
}

/// Renders `scene` with the forward and backward passes, on `opts.threads` threads.
pub fn render(
    scene: &DesktopScene,
    settings: &PhotonSettings,
    opts: &RenderOptions,
) -> Result<(Image, RenderStats), Error> {
    let cam = scene.camera();
    let (w, h) = (cam.width(), cam.height());
    let threads = opts.threads.max(1);
    let passes = opts.passes.max(1);
    let mut stats = RenderStats {
        width: w,
        height: h,
        threads,
        passes,
        ..RenderStats::default()
    };
    let mut sum = Image::new(w, h);
    let progress = Progress::new(opts.progress, passes);
    // Progressive passes gather with a fixed radius (a k-nearest radius would not
    // shrink with the passes, and the average would keep its bias).
    let settings = &settings.with_fixed_radius(settings.fixed_radius() || passes > 1);
    let mut photons = PhotonBuffer::for_budget(scene, settings)?;
    let mut image = Image::new(w, h);
    for pass in 0..passes {
        // Knaus & Zwicker (2011): r_i² = r_1²·i^(α−1), i = 1, 2, …
        let shrink = libm::powf((pass + 1) as f32, 0.5 * (opts.alpha - 1.0));
        let pass_settings = settings.with_max_radius(settings.max_radius() * shrink)?;
        photons.fill_with_progress(
            scene,
            &pass_settings,
            opts.seed,
            pass,
            threads,
            &mut stats,
            &progress,
        )?;
        let store =
            photon::store_over::<MAX_GATHER>(photons.tree(), photons.unit(), &pass_settings)?;
        let splats = settings.camera_splats().then(|| photons.splats());
        progress.phase(pass, "rows", h as usize);
        backward_pass(
            scene,
            &store,
            settings,
            (splats, shrink),
            opts,
            &mut image,
            &progress,
            &mut stats,
        )?;
        for (s, p) in sum.pixels.iter_mut().zip(&image.pixels) {
            *s += *p;
        }
    }
    progress.finish();
    if passes > 1 {
        let inv = 1.0 / passes as f32;
        for p in &mut sum.pixels {
            *p = *p * inv;
        }
    }
    Ok((sum, stats))
}

/// The backward pass against one caustic store, into `image`, on `opts.threads`
/// threads, adding its time, its gather time and its rays to `stats`.
///
/// With `splats` (the camera splats of the forward pass, and the pass's radius shrink
/// factor) the store gathers only behind glass and mirrors, and the splats are added to
/// the image, in emission order, after its rows.
#[allow(clippy::too_many_arguments)]
fn backward_pass<S: CausticStore + Sync>(
    scene: &DesktopScene,
    store: &S,
    settings: &PhotonSettings,
    (splats, shrink): (Option<&[Splat]>, f32),
    opts: &RenderOptions,
    image: &mut Image,
    progress: &Progress,
    stats: &mut RenderStats,
) -> Result<(), Error> {
    let timed = Timed {
        inner: store,
        nanos: AtomicU64::new(0),
    };
    let mut renderer: Renderer<'_, _, { super::MAX_OBJECTS }, { super::MAX_LIGHTS }, MAX_DEPTH> =
        Renderer::new(scene, &timed, settings.max_depth())?
            .with_sampling(opts.sampling)?
            .with_footprint_scale(shrink);
    if let Some(splats) = splats {
        renderer = renderer.with_splats(splats);
    }
    let t = Instant::now();
    stats.rays += render_rows(&renderer, image, opts.threads.max(1), progress);
    if let Some(splats) = splats {
        add_to_frame(splats, &mut image.pixels);
    }
    stats.render_ms += ms(t.elapsed());
    stats.gather_cpu_ms += timed.nanos.load(Ordering::Relaxed) as f64 * 1e-6;
    Ok(())
}

/// Renders all rows of `image` on `threads` threads, each taking the next free row.
pub fn render_rows<S: CausticStore + Sync, const O: usize, const L: usize, const D: usize>(
    renderer: &Renderer<'_, S, O, L, D>,
    image: &mut Image,
    threads: usize,
    progress: &Progress,
) -> RayCount {
    let width = image.width as usize;
    let rows = Mutex::new(image.pixels.chunks_mut(width).enumerate());
    let total = Mutex::new(RayCount::default());
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| {
                let mut mine = RayCount::default();
                loop {
                    let next = rows.lock().map(|mut r| r.next()).unwrap_or(None);
                    let Some((y, row)) = next else { break };
                    mine += renderer.row(y as u32, row);
                    progress.tick();
                }
                if let Ok(mut t) = total.lock() {
                    *t += mine;
                }
            });
        }
    });
    total.into_inner().unwrap_or_default()
}

/// Progress on stderr (indicatif): one bar per phase of a pass — `photons` (chunks
/// traced), `balance` (subtrees balanced), `rows` (rows rendered) — with the pass, the
/// phase's name, the steps done and an ETA. Hidden unless enabled and stderr is a
/// terminal. Workers tick it from any thread.
#[derive(Debug)]
pub struct Progress {
    bar: indicatif::ProgressBar,
    passes: u32,
}

impl Progress {
    /// A bar over `passes` passes; draws nothing unless `enabled` and stderr is a
    /// terminal.
    pub fn new(enabled: bool, passes: u32) -> Self {
        let bar = if enabled && std::io::stderr().is_terminal() {
            indicatif::ProgressBar::with_draw_target(None, indicatif::ProgressDrawTarget::stderr())
        } else {
            indicatif::ProgressBar::hidden()
        };
        let template = "{prefix:>16} [{bar:30}] {pos}/{len} {elapsed:>4} ETA {eta}";
        if let Ok(style) = indicatif::ProgressStyle::with_template(template) {
            bar.set_style(style.progress_chars("#>-"));
        }
        Self { bar, passes }
    }

    /// Starts phase `name` of pass `pass` (from 0) over `steps` steps.
    pub fn phase(&self, pass: u32, name: &str, steps: usize) {
        let prefix = if self.passes > 1 {
            std::format!("pass {}/{} {name}", pass + 1, self.passes)
        } else {
            name.into()
        };
        self.bar.reset();
        self.bar.set_prefix(prefix);
        self.bar.set_length(steps as u64);
    }

    /// The current phase has `steps` steps after all (once they are known).
    pub fn set_steps(&self, steps: usize) {
        self.bar.set_length(steps as u64);
    }

    /// One step done.
    pub fn tick(&self) {
        self.bar.inc(1);
    }

    /// Clears the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// Renders `scene` with Arvo's illumination maps (texels of side `texel_size` scene
/// units) as the caustic store instead of the kd-tree: one forward pass into a photon
/// array (timed as `emit_ms`), splatted into maps sized by the layout (timed as
/// `balance_ms`, the store's build), then the backward pass. One pass only: the maps
/// have no radius to shrink. Also returns what the map build did.
pub fn render_illumination(
    scene: &DesktopScene,
    settings: &PhotonSettings,
    opts: &RenderOptions,
    texel_size: f32,
) -> Result<(Image, RenderStats, photon::MapStats), Error> {
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
    let mut image = Image::new(w, h);
    let splats = settings.camera_splats().then_some(&splats[..]);
    stats.photons_splatted = splats.map_or(0, |s| s.len() as u64);
    backward_pass(
        scene,
        &maps,
        settings,
        (splats, 1.0),
        opts,
        &mut image,
        &progress,
        &mut stats,
    )?;
    progress.finish();
    Ok((image, stats, map_stats))
}

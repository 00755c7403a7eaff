//! The forward pass on the desktop: the photon array on the heap, traced in chunks
//! on every thread and balanced in parallel, bit-identical to the core's
//! [`photon::shoot_with_splats`] and [`balance`] whatever the thread count.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::Instant;
use std::vec;

use super::progress::Progress;
use super::run::{ms, RenderStats};
use super::MAX_PHOTONS;
use crate::error::within;
use crate::math::Vec3;
use crate::photon::{
    self, balance, photons_needed, Emitter, KdStore, KdTree, Photon, PhotonSettings, Splat,
    SplatSums, Subtree, NO_BOX,
};
use crate::scene::Scene;
use crate::Error;

/// The photon array of the forward pass, on the heap: allocated once for a budget and
/// refilled in place by every progressive pass (fixed memory, Knaus & Zwicker 2011).
#[derive(Debug)]
pub struct PhotonBuffer {
    photons: vec::Vec<Photon>,
    unit: f32,
    /// The camera splats of the pass, summed per pixel as their chunks arrive in
    /// emission order: no list of them is kept.
    splats: SplatSums,
    /// The coarse levels of the store (see [`KdStore::with_coarse_levels`]), balanced.
    coarse: [vec::Vec<Photon>; 2],
    /// The bounding box of `photons`, merged from the chunks' boxes.
    bounds: (Vec3, Vec3),
}

/// Photons one forward pass of `settings` stores at most; an error beyond the desktop's
/// [`MAX_PHOTONS`].
pub(super) fn desktop_budget<const O: usize, const L: usize>(
    scene: &Scene<O, L>,
    settings: &PhotonSettings,
) -> Result<usize, Error> {
    let needed = photons_needed(scene, settings);
    within(needed, MAX_PHOTONS, "photons (count × lights)")
}

/// Balances the kd-tree and its coarse levels on `threads` threads, the same arrays
/// as [`balance`] makes, bit for bit. A pool of jobs: the root is split on one thread
/// while another balances the coarse levels; each split hands out its two children,
/// down to the first level with four subtrees per thread, which are balanced whole.
fn balance_parallel(
    photons: &mut [Photon],
    coarse: &mut [vec::Vec<Photon>],
    threads: usize,
    pass: u32,
    progress: &Progress,
) {
    // Below this a thread costs more than it saves.
    const SERIAL: usize = 1 << 15;
    if threads <= 1 || photons.len() < SERIAL {
        progress.phase(pass, "balance", 1);
        for level in coarse.iter_mut() {
            balance(level);
        }
        balance(photons);
        progress.tick();
        return;
    }
    // Four subtrees per thread, rounded up to a level: balances the load.
    let levels = usize::BITS - (4 * threads - 1).leading_zeros();
    progress.phase(pass, "balance", 1 << levels);
    let mut jobs: vec::Vec<Job<'_>> = coarse.iter_mut().map(Job::Whole).collect();
    jobs.push(Job::Part(photons, Subtree::root(photons.len())));
    let pool = Pool {
        queue: Mutex::new((jobs, 0)),
        ready: Condvar::new(),
    };
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| {
                while let Some(job) = pool.take() {
                    match job {
                        Job::Whole(level) => balance(level),
                        Job::Part(slice, t) if t.depth < levels => {
                            pool.add(photon::split_subtree(slice, t).into_iter().flatten());
                        }
                        Job::Part(slice, t) => {
                            photon::balance_subtree(slice, t);
                            progress.tick();
                        }
                    }
                    pool.done();
                }
            });
        }
    });
}

/// A job of [`balance_parallel`].
enum Job<'a> {
    /// A coarse level, balanced whole.
    Whole(&'a mut vec::Vec<Photon>),
    /// A subtree of the map: split, or balanced whole at the bottom level.
    Part(&'a mut [Photon], Subtree),
}

/// The jobs waiting and the number being done, and a signal for either's change.
struct Pool<'a> {
    queue: Mutex<(vec::Vec<Job<'a>>, usize)>,
    ready: Condvar,
}

impl<'a> Pool<'a> {
    /// The next job, waiting while others may still add some; `None` when none is
    /// left and none is being done.
    fn take(&self) -> Option<Job<'a>> {
        let mut q = self.queue.lock().ok()?;
        loop {
            if let Some(job) = q.0.pop() {
                q.1 += 1;
                return Some(job);
            }
            if q.1 == 0 {
                return None;
            }
            q = self.ready.wait(q).ok()?;
        }
    }

    /// Adds the jobs a split made.
    fn add(&self, parts: impl Iterator<Item = (&'a mut [Photon], Subtree)>) {
        if let Ok(mut q) = self.queue.lock() {
            q.0.extend(parts.map(|(slice, t)| Job::Part(slice, t)));
        }
        self.ready.notify_all();
    }

    /// Marks a job taken by [`take`](Self::take) done.
    fn done(&self) {
        if let Ok(mut q) = self.queue.lock() {
            q.1 -= 1;
        }
        self.ready.notify_all();
    }
}

/// The forward pass's chunks, appended to the buffer in emission order as they finish
/// (their splats added to the sums, in the same order).
struct InOrder<'a> {
    /// The first chunk not yet appended.
    next: usize,
    /// Finished chunks waiting for an earlier one.
    done: vec::Vec<Option<Chunk>>,
    photons: &'a mut vec::Vec<Photon>,
    splats: &'a mut SplatSums,
    coarse: &'a mut [vec::Vec<Photon>; 2],
    bounds: &'a mut (Vec3, Vec3),
}

/// One chunk's photons, splats and the photons of each coarse level, and the
/// bounding box of its photons.
struct Chunk {
    photons: vec::Vec<Photon>,
    splats: vec::Vec<Splat>,
    coarse: [vec::Vec<Photon>; 2],
    bounds: (Vec3, Vec3),
}

impl InOrder<'_> {
    /// Chunk `k` is traced: appends it and every finished chunk after it that is due.
    fn finish(&mut self, k: usize, chunk: Chunk) {
        self.done[k] = Some(chunk);
        while let Some(c) = self.done.get_mut(self.next).and_then(Option::take) {
            self.photons.extend_from_slice(&c.photons);
            self.splats.add(&c.splats);
            for (level, from) in self.coarse.iter_mut().zip(&c.coarse) {
                level.extend_from_slice(from);
            }
            let (lo, hi) = c.bounds;
            *self.bounds = (self.bounds.0.min(lo), self.bounds.1.max(hi));
            self.next += 1;
        }
    }
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
        // Reserved, not written: a page is first touched by the pass that fills it.
        Ok(Self {
            photons: vec::Vec::with_capacity(needed),
            unit: 0.0,
            splats: SplatSums::default(),
            coarse: [vec::Vec::new(), vec::Vec::new()],
            bounds: NO_BOX,
        })
    }

    /// Runs forward pass `pass` into the buffer on `threads` threads and balances it,
    /// adding the times and counts to `stats` and showing its two phases (photons,
    /// balance) on `progress` ([`Progress::hidden`] for none). The photons are traced in
    /// chunks of `CHUNK` and kept in emission order: the same array as the core's
    /// [`photon::shoot_with_splats`], whatever the thread count.
    #[allow(clippy::too_many_arguments)]
    pub fn fill<const O: usize, const L: usize>(
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
        within(needed, self.photons.capacity(), "photons (count × lights)")?;
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
        // Each chunk is traced into its own lists; the finished ones are appended to
        // the buffer in emission order by whichever thread finishes the next one due,
        // while the others trace on.
        self.photons.clear();
        let camera = scene.camera();
        self.splats
            .clear(camera.width() as usize * camera.height() as usize);
        self.coarse.iter_mut().for_each(vec::Vec::clear);
        self.bounds = NO_BOX;
        // The coarse levels: photons chosen by their emission index
        // (`Emitter::coarse_levels`), each standing for THINNING of the level before.
        // Only the footprint gathers behind glass read them, and those need the camera
        // splats.
        let coarse = settings.camera_splats();
        let order = Mutex::new(InOrder {
            next: 0,
            done: (0..items.len()).map(|_| None).collect(),
            photons: &mut self.photons,
            splats: &mut self.splats,
            coarse: &mut self.coarse,
            bounds: &mut self.bounds,
        });
        let next = AtomicUsize::new(0);
        std::thread::scope(|scope| {
            for _ in 0..threads.clamp(1, items.len().max(1)) {
                scope.spawn(|| loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&(l, start, end)) = items.get(k) else {
                        break;
                    };
                    let mut chunk = Chunk {
                        photons: vec::Vec::with_capacity(CHUNK as usize),
                        splats: vec::Vec::new(),
                        coarse: [vec::Vec::new(), vec::Vec::new()],
                        bounds: NO_BOX,
                    };
                    let landed = emitter.land_range(l, start..end, |i, x| {
                        if let Some(p) = x.photon {
                            chunk.photons.push(p);
                            let levels = if coarse {
                                emitter.coarse_levels(l, i)
                            } else {
                                0
                            };
                            for level in &mut chunk.coarse[..levels] {
                                level.push(p);
                            }
                        }
                        chunk.splats.extend(x.splat);
                        Ok::<(), core::convert::Infallible>(())
                    });
                    let Ok(()) = landed;
                    // Read while the chunk's photons are in this core's cache.
                    chunk.bounds = photon::bounding_box(&chunk.photons);
                    if let Ok(mut order) = order.lock() {
                        order.finish(k, chunk);
                    }
                    progress.tick();
                });
            }
        });
        stats.emit_ms += ms(t.elapsed());
        let t = Instant::now();
        let (photons, coarse) = (&mut self.photons[..], &mut self.coarse);
        balance_parallel(photons, coarse, threads, pass, progress);
        stats.balance_ms += ms(t.elapsed());
        stats.photons_emitted += emitter.emitted();
        stats.photons_stored += self.photons.len() as u64;
        self.unit = emitter.power_unit();
        Ok(())
    }

    /// The balanced tree of the last pass.
    pub fn tree(&self) -> KdTree<'_> {
        KdTree::from_balanced(&self.photons)
    }

    /// The caustic store over the last pass's tree and its coarse levels, gathering up
    /// to `K` photons as `settings` say.
    pub fn store<const K: usize>(
        &self,
        settings: &PhotonSettings,
    ) -> Result<KdStore<'_, K>, Error> {
        let [level1, level2] = &self.coarse;
        debug_assert_eq!(self.bounds, photon::bounding_box(&self.photons));
        Ok(
            photon::store_within::<K>(self.tree(), self.unit, settings, self.bounds)?
                .with_coarse_levels(KdTree::from_balanced(level1), KdTree::from_balanced(level2)),
        )
    }

    /// Power of one stored unit, W.
    pub fn unit(&self) -> f32 {
        self.unit
    }

    /// The camera splats of the last pass, summed per pixel in emission order.
    pub fn splats(&self) -> &SplatSums {
        &self.splats
    }
}

//! The eye pass's rows on the desktop's threads.
//!
//! Under the adaptive sampling each line of pixel corners is traced once, before the
//! rows that read it ([`Renderer::corner_line`]), and the rows are then rendered from
//! those lines ([`Renderer::row_between`]), one at a time, the costly ones first. A
//! row's cost is known from its lines — the pixels whose corners disagree are the ones
//! supersampled ([`Renderer::supersampled`]) — and it varies a thousandfold: on the
//! balls, mirror and tube scene at 1.6M photons a light the rows through the glass take
//! 8–15 ms each and the rest 0.07 ms. Handed out top to bottom, in bands that shared
//! their corners, the last costly band left one thread working alone for 10–45 ms
//! (perf). Now the rows costlier than the mean go first and the cheap ones fill the
//! end, each group top to bottom: neighbouring rows gather the same photons, and strict
//! costliest-first order, which scatters them, cost 3% more eye-pass time (medians of 15
//! runs each: 440 ms against 426 ms; top to bottom row by row, 435 ms).
//!
//! A corner's sample depends on nothing but its position and a row's pixels on nothing
//! but its corners, so the image is the same bits whatever the order and the thread
//! count, and so is the count of rays: every corner is traced exactly once.

use std::sync::Mutex;
use std::vec;

use super::progress::Progress;
use crate::photon::{CausticStore, SplatSums};
use crate::render::{PixelEstimate, RayCount, Renderer, Sample};

/// Most bytes of corner lines held at once: the whole image's up to about 200 000
/// pixels (320×240: 3.1 MB), blocks of rows beyond, each block's lines traced before
/// its rows.
const CORNER_BYTES: usize = 8 << 20;

/// Renders all rows of `frame` (`width` pixels each) on `threads` threads (see the
/// module's notes), each row taking its pixels' `splats` as it is finished.
pub fn render_rows<S: CausticStore + Sync, const O: usize, const L: usize, const D: usize>(
    renderer: &Renderer<'_, S, O, L, D>,
    frame: &mut [PixelEstimate],
    (width, splats): (usize, Option<&SplatSums>),
    threads: usize,
    progress: &Progress,
) -> RayCount {
    let rows = (width, splats, CORNER_BYTES);
    render_in_blocks(renderer, frame, rows, threads, progress)
}

/// [`render_rows`] holding at most `corner_bytes` of corner lines at once.
fn render_in_blocks<S: CausticStore + Sync, const O: usize, const L: usize, const D: usize>(
    renderer: &Renderer<'_, S, O, L, D>,
    frame: &mut [PixelEstimate],
    (width, splats, corner_bytes): (usize, Option<&SplatSums>, usize),
    threads: usize,
    progress: &Progress,
) -> RayCount {
    let width = width.max(1);
    let mut rows: vec::Vec<Option<&mut [PixelEstimate]>> =
        frame.chunks_mut(width).map(Some).collect();
    let height = rows.len();
    // A rendered row takes its splats.
    let finish = |y: usize, row: &mut [PixelEstimate]| {
        if let Some(splats) = splats {
            splats.add_to_row(y as u32, row);
        }
        progress.tick();
    };
    if !renderer.reads_corners() {
        let jobs = rows
            .iter_mut()
            .enumerate()
            .filter_map(|(y, r)| Some((y, r.take()?)));
        return in_parallel(threads, jobs.collect(), |(y, row)| {
            let count = renderer.row(y as u32, row);
            finish(y, row);
            count
        });
    }
    let line_len = width + 1;
    let block = (corner_bytes / (line_len * size_of::<Sample>())).clamp(1, height.max(1));
    // Lines y0..=y0 + block of the current block, each allocated by the thread that
    // traces it (a 3 MB buffer zeroed first took one thread 3 ms); line 0 of a later
    // block is the last line of the one before, kept.
    let mut lines: vec::Vec<vec::Vec<Sample>> = (0..=block).map(|_| vec::Vec::new()).collect();
    let mut total = RayCount::default();
    let mut y0 = 0;
    while y0 < height {
        let n = block.min(height - y0);
        let first = if y0 == 0 { 0 } else { 1 };
        let todo = lines.iter_mut().enumerate().take(n + 1).skip(first);
        total += in_parallel(threads, todo.collect(), |(i, line)| {
            *line = vec![Sample::default(); line_len];
            renderer.corner_line((y0 + i) as u32, line)
        });
        let line = |i: usize| &lines[i][..];
        let mut jobs: vec::Vec<_> = (0..n)
            .filter_map(|i| {
                let row = rows[y0 + i].take()?;
                Some((renderer.supersampled(line(i), line(i + 1)), i, row))
            })
            .collect();
        // The rows costlier than the mean first, then the rest, each top to bottom.
        let mean = jobs.iter().map(|j| j.0).sum::<usize>() / jobs.len().max(1);
        jobs.sort_by_key(|&(cost, i, _)| (cost <= mean, i));
        total += in_parallel(threads, jobs, |(_, i, row)| {
            let count = renderer.row_between((y0 + i) as u32, (line(i), line(i + 1)), row);
            finish(y0 + i, row);
            count
        });
        lines.swap(0, n);
        y0 += n;
    }
    total
}

/// Runs `job` on every item of `jobs` on `threads` threads, each taking the next item
/// in order as it becomes free; the sum of the counts.
fn in_parallel<T: Send>(
    threads: usize,
    jobs: vec::Vec<T>,
    job: impl Fn(T) -> RayCount + Sync,
) -> RayCount {
    let queue = Mutex::new(jobs.into_iter());
    let total = Mutex::new(RayCount::default());
    std::thread::scope(|s| {
        for _ in 0..threads.max(1) {
            s.spawn(|| {
                let mut mine = RayCount::default();
                loop {
                    let next = match queue.lock() {
                        Ok(mut q) => q.next(),
                        Err(_) => None,
                    };
                    let Some(item) = next else { break };
                    mine += job(item);
                }
                if let Ok(mut t) = total.lock() {
                    *t += mine;
                }
            });
        }
    });
    total.into_inner().unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::desktop::photons::PhotonBuffer;
    use crate::desktop::{DesktopScene, RenderStats, MAX_DEPTH, MAX_LIGHTS, MAX_OBJECTS};
    use crate::photon::PhotonSettings;
    use crate::render::{Sampling, REFINE};

    /// Rows rendered in blocks of three lines of corners, on three threads, are the
    /// rows rendered alone, bit for bit, and trace every corner once, as in one block.
    #[test]
    fn blocks_of_corner_lines_give_the_rows() {
        let (w, h) = (24usize, 17u32);
        let scene: DesktopScene = crate::demo::glass(w as u32, h).unwrap();
        let settings = PhotonSettings::new(20_000, 32, 0.3, 8).unwrap();
        let mut buf = PhotonBuffer::for_budget(&scene, &settings).unwrap();
        let (mut stats, hidden) = (RenderStats::default(), Progress::hidden());
        buf.fill(&scene, &settings, 3, 0, 2, &mut stats, &hidden)
            .unwrap();
        let store = buf.store::<64>(&settings).unwrap();
        let r: Renderer<_, MAX_OBJECTS, MAX_LIGHTS, MAX_DEPTH> =
            Renderer::new(&scene, &store, settings.max_depth())
                .unwrap()
                .with_sampling(Sampling::Adaptive(REFINE))
                .unwrap();
        let mut alone = vec![PixelEstimate::default(); w * h as usize];
        for (y, row) in alone.chunks_mut(w).enumerate() {
            r.row(y as u32, row);
        }
        let line_bytes = (w + 1) * size_of::<Sample>();
        let mut rays = vec![];
        for (bytes, threads) in [(CORNER_BYTES, 1), (3 * line_bytes, 3), (line_bytes, 2)] {
            let mut frame = vec![PixelEstimate::default(); alone.len()];
            let rows = (w, None, bytes);
            rays.push(render_in_blocks(&r, &mut frame, rows, threads, &hidden));
            assert_eq!(frame, alone, "{bytes} bytes of lines");
        }
        assert!(rays[0].refined > 0, "{:?}", rays[0]);
        assert!(rays.iter().all(|&n| n == rays[0]), "{rays:?}");
    }
}

//! kd-tree build and query time against the number of photons (1k to 1M).
//!
//! `cargo bench --bench kdtree` prints a table: median of several repeats of the
//! in-place balance, and of a batch of k-nearest queries (k = 64, no radius bound, so
//! every query finds exactly 64) at random points of the photons' distribution. The build should grow as N log N (the `build/(N log2 N)`
//! column stays flat) and a query as log N (the per-query time grows by a constant
//! step per doubling, not in proportion to N); a brute-force scan is shown for scale.

use std::hint::black_box;
use std::time::Instant;

use caustic::math::{Rgb, UnitVec3, Vec3};
use caustic::photon::{balance, KdTree, Neighbor, Photon};
use caustic::sampling::Pcg32;

fn cloud(n: usize, seed: u64) -> Vec<Photon> {
    let mut g = Pcg32::new(seed);
    // A caustic-like set: points on a plane, denser in a bright blob.
    (0..n)
        .map(|i| {
            let (u, v) = (g.next_f32(), g.next_f32());
            let p = if i % 3 == 0 {
                Vec3::new(0.2 * u - 0.1, 0.0, 0.2 * v - 0.1)
            } else {
                Vec3::new(4.0 * u - 2.0, 0.0, 4.0 * v - 2.0)
            };
            Photon::new(p, -UnitVec3::Y, Rgb::ONE)
        })
        .collect()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    println!("| photons | build ms | build ns/(N log2 N) | query µs (k=64) | query ns/log2 N | brute-force radius scan µs |");
    println!("|---:|---:|---:|---:|---:|---:|");
    for &n in &[1_000usize, 4_000, 16_000, 64_000, 256_000, 1_000_000] {
        let base = cloud(n, n as u64);
        let repeats = if n >= 256_000 { 3 } else { 7 };
        let mut builds = Vec::new();
        let mut tree_photons = base.clone();
        for _ in 0..repeats {
            tree_photons.copy_from_slice(&base);
            let t = Instant::now();
            balance(black_box(&mut tree_photons));
            builds.push(t.elapsed().as_secs_f64());
        }
        let tree = KdTree::from_balanced(&tree_photons);
        let mut g = Pcg32::new(7);
        let queries: Vec<Vec3> = (0..2000)
            .map(|_| Vec3::new(4.0 * g.next_f32() - 2.0, 0.0, 4.0 * g.next_f32() - 2.0))
            .collect();
        let mut out: heapless::Vec<Neighbor, 64> = heapless::Vec::new();
        let mut times = Vec::new();
        for _ in 0..5 {
            let t = Instant::now();
            for &q in &queries {
                black_box(tree.k_nearest(q, f32::INFINITY, 64, &mut out));
            }
            times.push(t.elapsed().as_secs_f64() / queries.len() as f64);
        }
        let t = Instant::now();
        let brute_queries = 20;
        for &q in &queries[..brute_queries] {
            black_box(
                base.iter()
                    .filter(|p| (p.position() - q).length_squared() < 0.01)
                    .count(),
            );
        }
        let brute = t.elapsed().as_secs_f64() / brute_queries as f64;
        let b = median(builds);
        let q = median(times);
        let nlogn = n as f64 * (n as f64).log2();
        println!(
            "| {n} | {:.2} | {:.1} | {:.2} | {:.0} | {:.1} |",
            b * 1e3,
            b * 1e9 / nlogn,
            q * 1e6,
            q * 1e9 / (n as f64).log2(),
            brute * 1e6
        );
    }
}

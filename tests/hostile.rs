//! Bounded work on scenes built to be slow (issue 16): deep trees of forking classic
//! surfaces, dozens of overlapping glass objects, the camera inside glass, lights inside
//! objects, grazing planes, illumination maps with a tiny texel (see
//! `support::hostile`). Every scene either renders finite pixels or is refused with a
//! message, never panics, and stays within a deterministic bound on its work: rays
//! (eye and shadow) at most the ray budget per pixel and pass, photons emitted at
//! most `count × lights` per pass. Wall-clock bounds are only a safety net.

mod support;

use std::time::Instant;

use caustic::render::{Sampling, DEFAULT_RAY_BUDGET, REFINE};
use support::hostile::hostile_scene;
use support::{fnv1a, Rng};

/// Scenes through the program: the bar.
const SCENES: u64 = 150;

/// The wall-clock safety net per scene: the 10 s with an optimised program
/// (`tools/hostile_scenes.sh`), three times that in the test profile (opt-level 1, debug
/// assertions) on a shared machine. Measured: see the README's stability section.
const GUARD_SECONDS: f64 = if cfg!(debug_assertions) { 30.0 } else { 10.0 };

/// What one run of the program did.
struct Run {
    seconds: f64,
    rendered: bool,
}

/// Renders `scene` with the `caustic` program into `dir` and checks its outcome.
fn run_program(seed: u64, scene: &serde_json::Value, dir: &std::path::Path) -> Run {
    let path = dir.join(format!("hostile{seed}.json"));
    let pfm = dir.join(format!("hostile{seed}.pfm"));
    std::fs::write(&path, scene.to_string()).unwrap();
    let t = Instant::now();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_caustic"))
        .args([
            "render",
            path.to_str().unwrap(),
            "--stats",
            "--quiet",
            "--threads",
            "2",
        ])
        .arg("--pfm")
        .arg(&pfm)
        .output()
        .unwrap();
    let seconds = t.elapsed().as_secs_f64();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let rendered = match out.status.code() {
        Some(0) => {
            check_work(seed, scene, &serde_json::from_slice(&out.stdout).unwrap());
            let img = caustic::desktop::Image::read_pfm(&pfm).unwrap();
            assert!(
                img.pixels
                    .iter()
                    .all(|p| p.is_finite() && p.min_channel() >= 0.0),
                "seed {seed}: a pixel is not finite and non-negative"
            );
            true
        }
        Some(2) => {
            assert!(
                stderr.starts_with("caustic: ") && !stderr.contains("panicked"),
                "seed {seed}: {stderr}"
            );
            false
        }
        other => panic!("seed {seed}: exit {other:?}\n{stderr}"),
    };
    Run { seconds, rendered }
}

/// The deterministic bound on the work of a render, from its `--stats`.
fn check_work(seed: u64, scene: &serde_json::Value, stats: &serde_json::Value) {
    let passes = stats["passes"].as_u64().unwrap();
    let pixels = stats["width"].as_u64().unwrap() * stats["height"].as_u64().unwrap();
    let rays = stats["rays"]["eye"].as_u64().unwrap() + stats["rays"]["shadow"].as_u64().unwrap();
    // The default sampling: adaptive, refined on a REFINE × REFINE grid.
    let per_pixel = Sampling::Adaptive(REFINE).max_rays_per_pixel(DEFAULT_RAY_BUDGET);
    let most = pixels * per_pixel * passes;
    assert!(rays <= most, "seed {seed}: {rays} rays > {most}");
    let lights = scene["lights"].as_array().unwrap().len() as u64;
    let count = scene["photons"]["count"].as_u64().unwrap();
    let emitted = stats["photons"]["emitted"].as_u64().unwrap();
    assert!(
        emitted <= count * lights * passes,
        "seed {seed}: {emitted} photons emitted"
    );
    assert!(stats["photons"]["stored"].as_u64().unwrap() <= emitted);
}

/// The bar: 150 hostile scenes through the `caustic` program, each exits 0 with
/// finite pixels or 2 with a message, none panics, each within its work bound, and —
/// a safety net only, the bound above is the test — none over 10 s (optimised).
#[test]
fn hostile_scenes_through_the_program() {
    let dir = std::env::temp_dir().join(format!("caustic-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (mut rendered, mut slowest) = (0, (0.0f64, 0u64));
    let start = Instant::now();
    for seed in 0..SCENES {
        let run = run_program(seed, &hostile_scene(seed), &dir);
        rendered += run.rendered as usize;
        if run.seconds > slowest.0 {
            slowest = (run.seconds, seed);
        }
        assert!(
            run.seconds < GUARD_SECONDS,
            "seed {seed}: {:.1} s",
            run.seconds
        );
    }
    println!(
        "{SCENES} hostile scenes: {rendered} rendered, the others refused; slowest {:.2} s \
         (seed {}); {:.1} s in all",
        slowest.0,
        slowest.1,
        start.elapsed().as_secs_f64()
    );
    std::fs::remove_dir_all(&dir).ok();
    // They are scenes a user could write: nearly all must render.
    assert!(
        rendered as u64 * 10 >= SCENES * 9,
        "only {rendered} rendered"
    );
}

/// One scene of each kind, rendered in-process on 1 and 3 threads: the same bits
/// (hashed with FNV-1a), the same rays, and the ray count within its bound.
#[test]
fn hostile_scenes_are_the_same_bits_on_any_thread_count() {
    use caustic::desktop::{parse_scene, render, RenderOptions};
    for seed in 0..6u64 {
        let loaded = parse_scene(&hostile_scene(seed).to_string()).unwrap();
        let opts = |threads| RenderOptions {
            seed,
            threads,
            passes: loaded.passes,
            ..RenderOptions::default()
        };
        let hash = |threads| {
            let (img, stats) = render(&loaded.scene, &loaded.photons, &opts(threads)).unwrap();
            let bytes: Vec<u8> = img
                .pixels
                .iter()
                .flat_map(|p| p.to_array().map(f32::to_bits))
                .flat_map(u32::to_le_bytes)
                .collect();
            (fnv1a(&bytes), stats.rays)
        };
        let (one, three) = (hash(1), hash(3));
        assert_eq!(one, three, "seed {seed}");
        let rays = one.1.eye + one.1.shadow;
        let per_pixel = Sampling::Adaptive(REFINE).max_rays_per_pixel(DEFAULT_RAY_BUDGET);
        assert!(rays <= 16 * 12 * per_pixel * loaded.passes as u64);
    }
}

#[test]
fn fnv1a_and_splitmix_match_their_references() {
    // FNV-1a test vectors (Fowler, Noll & Vo): "", "a", "foobar".
    assert_eq!(fnv1a(b""), 0x811c_9dc5);
    assert_eq!(fnv1a(b"a"), 0xe40c_292c);
    assert_eq!(fnv1a(b"foobar"), 0xbf9c_f968);
    // SplitMix64 seeded with 0: the first outputs of Vigna's splitmix64.c.
    let mut r = Rng(0);
    assert_eq!(r.u64(), 0xe220_a839_7b1d_cdaf);
    assert_eq!(r.u64(), 0x6e78_9e6a_a1b9_65f4);
}

//! Run time against error: how far each photon budget is from the reference, and how
//! long it takes.
//!
//! `cargo bench --bench time_vs_error` renders every scene that has a reference image in
//! `tests/data/` at the reference's size, sweeping the photon budget, `k`, and the number
//! of progressive passes; records the median wall time of a few repeats (all threads)
//! and the relative RMSE against the reference over the full image and inside the
//! caustic region (pixels where the reference's caustic part exceeds 2% of its
//! 99.9th percentile), per pixel and 2×2-binned. It writes
//! `target/time_vs_error/time_vs_error.csv` and a log–log plot of caustic-region error
//! against time with each scene's Pareto front, `time_vs_error.svg` (PNG with
//! `rsvg-convert`). Rows of `docs/reference_baseline.csv` (the reference tool's own light
//! tracer at small budgets, made by `tools/reference/baseline.sh`) are plotted as a
//! baseline curve.
//!
//! `CAUSTIC_BENCH_QUICK=1` runs a reduced sweep; `CAUSTIC_BENCH_OUT=DIR` moves the output.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use caustic::desktop::image::{compare, mask_above, Image};
use caustic::desktop::run::render_illumination;
use caustic::desktop::{parse_scene, render, RenderOptions};
use caustic::photon::PhotonSettings;
use plotters::prelude::*;

/// One configuration of the sweep.
#[derive(Clone, Copy, Debug)]
struct Config {
    photons: u32,
    k: u32,
    passes: u32,
    supersample: u32,
    estimator: Estimator,
    /// Part of the progressive series (radius from `PROGRESSIVE_R1`, even at one pass).
    series_progressive: bool,
}

/// How the caustic light is estimated.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Estimator {
    /// The k nearest photons within [`NEAREST_RADIUS`].
    Nearest,
    /// Every photon within a fixed radius: [`FIXED_RADIUS`] for single passes (the
    /// reference's own kernel, so that what remains is noise and transport, not the
    /// choice of kernel at a caustic's fold); progressive passes start at
    /// [`PROGRESSIVE_R1`] and shrink as `r_i² = r_1²·i^(α−1)`.
    FixedRadius,
    /// Illumination maps with texels of side [`TEXEL`].
    IlluminationMap,
}

/// The k-nearest estimate's radius bound, scene units (a tenth of the spheres' radius).
const NEAREST_RADIUS: f32 = 0.1;
/// The single-pass fixed radius: the reference's kernel radius.
const FIXED_RADIUS: f32 = 0.015;
/// The first radius of the progressive passes.
const PROGRESSIVE_R1: f32 = 0.02;
/// The illumination maps' texel side.
const TEXEL: f32 = 0.02;

/// One measured point.
#[derive(Clone, Debug)]
struct Point {
    scene: String,
    series: String,
    config: Config,
    seconds: f64,
    full: f64,
    caustic: f64,
    full_bin2: f64,
    caustic_bin2: f64,
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The sweep: single passes over photon budgets for each estimator and k, then
/// progressive passes.
fn configs(quick: bool, supersample: u32) -> Vec<(String, Config)> {
    let mut out = Vec::new();
    let mut add = |series: String, photons: u32, k: u32, passes: u32, estimator: Estimator| {
        let series_progressive = series.starts_with("progressive");
        let c = Config {
            photons,
            k,
            passes,
            supersample,
            estimator,
            series_progressive,
        };
        out.push((series, c));
    };
    let budgets: &[u32] = if quick {
        &[10_000, 100_000]
    } else {
        &[10_000, 30_000, 100_000, 300_000, 1_000_000]
    };
    let ks: &[u32] = if quick { &[64] } else { &[16, 64, 256] };
    for &k in ks {
        for &photons in budgets {
            add(format!("kd-tree k={k}"), photons, k, 1, Estimator::Nearest);
        }
    }
    let budgets: &[u32] = if quick {
        &[100_000]
    } else {
        &[30_000, 100_000, 300_000, 500_000, 1_000_000, 3_000_000]
    };
    for &photons in budgets {
        add(
            "kd-tree fixed r=0.015".into(),
            photons,
            64,
            1,
            Estimator::FixedRadius,
        );
    }
    let budgets: &[u32] = if quick {
        &[100_000]
    } else {
        &[10_000, 30_000, 100_000, 300_000, 1_000_000]
    };
    for &photons in budgets {
        add(
            "illumination maps".into(),
            photons,
            64,
            1,
            Estimator::IlluminationMap,
        );
    }
    let passes: &[u32] = if quick {
        &[1, 4]
    } else {
        &[1, 2, 4, 8, 16, 32]
    };
    for &p in passes {
        add(
            "progressive 100k/pass".into(),
            100_000,
            64,
            p,
            Estimator::FixedRadius,
        );
    }
    out
}

fn measure(
    name: &str,
    reference: &str,
    supersample: u32,
    quick: bool,
    repeats: usize,
) -> Vec<Point> {
    let text = std::fs::read_to_string(root().join(format!("scenes/{name}.json"))).unwrap();
    let loaded = parse_scene(&text).unwrap();
    let reference_img =
        Image::read_pfm(&root().join(format!("tests/data/{reference}.ref.pfm"))).unwrap();
    let caustic_part =
        Image::read_pfm(&root().join(format!("tests/data/{reference}.ref.caustic.pfm"))).unwrap();
    let mask = mask_above(&caustic_part, 0.02);
    let mask2 = mask_above(&caustic_part.binned(2), 0.02);
    let ref2 = reference_img.binned(2);
    let mut scene = loaded.scene;
    scene.set_camera(
        scene
            .camera()
            .with_size(reference_img.width, reference_img.height)
            .unwrap(),
    );
    let p = loaded.photons;
    let mut points = Vec::new();
    for (series, c) in configs(quick, supersample) {
        let radius = match c.estimator {
            Estimator::Nearest => NEAREST_RADIUS,
            Estimator::FixedRadius if c.passes > 1 || c.series_progressive => PROGRESSIVE_R1,
            Estimator::FixedRadius => FIXED_RADIUS,
            Estimator::IlluminationMap => TEXEL,
        };
        let settings = PhotonSettings::new(c.photons, c.k, radius, p.max_depth())
            .unwrap()
            .with_fixed_radius(c.estimator == Estimator::FixedRadius);
        let opts = RenderOptions {
            passes: c.passes,
            sampling: caustic::render::Sampling::Grid(c.supersample),
            ..RenderOptions::default()
        };
        let mut times = Vec::new();
        let mut image = None;
        for _ in 0..repeats {
            let t = Instant::now();
            let result = match c.estimator {
                Estimator::IlluminationMap => {
                    render_illumination(&scene, &settings, &opts, TEXEL).map(|r| r.0)
                }
                _ => render(&scene, &settings, &opts).map(|r| r.0),
            };
            match result {
                Ok(img) => image = Some(img),
                Err(e) => {
                    // A budget the store refuses (e.g. too many texels) is a point we
                    // cannot measure, not a failure of the benchmark.
                    eprintln!("{name} {series} N={}: skipped: {e}", c.photons);
                    break;
                }
            }
            times.push(t.elapsed().as_secs_f64());
        }
        let Some(img) = image else { continue };
        let img2 = img.binned(2);
        let e = |a: &Image, b: &Image, m: Option<&[bool]>| {
            compare(a, b, m).map_or(f64::NAN, |e| e.rel_rmse)
        };
        let point = Point {
            scene: if supersample > 1 {
                format!("{name} ({supersample}×{supersample} spp)")
            } else {
                name.into()
            },
            series,
            config: c,
            seconds: median(times),
            full: e(&img, &reference_img, None),
            caustic: e(&img, &reference_img, Some(&mask)),
            full_bin2: e(&img2, &ref2, None),
            caustic_bin2: e(&img2, &ref2, Some(&mask2)),
        };
        eprintln!(
            "{:>28} {:>24} N={:>8} k={:>3} P={:>2}: {:8.3} s  full {:.4}  caustic {:.4}  (2×2: {:.4} / {:.4})",
            point.scene, point.series, c.photons, c.k, c.passes, point.seconds, point.full, point.caustic, point.full_bin2, point.caustic_bin2
        );
        points.push(point);
    }
    points
}

/// Points not beaten by any faster point: the best error reachable in a given time.
fn pareto(points: &[&Point]) -> Vec<(f64, f64)> {
    let mut v: Vec<(f64, f64)> = points
        .iter()
        .map(|p| (p.seconds, p.caustic))
        .filter(|p| p.1.is_finite())
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut front: Vec<(f64, f64)> = Vec::new();
    for p in v {
        if front.last().is_none_or(|l| p.1 < l.1) {
            front.push(p);
        }
    }
    front
}

/// `scene,photons,seconds,full,caustic` rows of the reference tool's own tracer.
fn baseline() -> Vec<(String, f64, f64)> {
    let Ok(text) = std::fs::read_to_string(root().join("docs/reference_baseline.csv")) else {
        return Vec::new();
    };
    text.lines()
        .skip(1)
        .filter_map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            Some((
                f.first()?.to_string(),
                f.get(2)?.parse().ok()?,
                f.get(4)?.parse().ok()?,
            ))
        })
        .collect()
}

fn plot(points: &[Point], out: &Path) -> Result<(), Box<dyn std::error::Error>> {
    let mut scenes: Vec<String> = points.iter().map(|p| p.scene.clone()).collect();
    scenes.dedup();
    let base = baseline();
    let root_area = SVGBackend::new(out, (900, 330 * scenes.len() as u32)).into_drawing_area();
    root_area.fill(&WHITE)?;
    let panels = root_area.split_evenly((scenes.len(), 1));
    for (panel, scene) in panels.iter().zip(&scenes) {
        let mine: Vec<&Point> = points.iter().filter(|p| &p.scene == scene).collect();
        let theirs: Vec<(f64, f64)> = base
            .iter()
            .filter(|b| scene.starts_with(&b.0))
            .map(|b| (b.1, b.2))
            .collect();
        let all_t = mine
            .iter()
            .map(|p| p.seconds)
            .chain(theirs.iter().map(|b| b.0));
        let all_e = mine
            .iter()
            .map(|p| p.caustic)
            .chain(theirs.iter().map(|b| b.1))
            .filter(|e| e.is_finite());
        let (t0, t1) = all_t.fold((f64::MAX, 0.0f64), |(a, b), t| (a.min(t), b.max(t)));
        let (e0, e1) = all_e.fold((f64::MAX, 0.0f64), |(a, b), e| (a.min(e), b.max(e)));
        let mut chart = ChartBuilder::on(panel)
            .caption(
                format!("{scene}: caustic-region relative RMSE vs time"),
                ("sans-serif", 18),
            )
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(56)
            .build_cartesian_2d(
                (t0 * 0.7..t1 * 1.4).log_scale(),
                (e0 * 0.7..e1 * 1.4).log_scale(),
            )?;
        chart
            .configure_mesh()
            .y_label_formatter(&|v| format!("{v:.3}"))
            .x_label_formatter(&|v| format!("{v:.3}"))
            .x_desc("wall time, s (median)")
            .y_desc("relative RMSE")
            .draw()?;
        let mut series: Vec<String> = mine.iter().map(|p| p.series.clone()).collect();
        series.dedup();
        for (i, s) in series.iter().enumerate() {
            let color = Palette99::pick(i).to_rgba();
            let mut pts: Vec<(f64, f64)> = mine
                .iter()
                .filter(|p| &p.series == s)
                .map(|p| (p.seconds, p.caustic))
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))?
                .label(s.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                });
            chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 3, color.filled())))?;
        }
        if !theirs.is_empty() {
            let mut pts = theirs.clone();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(pts.clone(), BLACK.stroke_width(2)))?
                .label("reference light tracer (Mitsuba ray queries)")
                .legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], BLACK.stroke_width(2))
                });
            chart.draw_series(
                pts.into_iter()
                    .map(|p| TriangleMarker::new(p, 5, BLACK.filled())),
            )?;
        }
        let front = pareto(&mine);
        chart
            .draw_series(LineSeries::new(
                front,
                RGBColor(120, 120, 120).stroke_width(1),
            ))?
            .label("Pareto front (caustic)")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], RGBColor(120, 120, 120)));
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE.mix(0.85))
            .draw()?;
    }
    root_area.present()?;
    Ok(())
}

fn main() {
    let quick = std::env::var_os("CAUSTIC_BENCH_QUICK").is_some();
    let out = std::env::var_os("CAUSTIC_BENCH_OUT")
        .map_or_else(|| root().join("target/time_vs_error"), PathBuf::from);
    std::fs::create_dir_all(&out).unwrap();
    let repeats = if quick { 1 } else { 3 };
    let mut points = Vec::new();
    for name in ["glass_sphere", "two_balls", "tube"] {
        if root().join(format!("tests/data/{name}.ref.pfm")).exists() {
            points.extend(measure(name, name, 1, quick, repeats));
        }
    }
    if root().join("tests/data/glass_sphere.ss4.ref.pfm").exists() {
        points.extend(measure(
            "glass_sphere",
            "glass_sphere.ss4",
            4,
            quick,
            repeats,
        ));
    }
    // Series and scene names hold no comma, so the CSV needs no quoting.
    let mut csv = String::from("scene,series,photons,k,passes,supersample,seconds,full_rel_rmse,caustic_rel_rmse,full_rel_rmse_bin2,caustic_rel_rmse_bin2\n");
    for p in &points {
        let c = p.config;
        writeln!(
            csv,
            "{},{},{},{},{},{},{:.5},{:.6},{:.6},{:.6},{:.6}",
            p.scene,
            p.series,
            c.photons,
            c.k,
            c.passes,
            c.supersample,
            p.seconds,
            p.full,
            p.caustic,
            p.full_bin2,
            p.caustic_bin2
        )
        .unwrap();
    }
    std::fs::write(out.join("time_vs_error.csv"), &csv).unwrap();
    plot(&points, &out.join("time_vs_error.svg")).unwrap();
    // Progressive convergence: slope of log MSE against log photons (theory: −2/3).
    let mut scenes: Vec<&str> = points.iter().map(|p| p.scene.as_str()).collect();
    scenes.dedup();
    for scene in scenes {
        let prog: Vec<(f64, f64)> = points
            .iter()
            .filter(|p| p.scene == scene && p.series.starts_with("progressive"))
            .map(|p| {
                (
                    ((p.config.photons * p.config.passes) as f64).ln(),
                    (p.caustic_bin2 * p.caustic_bin2).ln(),
                )
            })
            .collect();
        if prog.len() >= 2 {
            let n = prog.len() as f64;
            let (mx, my) = (
                prog.iter().map(|p| p.0).sum::<f64>() / n,
                prog.iter().map(|p| p.1).sum::<f64>() / n,
            );
            let slope = prog.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>()
                / prog.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>();
            println!("{scene}: progressive caustic MSE ∝ N^{slope:.2} (2×2-binned; theory −0.67, until the reference's own noise and kernel are reached)");
        }
    }
    println!("wrote {}", out.join("time_vs_error.csv").display());
    println!("{csv}");
}

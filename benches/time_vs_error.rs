//! Run time against error: how far each budget of the default estimator is from the
//! reference, and how long it takes.
//!
//! `cargo bench --bench time_vs_error` renders every scene that has a reference in
//! `tests/data/` (the three the defaults were tuned on and the three held-out ones) at
//! the reference's size (320×240) with the default estimator and a plain photons block
//! (`k` 64, `max_radius` 0.25, the file's `max_depth`): one pass at photon budgets from
//! 25k to 3.2M per light, and progressive passes of 100k. It records the median wall
//! time of three repeats (all threads; the render only, no file I/O) and the relative
//! RMSE `√mean((a−b)²)/mean(b)` against the reference over the full image and over the
//! caustic region (the reference's caustic part at least 10% of its luminance, Rec. 709:
//! the README's definition). It writes `target/time_vs_error/time_vs_error.csv` and a
//! log–log plot of the caustic region's error against time, one panel per scene, with
//! the reference's own noise there (`NAME.ref.json`: the committed mean's, from its
//! seeds' spread) as a dashed floor: `time_vs_error.svg`.
//!
//! `CAUSTIC_BENCH_QUICK=1` runs a reduced sweep (one repeat, fewer budgets);
//! `CAUSTIC_BENCH_OUT=DIR` moves the output.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use caustic::desktop::image::{compare, Image};
use caustic::desktop::{parse_scene, render, RenderOptions};
use caustic::photon::PhotonSettings;
use plotters::prelude::*;

/// The scenes: reference name, scene file, role.
const SCENES: [(&str, &str, &str); 6] = [
    ("glass_sphere", "scenes/glass_sphere.json", "tuning"),
    ("two_balls", "scenes/two_balls.json", "tuning"),
    ("tube", "scenes/tube.json", "tuning"),
    ("sphere_wall", "scenes/heldout/sphere_wall.json", "held out"),
    ("tilted_cube", "scenes/heldout/tilted_cube.json", "held out"),
    (
        "balls_mirror_tube",
        "scenes/heldout/balls_mirror_tube.json",
        "held out",
    ),
];

/// One measured point.
#[derive(Clone, Debug)]
struct Point {
    scene: String,
    series: &'static str,
    photons: u32,
    passes: u32,
    seconds: f64,
    full: f64,
    caustic: f64,
}

/// One scene's reference: full image, caustic-region mask, and the reference's own noise
/// in the caustic region.
struct Reference {
    image: Image,
    region: Vec<bool>,
    noise_caustic: f64,
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The sweep: (series, photons per light per pass, passes).
fn configs(quick: bool) -> Vec<(&'static str, u32, u32)> {
    let budgets: &[u32] = if quick {
        &[25_000, 400_000]
    } else {
        &[
            25_000, 50_000, 100_000, 200_000, 400_000, 800_000, 1_600_000, 3_200_000,
        ]
    };
    let passes: &[u32] = if quick { &[2] } else { &[2, 4, 8, 16] };
    let mut out: Vec<_> = budgets.iter().map(|&n| ("one pass", n, 1)).collect();
    out.extend(passes.iter().map(|&p| ("passes of 100k", 100_000, p)));
    out
}

fn reference(name: &str) -> Reference {
    let read = |suffix: &str| {
        Image::read_pfm(&root().join(format!("tests/data/{name}.{suffix}.pfm"))).unwrap()
    };
    let (image, caustic) = (read("ref"), read("ref.caustic"));
    let region = image
        .pixels
        .iter()
        .zip(&caustic.pixels)
        .map(|(f, c)| f.luminance() > 0.0 && c.luminance() >= 0.1 * f.luminance())
        .collect();
    let json = std::fs::read_to_string(root().join(format!("tests/data/{name}.ref.json")))
        .unwrap()
        .parse::<serde_json::Value>()
        .unwrap();
    let noise_caustic = json["noise"]["mean_of_seeds_rel_rmse_caustic_region"]
        .as_f64()
        .unwrap();
    Reference {
        image,
        region,
        noise_caustic,
    }
}

fn measure(name: &str, path: &str, r: &Reference, quick: bool) -> Vec<Point> {
    let text = std::fs::read_to_string(root().join(path)).unwrap();
    let loaded = parse_scene(&text).unwrap();
    let mut scene = loaded.scene;
    scene.set_camera(
        scene
            .camera()
            .with_size(r.image.width, r.image.height)
            .unwrap(),
    );
    let repeats = if quick { 1 } else { 3 };
    let mut points = Vec::new();
    for (series, photons, passes) in configs(quick) {
        let settings = PhotonSettings::new(photons, 64, 0.25, loaded.photons.max_depth()).unwrap();
        let opts = RenderOptions {
            passes,
            ..RenderOptions::default()
        };
        let mut times = Vec::new();
        let mut image = None;
        for _ in 0..repeats {
            let t = Instant::now();
            image = Some(render(&scene, &settings, &opts).unwrap().0);
            times.push(t.elapsed().as_secs_f64());
        }
        let img = image.unwrap();
        let e = |m: Option<&[bool]>| compare(&img, &r.image, m).map_or(f64::NAN, |e| e.rel_rmse);
        let point = Point {
            scene: name.into(),
            series,
            photons,
            passes,
            seconds: median(times),
            full: e(None),
            caustic: e(Some(&r.region)),
        };
        eprintln!(
            "{name:>18} {series:>15} N={photons:>8} P={passes:>2}: {:7.3} s  full {:.4}  caustic {:.4}",
            point.seconds, point.full, point.caustic
        );
        points.push(point);
    }
    points
}

/// One panel: the caustic region's error against time for each series of one scene,
/// and the reference's own noise as a dashed floor.
fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    mine: &[&Point],
    noise: f64,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let (t0, t1) = mine.iter().fold((f64::MAX, 0.0f64), |(a, b), p| {
        (a.min(p.seconds), b.max(p.seconds))
    });
    let (e0, e1) = mine
        .iter()
        .map(|p| p.caustic)
        .chain([noise])
        .fold((f64::MAX, 0.0f64), |(a, b), e| (a.min(e), b.max(e)));
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 16))
        .margin(10)
        .x_label_area_size(34)
        .y_label_area_size(52)
        .build_cartesian_2d(
            (t0 * 0.7..t1 * 1.4).log_scale(),
            (e0 * 0.7..e1 * 1.4).log_scale(),
        )?;
    chart
        .configure_mesh()
        .max_light_lines(0)
        .x_labels(12)
        .y_labels(12)
        .y_label_formatter(&|v| format!("{v:.3}"))
        .x_label_formatter(&|v| format!("{v:.1}"))
        .x_desc("wall time, s (median of 3)")
        .y_desc("caustic region rel. RMSE")
        .draw()?;
    let mut series: Vec<&str> = mine.iter().map(|p| p.series).collect();
    series.dedup();
    for (i, s) in series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        // In budget order: where the timings are noisy, the line shows it.
        let pts: Vec<(f64, f64)> = mine
            .iter()
            .filter(|p| p.series == *s)
            .map(|p| (p.seconds, p.caustic))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))?
            .label(*s)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
            });
        chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 3, color.filled())))?;
    }
    let dashes = (0..12).map(|i| {
        let a = (t0 * 0.7) * ((t1 * 2.0) / (t0 * 0.7)).powf(i as f64 / 12.0);
        let b = (t0 * 0.7) * ((t1 * 2.0) / (t0 * 0.7)).powf((i as f64 + 0.5) / 12.0);
        PathElement::new(vec![(a, noise), (b, noise)], BLACK)
    });
    chart
        .draw_series(dashes)?
        .label("reference's own noise")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 8, y)], BLACK));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .border_style(BLACK)
        .background_style(WHITE.mix(0.85))
        .draw()?;
    Ok(())
}

fn plot(points: &[Point], noises: &[f64], out: &Path) -> Result<(), Box<dyn std::error::Error>> {
    let rows = SCENES.len().div_ceil(2);
    let root_area = SVGBackend::new(out, (1100, 330 * rows as u32)).into_drawing_area();
    root_area.fill(&WHITE)?;
    let panels = root_area.split_evenly((rows, 2));
    for ((area, (name, _, role)), noise) in panels.iter().zip(SCENES).zip(noises) {
        let mine: Vec<&Point> = points.iter().filter(|p| p.scene == name).collect();
        if !mine.is_empty() {
            panel(area, &format!("{name} ({role})"), &mine, *noise)?;
        }
    }
    root_area.present()?;
    Ok(())
}

fn main() {
    let quick = std::env::var_os("CAUSTIC_BENCH_QUICK").is_some();
    let out = std::env::var_os("CAUSTIC_BENCH_OUT")
        .map_or_else(|| root().join("target/time_vs_error"), PathBuf::from);
    std::fs::create_dir_all(&out).unwrap();
    let mut points = Vec::new();
    let mut noises = Vec::new();
    for (name, path, _) in SCENES {
        let r = reference(name);
        points.extend(measure(name, path, &r, quick));
        noises.push(r.noise_caustic);
    }
    // Scene and series names hold no comma, so the CSV needs no quoting.
    let mut csv = String::from(
        "scene,series,photons,passes,seconds,full_rel_rmse,caustic_rel_rmse,ref_noise_caustic\n",
    );
    for p in &points {
        let noise = SCENES
            .iter()
            .position(|s| s.0 == p.scene)
            .map_or(f64::NAN, |i| noises[i]);
        writeln!(
            csv,
            "{},{},{},{},{:.4},{:.6},{:.6},{:.6}",
            p.scene, p.series, p.photons, p.passes, p.seconds, p.full, p.caustic, noise
        )
        .unwrap();
    }
    std::fs::write(out.join("time_vs_error.csv"), &csv).unwrap();
    plot(&points, &noises, &out.join("time_vs_error.svg")).unwrap();
    // Convergence of the single passes: slope of log error against log photons
    // (N^-1/2 for the unbiased parts, about N^-1/3 for a progressive gather).
    for (name, _, _) in SCENES {
        let one: Vec<(f64, f64)> = points
            .iter()
            .filter(|p| p.scene == name && p.passes == 1)
            .map(|p| ((p.photons as f64).ln(), p.caustic.ln()))
            .collect();
        if one.len() >= 2 {
            let n = one.len() as f64;
            let (mx, my) = (
                one.iter().map(|p| p.0).sum::<f64>() / n,
                one.iter().map(|p| p.1).sum::<f64>() / n,
            );
            let slope = one.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>()
                / one.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>();
            println!("{name}: caustic-region error ∝ N^{slope:.2} over one-pass budgets");
        }
    }
    println!("wrote {}", out.join("time_vs_error.csv").display());
    println!("{csv}");
}

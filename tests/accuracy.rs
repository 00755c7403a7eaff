//! Accuracy against independent references, so that it cannot silently regress.
//!
//! The references (`tests/data/NAME.ref.pfm` and their caustic parts, made by
//! `tools/reference/make_test_data.sh`) are pixel-area averages at 320×240 computed
//! with Mitsuba 3's ray queries and the reference's own estimators — random sub-pixel
//! eye samples, light-traced caustics where the eye sees them directly, a gather far
//! below a pixel behind glass — validated against Mitsuba's `ptracer`, and the mean of
//! two seeds or more whose spread gives its noise (`NAME.ref.json`). Nothing here shares
//! the renderer's kernels, radii or sampling patterns.
//!
//! The renders are 160×120 and the references are binned 2×2 to match: a box filter of
//! pixel-area averages is the pixel-area average of the larger pixel, exactly. The
//! caustic region is the pixels whose reference caustic part is at least a tenth of
//! their luminance. Each scene file's photons block is replaced by a plain one
//! (`k` 64, `max_radius` 0.25, the k nearest): the estimator must be right without
//! hints. `glass_sphere` and `two_balls` chose the defaults; `tube` was measured after
//! them and has since been tuned on too, and `mirror_lens` was written in session 38 as a
//! tuning scene of the held-out kind; the three scenes of `scenes/heldout/` never
//! were. The seven scenes are rendered once at 25k, 100k and 400k photons (the sweep) and
//! every test reads those twenty-one renders. Bounds are about 1.3 times the values
//! measured when they were set (against the references re-rendered at 20M photons a
//! light), printed by `cargo test --release --test accuracy -- --nocapture` (the same
//! figures at 320×240: `docs/error_calibration.csv`).

use caustic::desktop::image::{compare, Image};
use caustic::desktop::{parse_scene, render_with_error, RenderOptions, Rendered};
use caustic::photon::PhotonSettings;
use std::sync::OnceLock;

mod support;

const W: u32 = 160;
const H: u32 = 120;

/// The reference's full image and caustic part, binned to 160×120.
fn reference(name: &str) -> (Image, Image) {
    let root = env!("CARGO_MANIFEST_DIR");
    let read = |suffix: &str| {
        let path = format!("{root}/tests/data/{name}.{suffix}.pfm");
        Image::read_pfm(path.as_ref())
            .unwrap_or_else(|e| panic!("{path}: {e}"))
            .binned(2)
    };
    (read("ref"), read("ref.caustic"))
}

/// `scenes/NAME.json` (or `scenes/heldout/NAME.json`) at 160×120 with a plain photons
/// block of `count` photons.
fn render(name: &str, count: u32) -> Rendered {
    let root = env!("CARGO_MANIFEST_DIR");
    let dir = if HELD_OUT.contains(&name) {
        "scenes/heldout"
    } else {
        "scenes"
    };
    let text = std::fs::read_to_string(format!("{root}/{dir}/{name}.json")).unwrap();
    let loaded = parse_scene(&text).unwrap();
    let mut scene = loaded.scene;
    scene.set_camera(scene.camera().with_size(W, H).unwrap());
    let settings = PhotonSettings::new(count, 64, 0.25, loaded.photons.max_depth()).unwrap();
    render_with_error(&scene, &settings, &RenderOptions::default()).unwrap()
}

/// The budgets of the sweep: 16 times from the first to the last.
const BUDGETS: [u32; 3] = [25_000, 100_000, 400_000];
/// The tuning scenes of the sweep: `glass_sphere` and `two_balls` chose the defaults;
/// `tube`, measured after them, has been among the scenes later changes were chosen on;
/// `mirror_lens` (session 38) puts more of its image behind glass at two depths and in
/// a mirror, as the held-out scenes do, where the eye pass's sampling decides the error.
const SCENES: [&str; 4] = ["glass_sphere", "two_balls", "tube", "mirror_lens"];

/// The held-out scenes of the sweep (`scenes/heldout/`): written after the defaults by
/// the references' author and never tuned to.
const HELD_OUT: [&str; 3] = ["tilted_cube", "balls_mirror_tube", "sphere_wall"];

/// One render of the sweep against its reference: relative RMSE measured and estimated,
/// full image and caustic region.
struct Measured {
    name: &'static str,
    count: u32,
    full: f64,
    caustic: f64,
    estimated_full: f64,
    estimated_caustic: f64,
}

/// The reference's own noise at 160×120 (full image, caustic region): the relative RMSE
/// of the committed mean of its seeds over 2×2 bins, from the seeds' spread
/// (`NAME.ref.json`; for two seeds half their pair's).
fn reference_noise(name: &str) -> (f64, f64) {
    let json: serde_json::Value =
        serde_json::from_str(&support::data_text(&format!("{name}.ref.json"))).unwrap();
    let noise = |key: &str| {
        json["noise"][key]
            .as_f64()
            .unwrap_or_else(|| panic!("{name}: {key}"))
    };
    (
        noise("mean_of_seeds_rel_rmse_full_2x2"),
        noise("mean_of_seeds_rel_rmse_caustic_region_2x2"),
    )
}

fn measure(name: &'static str, count: u32) -> Measured {
    let (full, caustic) = reference(name);
    let r = render(name, count);
    let region: Vec<bool> = full
        .pixels
        .iter()
        .zip(&caustic.pixels)
        .map(|(f, c)| f.luminance() > 0.0 && c.luminance() >= 0.1 * f.luminance())
        .collect();
    let m = Measured {
        name,
        count,
        full: compare(&r.image, &full, None).unwrap().rel_rmse,
        caustic: compare(&r.image, &full, Some(&region)).unwrap().rel_rmse,
        estimated_full: r.stats.error.rel_rmse.unwrap(),
        estimated_caustic: r.stats.error.rel_rmse_caustic.unwrap(),
    };
    println!(
        "{name:>12} {count:>7} photons: rel. RMSE full {:.4} (estimated {:.4}), caustic region {:.4} (estimated {:.4}, {} px)",
        m.full,
        m.estimated_full,
        m.caustic,
        m.estimated_caustic,
        region.iter().filter(|&&b| b).count()
    );
    m
}

/// Every scene at every budget, rendered once for all the tests here (each render
/// takes all cores; the tests wait for the first to finish the sweep).
fn sweep() -> &'static [Measured] {
    static SWEEP: OnceLock<Vec<Measured>> = OnceLock::new();
    SWEEP.get_or_init(|| {
        SCENES
            .iter()
            .chain(&HELD_OUT)
            .flat_map(|&name| BUDGETS.iter().map(move |&count| measure(name, count)))
            .collect()
    })
}

fn at(name: &str, count: u32) -> &'static Measured {
    sweep()
        .iter()
        .find(|m| m.name == name && m.count == count)
        .unwrap()
}

/// More photons, less error, on the tuning scenes: 16 times the photons cut the caustic
/// region's error 5.2 times on the glass sphere, 4.3 times on the two balls and 4.7
/// times on the tube against the 20M-photon references, each reference's own noise
/// (0.8–1.2% here after binning) taken out in quadrature (4 times is the ideal of an
/// unbiased estimate; on the two balls the 4×4 grids' aliasing where a thin bright band
/// crosses a pixel is part of what is left at 400k). As measured, with that noise in,
/// the glass sphere's gain is only 3.0: its error at 400k, 0.015, is mostly the
/// reference's 0.011. The mirror and lenses scene (session 38; a four-seed reference):
/// 0.0398 → 0.0132, 3.16 times.
#[test]
fn the_caustics_converge_to_the_reference() {
    for (name, bound, least_gain) in [
        ("glass_sphere", 0.023, 3.2),
        ("two_balls", 0.035, 2.4),
        ("tube", 0.052, 3.0),
        ("mirror_lens", 0.017, 2.4),
    ] {
        converges(name, bound, least_gain);
    }
}

/// The same on the held-out scenes, which no default or constant was chosen on: 5.3
/// times (tilted cube) and 5.3 times (sphere + wall) for 16 times the photons, and on
/// balls + mirror + tube 2.9 times (2.0 while the coarse levels took every 16th photon,
/// whose 400k render here read 0.0176; then 0.0133, the render's own: the references of
/// these two are means of eight seeds, with 0.3% and 0.2% of noise at this size, where
/// the balls scene's two-seed one had 0.7%, enough to make its gain read 2.7); the
/// references' noise taken out as above.
#[test]
fn the_caustics_converge_on_held_out_scenes() {
    for (name, bound, least_gain) in [
        ("tilted_cube", 0.022, 3.5),
        ("sphere_wall", 0.12, 2.3),
        ("balls_mirror_tube", 0.029, 2.0),
    ] {
        converges(name, bound, least_gain);
    }
}

/// Scene `name`'s caustic region at 400k photons is below `bound` (as measured), its
/// error at 25k at least `least_gain` times that (the reference's own noise taken out
/// in quadrature from both: `E[measured²] = true² + noise²`), and its full image's
/// error falls too.
fn converges(name: &str, bound: f64, least_gain: f64) {
    let low = at(name, BUDGETS[0]);
    let high = at(name, BUDGETS[2]);
    assert!(high.caustic < bound, "{name}: {}", high.caustic);
    let noise = reference_noise(name).1;
    let truth = |measured: f64| (measured * measured - noise * noise).max(0.0).sqrt();
    let gain = truth(low.caustic) / truth(high.caustic);
    eprintln!("{name}: 16 times the photons, the caustic region's error {gain:.2} times lower");
    assert!(
        gain > least_gain,
        "{name}: the error fell only {gain:.2} times"
    );
    assert!(high.full < 0.6 * low.full, "{name}");
}

/// The render's own error estimate, full image and caustic region, is within a factor 2
/// below and 3.5 above the error measured against the reference, on every tuning scene
/// and budget of the sweep (on the held-out sphere + wall the estimate's caustic region
/// holds pixels seen through the sphere that the reference's does not: docs/accuracy.md,
/// "Estimated against measured"). The reference is noisy too, independently of the
/// render, so `E[measured²] = true² + noise²`: its noise is subtracted in quadrature (at
/// most 0.4% / 1.2% absolute, full / caustic region, here; up to 70% of the measured
/// figure, on the glass sphere at 400k). Too low an estimate would stop
/// `--target-error` early, too high one only renders longer: the upper bound is the
/// looser. The worst, 3.05 on the glass sphere's caustic region at 400k, is where the
/// true error (0.0085) is below the reference's own noise (0.0116): the estimate, 0.0258,
/// holds the eye sampling's part (a checkerboard of a handful of pixels at the focus)
/// and, since the coarse levels keep both halves' photons (`thinning_level`), each
/// half's own noise there (0.0249 before, when every 16th photon kept one half where
/// all landed, and the measured error 0.0163; 0.0151 with the rim pixels refined, the
/// estimate 0.0279 and the ratio 2.89; 0.0144 since the grazing pixels' gathers visit
/// up to `GRAZING_VISITS` photons within secant-bounded footprints, which lowered the
/// true error more than the estimate). The truth is the measured error less the
/// reference's noise in quadrature, and here most of the measured error is that noise:
/// the reference's noise 5% lower would put the ratio at 2.8.
#[test]
fn the_error_estimate_is_calibrated() {
    let mut worst = (1.0f64, "");
    for m in sweep().iter().filter(|m| SCENES.contains(&m.name)) {
        let (noise_full, noise_caustic) = reference_noise(m.name);
        for (what, estimated, measured, noise) in [
            ("full", m.estimated_full, m.full, noise_full),
            ("caustic", m.estimated_caustic, m.caustic, noise_caustic),
        ] {
            let truth = (measured * measured - noise * noise).max(0.0).sqrt();
            let ratio = estimated / truth;
            println!(
                "{:>12} {:>7} {what:>7}: estimated {estimated:.4}, true {truth:.4} (measured {measured:.4}), ratio {ratio:.2}",
                m.name, m.count
            );
            assert!(
                (0.5..3.5).contains(&ratio),
                "{} at {} photons, {what}: estimated {estimated:.4}, true {truth:.4}",
                m.name,
                m.count
            );
            if ratio.ln().abs() > worst.0.ln().abs() {
                worst = (ratio, m.name);
            }
        }
    }
    println!("worst ratio {:.2} ({})", worst.0, worst.1);
}

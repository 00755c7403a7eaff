//! Accuracy against independent references, so that it cannot silently regress.
//!
//! The references (`tests/data/NAME.ref.pfm` and their caustic parts, made by
//! `tools/reference/make_test_data.sh`) are pixel-area averages at 320×240 computed
//! with Mitsuba 3's ray queries and the reference's own estimators — random sub-pixel
//! eye samples, light-traced caustics where the eye sees them directly, a gather far
//! below a pixel behind glass — validated against Mitsuba's `ptracer`, and the mean of
//! two seeds whose difference gives their noise (`NAME.ref.json`). Nothing here shares
//! the renderer's kernels, radii or sampling patterns.
//!
//! The renders are 160×120 and the references are binned 2×2 to match: a box filter of
//! pixel-area averages is the pixel-area average of the larger pixel, exactly. The
//! caustic region is the pixels whose reference caustic part is at least a tenth of
//! their luminance. Each scene file's photons block is replaced by a plain one
//! (`k` 64, `max_radius` 0.25, the k nearest): the estimator must be right without
//! hints. `glass_sphere` and `two_balls` chose the defaults; `tube` was measured after.
//! Bounds are about 1.3 times the values measured when they were set, printed by
//! `cargo test --release --test accuracy -- --nocapture`.

use caustic::desktop::image::{compare, Image};
use caustic::desktop::{parse_scene, render_with_error, RenderOptions, Rendered};
use caustic::photon::PhotonSettings;

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

/// `scenes/NAME.json` at 160×120 with a plain photons block of `count` photons.
fn render(name: &str, count: u32) -> Rendered {
    let root = env!("CARGO_MANIFEST_DIR");
    let text = std::fs::read_to_string(format!("{root}/scenes/{name}.json")).unwrap();
    let loaded = parse_scene(&text).unwrap();
    let mut scene = loaded.scene;
    scene.set_camera(scene.camera().with_size(W, H).unwrap());
    let settings = PhotonSettings::new(count, 64, 0.25, loaded.photons.max_depth()).unwrap();
    render_with_error(&scene, &settings, &RenderOptions::default()).unwrap()
}

/// Relative RMSE of the full image and of the caustic region.
struct Measured {
    full: f64,
    caustic: f64,
    estimated_full: f64,
}

fn measure(name: &str, count: u32) -> Measured {
    let (full, caustic) = reference(name);
    let r = render(name, count);
    let region: Vec<bool> = full
        .pixels
        .iter()
        .zip(&caustic.pixels)
        .map(|(f, c)| f.luminance() > 0.0 && c.luminance() >= 0.1 * f.luminance())
        .collect();
    let m = Measured {
        full: compare(&r.image, &full, None).unwrap().rel_rmse,
        caustic: compare(&r.image, &full, Some(&region)).unwrap().rel_rmse,
        estimated_full: r.stats.error.rel_rmse.unwrap(),
    };
    println!(
        "{name:>12} {count:>8} photons: rel. RMSE full {:.4} (estimated {:.4}), caustic region {:.4} ({} px)",
        m.full,
        m.estimated_full,
        m.caustic,
        region.iter().filter(|&&b| b).count()
    );
    m
}

/// More photons, less error: 16 times the photons cut the caustic region's error 2.26
/// times on the glass sphere and 1.56 times on the two balls when these bounds were set
/// (4 times is the ideal of an unbiased estimate; the reference's own noise, 1–1.3%
/// here after binning, is part of what is left). What keeps the two balls from doing
/// better is known: behind a ball the floor is magnified, and the gather's footprint,
/// taken from the pixel's ray cone without the lens's magnification, is wider than the
/// pixel there (a bias at the focus seen through the glass).
#[test]
fn the_caustics_converge_to_the_reference() {
    for (name, bound, least_gain) in [("glass_sphere", 0.05, 2.0), ("two_balls", 0.075, 1.4)] {
        let low = measure(name, 50_000);
        let high = measure(name, 800_000);
        assert!(high.caustic < bound, "{name}: {}", high.caustic);
        let gain = low.caustic / high.caustic;
        assert!(
            gain > least_gain,
            "{name}: the error fell only {gain:.2} times"
        );
        assert!(high.full < 0.7 * low.full, "{name}");
    }
}

/// A scene the defaults were not chosen on, at its file's budget.
#[test]
fn a_held_out_scene_meets_its_bound() {
    let m = measure("tube", 100_000);
    assert!(
        m.full < 0.05 && m.caustic < 0.14,
        "{:.4} {:.4}",
        m.full,
        m.caustic
    );
}

/// The render's own error estimate is within a factor 2 of the error measured against
/// the reference, on every scene and budget here.
#[test]
fn the_error_estimate_is_calibrated() {
    for (name, count) in [("glass_sphere", 100_000), ("tube", 400_000)] {
        let m = measure(name, count);
        let ratio = m.estimated_full / m.full;
        assert!(
            (0.5..2.0).contains(&ratio),
            "{name} at {count}: estimated {:.4}, measured {:.4}",
            m.estimated_full,
            m.full
        );
    }
}

//! The backward pass end to end: analytic radiance, refraction geometry, determinism
//! across threads, and the scene files' error messages.

mod support;

use caustic::camera::Camera;
use caustic::desktop::image::compare;
use caustic::desktop::photons::PhotonBuffer;
use caustic::desktop::progress::Progress;
use caustic::desktop::rows::render_rows;
use caustic::desktop::{parse_scene, render, DesktopScene, RenderOptions};
use caustic::desktop::{MAX_DEPTH, MAX_LIGHTS, MAX_OBJECTS};
use caustic::geometry::{Ray, Shape};
use caustic::material::Classic;
use caustic::material::{interface, Material};
use caustic::math::{reflect, Rgb, UnitVec3, Vec3};
use caustic::photon;
use caustic::photon::{CausticStore, NoCaustics, PhotonSettings};
use caustic::render::{PixelEstimate, Sampling, REFINE, REFINE_FLOOR};
use caustic::render::{RayCount, Renderer, RowsError, DEFAULT_CUTOFF, DEFAULT_RAY_BUDGET};
use caustic::scene::Scene;
use support::{add_floor, add_glass_sphere, add_light, scene_text};

/// A diffuse floor of albedo ρ under a point light: every pixel that sees the floor has
/// radiance ρ·I·cosθ/(π·d²), evaluated here in f64 from the analytic ray–plane hit.
#[test]
fn direct_light_on_a_diffuse_floor_is_analytic() {
    let (albedo, intensity, light) = (0.63f32, Rgb::new(10.0, 5.0, 2.5), Vec3::new(0.4, 2.5, -0.3));
    let camera = Camera::new(Vec3::new(0.0, 3.0, 4.0), Vec3::NEG_Z, Vec3::Y, 50.0, 48, 36).unwrap();
    let mut scene: Scene<1, 1> = Scene::new(camera);
    add_floor(&mut scene, Rgb::splat(albedo));
    add_light(&mut scene, light, intensity);
    let r: Renderer<_, 1, 1, 4> = Renderer::new(&scene, &NoCaustics, 4).unwrap();
    let mut worst = 0.0f64;
    let mut seen = 0;
    for y in 0..36 {
        for x in 0..48 {
            let ray = camera.ray(x, y);
            let got = r.radiance(ray, &mut RayCount::default());
            let (o, d) = (ray.origin.as_dvec3(), ray.dir.get().as_dvec3());
            if d.y >= 0.0 {
                assert_eq!(got, Rgb::ZERO);
                continue;
            }
            let p = o + d * (-o.y / d.y);
            let to = light.as_dvec3() - p;
            let cos = to.y / to.length();
            for (c, i) in got.to_array().into_iter().zip(intensity.to_array()) {
                let want =
                    albedo as f64 * i as f64 * cos / (std::f64::consts::PI * to.length_squared());
                worst = worst.max((c as f64 - want).abs() / want);
            }
            seen += 1;
        }
    }
    assert!(seen > 500);
    assert!(worst < 1e-3, "worst relative error {worst}");
}

/// A ray through a parallel glass slab leaves parallel to how it came in, displaced.
#[test]
fn refraction_through_a_slab_exits_parallel() {
    let slab = Shape::cuboid(Vec3::ZERO, Vec3::new(100.0, 0.5, 100.0), Vec3::ZERO).unwrap();
    for (i, angle) in [0.0f32, 0.2, 0.5, 0.9, 1.3].into_iter().enumerate() {
        let d = UnitVec3::new(Vec3::new(angle.sin(), -angle.cos(), 0.1 * i as f32)).unwrap();
        let ray = Ray::new(Vec3::new(0.0, 2.0, 0.0), d);
        let h = slab.intersect(&ray, f32::INFINITY).unwrap();
        let inside = interface(d, h.normal, 1.0 / 1.5).refracted.unwrap();
        let r2 = Ray::spawn(&h, inside);
        let h2 = slab.intersect(&r2, f32::INFINITY).unwrap();
        assert!(
            h2.normal.dot(inside.get()) > 0.0,
            "must leave through the far face"
        );
        let out = interface(inside, -h2.normal, 1.5).refracted.unwrap();
        assert!(
            (out.get() - d.get()).length() < 1e-5,
            "angle {angle}: {out:?} vs {d:?}"
        );
        if angle > 0.0 {
            assert!(
                (h2.point - h.point).normalize().dot(d.get()) < 0.9999,
                "the path bends inside"
            );
        }
    }
    // Mirror reflection of a reflection is the identity.
    let d = UnitVec3::new(Vec3::new(0.3, -0.8, 0.1)).unwrap();
    let n = UnitVec3::new(Vec3::new(0.1, 1.0, 0.2)).unwrap();
    assert!((reflect(reflect(d, n), n).get() - d.get()).length() < 1e-6);
}

/// Glass and mirrors block direct light: under a glass sphere the floor gets no direct
/// light, only what the caustic store adds.
#[test]
fn glass_casts_a_shadow_for_direct_light() {
    let camera = Camera::new(Vec3::new(0.0, 5.0, 0.001), Vec3::ZERO, Vec3::Y, 10.0, 9, 9).unwrap();
    let mut scene: Scene<2, 1> = Scene::new(camera);
    add_floor(&mut scene, Rgb::ONE);
    add_glass_sphere(&mut scene, Vec3::new(5.0, 2.0, 0.0), 0.5);
    add_light(&mut scene, Vec3::new(10.0, 4.0, 0.0), Rgb::ONE);
    let r: Renderer<_, 2, 1, 4> = Renderer::new(&scene, &NoCaustics, 4).unwrap();
    // The floor point (0,0,0) lies exactly behind the sphere as seen from the light.
    let down = Ray::new(Vec3::new(0.0, 1.0, 0.0), -UnitVec3::Y);
    assert_eq!(r.radiance(down, &mut RayCount::default()), Rgb::ZERO);
    let beside = Ray::new(Vec3::new(0.0, 1.0, 3.0), -UnitVec3::Y);
    assert!(r.radiance(beside, &mut RayCount::default()).r > 0.0);
}

/// `max_depth` bounds specular interactions: between two parallel mirrors an eye ray
/// bounces exactly `max_depth` times and then contributes nothing (not the background).
#[test]
fn max_depth_ends_paths_at_a_further_specular_surface() {
    let camera = Camera::new(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), Vec3::Y, 10.0, 1, 1).unwrap();
    let mut scene: Scene<2, 1> = Scene::new(camera);
    let mirror = Material::mirror(Rgb::splat(0.5)).unwrap();
    scene
        .add(
            Shape::plane(Vec3::new(0.0, 0.0, -1.0), Vec3::Z).unwrap(),
            mirror,
        )
        .unwrap();
    scene
        .add(
            Shape::plane(Vec3::new(0.0, 0.0, 1.0), -Vec3::Z).unwrap(),
            mirror,
        )
        .unwrap();
    scene.set_background(Rgb::ONE).unwrap();
    for depth in [0u32, 1, 3, 7] {
        let r: Renderer<_, 2, 1, 8> = Renderer::new(&scene, &NoCaustics, depth).unwrap();
        let mut count = RayCount::default();
        let l = r.radiance(camera.ray(0, 0), &mut count);
        assert_eq!(l, Rgb::ZERO);
        assert_eq!(count.eye, depth as u64 + 1, "depth {depth}");
    }
    assert!(
        Renderer::<_, 2, 1, 8>::new(&scene, &NoCaustics, 9).is_err(),
        "max_depth beyond the stack"
    );
}

/// The glass sphere rendered with the default throughput cut-off and ray budget, and
/// with neither (cut-off 0, a budget no pixel reaches), against the same caustic store:
/// what the pruning leaves out stays below 1e-3 of the image (relative RMSE).
#[test]
fn pruned_eye_paths_stay_within_tolerance_of_the_full_tree() {
    let (scene, mut settings) = small("glass_sphere.json", 64, 48);
    settings = PhotonSettings::new(20_000, 64, 0.05, settings.max_depth()).unwrap();
    let photons = filled(&scene, &settings, 1);
    let store = photon::store_over::<128>(photons.tree(), photons.unit(), &settings).unwrap();
    let image = |cutoff: f32, budget: u32| {
        let r: Renderer<'_, _, { MAX_OBJECTS }, { MAX_LIGHTS }, { MAX_DEPTH }> =
            Renderer::new(&scene, &store, settings.max_depth())
                .unwrap()
                .with_cutoff(cutoff)
                .unwrap()
                .with_ray_budget(budget)
                .unwrap();
        let mut frame = vec![PixelEstimate::default(); 64 * 48];
        let rays = render_rows(&r, &mut frame, (64, None), 2, &Progress::new(false, 48));
        let mut img = caustic::desktop::Image::new(64, 48);
        for (p, f) in img.pixels.iter_mut().zip(&frame) {
            *p = f.radiance;
        }
        (img, rays)
    };
    let (pruned, pruned_rays) = image(DEFAULT_CUTOFF, DEFAULT_RAY_BUDGET);
    let (full, full_rays) = image(0.0, u32::MAX);
    let e = compare(&pruned, &full, None).unwrap();
    println!(
        "rel RMSE {:.2e}; eye rays {} pruned, {} full",
        e.rel_rmse, pruned_rays.eye, full_rays.eye
    );
    assert!(e.rel_rmse < 1e-3, "rel RMSE {}", e.rel_rmse);
    // The cut-off did prune something (else this test measures nothing).
    assert!(pruned_rays.eye < full_rays.eye);
}

/// Overlapping classic spheres, each both reflective and transparent, inside a
/// classic box, at `max_depth` 30: 2^30 branches per pixel without a bound. With the
/// cut-off off, every pixel's rays (eye + shadow) stay within the budget, and spend
/// most of it; with the default cut-off too.
#[test]
fn a_deep_classic_scene_spends_at_most_the_ray_budget_per_pixel() {
    let camera = Camera::new(Vec3::new(0.0, 0.0, 0.5), Vec3::NEG_Z, Vec3::Y, 60.0, 16, 12).unwrap();
    let mut scene: Scene<8, 2> = Scene::new(camera);
    let glassy = Material::classic(Classic::new(
        Rgb::splat(0.9),
        0.1,
        0.5,
        0.5,
        20.0,
        0.5,
        0.5,
        1.5,
    ))
    .unwrap();
    for (x, y, z) in [
        (0.0, 0.0, -1.0),
        (0.4, 0.1, -1.2),
        (-0.3, -0.2, -0.8),
        (0.1, 0.3, -1.5),
    ] {
        scene
            .add(Shape::sphere(Vec3::new(x, y, z), 0.5).unwrap(), glassy)
            .unwrap();
    }
    let walls =
        Material::classic(Classic::new(Rgb::ONE, 0.1, 0.2, 0.0, 1.0, 0.8, 0.2, 1.2)).unwrap();
    scene
        .add(
            Shape::cuboid(Vec3::new(0.0, 0.0, -1.0), Vec3::splat(6.0), Vec3::ZERO).unwrap(),
            walls,
        )
        .unwrap();
    add_light(&mut scene, Vec3::new(0.5, 1.0, 0.0), Rgb::splat(5.0));
    add_light(&mut scene, Vec3::new(-1.0, -1.0, -1.0), Rgb::splat(2.0));
    for (cutoff, budget) in [
        (0.0, 300),
        (0.0, DEFAULT_RAY_BUDGET),
        (DEFAULT_CUTOFF, DEFAULT_RAY_BUDGET),
    ] {
        let r: Renderer<_, 8, 2, 32> = Renderer::new(&scene, &NoCaustics, 30)
            .unwrap()
            .with_cutoff(cutoff)
            .unwrap()
            .with_ray_budget(budget)
            .unwrap();
        let mut most = 0;
        for y in 0..12 {
            for x in 0..16 {
                let mut count = RayCount::default();
                let l = r.radiance(camera.ray(x, y), &mut count);
                assert!(l.is_finite());
                let rays = count.eye + count.shadow;
                assert!(
                    rays <= budget as u64,
                    "pixel ({x}, {y}): {rays} rays > {budget}"
                );
                most = most.max(rays);
            }
        }
        println!("cut-off {cutoff}, budget {budget}: at most {most} rays in a pixel");
        if cutoff == 0.0 {
            // Without the cut-off the tree is far larger than any budget: it is the
            // budget that stopped it, within one eye ray and its shadow rays.
            assert!(most + 3 > budget as u64, "{most}");
        }
    }
    // A budget that cannot shade one camera ray (1 eye + 2 shadow rays) is refused.
    assert!(Renderer::<_, 8, 2, 32>::new(&scene, &NoCaustics, 30)
        .unwrap()
        .with_ray_budget(2)
        .is_err());
}

/// `rows` refuses a row buffer shorter than the width (no cropped image) and hands the
/// sink exactly `width` pixels from a longer one.
#[test]
fn rows_refuses_a_short_row_buffer() {
    let camera = Camera::new(Vec3::new(0.0, 1.0, 3.0), Vec3::ZERO, Vec3::Y, 40.0, 8, 2).unwrap();
    let mut scene: Scene<1, 1> = Scene::new(camera);
    add_floor(&mut scene, Rgb::ONE);
    let r: Renderer<_, 1, 1, 4> = Renderer::new(&scene, &NoCaustics, 4).unwrap();
    let mut short = [Rgb::ZERO; 7];
    let mut called = false;
    let e = r
        .rows(&mut short, |_, _| -> Result<(), ()> {
            called = true;
            Ok(())
        })
        .unwrap_err();
    assert!(!called, "nothing is rendered into a short buffer");
    match e {
        RowsError::Render(caustic::Error::Capacity {
            requested,
            capacity,
            ..
        }) => {
            assert_eq!((requested, capacity), (8, 7))
        }
        other => panic!("{other:?}"),
    }
    let mut long = [Rgb::ZERO; 10];
    let mut widths = Vec::new();
    r.rows(&mut long, |_, px| -> Result<(), ()> {
        widths.push(px.len());
        Ok(())
    })
    .unwrap();
    assert_eq!(widths, [8, 8]);
    // The sink's own error comes back as such, at its first row.
    let e = r
        .rows(&mut long, |y, _| if y == 1 { Err(y) } else { Ok(()) })
        .unwrap_err();
    assert_eq!(e, RowsError::Sink(1));
}

fn small(name: &str, w: u32, h: u32) -> (DesktopScene, PhotonSettings) {
    let loaded = parse_scene(&scene_text(name)).unwrap();
    let mut scene = loaded.scene;
    scene.set_camera(scene.camera().with_size(w, h).unwrap());
    let p = loaded.photons;
    (
        scene,
        PhotonSettings::new(20_000, p.k(), p.max_radius(), p.max_depth()).unwrap(),
    )
}

/// The photon buffer of one forward pass (pass 0, seed `seed`, two threads).
fn filled(scene: &DesktopScene, settings: &PhotonSettings, seed: u64) -> PhotonBuffer {
    let mut buf = PhotonBuffer::for_budget(scene, settings).unwrap();
    let mut stats = caustic::desktop::RenderStats::default();
    buf.fill(scene, settings, seed, 0, 2, &mut stats, &Progress::hidden())
        .unwrap();
    buf
}

/// The desktop's eye pass over `store` under `sampling`, with the splats' caustics
/// left out of the rows (the desktop adds their sums to each finished row).
fn eye_pass<'a, S: CausticStore>(
    scene: &'a DesktopScene,
    store: &'a S,
    settings: &PhotonSettings,
    sampling: Sampling,
) -> Renderer<'a, S, MAX_OBJECTS, MAX_LIGHTS, MAX_DEPTH> {
    Renderer::new(scene, store, settings.max_depth())
        .unwrap()
        .with_sampling(sampling)
        .unwrap()
        .with_splats(&[])
}

/// [`eye_pass`] under the desktop's adaptive sampling.
fn adaptive<'a, S: CausticStore>(
    scene: &'a DesktopScene,
    store: &'a S,
    settings: &PhotonSettings,
) -> Renderer<'a, S, MAX_OBJECTS, MAX_LIGHTS, MAX_DEPTH> {
    eye_pass(scene, store, settings, Sampling::Adaptive(REFINE))
}

fn bits(img: &caustic::desktop::Image) -> Vec<[u32; 3]> {
    img.pixels
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

/// Threads only change the order rows are computed in: the image is bit-identical.
#[test]
fn images_are_bit_identical_whatever_the_thread_count() {
    for name in ["two_balls.json", "fig6.json"] {
        let (scene, settings) = small(name, 64, 48);
        let one = RenderOptions {
            threads: 1,
            seed: 3,
            ..RenderOptions::default()
        };
        let (a, sa) = render(&scene, &settings, &one).unwrap();
        let (b, sb) = render(
            &scene,
            &settings,
            &RenderOptions {
                threads: 5,
                ..one.clone()
            },
        )
        .unwrap();
        assert_eq!(bits(&a), bits(&b), "{name}");
        assert_eq!((sa.rays, sa.photons_stored), (sb.rays, sb.photons_stored));
        assert!(sa.photons_stored > 0 && a.pixels.iter().all(|p| p.is_finite()));
        // Another seed gives other photons, and so another image.
        let (c, _) = render(
            &scene,
            &settings,
            &RenderOptions {
                seed: 4,
                ..one.clone()
            },
        )
        .unwrap();
        assert_ne!(bits(&a), bits(&c), "{name}");
    }
}

/// Rows rendered from corner lines traced beforehand are the rows rendered alone, bit
/// for bit, for half the corner rays (each line traced once instead of twice); the
/// rows' counts of supersampled pixels are what their renders report.
#[test]
fn rows_between_corner_lines_are_the_rows() {
    let (scene, settings) = small("two_balls.json", 40, 30);
    let buf = filled(&scene, &settings, 1);
    let store = buf.store::<64>(&settings).unwrap();
    let r = adaptive(&scene, &store, &settings);
    let (w, h) = (40usize, 30u32);
    let mut lines = vec![vec![caustic::render::Sample::default(); w + 1]; h as usize + 1];
    let mut traced = RayCount::default();
    for (cy, line) in lines.iter_mut().enumerate() {
        traced += r.corner_line(cy as u32, line);
    }
    let (mut alone, mut between) = (RayCount::default(), traced);
    let mut supersampled = 0;
    for y in 0..h {
        let (mut a, mut b) = (
            vec![PixelEstimate::default(); w],
            vec![PixelEstimate::default(); w],
        );
        alone += r.row(y, &mut a);
        let (top, bottom) = (&lines[y as usize], &lines[y as usize + 1]);
        let got = r.row_between(y, (top, bottom), &mut b);
        assert_eq!(a, b, "row {y}");
        assert_eq!(got.refined, r.supersampled(top, bottom) as u64, "row {y}");
        supersampled += got.refined;
        between += got;
    }
    assert!(supersampled > 0);
    // Rows alone trace every line but the first and last twice: 29 lines of 41
    // corners, each at least one eye ray.
    assert!(alone.eye - between.eye >= 29 * 41, "{between:?} {alone:?}");
    assert_eq!((alone.refined, alone.shadow > 0), (between.refined, true));
}

/// Progressive passes too: the same seed gives the same bits on any number of threads.
#[test]
fn progressive_passes_are_bit_identical_whatever_the_thread_count() {
    let (scene, settings) = small("glass_sphere.json", 48, 36);
    let one = RenderOptions {
        threads: 1,
        seed: 5,
        passes: 3,
        ..RenderOptions::default()
    };
    let (a, sa) = render(&scene, &settings, &one).unwrap();
    let (b, _) = render(&scene, &settings, &RenderOptions { threads: 4, ..one }).unwrap();
    assert_eq!(bits(&a), bits(&b));
    assert_eq!(sa.passes, 3);
    assert_eq!(sa.photons_emitted, 3 * settings.count() as u64);
}

/// The Fig. 6 scene the device builds in code is the scene in `scenes/fig6.json`.
#[test]
fn the_device_scene_is_the_scene_file() {
    let file = parse_scene(&scene_text("fig6.json")).unwrap().scene;
    let code: DesktopScene = caustic::demo::fig6(320, 240).unwrap();
    assert_eq!(file.objects(), code.objects());
    assert_eq!(file.lights(), code.lights());
    assert_eq!(file.camera(), code.camera());
    assert_eq!(
        (file.background(), file.ambient()),
        (code.background(), code.ambient())
    );
}

/// Every scene in `scenes/` parses.
#[test]
fn example_scenes_parse() {
    for entry in std::fs::read_dir(format!("{}/scenes", env!("CARGO_MANIFEST_DIR"))).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "json") {
            parse_scene(&std::fs::read_to_string(&path).unwrap())
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        }
    }
}

/// Applies `edit` to the glass-sphere scene's JSON and returns the parse error.
fn error_after(edit: impl FnOnce(&mut serde_json::Value)) -> caustic::desktop::SceneError {
    let mut v: serde_json::Value = serde_json::from_str(&scene_text("glass_sphere.json")).unwrap();
    edit(&mut v);
    parse_scene(&v.to_string()).expect_err("must be rejected")
}

/// `(JSON pointer, new value)`: sets the value there (adding an object key if needed).
fn set(pointer: &str, value: serde_json::Value) -> impl FnOnce(&mut serde_json::Value) {
    let pointer = pointer.to_string();
    move |v| {
        let (parent, key) = pointer.rsplit_once('/').unwrap();
        let p = v.pointer_mut(parent).unwrap();
        match p {
            serde_json::Value::Array(a) => a[key.parse::<usize>().unwrap()] = value,
            serde_json::Value::Object(o) => {
                o.insert(key.to_string(), value);
            }
            _ => panic!("{pointer}"),
        }
    }
}

/// Each `(pointer, value, path, message)`: the glass-sphere scene with that value set
/// fails to parse, with an error at `path` whose message contains `message`.
fn check_errors(cases: Vec<(&str, serde_json::Value, &str, &str)>) {
    for (pointer, value, path, message) in cases {
        let e = error_after(set(pointer, value));
        assert_eq!(e.path, path, "{pointer}: {e}");
        assert!(
            e.message.contains(message),
            "{pointer}: {e} (wanted “{message}”)"
        );
    }
}

#[test]
fn object_errors_name_their_path_and_problem() {
    use serde_json::json;
    check_errors(vec![
        ("/camra", json!(1), "camra", "unknown field `camra`"),
        (
            "/objects/1/radius",
            json!(0),
            "objects[1].radius",
            "must be positive",
        ),
        (
            "/objects/1/radius",
            json!(-2.5),
            "objects[1].radius",
            "must be positive",
        ),
        (
            "/objects/1/radius",
            json!("big"),
            "objects[1].radius",
            "invalid type",
        ),
        (
            "/objects/1/radius",
            json!(1e300),
            "objects[1].radius",
            "finite",
        ),
        (
            "/objects/1/radus",
            json!(1),
            "objects[1].radus",
            "unknown field `radus`",
        ),
        (
            "/objects/0/type",
            json!("torus"),
            "objects[0].type",
            "unknown type \"torus\"",
        ),
        (
            "/objects/0/normal",
            json!([0, 0, 0]),
            "objects[0].normal",
            "degenerate",
        ),
        (
            "/objects/1/material",
            json!("glas"),
            "objects[1].material",
            "unknown material \"glas\"",
        ),
        (
            "/objects/1/center",
            json!([0, 1]),
            "objects[1].center",
            "invalid length 2",
        ),
        (
            "/objects/1",
            json!({"type": "box", "center": [0,0,0], "size": [1, 0, 1], "material": "glass"}),
            "objects[1].size",
            "must be positive",
        ),
        (
            "/objects/1",
            json!({"type": "cylinder", "base": [0,0,0], "axis": [0,0,0], "radius": 1,
                   "height": 1, "material": "glass"}),
            "objects[1].axis",
            "degenerate",
        ),
        (
            "/background",
            json!([0, f64::MAX, 0]),
            "background",
            "finite",
        ),
    ]);
    let e = error_after(|v| {
        v["objects"][1].as_object_mut().unwrap().remove("radius");
    });
    assert_eq!(e.path, "objects[1]", "{e}");
    assert!(e.message.contains("missing field `radius`"), "{e}");
    let e = parse_scene("{ \"camera\": ").unwrap_err();
    assert!(e.message.starts_with("invalid JSON"), "{e}");
    let e = parse_scene("[1, 2]").unwrap_err();
    assert!(e.message.contains("invalid type"), "{e}");
}

#[test]
fn material_and_light_errors_name_their_path_and_problem() {
    use serde_json::json;
    let classic = json!({"type": "classic", "color": [1,1,1], "ambient": 0.1, "diffuse": 0.5,
        "specular": 0.1, "shininess": 5, "reflectivity": 0.6, "transparency": 0.6, "ior": 1.2});
    check_errors(vec![
        (
            "/materials/glass/ior",
            json!(-1),
            "materials.glass.ior",
            "must be positive",
        ),
        (
            "/materials/floor/albedo",
            json!([1.5, 0, 0]),
            "materials.floor.albedo",
            "[0, 1]",
        ),
        (
            "/materials/floor/type",
            json!("lambert"),
            "materials.floor.type",
            "unknown type",
        ),
        (
            "/materials/c",
            classic,
            "materials.c.reflectivity",
            "reflectivity + transparency",
        ),
        (
            "/lights/0/intensity",
            json!([-1, 0, 0]),
            "lights[0].intensity",
            "[0,",
        ),
        (
            "/lights/0/type",
            json!("spot"),
            "lights[0].type",
            "unknown type \"spot\"",
        ),
    ]);
}

#[test]
fn camera_and_image_errors_name_their_path_and_problem() {
    use serde_json::json;
    check_errors(vec![
        (
            "/camera/look_at",
            json!([0, 4, 7]),
            "camera.look_at",
            "degenerate",
        ),
        (
            "/camera/fov_y_deg",
            json!(180),
            "camera.fov_y_deg",
            "[0.001, 179]",
        ),
        ("/camera/up", json!([0, 0, 0]), "camera.up", "degenerate"),
        ("/image/width", json!(0), "image.width", "must lie in [1,"),
        ("/image/height", json!(-3), "image.height", "invalid value"),
    ]);
}

#[test]
fn photon_errors_name_their_path_and_problem() {
    use serde_json::json;
    check_errors(vec![
        ("/photons/k", json!(0), "photons.k", "must be positive"),
        ("/photons/k", json!(100_000), "photons.k", "gather capacity"),
        (
            "/photons/max_radius",
            json!(0),
            "photons.max_radius",
            "must be positive",
        ),
        (
            "/photons/max_depth",
            json!(40),
            "photons.max_depth",
            "path stack capacity",
        ),
        (
            "/photons/max_depth",
            json!(1000),
            "photons.max_depth",
            "[0, 255]",
        ),
        (
            "/photons/gather",
            json!("knn"),
            "photons.gather",
            "unknown gather \"knn\"",
        ),
        ("/photons/passes", json!(0), "photons.passes", "at least 1"),
        ("/photons/alpha", json!(1.5), "photons.alpha", "(0, 1)"),
        (
            "/photons/count",
            json!(-5),
            "photons.count",
            "invalid value",
        ),
        (
            "/photons/caustic_store",
            json!({"type": "octree"}),
            "photons.caustic_store.type",
            "unknown type",
        ),
    ]);
}

/// The program exits with status 2 and names the JSON path on bad input; on good input
/// it writes a PNG and a PFM and prints its statistics as one JSON object.
#[test]
fn the_program_reports_bad_input_with_exit_status_2() {
    let dir = std::env::temp_dir().join(format!("caustic-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.json");
    std::fs::write(
        &bad,
        scene_text("glass_sphere.json").replace("\"radius\": 1.0", "\"radius\": 0"),
    )
    .unwrap();
    let exe = env!("CARGO_BIN_EXE_caustic");
    let out = std::process::Command::new(exe)
        .args(["render", bad.to_str().unwrap(), "-o"])
        .arg(dir.join("x.png"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("objects[1].radius"), "{stderr}");
    let out = std::process::Command::new(exe)
        .args(["render", "--bogus"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    std::fs::remove_dir_all(dir).ok();
}

/// Runs `command`, asserts that it succeeded (else shows its stderr) and parses its
/// stdout as JSON.
fn json_stdout(command: &mut std::process::Command) -> serde_json::Value {
    let out = command.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// The program renders what the library renders: its PFM holds the library's bits, its
/// `--stats` the sizes and counts, and `compare` measures a known difference.
#[test]
fn the_program_writes_the_library_image_and_compares_it() {
    let dir = std::env::temp_dir().join(format!("caustic-cli-ok-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let exe = env!("CARGO_BIN_EXE_caustic");
    let scene = format!("{}/scenes/glass_sphere.json", env!("CARGO_MANIFEST_DIR"));
    let (png, pfm) = (dir.join("g.png"), dir.join("g.pfm"));
    let stats = json_stdout(
        std::process::Command::new(exe)
            .args([
                "render",
                &scene,
                "--width",
                "40",
                "--height",
                "30",
                "--photons",
                "5000",
                "--stats",
                "--quiet",
                "-o",
            ])
            .arg(&png)
            .arg("--pfm")
            .arg(&pfm),
    );
    assert_eq!(
        (stats["width"].as_u64(), stats["height"].as_u64()),
        (Some(40), Some(30))
    );
    assert_eq!(stats["photons"]["emitted"].as_u64(), Some(5000));
    assert!(
        stats["rays"]["eye"].as_u64().unwrap() >= 1200
            && stats["time_ms"]["render"].as_f64().is_some()
    );
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));
    let img = caustic::desktop::Image::read_pfm(&pfm).unwrap();
    assert_eq!((img.width, img.height), (40, 30));
    // The PFM holds exactly the image the library renders from the same file and flags
    // (seed 0, the file's gather): the program adds nothing and the PFM round trip
    // loses no bit.
    let loaded = parse_scene(&scene_text("glass_sphere.json")).unwrap();
    let mut want_scene = loaded.scene;
    want_scene.set_camera(want_scene.camera().with_size(40, 30).unwrap());
    let p = loaded.photons;
    let want_settings = PhotonSettings::new(5000, p.k(), p.max_radius(), p.max_depth())
        .unwrap()
        .with_fixed_radius(p.fixed_radius());
    let (want, _) = render(&want_scene, &want_settings, &RenderOptions::default()).unwrap();
    assert_eq!(bits(&img), bits(&want));
    // `compare` against a copy whose every value is ×1.25: the relative RMSE of a
    // uniform scaling a·x vs x is |a − 1|·√mean(x²)/mean(x).
    let mut scaled = img.clone();
    for p in &mut scaled.pixels {
        *p = *p * 1.25;
    }
    let scaled_path = dir.join("scaled.pfm");
    scaled.write_pfm(&scaled_path).unwrap();
    let c = json_stdout(
        std::process::Command::new(exe)
            .args(["compare"])
            .arg(&scaled_path)
            .arg(&pfm),
    );
    let values: Vec<f64> = img
        .pixels
        .iter()
        .flat_map(|p| p.to_array().map(f64::from))
        .collect();
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let rms = (values.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
    let want = 0.25 * rms / mean;
    let got = c["rel_rmse"].as_f64().unwrap();
    assert!((got - want).abs() < 1e-6 * want, "{got} vs {want}");
    std::fs::remove_dir_all(dir).ok();
}

/// The eye-sampled luminance (the light-traced splats aside) of pixel `(x, y)` of scene
/// `name` at 320×240 and 20k photons (seed 0), under each of `samplings`: the same
/// photons for all. The adaptive sampling refines as the desktop's does, above a floor
/// of [`REFINE_FLOOR`] times the image's mean.
fn pixel_under(name: &str, (x, y): (usize, u32), samplings: [Sampling; 3]) -> [f32; 3] {
    let (scene, settings) = small(name, 320, 240);
    let buf = filled(&scene, &settings, 0);
    let store = buf.store::<64>(&settings).unwrap();
    samplings.map(|sampling| {
        let r = eye_pass(&scene, &store, &settings, sampling)
            .with_image_floor(&mut RayCount::default())
            .unwrap();
        let mut row = vec![PixelEstimate::default(); 320];
        r.row(y, &mut row);
        row[x].radiance.luminance()
    })
}

/// Pixel `px` of scene `name` ([`pixel_under`]) on an `n × n` grid, under the adaptive
/// sampling and on a `fine × fine` grid (`[n, fine]`): asserts that the coarse grid is
/// off the fine one by more than `off` of its value and the adaptive sampling within
/// `within` of it (`[off, within]`); returns the coarse and fine values.
fn adaptive_reaches_the_fine_grid(
    name: &str,
    px: (usize, u32),
    [n, fine]: [u32; 2],
    [off, within]: [f32; 2],
) -> (f32, f32) {
    let [coarse, adaptive, exact] = pixel_under(
        name,
        px,
        [
            Sampling::Grid(n),
            Sampling::Adaptive(REFINE),
            Sampling::Grid(fine),
        ],
    );
    assert!(
        (coarse - exact).abs() > off * exact,
        "the {n}×{n} grid is already right: {coarse} {exact}"
    );
    assert!(
        (adaptive - exact).abs() < within * exact,
        "adaptive {adaptive}, {fine}×{fine} {exact}, {n}×{n} {coarse}"
    );
    (coarse, exact)
}

/// A sliver between the grid's rows: pixel (172, 72) of the sphere + wall c (320×240)
/// has the wall at its top corners and the sphere's rim at its bottom ones, and through
/// the last eighth of the pixel's height the rim shows a focus. Every sample of a 4×4
/// grid misses it (they all see the wall); the adaptive sampling, finding the corners'
/// paths different and the grid's all alike, goes on to the 8×8 grid, whose rows lie
/// between the 4×4 grid's, and from there as its error estimate asks: it agrees with a
/// 32×32 grid within 5% (0.348 against 0.345; the reference's own average: 0.36, the
/// wall alone 0.21).
#[test]
fn a_sliver_between_the_grids_rows_is_sampled() {
    let (grid4, grid32) = adaptive_reaches_the_fine_grid(
        "heldout/more/sphere_wall_c.json",
        (172, 72),
        [4, 32],
        [0.2, 0.05],
    );
    assert!(
        grid4 < grid32,
        "the 4×4 grid sees the focus: {grid4} {grid32}"
    );
}

/// A grazing pixel whose first grid's halves agree: pixel (177, 73) of the sphere +
/// wall c (320×240, 20k photons) sees the focus through the sphere's upper rim, where
/// its samples graze the glass. Its first grid costs too many rays for the jump to the
/// 16×16 grid, and both checkerboard halves of that 4×4 grid alias the focus alike, so
/// they agree: trusted, the pixel stopped there, 6% below a 32×32 grid. It now refines
/// at least once whatever its halves say, and reads the 32×32 grid's value within 1%.
#[test]
fn a_grazing_pixel_refines_past_a_first_grid_whose_halves_agree() {
    adaptive_reaches_the_fine_grid(
        "heldout/more/sphere_wall_c.json",
        (177, 73),
        [4, 32],
        [0.04, 0.01],
    );
}

/// The focus seen through a ball's rim: pixel (143, 148) of the sphere + wall (320×240,
/// 20k photons) looks through the sphere's lower rim at grazing incidence onto the
/// focus under it. Of its eye-sampled part, a 16×16 grid — where the grazing rule used
/// to stop — reads 0.059, twice a 64×64 grid's 0.028 (the same photons); the adaptive
/// sampling refines on to 32×32 and agrees with the 64×64 grid within 1.5% (0.0277).
#[test]
fn a_focus_seen_through_a_rim_refines_past_the_16x16_grid() {
    adaptive_reaches_the_fine_grid(
        "heldout/sphere_wall.json",
        (143, 148),
        [16, 64],
        [0.05, 0.015],
    );
}

/// Two grids in a row whose halves agree: pixel (172, 145) of the glass sphere
/// (320×240, 20k photons) sees the focus through the sphere's rim, where its samples
/// graze the glass. Its 4×4 grid reads 2.32, then the 8×8 one 1.80 with halves that
/// agree by chance: trusted, the pixel stopped there, 8% below a 32×32 grid (1.95). A
/// grazing pixel now also asks two grids in a row to agree, and goes on to the 16×16
/// grid (1.94).
#[test]
fn a_grazing_pixel_refines_until_two_grids_agree() {
    adaptive_reaches_the_fine_grid("glass_sphere.json", (172, 145), [8, 32], [0.05, 0.01]);
}

/// A corner brighter than every sample: pixel (221, 150) of the two balls (320×240,
/// 20k photons) has at its top-right corner a focus seen through a ball, 24 times the
/// brightness of the rest of the pixel, and no sample of its 4×4 grid sees it. The
/// grid's halves agree, so the pixel stopped there at half its value; a corner outside
/// the range of the grid's samples now counts as the error of the half sub-pixel
/// around it, and the pixel goes on to finer grids.
#[test]
fn a_corner_no_sample_matches_refines_the_pixel() {
    adaptive_reaches_the_fine_grid("two_balls.json", (221, 150), [4, 32], [0.4, 0.05]);
}

/// The image's mean luminance comes from a lattice of corners that, on an image at most
/// 32 pixels a side, is every corner once: the mean of all corner lines, bit for bit.
/// On a larger image the lattice's mean stays within 10% of all corners' mean.
#[test]
fn the_mean_luminance_samples_the_whole_image() {
    for (w, h, tolerance) in [(24, 17, 0.0), (32, 32, 0.0), (96, 72, 0.1)] {
        let (scene, settings) = small("two_balls.json", w, h);
        let buf = filled(&scene, &settings, 1);
        let store = buf.store::<64>(&settings).unwrap();
        let r = adaptive(&scene, &store, &settings);
        let mut line = vec![caustic::render::Sample::default(); w as usize + 1];
        let (mut sum, mut traced) = (0.0f64, RayCount::default());
        for cy in 0..=h {
            traced += r.corner_line(cy, &mut line);
            sum += line
                .iter()
                .map(|s| s.radiance.luminance() as f64)
                .sum::<f64>();
        }
        let all = (sum / ((w + 1) * (h + 1)) as f64) as f32;
        let mut rays = RayCount::default();
        let lattice = r.mean_luminance(&mut rays);
        assert!(all > 0.0, "{w}×{h}");
        assert!(
            (lattice - all).abs() <= tolerance * all,
            "{w}×{h}: {lattice} {all}"
        );
        if tolerance == 0.0 {
            assert_eq!(rays, traced, "{w}×{h}");
        } else {
            assert_eq!(rays.eye >= 33 * 33, rays.eye < traced.eye, "{rays:?}");
        }
    }
}

/// The refinement's floor changes only the pixels dimmer than it: a pixel whose
/// brightest corner reaches the floor is the same bits with and without it, the dimmer
/// ones stop refining sooner (fewer eye rays), and an infinite floor stops every pixel
/// at its first grid (fewer still). A negative or NaN floor is refused.
#[test]
fn the_refine_floor_spares_only_dim_pixels() {
    let (scene, settings) = small("two_balls.json", 64, 48);
    let buf = filled(&scene, &settings, 2);
    let store = buf.store::<64>(&settings).unwrap();
    let fresh = || adaptive(&scene, &store, &settings);
    let plain = fresh();
    let floor = REFINE_FLOOR * plain.mean_luminance(&mut RayCount::default());
    let render = |f: f32| {
        let r = fresh().with_refine_floor(f).unwrap();
        let mut img = vec![PixelEstimate::default(); 64 * 48];
        let mut rays = RayCount::default();
        for (y, row) in img.chunks_mut(64).enumerate() {
            rays += r.row(y as u32, row);
        }
        (img, rays)
    };
    let ((a, ra), (b, rb), (_, rc)) = (render(0.0), render(floor), render(f32::INFINITY));
    let mut line = vec![caustic::render::Sample::default(); 65];
    let corners: Vec<Vec<f32>> = (0..=48)
        .map(|cy| {
            plain.corner_line(cy, &mut line);
            line.iter().map(|s| s.radiance.luminance()).collect()
        })
        .collect();
    let (mut same, mut dim_changed) = (0, 0);
    for (i, (pa, pb)) in a.iter().zip(&b).enumerate() {
        let (x, y) = (i % 64, i / 64);
        let bright = [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)]
            .map(|(cx, cy)| corners[cy][cx])
            .into_iter()
            .fold(0.0, f32::max);
        if bright >= floor {
            assert_eq!(pa, pb, "pixel ({x}, {y})");
            same += 1;
        } else if pa != pb {
            dim_changed += 1;
        }
    }
    assert!(same > 0 && dim_changed > 0, "{same} {dim_changed}");
    assert_eq!((ra.refined, rb.refined), (rc.refined, rc.refined));
    assert!(rc.eye < rb.eye && rb.eye < ra.eye, "{ra:?} {rb:?} {rc:?}");
    for bad in [-1.0, f32::NAN] {
        assert!(fresh().with_refine_floor(bad).is_err(), "{bad}");
    }
}

//! The forward pass against analytic answers: photon density, energy through glass,
//! and projection maps against full-sphere emission.

mod support;

use std::f64::consts::PI;

use caustic::camera::Camera;
use caustic::desktop::{parse_scene, DesktopScene, Image};
use caustic::geometry::Shape;
use caustic::material::{interface, Material};
use caustic::math::{Rgb, UnitVec3, Vec3};
use caustic::photon::{
    self, balance, store_over, CausticStore, KdTree, NoCaustics, Photon, PhotonSettings,
};
use caustic::render::Renderer;
use caustic::scene::Scene;
use support::{add_floor, add_light, scene_text, worst_floor_irradiance_error};

/// Shoots, balances and returns the photons and their power unit.
fn photons<const O: usize, const L: usize>(
    scene: &Scene<O, L>,
    s: &PhotonSettings,
    seed: u64,
) -> (Vec<Photon>, f32, u64) {
    let mut buf = vec![Photon::ZERO; photon::photons_needed(scene, s)];
    let f = photon::shoot_with_splats(scene, s, seed, 0, &mut buf, &mut ()).unwrap();
    buf.truncate(f.stored);
    balance(&mut buf);
    (buf, f.power_unit, f.emitted)
}

fn camera() -> Camera {
    Camera::new(Vec3::new(0.0, 5.0, 5.0), Vec3::ZERO, Vec3::Y, 40.0, 8, 8).unwrap()
}

/// Direct photons stored on a plane: the estimate reproduces the analytic irradiance
/// `I·cosθ/d²` within 3% away from the edges.
#[test]
fn density_estimate_reproduces_analytic_irradiance() {
    let light = Vec3::new(0.0, 2.0, 0.0);
    let intensity = 7.0f32;
    let mut scene: Scene<1, 1> = Scene::new(camera());
    add_floor(&mut scene, Rgb::ONE);
    add_light(&mut scene, light, Rgb::splat(intensity));
    let settings = PhotonSettings::new(400_000, 400, 0.5, 4)
        .unwrap()
        .with_direct_photons(true);
    let (map, unit, _) = photons(&scene, &settings, 11);
    assert!(
        map.len() > 190_000,
        "half the sphere reaches the floor: {}",
        map.len()
    );
    let store = store_over::<512>(KdTree::from_balanced(&map), unit, &settings).unwrap();
    let worst = worst_floor_irradiance_error(light, intensity, 0.05, |x| {
        // Photons arrive from above: seen from below the floor, nothing.
        assert_eq!(store.irradiance(x, -UnitVec3::Y), Rgb::ZERO);
        store.irradiance(x, UnitVec3::Y).r as f64
    });
    eprintln!(
        "density: worst relative error {:.3}% over 40 points",
        worst * 100.0
    );
    assert!(worst < 0.03, "worst relative error {worst}");
}

/// A footprint gather over direct photons on a plane: its total is the photons inside
/// the parallelogram over its area, and the difference of the forward pass's two
/// halves estimates its error against the analytic irradiance (batch means): the
/// root-mean-square split over 200 footprints is within 0.6–1.6 of the root-mean-square
/// error. A photon that forgot its half would leave the split at ±total (ratio ≫ 1);
/// halves that shared photons would cancel it (ratio ≪ 1).
#[test]
fn a_footprint_gathers_halves_estimate_its_error() {
    let light = Vec3::new(0.0, 2.0, 0.0);
    let intensity = 7.0f32;
    let mut scene: Scene<1, 1> = Scene::new(camera());
    add_floor(&mut scene, Rgb::ONE);
    add_light(&mut scene, light, Rgb::splat(intensity));
    let settings = PhotonSettings::new(400_000, 16, 0.5, 4)
        .unwrap()
        .with_direct_photons(true);
    let (map, unit, _) = photons(&scene, &settings, 5);
    let store = store_over::<16>(KdTree::from_balanced(&map), unit, &settings).unwrap();
    let (mut err2, mut split2) = (0.0f64, 0.0f64);
    for i in 0..200 {
        let a = i as f32 * 0.61;
        let r = 0.004 * i as f32;
        let x = Vec3::new(r * a.cos(), 0.0, r * a.sin());
        // A slanted parallelogram of area 4·|a × b| = 4·0.06·0.04 = 0.0096, about 75
        // photons near the centre (each carries 4π·7 W / 400 000): more than
        // SPARSE_FOOTPRINT, so it is not grown.
        let f = photon::Footprint {
            a: Vec3::new(0.06, 0.0, 0.0),
            b: Vec3::new(0.02, 0.0, 0.04),
            throughput: 1.0,
            direct: 0.0,
            curvature: 0.0,
            visits: photon::FOOTPRINT_VISITS,
        };
        let h = store.irradiance_within(x, UnitVec3::Y, &f);
        let to = (light - x).as_dvec3();
        let want = intensity as f64 * (to.y / to.length()) / to.length_squared();
        err2 += (h.total.r as f64 - want).powi(2) / (want * want);
        split2 += (h.split.r as f64).powi(2) / (want * want);
    }
    let ratio = (split2 / err2).sqrt();
    eprintln!(
        "footprint: rms error {:.4}, rms split {:.4}",
        (err2 / 200.0).sqrt(),
        (split2 / 200.0).sqrt()
    );
    assert!((0.6..1.6).contains(&ratio), "split / error = {ratio}");
}

/// A clear glass slab between a light and the floor: the flux stored below equals the
/// flux the light sends onto the slab's top face times the slab's transmittance,
/// `(1 − F)²/(1 − F²)` (both faces, with every order of internal reflection), integrated
/// over the face by brute force.
#[test]
fn flux_through_a_glass_slab_matches_fresnel_transmission() {
    let (ior, half, top, light_h, intensity) = (1.5f32, 3.0f32, 1.0f32, 2.0f32, 5.0f32);
    let thickness = 0.02f32;
    let mut scene: Scene<2, 1> = Scene::new(camera());
    add_floor(&mut scene, Rgb::ONE);
    let slab = Shape::cuboid(
        Vec3::new(0.0, top - 0.5 * thickness, 0.0),
        Vec3::new(2.0 * half, thickness, 2.0 * half),
        Vec3::ZERO,
    );
    scene
        .add(slab.unwrap(), Material::dielectric(ior, Rgb::ZERO).unwrap())
        .unwrap();
    add_light(
        &mut scene,
        Vec3::new(0.0, top + light_h, 0.0),
        Rgb::splat(intensity),
    );
    let settings = PhotonSettings::new(300_000, 8, 0.1, 16).unwrap();
    let (map, unit, emitted) = photons(&scene, &settings, 5);
    assert_eq!(emitted, 300_000);
    let stored: f64 = map.iter().map(|p| p.power().r as f64 * unit as f64).sum();

    // ∫ over the top face of (I cos θ / d²) · T(θ), midpoint rule on a fine grid.
    let n = 600;
    let step = 2.0 * half as f64 / n as f64;
    let mut want = 0.0;
    for i in 0..n {
        for j in 0..n {
            let (x, z) = (
                -half as f64 + (i as f64 + 0.5) * step,
                -half as f64 + (j as f64 + 0.5) * step,
            );
            let d2 = x * x + z * z + (light_h as f64).powi(2);
            let cos = light_h as f64 / d2.sqrt();
            let d = UnitVec3::new(Vec3::new(x as f32, -light_h, z as f32)).unwrap();
            let f = interface(d, UnitVec3::Y, 1.0 / ior).reflectance as f64;
            want +=
                intensity as f64 * cos / d2 * (1.0 - f) * (1.0 - f) / (1.0 - f * f) * step * step;
        }
    }
    let rel = (stored - want) / want;
    eprintln!(
        "slab: stored {stored:.5} W, analytic {want:.5} W ({:+.3}%)",
        rel * 100.0
    );
    // Noise: Russian roulette at ~2 interfaces over ~10⁵ photons. With independent
    // choices (a PCG32 stream) σ ≈ 0.1% (+0.175% at this seed); drawn as further
    // coordinates of each photon's point, the choices are stratified (+0.020%). Light
    // leaving through the slab's thin sides is part of that.
    assert!(
        rel.abs() < 0.0006,
        "stored {stored:.5} W vs analytic {want:.5} W ({:+.3}%)",
        rel * 100.0
    );
    // And never more than the light emitted.
    assert!(stored < 4.0 * PI * intensity as f64);
}

/// The light tracer's photons split at glass (the refracted path always on with
/// `1 − F` of the power, the reflected one with probability `F`): on the glass sphere
/// over a floor, whose caustic the camera sees directly, the photons stored are those
/// of Russian roulette bit for bit, the splats' total radiance is the roulette's
/// within 1% (+0.01% here; leaving out the `1 − F` weight would add the ~8% the sphere
/// reflects, leaving out the reflected paths would lose it), and the two halves of the
/// pass disagree less pixel by pixel (their squared difference ×0.69 here, where the
/// focus's dense, well stratified photons are most of it): the roulette's thinning of
/// the refracted light is noise that splitting removes.
#[test]
fn splitting_at_glass_keeps_the_stored_photons_and_the_mean_and_cuts_the_noise() {
    let loaded = parse_scene(&scene_text("glass_sphere.json")).unwrap();
    let scene = &loaded.scene;
    let pixels = (scene.camera().width() * scene.camera().height()) as usize;
    let settings = PhotonSettings::new(200_000, 8, 0.1, 8).unwrap();
    assert!(settings.glass_splitting() && settings.camera_splats());
    // Stored photons; total splat luminance; Σ over pixels of (half 0 − half 1)².
    let run = |split: bool| {
        let settings = settings.with_glass_splitting(split);
        let (mut stored, mut halves) = (Vec::new(), vec![[0.0f64; 2]; pixels]);
        photon::forward(scene, &settings, 3, 0, |x| {
            stored.extend(x.photon);
            if let Some(s) = x.splat {
                halves[s.pixel() as usize][s.half() as usize] += s.radiance.luminance() as f64;
            }
            Ok(())
        })
        .unwrap();
        let total: f64 = halves.iter().map(|h| h[0] + h[1]).sum();
        let disagreement: f64 = halves.iter().map(|h| (h[0] - h[1]).powi(2)).sum();
        (stored, total, disagreement)
    };
    let (split, roulette) = (run(true), run(false));
    assert!(split.0.len() > 100_000);
    assert!(split.0 == roulette.0, "the stored photons differ");
    let rel = split.1 / roulette.1 - 1.0;
    let noise = split.2 / roulette.2;
    eprintln!(
        "split/roulette: total {:+.3}%, halves' disagreement ×{noise:.3}",
        rel * 100.0
    );
    assert!(
        rel.abs() < 0.01,
        "total splat radiance {:+.3}%",
        rel * 100.0
    );
    assert!(noise < 0.8, "halves' disagreement ×{noise:.3}");
}

/// The caustic term alone, as an image: the render with the photon store minus the
/// render of the same eye paths with no caustic store (direct light, which both
/// contain bit for bit, cancels), so that images compare the forward pass only.
fn caustic_image(scene: &DesktopScene, settings: &PhotonSettings, seed: u64) -> (Image, u64) {
    let (map, unit, emitted) = photons(scene, settings, seed);
    let store = store_over::<1024>(KdTree::from_balanced(&map), unit, settings).unwrap();
    fn draw<S: CausticStore>(scene: &DesktopScene, store: &S, depth: u32) -> Image {
        let cam = scene.camera();
        let mut img = Image::new(cam.width(), cam.height());
        let r: Renderer<_, 64, 16, 32> = Renderer::new(scene, store, depth).unwrap();
        for (y, row) in img.pixels.chunks_mut(cam.width() as usize).enumerate() {
            r.row(y as u32, row);
        }
        img
    }
    let depth = settings.max_depth();
    let (mut img, direct) = (draw(scene, &store, depth), draw(scene, &NoCaustics, depth));
    for (p, d) in img.pixels.iter_mut().zip(&direct.pixels) {
        *p += *d * -1.0;
    }
    (img, emitted)
}

/// Projection maps aim every photon at the objects that make caustics. The caustic they
/// give equals the one from full-sphere emission with the same number of photons hitting
/// the objects, to within the noise between two seeds, for a fraction of the photons.
#[test]
fn projection_maps_match_full_sphere_emission_for_a_fraction_of_the_work() {
    let text = scene_text("glass_sphere.json");
    let loaded = parse_scene(&text).unwrap();
    let mut scene = loaded.scene;
    // Only the caustic: light the floor with nothing else (a dark light would emit no
    // photons, so keep the light but compare caustic-only images).
    scene.set_camera(scene.camera().with_size(64, 48).unwrap());
    let n = 40_000u32;
    let maps = PhotonSettings::new(n, 64, 0.1, 8).unwrap();
    // The sphere's cone from the light: Ω = 2π(1 − cos θ), sin θ = R/d.
    let light = scene.lights()[0].position();
    let d = (Vec3::new(0.0, 1.0, 0.0) - light).length() as f64;
    let omega = 2.0 * PI * (1.0 - (1.0 - 1.0 / (d * d)).sqrt());
    let full_n = (n as f64 * 4.0 * PI / omega).round() as u32;
    let full = PhotonSettings::new(full_n, 64, 0.1, 8)
        .unwrap()
        .with_full_sphere(true);

    let (a, emitted_a) = caustic_image(&scene, &maps, 1);
    let (b, _) = caustic_image(&scene, &maps, 2);
    let (c, emitted_c) = caustic_image(&scene, &full, 1);
    assert!(
        emitted_c as f64 > 10.0 * emitted_a as f64,
        "maps save the photons that would miss"
    );
    let mean =
        |img: &Image| img.pixels.iter().map(|p| p.r as f64).sum::<f64>() / img.pixels.len() as f64;
    let rmse = |x: &Image, y: &Image| {
        (x.pixels
            .iter()
            .zip(&y.pixels)
            .map(|(p, q)| ((p.r - q.r) as f64).powi(2))
            .sum::<f64>()
            / x.pixels.len() as f64)
            .sqrt()
    };
    assert!(mean(&a) > 0.0);
    // Two unbiased estimates differ by √(σ_a² + σ_c²); two seeds of one by √2·σ. The
    // full sphere's photons are the noisier (0.020 against 0.008 per pixel here): its
    // point set spends most of its strata on directions that miss.
    let (d, _) = caustic_image(&scene, &full, 2);
    let (noise_maps, noise_full) = (rmse(&a, &b), rmse(&c, &d));
    let noise = ((noise_maps.powi(2) + noise_full.powi(2)) / 2.0).sqrt();
    let diff = rmse(&a, &c);
    eprintln!("projection maps: rmse vs full sphere {diff:.5}, seed noise {noise_maps:.5} (maps) {noise_full:.5} (full sphere), photons {emitted_a} vs {emitted_c}");
    assert!(
        diff < 1.5 * noise,
        "maps vs full sphere {diff:.4} exceeds their seed-to-seed noise {noise:.4}"
    );
    // Total caustic light agrees within 2%, each the mean of its two seeds (the full
    // sphere's two totals differ by 3.6%).
    let (maps_total, full_total) = (mean(&a) + mean(&b), mean(&c) + mean(&d));
    assert!(
        (maps_total - full_total).abs() / full_total < 0.02,
        "{maps_total} vs {full_total}"
    );
}

/// A scene with nothing to focus light does no forward pass at all.
#[test]
fn a_scene_without_caustic_objects_shoots_nothing() {
    let mut scene: Scene<1, 1> = Scene::new(camera());
    scene
        .add(
            Shape::sphere(Vec3::ZERO, 1.0).unwrap(),
            Material::diffuse(Rgb::ONE).unwrap(),
        )
        .unwrap();
    add_light(&mut scene, Vec3::Y * 3.0, Rgb::ONE);
    let s = PhotonSettings::new(1000, 8, 0.1, 4).unwrap();
    let mut buf = vec![Photon::ZERO; 1000];
    let f = photon::shoot_with_splats(&scene, &s, 0, 0, &mut buf, &mut ()).unwrap();
    assert_eq!((f.emitted, f.stored), (0, 0));
    // A budget larger than the storage is an error, not a truncation.
    let mut small = vec![Photon::ZERO; 10];
    assert!(photon::shoot_with_splats(&scene, &s, 0, 0, &mut small, &mut ()).is_err());
}

/// The desktop's parallel forward pass and balance give exactly the core's tree, on any
/// number of threads (so the image cannot depend on them).
#[test]
fn the_parallel_forward_pass_is_the_serial_one() {
    use caustic::desktop::photons::PhotonBuffer;
    use caustic::desktop::progress::Progress;
    use caustic::desktop::RenderStats;
    use caustic::photon::SplatSums;
    let text = scene_text("two_balls.json");
    let scene = parse_scene(&text).unwrap().scene;
    // Enough photons that the balance runs in parallel too (above 2^15 stored).
    let s = PhotonSettings::new(60_000, 16, 0.1, 8).unwrap();
    let (serial, unit, _) = photons(&scene, &s, 9);
    assert!(serial.len() > 1 << 15, "{}", serial.len());
    let mut splats = Vec::new();
    let mut buf = vec![Photon::ZERO; photon::photons_needed(&scene, &s)];
    photon::shoot_with_splats(&scene, &s, 9, 0, &mut buf, &mut splats).unwrap();
    assert!(splats.len() > 1000, "{}", splats.len());
    let pixels = (scene.camera().width() * scene.camera().height()) as usize;
    for threads in [1, 3] {
        let mut buf = PhotonBuffer::for_budget(&scene, &s).unwrap();
        buf.fill(
            &scene,
            &s,
            9,
            0,
            threads,
            &mut RenderStats::default(),
            &Progress::hidden(),
        )
        .unwrap();
        assert_eq!(buf.unit(), unit);
        assert_eq!(buf.tree().photons(), &serial[..], "{threads} threads");
        let mut sums = SplatSums::new(pixels);
        sums.add(&splats);
        assert_eq!(buf.splats(), &sums, "{threads} threads: splats in order");
    }
}

/// A range of photons landed together (each half's directions worked out eight at a
/// time) leaves what each photon landed alone leaves, in the same order: from an odd
/// start, across the two halves, to an end that is not a whole batch, on both lights
/// of a scene whose cones overlap (glass balls, a mirror box and a tube).
#[test]
fn landing_a_range_is_landing_each_photon() {
    let text = scene_text("heldout/balls_mirror_tube.json");
    let scene = parse_scene(&text).unwrap().scene;
    let s = PhotonSettings::new(50_000, 16, 0.1, 8).unwrap();
    let emitter = photon::Emitter::new(&scene, &s, 5, 0);
    for l in 0..scene.lights().len() {
        let mut together = Vec::new();
        emitter
            .land_range(l, 7..3001, |i, x| {
                together.push((i, x));
                Ok::<(), ()>(())
            })
            .unwrap();
        let mut alone = Vec::new();
        for i in 7..3001 {
            emitter
                .land(l, i, |x| {
                    alone.push((i, x));
                    Ok::<(), ()>(())
                })
                .unwrap();
        }
        assert!(alone.len() > 1500, "{}", alone.len());
        assert_eq!(together, alone, "light {l}");
    }
}

/// A far, sun-like light sends as much power through a glass tube and a glass box as
/// the same light fifty times nearer (each at intensity `∝ d²`, so the irradiance it
/// brings is the same and its photons arrive nearly parallel): from 10⁴ units the
/// shapes' bounding-sphere rejection once turned away half the photons aimed through the
/// tube and a quarter of those through a box (its `|f|² − (f·d)²` cancelled), and the
/// projection map counted both objects' cones for every photon, halving the tube's
/// photons' power (a cone's cosine test rounds to 1 for half-angles below 3·10⁻⁴).
/// Each alone fails this test (far/near 0.69 and 0.58).
#[test]
fn a_far_light_sends_its_photons_through_tubes_and_boxes() {
    let stored_power = |distance: f32| {
        let mut scene: Scene<3, 1> = Scene::new(camera());
        add_floor(&mut scene, Rgb::ONE);
        let glass = Material::dielectric(1.5, Rgb::ZERO).unwrap();
        let tube = Shape::cylinder(Vec3::new(-1.0, 0.3, 0.0), Vec3::X, 0.3, 1.2, true);
        let cube = Shape::cuboid(
            Vec3::new(1.0, 0.6, 0.0),
            Vec3::splat(0.4),
            Vec3::new(0.0, 30.0, 10.0),
        );
        for shape in [tube, cube] {
            scene.add(shape.unwrap(), glass).unwrap();
        }
        let towards = Vec3::new(0.3, 1.0, 0.2).normalize();
        add_light(
            &mut scene,
            towards * distance,
            Rgb::splat(distance * distance),
        );
        let settings = PhotonSettings::new(40_000, 64, 0.25, 4).unwrap();
        let (map, unit, _) = photons(&scene, &settings, 3);
        let total: f64 = map.iter().map(|p| p.power().r as f64 * unit as f64).sum();
        (map.len(), total)
    };
    let (near_count, near) = stored_power(200.0);
    let (far_count, far) = stored_power(1.0e4);
    assert!(near_count > 15_000, "{near_count}");
    let ratio = far / near;
    assert!(
        (ratio - 1.0).abs() < 0.02,
        "stored power from 10^4 units {far} against 200 units {near} ({far_count} / {near_count} photons)"
    );
}

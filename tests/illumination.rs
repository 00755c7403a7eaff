//! Illumination maps (Arvo; paper section 3.1) against analytic answers: flat maps
//! from uniform flux, energy conservation, true texel areas, the single-photon round
//! trip, determinism, and the streaming forward pass against `shoot_with_splats`.

mod support;

use std::f64::consts::PI;

use caustic::camera::Camera;
use caustic::desktop::parse_scene;
use caustic::geometry::Shape;
use caustic::light::PointLight;
use caustic::material::Material;
use caustic::math::{Rgb, UnitVec3, Vec3};
use caustic::photon::{
    self, for_each_photon, CausticStore, FixedIlluminationMaps, IlluminationMaps, Photon,
    PhotonSettings,
};
use caustic::scene::Scene;
use support::{add_light, data_text, scene_text, worst_floor_irradiance_error};

type Maps = IlluminationMaps<Vec<Rgb>, 8>;

fn camera() -> Camera {
    Camera::new(Vec3::new(0.0, 5.0, 5.0), Vec3::ZERO, Vec3::Y, 40.0, 8, 8).unwrap()
}

fn diffuse() -> Material {
    Material::diffuse(Rgb::ONE).unwrap()
}

fn scene_of(shapes: &[Shape]) -> Scene<8, 1> {
    let mut s: Scene<8, 1> = Scene::new(camera());
    for &sh in shapes {
        s.add(sh, diffuse()).unwrap();
    }
    s.add_light(PointLight::new(Vec3::new(0.0, 5.0, 0.0), Rgb::splat(1.0)).unwrap())
        .unwrap();
    s
}

fn down() -> UnitVec3 {
    -UnitVec3::Y
}

/// A uniform flux of photons (a regular grid, power 1 unit each) over a square of the
/// plane gives a flat map equal to `N·Φ/A` in every texel, and the reconstruction
/// anywhere inside equals it too.
#[test]
fn uniform_flux_gives_a_flat_map_equal_to_the_analytic_irradiance() {
    let scene = scene_of(&[Shape::plane(Vec3::ZERO, Vec3::Y).unwrap()]);
    // 200 × 200 photons on [0, 2)², texel 0.1: 10 × 10 photons per texel.
    let (n, side, unit) = (200usize, 2.0f32, 0.5f32);
    let step = side / n as f32;
    let photons: Vec<Photon> = (0..n * n)
        .map(|k| {
            let (i, j) = (k % n, k / n);
            let p = Vec3::new((i as f32 + 0.5) * step, 0.0, (j as f32 + 0.5) * step);
            Photon::new(p, down(), Rgb::ONE)
        })
        .collect();
    let mut maps = Maps::new(Vec::new(), 0.1).unwrap().with_trim(0.0).unwrap();
    let stats = maps.build_from_photons(&scene, &photons, unit).unwrap();
    assert_eq!(stats.splatted_photons, (n * n) as u64);
    let want = (n * n) as f64 * unit as f64 / (side as f64 * side as f64);
    let (w, h) = maps.chart_size(0, 0).unwrap();
    assert_eq!((w, h), (20, 20));
    let texels = maps.chart_texels(0, 0).unwrap();
    let mut worst = 0.0f64;
    for j in 0..h as usize {
        for i in 0..w as usize {
            // The rectangle is the photons' bounding box: 20 texels of 0.1 from the
            // first photon at step/2, so the edge texels' clamped weights do not see
            // the half photon spacing at the first edge and reach past the photons at
            // the last: only the border differs.
            if i == 0 || j == 0 || i + 1 == w as usize || j + 1 == h as usize {
                continue;
            }
            let e = texels[j * w as usize + i].g as f64;
            worst = worst.max((e - want).abs() / want);
        }
    }
    eprintln!("flat map: worst relative deviation {worst:.2e} (E = {want})");
    assert!(worst < 2e-3, "worst {worst}");
    for k in 0..50 {
        let x = Vec3::new(0.2 + 0.027 * k as f32, 0.0, 1.7 - 0.021 * k as f32);
        let e = maps.irradiance(x, UnitVec3::Y).b as f64;
        assert!((e - want).abs() / want < 2e-3, "{x:?}: {e} vs {want}");
        // Seen from behind: nothing.
        assert_eq!(maps.irradiance(x, -UnitVec3::Y), Rgb::ZERO);
    }
}

/// Direct photons from a point light (the forward pass, no array): the map
/// reproduces `I·cosθ/d²` near the light's foot.
#[test]
fn direct_photons_reproduce_the_analytic_irradiance() {
    let light = Vec3::new(0.0, 2.0, 0.0);
    let intensity = 7.0f32;
    let mut scene: Scene<1, 1> = Scene::new(camera());
    scene
        .add(Shape::plane(Vec3::ZERO, Vec3::Y).unwrap(), diffuse())
        .unwrap();
    add_light(&mut scene, light, Rgb::splat(intensity));
    let settings = PhotonSettings::new(400_000, 64, 0.5, 4)
        .unwrap()
        .with_direct_photons(true);
    // A 20 × 20 scene-unit floor at texel 0.1 needs far more than this: the trim
    // keeps the central part, where the photons are dense.
    let mut maps = IlluminationMaps::<Vec<Rgb>, 1>::new(Vec::new(), 0.1)
        .unwrap()
        .with_trim(0.2)
        .unwrap();
    let (forward, stats) = maps.build(&scene, &settings, 11).unwrap();
    assert!(forward.stored > 190_000);
    eprintln!("direct: {:?}", stats);
    let worst = worst_floor_irradiance_error(light, intensity, 0.02, |x| {
        maps.irradiance(x, UnitVec3::Y).r as f64
    });
    eprintln!("direct: worst relative error {:.3}%", worst * 100.0);
    assert!(worst < 0.03, "worst {worst}");
}

/// The energy in the maps (`Σ E·area`) equals the energy splatted into them, and
/// splatted + dropped equals what the forward pass stored, on a real caustic scene.
#[test]
fn total_energy_equals_the_energy_splatted() {
    let text = scene_text("glass_sphere.json");
    let loaded = parse_scene(&text).unwrap();
    let settings = PhotonSettings::new(20_000, 32, 0.1, 8).unwrap();
    let mut maps = IlluminationMaps::<Vec<Rgb>, 64>::new(Vec::new(), 0.05).unwrap();
    let (forward, stats) = maps.build(&loaded.scene, &settings, 3).unwrap();
    assert!(forward.stored > 1000);
    let total = maps.total_energy();
    let s = stats.splatted;
    for (t, want) in total.iter().zip([s.r, s.g, s.b]) {
        assert!(
            (t - want as f64).abs() / (want as f64) < 1e-4,
            "{t} vs {want}"
        );
    }
    let mut stored = [0.0f64; 3];
    for_each_photon(&loaded.scene, &settings, 3, 0, |p| {
        for (a, c) in stored.iter_mut().zip(p.power().to_array()) {
            *a += (c * forward.power_unit) as f64;
        }
    });
    let sum = stats.splatted + stats.dropped;
    assert!((stored[0] - sum.r as f64).abs() / stored[0] < 1e-4);
    assert_eq!(
        stats.splatted_photons + stats.dropped_photons,
        forward.stored as u64
    );
    eprintln!(
        "glass sphere: {} texels, {} dropped of {} photons",
        stats.texels, stats.dropped_photons, forward.stored
    );
}

/// One photon on each shape lays out its charts; their true texel areas sum to the
/// analytic areas: 4πr² for a sphere, 2πrh for a cylinder's side, πr² for each cap,
/// each face of a box.
#[test]
fn texel_areas_integrate_to_the_surface_areas() {
    let r = 0.7f32;
    let (cr, ch) = (0.45f32, 1.3f32);
    let scene = scene_of(&[
        Shape::sphere(Vec3::new(0.0, 1.0, 0.0), r).unwrap(),
        Shape::cylinder(
            Vec3::new(3.0, 0.0, 0.0),
            Vec3::new(0.2, 1.0, 0.1),
            cr,
            ch,
            true,
        )
        .unwrap(),
        Shape::cuboid(
            Vec3::new(-3.0, 1.0, 0.0),
            Vec3::new(1.0, 0.6, 0.35),
            Vec3::new(10.0, 20.0, 30.0),
        )
        .unwrap(),
    ]);
    let top_of = |k: usize| -> Photon {
        // A photon falling on the top of object k.
        let o = scene.objects()[k].shape;
        let ray = caustic::geometry::Ray::new(
            match o {
                Shape::Sphere(s) => s.center(),
                Shape::Cylinder(c) => c.base() + c.axis().get() * 0.5,
                Shape::Box(b) => b.center(),
                Shape::Plane(_) => unreachable!(),
            } + Vec3::new(0.0, 5.0, 0.0),
            down(),
        );
        let hit = o.intersect(&ray, f32::INFINITY).unwrap();
        Photon::new(hit.point, down(), Rgb::ONE)
    };
    let photons: Vec<Photon> = (0..3).map(top_of).collect();
    for texel in [0.3f32, 0.05, 0.011] {
        let mut maps = Maps::new(Vec::new(), texel).unwrap();
        let stats = maps.build_from_photons(&scene, &photons, 1.0).unwrap();
        assert_eq!(stats.splatted_photons, 3);
        let sphere = maps.chart_area(0, 0).unwrap();
        let want = 4.0 * PI * (r as f64).powi(2);
        assert!(
            (sphere - want).abs() / want < 1e-6,
            "{texel}: {sphere} vs {want}"
        );
        let side = maps.chart_area(1, 0).unwrap();
        let want = 2.0 * PI * cr as f64 * ch as f64;
        assert!(
            (side - want).abs() / want < 1e-6,
            "{texel}: {side} vs {want}"
        );
        for cap in [1, 2] {
            let a = maps.chart_area(1, cap).unwrap();
            let want = PI * (cr as f64).powi(2);
            assert!((a - want).abs() / want < 1e-6, "{texel}: cap {a} vs {want}");
        }
        let faces: f64 = (0..6).map(|f| maps.chart_area(2, f).unwrap()).sum();
        let want = 2.0 * (1.0 * 0.6 + 0.6 * 0.35 + 0.35 * 1.0);
        assert!((faces - want).abs() / want < 1e-6, "{faces} vs {want}");
        let (w, h) = maps.chart_size(0, 0).unwrap();
        eprintln!("texel {texel}: sphere {w}×{h}, {} texels", stats.texels);
    }
}

/// Numerical ∫ E dA of the reconstruction over a sphere (midpoint rule in longitude
/// and latitude, `dA = r² cos v du dv`).
fn sphere_integral(maps: &Maps, center: Vec3, r: f32, steps: (usize, usize)) -> f64 {
    let (nu, nv) = steps;
    let mut sum = 0.0f64;
    for j in 0..nv {
        let v = -PI / 2.0 + (j as f64 + 0.5) * PI / nv as f64;
        for i in 0..nu {
            let u = (i as f64 + 0.5) * 2.0 * PI / nu as f64;
            let d = Vec3::new(
                (v.cos() * u.cos()) as f32,
                v.sin() as f32,
                (v.cos() * u.sin()) as f32,
            );
            let n = UnitVec3::new(d).unwrap();
            let e = maps.irradiance(center + n.get() * r, n).g as f64;
            sum += e * (r as f64).powi(2) * v.cos() * (2.0 * PI / nu as f64) * (PI / nv as f64);
        }
    }
    sum
}

/// One photon, splatted bilinearly and reconstructed bilinearly: the integral of the
/// irradiance over the surface is its energy, on a sphere (non-uniform texel areas,
/// wrapping longitude), near a pole, and on a plane.
#[test]
fn single_photon_round_trip_conserves_energy() {
    let (c, r) = (Vec3::new(0.0, 1.0, 0.0), 1.0f32);
    let scene = scene_of(&[Shape::sphere(c, r).unwrap()]);
    for (u, v) in [(0.3f32, 0.4f32), (6.27, -0.2), (1.0, 1.5)] {
        let d = Vec3::new(v.cos() * u.cos(), v.sin(), v.cos() * u.sin());
        let photon = Photon::new(c + d * r, UnitVec3::new(-d).unwrap(), Rgb::splat(1.0));
        let mut maps = Maps::new(Vec::new(), 0.1).unwrap();
        maps.build_from_photons(&scene, &[photon], 2.5).unwrap();
        let total = sphere_integral(&maps, c, r, (63 * 24, 32 * 24));
        eprintln!("sphere photon at ({u}, {v}): ∫E dA = {total}");
        assert!((total - 2.5).abs() / 2.5 < 2e-3, "({u}, {v}): {total}");
        let stored = maps.total_energy()[1];
        assert!((stored - 2.5).abs() < 1e-5, "{stored}");
    }
    // A plane: a 1 × 1 rectangle (zero-power photons at its corners), one photon inside.
    let scene = scene_of(&[Shape::plane(Vec3::ZERO, Vec3::Y).unwrap()]);
    let mut photons: Vec<Photon> = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
        .iter()
        .map(|&(x, z)| Photon::new(Vec3::new(x, 0.0, z), down(), Rgb::ZERO))
        .collect();
    photons.push(Photon::new(Vec3::new(0.437, 0.0, 0.611), down(), Rgb::ONE));
    let mut maps = Maps::new(Vec::new(), 0.1).unwrap().with_trim(0.0).unwrap();
    maps.build_from_photons(&scene, &photons, 1.0).unwrap();
    let steps = 400;
    let mut sum = 0.0f64;
    for j in 0..steps {
        for i in 0..steps {
            let x = Vec3::new(
                (i as f32 + 0.5) / steps as f32,
                0.0,
                (j as f32 + 0.5) / steps as f32,
            );
            sum += maps.irradiance(x, UnitVec3::Y).r as f64 / (steps * steps) as f64;
        }
    }
    assert!((sum - 1.0).abs() < 1e-3, "plane: {sum}");
}

/// The same seed gives the same bits; the streaming forward pass hands out exactly
/// the photons `shoot_with_splats` stores, so maps built either way are identical; and a fixed
/// array holds the same maps as a `Vec`.
#[test]
fn same_seed_same_bits_and_streaming_equals_stored() {
    let text = scene_text("tube.json");
    let loaded = parse_scene(&text).unwrap();
    let scene = &loaded.scene;
    let settings = PhotonSettings::new(5_000, 32, 0.1, 8).unwrap();
    let mut shot = vec![Photon::ZERO; photon::photons_needed(scene, &settings)];
    let f = photon::shoot_with_splats(scene, &settings, 9, 0, &mut shot, &mut ()).unwrap();
    shot.truncate(f.stored);
    let mut streamed = Vec::new();
    let g = for_each_photon(scene, &settings, 9, 0, |p| streamed.push(*p));
    assert_eq!(f, g);
    assert_eq!(shot, streamed);

    let build = || {
        let mut m = IlluminationMaps::<Vec<Rgb>, 64>::new(Vec::new(), 0.04).unwrap();
        m.build(scene, &settings, 9).unwrap();
        m
    };
    let (a, b) = (build(), build());
    let bits = |m: &IlluminationMaps<Vec<Rgb>, 64>| -> Vec<u32> {
        m.chart_texels(0, 0)
            .unwrap()
            .iter()
            .flat_map(|t| t.to_array().map(f32::to_bits))
            .collect()
    };
    assert_eq!(bits(&a), bits(&b));
    let mut c = IlluminationMaps::<Vec<Rgb>, 64>::new(Vec::new(), 0.04).unwrap();
    c.build_from_photons(scene, &shot, f.power_unit).unwrap();
    assert_eq!(bits(&a), bits(&c));
    // Another seed: other bits.
    let mut d = IlluminationMaps::<Vec<Rgb>, 64>::new(Vec::new(), 0.04).unwrap();
    d.build(scene, &settings, 10).unwrap();
    assert_ne!(bits(&a), bits(&d));

    // A fixed array: the same texels.
    let mut fixed: Box<FixedIlluminationMaps<40_000, 4>> =
        Box::new(FixedIlluminationMaps::fixed(0.04).unwrap());
    let scene4 = {
        let mut s: Scene<4, 1> = Scene::new(*scene.camera());
        for o in scene.objects() {
            s.add(o.shape, o.material).unwrap();
        }
        s.add_light(scene.lights()[0]).unwrap();
        s
    };
    let st = fixed.build(&scene4, &settings, 9).unwrap().1;
    assert!(st.texels <= 40_000);
    let fixed_bits: Vec<u32> = fixed
        .chart_texels(0, 0)
        .unwrap()
        .iter()
        .flat_map(|t| t.to_array().map(f32::to_bits))
        .collect();
    assert_eq!(bits(&a), fixed_bits);
    // Too small an array: the layout coarsens to fit it, and still holds the energy.
    let mut small: FixedIlluminationMaps<16, 4> = FixedIlluminationMaps::fixed(0.04).unwrap();
    let st = small.build(&scene4, &settings, 9).unwrap().1;
    assert!(st.texels <= 16 && st.coarsened_objects >= 1, "{st:?}");
    let total = small.total_energy()[0];
    assert!((total - st.splatted.r as f64).abs() / total < 1e-4);
}

/// Photons arriving from behind a surface are dropped, as in the kd-tree store.
#[test]
fn photons_from_behind_are_not_splatted() {
    let scene = scene_of(&[Shape::plane(Vec3::ZERO, Vec3::Y).unwrap()]);
    let photons = [
        Photon::new(Vec3::new(0.0, 0.0, 0.0), down(), Rgb::ZERO),
        Photon::new(Vec3::new(1.0, 0.0, 1.0), down(), Rgb::ZERO),
        Photon::new(Vec3::new(0.5, 0.0, 0.5), UnitVec3::Y, Rgb::ONE),
    ];
    let mut maps = Maps::new(Vec::new(), 0.1).unwrap().with_trim(0.0).unwrap();
    let stats = maps.build_from_photons(&scene, &photons, 1.0).unwrap();
    assert_eq!((stats.splatted_photons, stats.dropped_photons), (2, 1));
    assert_eq!(maps.total_energy(), [0.0; 3]);
}

/// Photons scattered far over an infinite plane with a small texel would need far more
/// texels than the budget: the layout coarsens instead of failing, stays within the
/// budget, and a budget below one texel a chart is an error, not a truncation.
#[test]
fn a_layout_beyond_the_texel_budget_is_coarsened_to_fit() {
    let text = scene_text("two_balls.json");
    let scene = caustic::desktop::parse_scene(&text).unwrap().scene;
    let settings = PhotonSettings::new(20_000, 16, 0.02, 8).unwrap();
    for budget in [100_000usize, 5_000, 64] {
        let mut maps = IlluminationMaps::<Vec<Rgb>, 64>::new(Vec::new(), 0.002)
            .unwrap()
            .with_texel_budget(budget)
            .unwrap();
        let (_, st) = maps.build(&scene, &settings, 1).unwrap();
        eprintln!("budget {budget}: {st:?}");
        assert!(st.requested_texels > budget as f64, "{st:?}");
        assert!(st.texels <= budget && st.texels > budget / 2, "{st:?}");
        assert!(st.coarsened_objects >= 1 && st.largest_texel > 0.002);
        // The texel chosen per object is the largest of them, and ≥ the request.
        let chosen: Vec<f32> = (0..scene.objects().len())
            .filter_map(|k| maps.object_texel_size(k))
            .collect();
        assert!(chosen.iter().all(|&t| t >= 0.002 && t <= st.largest_texel));
        assert!(chosen.contains(&st.largest_texel));
        // Energy is still conserved in the coarser maps.
        let total = maps.total_energy()[0];
        assert!((total - st.splatted.r as f64).abs() / total < 1e-4);
    }
    let mut tiny = IlluminationMaps::<Vec<Rgb>, 64>::new(Vec::new(), 0.002)
        .unwrap()
        .with_texel_budget(1)
        .unwrap();
    let e = tiny.build(&scene, &settings, 1).unwrap_err();
    assert!(matches!(e, caustic::Error::Capacity { .. }), "{e}");
    // A budget beyond what the storage can hold is refused at the build.
    let mut over: FixedIlluminationMaps<16, 64> = FixedIlluminationMaps::fixed(0.002)
        .unwrap()
        .with_texel_budget(17)
        .unwrap();
    assert!(over.build(&scene, &settings, 1).is_err());
}

/// A glass sphere over a floor with a wall behind it (tests/data/glass_sphere_wall.json),
/// illumination maps at texel 0.02: at that size the photons scattered over the wall
/// and the floor would need ~5·10⁸ texels. It fits the default budget (the wall
/// coarsened, the floor at the requested size), the maps hold exactly the energy
/// splatted (and drop little of what landed), and the caustic flux on the floor is
/// within 15% of the kd-tree store's and within 2% of the photons that landed there.
#[test]
fn a_back_wall_fits_the_budget_and_keeps_the_caustic_energy() {
    use caustic::desktop::photons::PhotonBuffer;
    use caustic::desktop::progress::Progress;
    use caustic::desktop::{RenderStats, MAX_GATHER, MAX_OBJECTS};
    use caustic::photon::DEFAULT_HEAP_TEXELS;

    let text = data_text("glass_sphere_wall.json");
    let loaded = parse_scene(&text).unwrap();
    let texel = match loaded.caustic_store {
        caustic::desktop::scene_file::StoreChoice::IlluminationMap { texel_size } => texel_size,
        other => panic!("{other:?}"),
    };
    assert_eq!(texel, 0.02);
    let (scene, settings) = (&loaded.scene, &loaded.photons);
    let mut maps = IlluminationMaps::<Vec<Rgb>, MAX_OBJECTS>::new(Vec::new(), texel).unwrap();
    let (forward, st) = maps.build(scene, settings, 7).unwrap();
    eprintln!("wall scene: {st:?}");
    assert!(st.requested_texels > 1e8, "{st:?}");
    assert!(st.texels <= DEFAULT_HEAP_TEXELS && st.coarsened_objects >= 1);
    // The floor under the sphere (object 0) receives most photons and keeps a fine
    // texel; the wall (object 1) is coarser.
    let (floor, wall) = (
        maps.object_texel_size(0).unwrap(),
        maps.object_texel_size(1).unwrap(),
    );
    eprintln!("texel: floor {floor}, wall {wall}");
    assert!(floor < 0.05 && wall > floor, "floor {floor}, wall {wall}");
    // The map integral is the energy splatted; little of what landed is dropped.
    let total = maps.total_energy();
    for (t, want) in total.iter().zip(st.splatted.to_array()) {
        assert!(
            (t - want as f64).abs() / (want as f64) < 1e-4,
            "{t} vs {want}"
        );
    }
    let landed = (st.splatted + st.dropped).g as f64;
    assert!(st.dropped.g as f64 / landed < 0.03, "{st:?}");
    assert_eq!(
        st.splatted_photons + st.dropped_photons,
        forward.stored as u64
    );

    // The caustic flux on the floor around the sphere, three ways: the photons that
    // landed in the window (what both stores estimate), ∫E dA of the maps and of the
    // kd-tree's estimate (midpoint rule, step 0.01: finer than a texel and the radius).
    let (half, step) = (2.0f32, 0.01f32);
    let inside = |x: Vec3| x.x.abs() < half && x.z.abs() < half && x.y.abs() < 1e-3;
    let mut landed = 0.0f64;
    for_each_photon(scene, settings, 7, 0, |p| {
        if inside(p.position()) && p.direction().get().y < 0.0 {
            landed += (p.power().g * forward.power_unit) as f64;
        }
    });
    let integral = |store: &dyn CausticStore| -> f64 {
        let n = (2.0 * half / step) as usize;
        let mut sum = 0.0f64;
        for j in 0..n {
            for i in 0..n {
                let x = -half + (i as f32 + 0.5) * step;
                let z = -half + (j as f32 + 0.5) * step;
                sum += store.irradiance(Vec3::new(x, 0.0, z), UnitVec3::Y).g as f64;
            }
        }
        sum * (step * step) as f64
    };
    let mut photons = PhotonBuffer::for_budget(scene, settings).unwrap();
    photons
        .fill(
            scene,
            settings,
            7,
            0,
            2,
            &mut RenderStats::default(),
            &Progress::hidden(),
        )
        .unwrap();
    let kd = photon::store_over::<MAX_GATHER>(photons.tree(), photons.unit(), settings).unwrap();
    let (e_maps, e_kd) = (integral(&maps), integral(&kd));
    eprintln!(
        "caustic flux on the floor: landed {landed:.4} W, maps {e_maps:.4}, kd-tree {e_kd:.4}"
    );
    assert!(
        landed > 0.5 * st.splatted.g as f64,
        "the caustic is in the window"
    );
    assert!(
        (e_maps - e_kd).abs() / e_kd < 0.15,
        "maps {e_maps}, kd {e_kd}"
    );
    assert!(
        (e_maps - landed).abs() / landed < 0.05,
        "maps {e_maps}, landed {landed}"
    );
}

/// The forward pass knows the object each photon landed on, and the maps splat it
/// there, not onto whichever surface lies nearest its position: two coincident planes,
/// photons marked for the second go to the second.
#[test]
fn photons_are_splatted_on_the_object_they_landed_on() {
    let plane = Shape::plane(Vec3::ZERO, Vec3::Y).unwrap();
    let scene = scene_of(&[plane, plane]);
    let photons: Vec<Photon> = (0..10)
        .map(|i| Photon::new(Vec3::new(0.1 * i as f32, 0.0, 0.3), down(), Rgb::ONE))
        .collect();
    let mut maps = Maps::new(Vec::new(), 0.1).unwrap().with_trim(0.0).unwrap();
    let st = maps
        .build_with(&scene, |f| {
            photons.iter().for_each(|p| f(p, Some(1)));
            1.0
        })
        .unwrap();
    assert_eq!(
        (st.splatted_photons, maps.charts(0), maps.charts(1)),
        (10, 0, 1)
    );
    // Unmarked, the nearest surface (the first of two at distance 0) takes them.
    maps.build_from_photons(&scene, &photons, 1.0).unwrap();
    assert_eq!((maps.charts(0), maps.charts(1)), (1, 0));

    let loaded = parse_scene(&scene_text("glass_sphere.json")).unwrap();
    let settings = PhotonSettings::new(2_000, 8, 0.1, 8).unwrap();
    let mut n = 0;
    caustic::photon::forward(&loaded.scene, &settings, 1, 0, |x| {
        // Object 0 is the floor; every path lands on it (y = 0), and the photons stored
        // (one per photon, on its roulette's path) with it.
        assert_eq!(x.object, 0);
        if let Some(photon) = x.photon {
            assert!(photon.position().y.abs() < 1e-5);
            n += 1;
        }
        Ok(())
    })
    .unwrap();
    assert!(n > 1000);
}

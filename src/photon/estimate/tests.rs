//! The estimates' tests: footprints against brute-force sums, the levels, the widening.

extern crate std;
use super::*;
use crate::photon::balance;
use crate::photon::Photon;
use crate::sampling::Pcg32;
use std::vec::Vec;

/// A sliver whose half-axes are both long and nearly parallel — the differentials
/// of a ray entering glass at grazing incidence — is cut across its long diagonal,
/// into pieces whose reach is a fraction of the whole's; an unsheared one as before.
#[test]
fn a_sheared_sliver_is_cut_across_its_diagonal() {
    let a = Vec3::new(0.1, 0.0, 0.0);
    let b = Vec3::new(0.1, 0.0, 0.004);
    let fp = |a, b| Footprint {
        a,
        b,
        throughput: 1.0,
        direct: 0.0,
        curvature: 0.0,
        visits: FOOTPRINT_VISITS,
    };
    let region = Region::new(&fp(a, b), 1.0).unwrap();
    let cut = region.cut();
    assert_eq!(cut.segments, 16);
    let (long, short) = cut.axes(&region);
    assert_eq!((long, short), (a + b, a - b));
    let piece = long / cut.segments as f32;
    let reach2 = (piece + short)
        .length_squared()
        .max((piece - short).length_squared());
    assert!(
        reach2 < region.reach2 / 50.0,
        "{reach2} of {}",
        region.reach2
    );
    // Its coordinate along the diagonal spans [−1, 1] over the parallelogram.
    assert_eq!(cut.along(1.0, 1.0), 1.0);
    assert_eq!(cut.along(-1.0, -1.0), -1.0);
    assert_eq!(cut.along(1.0, -1.0), 0.0);
    // A rectangle four times as long as wide: four pieces across `a`, as before.
    let r = Region::new(&fp(a, Vec3::new(0.0, 0.0, 0.025)), 1.0).unwrap();
    assert_eq!(r.cut().segments, 4);
    assert_eq!(r.cut().axes(&r), (r.a, r.b));
}

/// A footprint on a faint path is the brute-force sum over the first coarse level's
/// photons inside it, each counted [`THINNING`] times (on a path below `FAINT²`, the
/// second level's, each counted `THINNING²` times); the same footprint on a
/// full-weight path reads the map itself.
#[test]
fn a_faint_footprint_is_gathered_on_the_first_coarse_level() {
    let mut g = Pcg32::new(5);
    let up = UnitVec3::Y;
    let levels = levels(&mut g);
    let [photons, level1, level2] = &levels;
    let store = store_with_levels(&levels);
    let brute = |level: &[Photon], x: Vec3, f: &Footprint| {
        let (sum, area, _) = inside(level, x, f);
        (sum, area)
    };
    let mut differ = 0;
    for q in 0..100 {
        let x = Vec3::new(g.next_f32() - 0.5, 0.0, g.next_f32() - 0.5);
        let s = 0.05 + 0.1 * g.next_f32();
        let (a, b) = (
            Vec3::new(s, 0.0, 0.2 * s),
            Vec3::new(-0.3 * s, 0.0, 0.7 * s),
        );
        let faint = Footprint {
            a,
            b,
            throughput: 0.5 * FAINT,
            direct: 0.0,
            curvature: 0.0,
            visits: FOOTPRINT_VISITS,
        };
        let (sum, area) = brute(level1, x, &faint);
        let want = sum * THINNING as f32 / area;
        let got = store.irradiance_within(x, up, &faint).total.r;
        assert!(
            (got - want).abs() <= 1e-4 * want.max(1.0),
            "footprint {q}: {got} {want}"
        );
        let fainter = Footprint {
            throughput: 0.5 * FAINT * FAINT,
            ..faint
        };
        let (sum, area) = brute(level2, x, &fainter);
        let want = sum * (THINNING * THINNING) as f32 / area;
        let got2 = store.irradiance_within(x, up, &fainter).total.r;
        assert!(
            (got2 - want).abs() <= 1e-4 * want.max(1.0),
            "footprint {q}: {got2} {want}"
        );
        let full = Footprint {
            throughput: 1.0,
            ..faint
        };
        let (sum, area) = brute(photons, x, &full);
        let fine = store.irradiance_within(x, up, &full).total.r;
        assert!(
            (fine - sum / area).abs() <= 1e-4 * fine.max(1.0),
            "footprint {q}"
        );
        differ += (fine != got) as u32;
    }
    assert!(
        differ > 90,
        "the faint gathers read the map itself: {differ}"
    );
}

/// 64 000 photons uniform over the square `[−2, 2]²` of the plane `y = 0` (4 000 a
/// unit of area), balanced, with the two coarse levels of every [`THINNING`]-th.
fn levels(g: &mut Pcg32) -> [Vec<Photon>; 3] {
    let mut photons: Vec<Photon> = (0..64_000)
        .map(|i| {
            let p = Vec3::new(g.next_f32() * 4.0 - 2.0, 0.0, g.next_f32() * 4.0 - 2.0);
            let power = Rgb::splat(1.0 + g.next_f32());
            Photon::new(p, -UnitVec3::Y, power).with_half(i % 2 == 0)
        })
        .collect();
    let mut level1: Vec<Photon> = photons.iter().step_by(THINNING).copied().collect();
    let mut level2: Vec<Photon> = level1.iter().step_by(THINNING).copied().collect();
    for level in [&mut photons, &mut level1, &mut level2] {
        balance(level);
    }
    [photons, level1, level2]
}

/// A footprint holding about 2 000 photons (a square 0.7 on a side) is gathered on
/// the first coarse level under [`FOOTPRINT_VISITS`] — the brute-force sum of that
/// level's photons inside it, each counted [`THINNING`] times — and on the map
/// itself, every photon once, under [`GRAZING_VISITS`].
#[test]
fn the_visit_cap_chooses_the_level() {
    let mut g = Pcg32::new(9);
    let levels = levels(&mut g);
    let store = store_with_levels(&levels);
    let (half, up) = (0.35, UnitVec3::Y);
    for q in 0..20 {
        let x = Vec3::new(g.next_f32() - 0.5, 0.0, g.next_f32() - 0.5);
        let capped = Footprint {
            visits: FOOTPRINT_VISITS,
            ..square(half)
        };
        let (coarse, area, _) = inside(&levels[1], x, &capped);
        let (fine, _, held) = inside(&levels[0], x, &capped);
        assert!(held > FOOTPRINT_VISITS, "footprint {q} holds {held}");
        let got = store.irradiance_within(x, up, &capped).total.r;
        let want = coarse * THINNING as f32 / area;
        assert!((got - want).abs() <= 1e-4 * want, "{q}: {got} {want}");
        let grazing = Footprint {
            visits: GRAZING_VISITS,
            ..capped
        };
        let got = store.irradiance_within(x, up, &grazing).total.r;
        assert!((got - fine / area).abs() <= 1e-4 * got, "{q}: {got}");
    }
}

/// [`store_of`] `levels[0]`, with `levels[1]` and `levels[2]` its coarse levels.
fn store_with_levels(levels: &[Vec<Photon>; 3]) -> KdStore<'_, 8> {
    let [_, level1, level2] = levels.each_ref().map(|l| KdTree::from_balanced(l));
    store_of(&levels[0]).with_coarse_levels(level1, level2)
}

/// The photons of `level` inside footprint `f` about `x` (a radius of 1): the sum of
/// their red power, the footprint's area and their count.
fn inside(level: &[Photon], x: Vec3, f: &Footprint) -> (f32, f32, usize) {
    let region = Region::new(f, 1.0).unwrap();
    let coordinates = region.coordinates();
    let inside = level
        .iter()
        .filter(|p| coordinates.of(p.position() - x).is_some());
    let (sum, count) = inside.fold((0.0, 0), |(s, c), p| (s + p.power().r, c + 1));
    (sum, region.area, count)
}

/// `uniform_quarter` is the two-sided binomial test it claims, for the counts the
/// widening asks about (`c < 32`, `C` up to a device map's 1024), against tails
/// summed in f64 from the binomial coefficients (decisions within 10⁻⁴ of the
/// threshold skipped: f32 rounding may fall either way there), and every count
/// above `6c + 18` fails it: the bound past which `uniform_quarter` refuses at once,
/// so that `(3/4)ⁿ` is never computed where it would underflow.
#[test]
fn the_uniformity_test_is_the_binomial_tails() {
    let pmf = |c: u32, n: u32| -> f64 {
        let mut binom = 1.0f64;
        for i in 0..c {
            binom = binom * (n - i) as f64 / (i + 1) as f64;
        }
        binom * 0.25f64.powi(c as i32) * 0.75f64.powi((n - c) as i32)
    };
    let (mut checked, mut passed) = (0, 0);
    for n in 0..=1024u32 {
        for c in 0..=n.min(31) {
            let below: f64 = (0..=c).map(|i| pmf(i, n)).sum();
            let above = 1.0 - below + pmf(c, n);
            let want = below >= 0.01 && above >= 0.01;
            if n > 6 * c + 18 {
                assert!(!want && !uniform_quarter(c, n), "{c} of {n} passes");
            }
            if (below - 0.01).abs() < 1e-4 || (above - 0.01).abs() < 1e-4 {
                continue;
            }
            assert_eq!(uniform_quarter(c, n), want, "{c} of {n}");
            checked += 1;
            passed += want as u32;
        }
    }
    assert!(checked > 30_000 && passed > 300, "{checked} {passed}");
}

/// The store of radius 1 over balanced `photons` (power unit 1, `K` = 8).
fn store_of(photons: &[Photon]) -> KdStore<'_, 8> {
    KdStore::new(KdTree::from_balanced(photons), 1.0, None, 1.0, None)
}

/// The photons (both halves) that footprint `fp` about `x`, on a surface facing +y,
/// counts in one search within its visits.
fn counted(store: &KdStore<'_, 8>, x: Vec3, fp: &Footprint) -> u32 {
    let region = Region::new(fp, store.max_radius2).unwrap();
    let mut weight = |_: UnitVec3, p: Rgb| p;
    let tree = Some(*store.tree());
    let (_, visits, found) = store.sum_in(tree, x, UnitVec3::Y, &region, false, Some(&mut weight));
    assert!(visits.is_some());
    found[0] + found[1]
}

/// A floor's footprint by a wall counts the floor's photons alone: the wall's, on
/// the parallelogram's side of the corner and arriving downwards (on the floor's
/// front), lie off the floor's plane. Their density there is 20 times the floor's,
/// so counting the wall's photons within the footprint's reach would more than
/// double the estimate.
#[test]
fn a_floor_footprint_by_a_wall_counts_the_floor_alone() {
    let mut g = Pcg32::new(5);
    let down = UnitVec3::new(Vec3::new(0.0, -0.6, -0.8)).unwrap();
    let mut photons: Vec<Photon> = Vec::new();
    for i in 0..20_000 {
        let floor = Vec3::new(g.next_f32() - 0.5, 0.0, -g.next_f32());
        photons.push(Photon::new(floor, down, Rgb::splat(1.0)).with_half(i % 2 == 0));
    }
    for i in 0..40_000 {
        let wall = Vec3::new(g.next_f32() - 0.5, g.next_f32() * 0.1, 0.0);
        photons.push(Photon::new(wall, down, Rgb::splat(1.0)).with_half(i % 2 == 0));
    }
    balance(&mut photons);
    let store = store_of(&photons);
    // A square of half-side 0.05 about a point 0.02 from the wall: it reaches
    // across the corner into the wall.
    let x = Vec3::new(0.0, 0.0, -0.02);
    let region = Region::new(&square(0.05), store.max_radius2).unwrap();
    // The floor's, and the wall's within rounding of the floor (a hundredth of the
    // reach and 10⁻⁴·0.02: the corner itself, a few photons).
    let (mut floor, mut wall) = (0u32, 0u32);
    for p in &photons {
        let q = p.position() - x;
        let within = q.x.abs() <= 0.05 && q.z.abs() <= 0.05;
        let near = q.length_squared() <= region.reach2;
        floor += (within && q.y <= 0.01 * region.reach2.sqrt() + 2e-6) as u32;
        wall += (within && near && q.y > 0.0) as u32;
    }
    assert_eq!(counted(&store, x, &square(0.05)), floor);
    assert!(
        wall > floor,
        "{wall} wall photons in reach, {floor} on the floor"
    );
}

/// On a ball the patch's photons lie off its tangent plane by up to the sagitta of
/// the reach, and they count: 4 000 photons spread evenly over a sphere of radius
/// 0.5 (few enough for one search's visits), square footprints at its top of
/// half-sides 0.1 and 0.3 (reaches `ρ` 0.14 and 0.42). At the larger, a corner's
/// photons lie 0.235 below the top — more than `ρ²κ/2` = 0.18, the sagitta of a
/// chord `ρ` rather than of a distance `ρ` along the plane — and 0.485 from it,
/// past a search ball of radius `ρ`. A flat surface's thickness would drop most
/// of them.
#[test]
fn a_curved_footprint_counts_its_surface_within_the_sagitta() {
    let mut g = Pcg32::new(6);
    let radius = 0.5;
    let mut photons: Vec<Photon> = (0..4_000)
        .map(|i| {
            let z = g.next_f32() * 2.0 - 1.0;
            let a = g.next_f32() * core::f32::consts::TAU;
            let r = libm::sqrtf(1.0 - z * z);
            let n = Vec3::new(r * libm::cosf(a), z, r * libm::sinf(a));
            let dir = UnitVec3::new(-n).unwrap();
            Photon::new(n * radius, dir, Rgb::splat(1.0)).with_half(i % 2 == 0)
        })
        .collect();
    balance(&mut photons);
    let store = store_of(&photons);
    let x = Vec3::new(0.0, radius, 0.0);
    let count = |half: f32, curvature: f32| {
        let fp = Footprint {
            curvature,
            ..square(half)
        };
        counted(&store, x, &fp)
    };
    // The upper cap's photons whose projection lies in the square.
    let want = |half: f32| {
        photons
            .iter()
            .map(|p| p.position())
            .filter(|q| q.y > 0.0 && q.x.abs() <= half && q.z.abs() <= half)
            .count() as u32
    };
    for half in [0.1, 0.3] {
        assert_eq!(count(half, 1.0 / radius), want(half), "half-side {half}");
    }
    let flat = count(0.1, 0.0);
    assert!(flat < want(0.1) / 4, "{flat} of {}", want(0.1));
}

/// Photons over `[−2, 2]²` of the plane y = 0 at `density` per unit area, plus a
/// disk of radius 0.05 about `(0.3, 0, 0)` 400 times as dense (a focus), each of
/// power 1, in a store of radius 1.
fn field(density: f32) -> Vec<Photon> {
    let mut g = Pcg32::new(9);
    let mut points: Vec<Vec3> = (0..(density * 16.0) as usize)
        .map(|_| Vec3::new(g.next_f32() * 4.0 - 2.0, 0.0, g.next_f32() * 4.0 - 2.0))
        .collect();
    let focus = density * 400.0 * core::f32::consts::PI * 0.05 * 0.05;
    for _ in 0..focus as usize {
        let (r, a) = (
            0.05 * libm::sqrtf(g.next_f32()),
            g.next_f32() * core::f32::consts::TAU,
        );
        points.push(Vec3::new(0.3 + r * libm::cosf(a), 0.0, r * libm::sinf(a)));
    }
    let mut photons: Vec<Photon> = points
        .iter()
        .enumerate()
        .map(|(i, &p)| Photon::new(p, -UnitVec3::Y, Rgb::splat(1.0)).with_half(i % 2 == 0))
        .collect();
    balance(&mut photons);
    photons
}

/// A square footprint of half-side `h` about `x` on the plane y = 0.
fn square(h: f32) -> Footprint {
    Footprint {
        a: Vec3::new(h, 0.0, 0.0),
        b: Vec3::new(0.0, 0.0, h),
        throughput: 1.0,
        direct: 0.0,
        curvature: 0.0,
        visits: FOOTPRINT_VISITS,
    }
}

/// A square footprint that holds `lambda` photons of `density` on average, seen
/// magnified 1000 times or not at all.
fn holding(lambda: f32, density: f32, magnified: bool) -> Footprint {
    let h = 0.5 * libm::sqrtf(lambda / density); // (2h)² · density = λ
    Footprint {
        direct: if magnified { 4.0 * h * h * 1000.0 } else { 0.0 },
        ..square(h)
    }
}

/// `n` random centres in `[−1.5, −0.5] × [−1, 1]` on the plane `y = 0` (PCG32 stream
/// `seed`).
fn centres(n: usize, seed: u64) -> impl Iterator<Item = Vec3> {
    let mut g = Pcg32::new(seed);
    (0..n).map(move |_| Vec3::new(g.next_f32() - 1.5, 0.0, g.next_f32() * 2.0 - 1.0))
}

/// The estimates of `fp` about `n` random centres in `[−1.5, −0.5] × [−1, 1]` (PCG32
/// stream `seed`) over `density`, as fractions of it: their mean, their standard
/// deviation and the estimates themselves.
fn estimates(
    store: &KdStore<'_, 8>,
    fp: &Footprint,
    density: f32,
    n: usize,
    seed: u64,
) -> (f32, f32, Vec<f32>) {
    let estimates: Vec<f32> = centres(n, seed)
        .map(|x| store.irradiance_within(x, UnitVec3::Y, fp).total.r / density)
        .collect();
    let mean = estimates.iter().sum::<f32>() / n as f32;
    let var = estimates
        .iter()
        .map(|e| (e - mean) * (e - mean))
        .sum::<f32>()
        / (n - 1) as f32;
    (mean, libm::sqrtf(var), estimates)
}

/// Over a uniform density, footprints that hold one to four photons are widened:
/// their estimates average to the density (no bias: each half is summed over a
/// patch the other half chose) with a spread well below the unwidened
/// count-over-area's `1/sqrt(λ)` for λ photons (a patch four times the area:
/// `1/(2·sqrt(λ))`).
#[test]
fn sparse_footprints_over_a_uniform_density_are_widened() {
    let density = 2000.0;
    let photons = field(density);
    let store = store_of(&photons);
    for lambda in [1.0, 2.0, 4.0] {
        let fp = holding(lambda, density, false);
        let (mean, spread, _) = estimates(&store, &fp, density, 2000, 3);
        let spread = spread * libm::sqrtf(lambda);
        assert!((mean - 1.0).abs() < 0.04, "λ {lambda}: mean {mean}");
        assert!(spread < 0.8, "λ {lambda}: spread × sqrt(λ) {spread}");
    }
}

/// A footprint seen magnified that holds about a hundredth of a photon widens until
/// each half is placed by half of [`SPARSE_FOOTPRINT`] photons of the other: over a
/// uniform density its estimates still average to the density (1.003), their spread
/// 0.34 times it (1.3 when one photon placed a half), against 5.2 for the same
/// footprint not magnified (one widening ×4 from a patch that holds a photon in a
/// hundred). A magnified footprint that is not sparse is gathered as any other, to
/// the bit.
#[test]
fn sparse_magnified_footprints_widen_to_the_next_photons() {
    let density = 2000.0;
    let photons = field(density);
    let store = store_of(&photons);
    let stats = |lambda: f32, magnified: bool| {
        estimates(
            &store,
            &holding(lambda, density, magnified),
            density,
            4000,
            5,
        )
    };
    let (mean, spread, _) = stats(0.01, true);
    assert!((mean - 1.0).abs() < 0.05, "magnified: mean {mean}");
    assert!(spread < 0.6, "magnified: spread {spread}");
    let (plain_mean, plain_spread, _) = stats(0.01, false);
    assert!(plain_spread > 3.0, "plain: spread {plain_spread}");
    assert!((plain_mean - 1.0).abs() < 0.5, "plain: mean {plain_mean}");
    let (_, _, dense) = stats(40.0, true);
    let (_, _, dense_plain) = stats(40.0, false);
    assert!(dense
        .iter()
        .zip(&dense_plain)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
}

/// Only an estimate widened far past its footprint (a sparse one seen magnified)
/// says so: of the magnified footprints that hold 0.01 photons on average nearly all
/// need the far widening; an unmagnified one never takes it, nor does a magnified one
/// that holds photons enough.
#[test]
fn estimates_widened_far_say_so() {
    let density = 2000.0;
    let photons = field(density);
    let store = store_of(&photons);
    let widened = |lambda: f32, magnified: bool| {
        let fp = holding(lambda, density, magnified);
        centres(1000, 9)
            .filter(|&x| store.irradiance_within(x, UnitVec3::Y, &fp).widened)
            .count()
    };
    let far = widened(0.01, true);
    assert!(far > 900, "{far} of 1000");
    assert_eq!(widened(0.01, false), 0);
    assert_eq!(widened(40.0, true), 0);
}

/// Next to a focus, an empty footprint is not widened into it: the patch twice its
/// size would hold the focus's photons in a quarter a uniform density would not
/// give them, and the estimate stays the sparse field's (here, none).
#[test]
fn a_sparse_footprint_beside_a_focus_is_not_widened_into_it() {
    let density = 2000.0;
    let photons = field(density);
    let store = store_of(&photons);
    let h = 0.5 / libm::sqrtf(density);
    let mut beside = 0;
    for i in 0..40 {
        // Centres 0.07–0.11 from the focus's centre: a patch of half-side 2h to
        // 16h about them reaches into the focus.
        let a = i as f32 * 0.157;
        let d = 0.07 + 0.001 * i as f32;
        let x = Vec3::new(0.3 + d * libm::cosf(a), 0.0, d * libm::sinf(a));
        let region = Region::new(&square(h), 1.0).unwrap();
        let mut unit = |_: UnitVec3, p: Rgb| p;
        let (own, _, found) = store.sum_in(
            Some(store.tree),
            x,
            UnitVec3::Y,
            &region,
            false,
            Some(&mut unit),
        );
        if found != [0, 0] {
            continue;
        }
        beside += 1;
        let e = store.irradiance_within(x, UnitVec3::Y, &square(h)).total.r;
        assert!(own[0].r + own[1].r == 0.0);
        assert!(e < 3.0 * density, "footprint {i}: {e} against {density}");
    }
    assert!(beside > 10, "{beside} empty footprints");
}

/// Every footprint's sums — one search or cut into disks, with the box that prunes
/// the walk — are the brute-force sums over the photons inside its parallelogram,
/// within its thickness of the plane (curvatures 0, 2 and 20), that arrived
/// on the front: photons near a tilted plane, some off it, some arriving from
/// behind, footprints from squares to slivers.
#[test]
fn footprint_sums_are_the_brute_force_sums() {
    let mut g = Pcg32::new(11);
    let normal = UnitVec3::new(Vec3::new(0.3, 1.0, -0.2)).unwrap();
    let (u, v) = normal.basis();
    let mut photons: Vec<Photon> = (0..40_000)
        .map(|i| {
            let (s, t) = (g.next_f32() * 4.0 - 2.0, g.next_f32() * 4.0 - 2.0);
            let off = (g.next_f32() - 0.5) * 0.01;
            let p = u.get() * s + v.get() * t + normal.get() * off;
            let dir = if i % 5 == 0 {
                normal.get()
            } else {
                -normal.get()
            };
            let power = Rgb::new(1.0 + g.next_f32(), 1.0, 0.5);
            Photon::new(p, UnitVec3::new(dir).unwrap(), power).with_half(i % 2 == 0)
        })
        .collect();
    balance(&mut photons);
    let tree = KdTree::from_balanced(&photons);
    let store: KdStore<'_, 8> = KdStore::new(tree, 1.0, None, 1.0, None);
    let (mut checked, mut counted) = (0, 0);
    for q in 0..200 {
        let x = u.get() * (g.next_f32() * 2.0 - 1.0) + v.get() * (g.next_f32() * 2.0 - 1.0);
        let angle = g.next_f32() * core::f32::consts::TAU;
        let (c, s) = (libm::cosf(angle), libm::sinf(angle));
        let long = (u.get() * c + v.get() * s) * (0.01 + 0.1 * g.next_f32());
        let short = (v.get() * c - u.get() * s) * [1.0, 0.2, 0.02][q % 3] * g.next_f32();
        let shear = long * (g.next_f32() - 0.5);
        let curvature = [0.0, 2.0, 20.0][q % 3];
        let fp = Footprint {
            throughput: 1.0,
            a: long,
            b: short + shear,
            direct: 0.0,
            curvature,
            visits: FOOTPRINT_VISITS,
        };
        let Some(region) = Region::new(&fp, store.max_radius2) else {
            continue;
        };
        for cut in [false, true] {
            let mut weight = |_: UnitVec3, p: Rgb| p;
            let (sum, visits, found) =
                store.sum_in(Some(tree), x, normal, &region, cut, Some(&mut weight));
            if visits.is_none() {
                continue; // over the visit bound: the caller moves on
            }
            checked += 1;
            counted += found[0] + found[1];
            // Cut, segment j holds the photons within its own ball whose long
            // coordinate is in [−1 + j·2/s, −1 + (j+1)·2/s), the last one closed.
            let how = if cut { region.cut() } else { Cut::WHOLE };
            let s = how.segments;
            let (long, short) = how.axes(&region);
            let piece = long / s as f32;
            let thickness = region.thickness(x);
            let r2 = thickness * thickness
                + if s == 1 {
                    region.reach2
                } else {
                    (piece + short)
                        .length_squared()
                        .max((piece - short).length_squared())
                };
            let (mut want, mut count) = ([Rgb::ZERO; 2], [0u32; 2]);
            for p in &photons {
                let q = p.position() - x;
                let on = q.dot(normal.get()).abs() <= thickness;
                let inside = on
                    && region.coordinates().of(q).is_some_and(|(alpha, beta)| {
                        let t = how.along(alpha, beta);
                        let j = (((t + 1.0) * s as f32 * 0.5) as u32).min(s - 1);
                        let centre = long * (-1.0 + (2 * j + 1) as f32 / s as f32);
                        (q - centre).length_squared() < r2
                    });
                if inside && normal.dot(p.direction().get()) < 0.0 {
                    want[p.half() as usize] += p.power();
                    count[p.half() as usize] += 1;
                }
            }
            assert_eq!(found, count, "footprint {q}, cut {cut}");
            for h in 0..2 {
                let (a, b) = (sum[h].r, want[h].r);
                assert!((a - b).abs() <= 1e-4 * b.max(1.0), "footprint {q}: {a} {b}");
            }
        }
    }
    std::eprintln!("{checked} footprints checked, {counted} photons counted");
    assert!(
        checked > 300 && counted > 6_000,
        "{checked} footprints, {counted} photons"
    );
}

//! Tracing one photon through mirrors and glass to where it lands.

use crate::geometry::{Hit, Ray};
use crate::material::{interface, Material};
use crate::math::{reflect, Rgb, UnitVec3};
use crate::sampling::PathSampler;
use crate::scene::Scene;

/// Where a photon's path came to rest on a surface with a diffuse part.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Landing {
    /// The surface hit (point, normal, error bound).
    pub hit: Hit,
    /// Index of the object it landed on.
    pub object: usize,
    /// Direction of travel.
    pub dir: UnitVec3,
    /// Its power before splitting, W: what Russian roulette's path carries.
    pub power: Rgb,
    /// The product of the `1 − F` of the glass surfaces it was split at: its power as
    /// the light tracer counts it is `weight · power` (see [`trace`]).
    pub weight: f32,
    /// Whether this is the path Russian roulette follows, the one stored.
    pub stored: bool,
}

/// Follows one photon from the light, handing `land` each place one of its paths
/// comes to rest (an error from `land` ends it).
///
/// Mirrors multiply its power by their reflectance; Beer absorption scales it along
/// paths inside glass. At a dielectric of Fresnel reflectance `F`, with `ξ` the
/// photon's next number ([`PathSampler`]: its point set's further coordinates):
///
/// - **for the photon store**, Russian roulette: reflection if `ξ < F`, else
///   refraction, the power unchanged (Jensen 2001, §5.2): one path per photon, every
///   stored photon of about the same power, which density estimation wants;
/// - **for the light tracer**, splitting: the refracted path always goes on, with
///   `(1 − F)` of the power, and the reflected one, with all of it, only if `ξ < F`
///   (expected power `F` reflected, `1 − F` refracted: unbiased). The roulette's
///   thinning of the refracted light — binomial noise in the count of each pixel's
///   photons, which the stratified directions do not remove — is gone from the
///   caustics seen directly, at the cost of the extra refracted paths (about `ΣF` per
///   photon). The path roulette would follow is one of these, and it alone is stored
///   ([`Landing::stored`], with its power undivided by `1 − F`): the same photons, bit
///   for bit, as without splitting.
///
/// Under total internal reflection both reflect. A `classic` surface reflects with
/// probability `reflectivity`, transmits with probability `transparency`, and absorbs
/// otherwise. Each path makes at most `max_depth` specular interactions and ends at the
/// first surface with a diffuse part that it reaches *from the front* after at least
/// one of them (or at its first hit when `store_direct`). Without `split` (no light
/// tracer to serve, or settings without glass splitting) and on a device every
/// interface is the roulette's alone. At most [`BRANCHES`] paths split off per photon,
/// followed in the order they split off; past that its interfaces are the roulette's
/// alone, so a photon traces at most `BRANCHES + 1` paths of at most `max_depth`
/// interactions. Its first segment is tested against the objects of `first`, the
/// others against `all`.
pub(crate) fn trace<E, const O: usize, const L: usize>(
    scene: &Scene<O, L>,
    ray: Ray,
    power: Rgb,
    (max_depth, store_direct, split): (u32, bool, bool),
    rng: &mut PathSampler,
    (all, first): (Reach, Reach),
    mut land: impl FnMut(Landing) -> Result<(), E>,
) -> Result<(), E> {
    let mut branches: heapless::Vec<(Path, PathSampler), BRANCHES> = heapless::Vec::new();
    let start = Path {
        ray,
        power,
        weight: 1.0,
        stored: true,
        bounces: 0,
    };
    let limits = (max_depth, store_direct, split);
    if let Some(l) = follow(scene, start, first, all, limits, rng, &mut branches) {
        land(l)?;
    }
    let mut next = 0;
    while let Some((path, mut rng)) = branches.get(next).cloned() {
        next += 1;
        if let Some(l) = follow(scene, path, all, all, limits, &mut rng, &mut branches) {
            land(l)?;
        }
    }
    Ok(())
}

/// Paths that may split off one photon: none on a device, which keeps one path per
/// photon (see
/// [`PhotonSettings::with_glass_splitting`](super::PhotonSettings::with_glass_splitting)).
pub(crate) const BRANCHES: usize = if SPLITS { 4 } else { 0 };

/// Whether photons split at glass where the settings ask: with `std` only. A constant,
/// so that a device's build compiles the splitting away and keeps its old code.
const SPLITS: bool = cfg!(feature = "std");

/// One path of a photon: where it goes, with what power before splitting and what
/// split weight (see [`Landing`]), whether it is the roulette's, after how many
/// specular interactions.
#[derive(Clone, Copy, Debug)]
struct Path {
    ray: Ray,
    power: Rgb,
    weight: f32,
    stored: bool,
    bounces: u32,
}

/// Follows one path of [`trace`] to where it lands, adding the paths it splits off to
/// `branches`, each with a copy of `rng` as it stands there: every path draws the
/// numbers a lone path would draw at its interfaces, so the roulette's path, and with
/// it every stored photon, is the one the photon takes without splitting.
/// `limits`: `(max_depth, store_direct, split)`.
fn follow<const O: usize, const L: usize>(
    scene: &Scene<O, L>,
    path: Path,
    first: Reach,
    all: Reach,
    (max_depth, store_direct, split): (u32, bool, bool),
    rng: &mut PathSampler,
    branches: &mut heapless::Vec<(Path, PathSampler), BRANCHES>,
) -> Option<Landing> {
    let Path {
        mut ray,
        mut power,
        mut weight,
        mut stored,
        mut bounces,
    } = path;
    let mut reach = first;
    loop {
        let (hit, index) = reach.nearest(scene, &ray)?;
        reach = all;
        let material = &scene.objects()[index].material;
        let front = hit.front_face(ray.dir);
        let facing = if front { hit.normal } else { -hit.normal };
        let may_store = (bounces >= 1 || store_direct) && front && material.stores_photons();
        if may_store {
            return Some(Landing {
                hit,
                object: index,
                dir: ray.dir,
                power,
                weight,
                stored,
            });
        }
        let dir = match material {
            Material::Diffuse(_) => return None,
            _ if bounces >= max_depth => return None,
            Material::Mirror(m) => {
                power *= m.reflectance;
                reflect(ray.dir, facing)
            }
            Material::Dielectric(g) => {
                if !front {
                    power *= g.absorption.beer(hit.t);
                }
                let eta = if front { 1.0 / g.ior } else { g.ior };
                let i = interface(ray.dir, facing, eta);
                match i.refracted {
                    Some(t) if SPLITS && split && !branches.is_full() => {
                        if rng.next_f32() < i.reflectance {
                            // Cannot fail: not full. The roulette goes this way, with
                            // the numbers it would draw next.
                            let branch = Path {
                                ray: Ray::spawn(&hit, reflect(ray.dir, facing)),
                                power,
                                weight,
                                stored,
                                bounces: bounces + 1,
                            };
                            let _ = branches.push((branch, rng.clone()));
                            stored = false;
                        }
                        weight *= 1.0 - i.reflectance;
                        t
                    }
                    // Roulette alone: the path is the store's and the tracer's.
                    Some(t) if rng.next_f32() >= i.reflectance => t,
                    _ => reflect(ray.dir, facing),
                }
            }
            Material::Classic(c) => {
                let xi = rng.next_f32();
                if xi < c.reflectivity {
                    reflect(ray.dir, facing)
                } else if xi < c.reflectivity + c.transparency {
                    let eta = if front { 1.0 / c.ior } else { c.ior };
                    interface(ray.dir, facing, eta)
                        .refracted
                        .unwrap_or_else(|| reflect(ray.dir, facing))
                } else {
                    return None;
                }
            }
        };
        if power.is_black() {
            return None;
        }
        bounces += 1;
        ray = Ray::spawn(&hit, dir);
    }
}

/// The objects one segment of a photon's path is tested against, as bit sets of their
/// indices: the bounded ones, tried first, and the planes — the order of
/// [`Scene::intersect`], whose hit [`nearest`](Self::nearest) returns bit for bit. The
/// segment from the light into a projection-map cone skips every object whose bounding
/// sphere lies outside the cone (`Emission::reach`), whose own test could only miss.
///
/// On the desktop (scenes of at most 64 objects). The search also keeps its best hit
/// in registers rather than in an `Option<(Hit, usize)>` rebuilt in memory at each
/// hit, which a later load could not forward from the stores that built it.
#[cfg(feature = "std")]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Reach {
    bounded: u64,
    planes: u64,
}

#[cfg(feature = "std")]
impl Reach {
    /// Every object of `scene`.
    pub(crate) fn all<const O: usize, const L: usize>(scene: &Scene<O, L>) -> Reach {
        let (mut bounded, mut planes) = (0u64, 0u64);
        for (i, o) in scene.objects().iter().enumerate().take(64) {
            if o.shape.is_bounded() {
                bounded |= 1 << i;
            } else {
                planes |= 1 << i;
            }
        }
        Reach { bounded, planes }
    }

    /// Only the objects of this set that are also in `set` (bit `i`: object `i`).
    pub(crate) fn within(self, set: u64) -> Reach {
        Reach {
            bounded: self.bounded & set,
            planes: self.planes & set,
        }
    }

    /// [`Scene::intersect`]`(ray, ∞)`, trying only the objects of this set (the others
    /// are known to miss `ray`): the nearest hit, and on an exact tie the lower index.
    #[inline]
    fn nearest<const O: usize, const L: usize>(
        self,
        scene: &Scene<O, L>,
        ray: &Ray,
    ) -> Option<(Hit, usize)> {
        if O > 64 {
            return scene.intersect(ray, f32::INFINITY);
        }
        let objects = scene.objects();
        let mut best = Hit {
            t: f32::INFINITY,
            point: crate::math::Vec3::ZERO,
            normal: UnitVec3::X,
            error: 0.0,
        };
        let mut index = usize::MAX; // none yet
        for mut set in [self.bounded, self.planes] {
            while set != 0 {
                let i = set.trailing_zeros() as usize;
                set &= set - 1;
                // A later index must be strictly nearer; an earlier one wins a tie.
                let reach = if index > i {
                    crate::scene::next_up(best.t)
                } else {
                    best.t
                };
                if let Some(h) = objects[i].shape.intersect(ray, reach) {
                    best = h;
                    index = i;
                }
            }
        }
        (index != usize::MAX).then_some((best, index))
    }
}

/// On a device, every object, by [`Scene::intersect`] (one search in flash).
#[cfg(not(feature = "std"))]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Reach;

#[cfg(not(feature = "std"))]
impl Reach {
    /// Every object of `scene`.
    pub(crate) fn all<const O: usize, const L: usize>(_: &Scene<O, L>) -> Reach {
        Reach
    }

    /// [`Scene::intersect`]`(ray, ∞)`.
    #[inline]
    fn nearest<const O: usize, const L: usize>(
        self,
        scene: &Scene<O, L>,
        ray: &Ray,
    ) -> Option<(Hit, usize)> {
        scene.intersect(ray, f32::INFINITY)
    }
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::geometry::Shape;
    use crate::light::PointLight;
    use crate::math::Vec3;
    use crate::photon::emit::Emission;
    use crate::sampling::Pcg32;

    /// The objects of `scenes/heldout/balls_mirror_tube.json`, a plane moved between
    /// them: two glass balls, a mirror box and a glass tube (whose cones overlap).
    fn scene() -> Scene<8, 1> {
        let cam = Camera::new(Vec3::new(0.5, 3.8, 7.5), Vec3::ZERO, Vec3::Y, 45.0, 8, 6).unwrap();
        let mut s = Scene::new(cam);
        let diffuse = Material::diffuse(Rgb::splat(0.7)).unwrap();
        let glass = Material::dielectric(1.5, Rgb::ZERO).unwrap();
        let mirror = Material::mirror(Rgb::splat(0.9)).unwrap();
        let shapes = [
            (Shape::plane(Vec3::ZERO, Vec3::Y), diffuse),
            (Shape::sphere(Vec3::new(-1.6, 0.75, 0.2), 0.7), glass),
            (Shape::plane(Vec3::new(0.0, 0.0, -3.5), Vec3::Z), diffuse),
            (Shape::sphere(Vec3::new(0.2, 0.55, 1.0), 0.5), glass),
            (
                Shape::cuboid(
                    Vec3::new(1.9, 0.61, -1.2),
                    Vec3::new(0.12, 1.2, 1.4),
                    Vec3::new(0.0, -35.0, 0.0),
                ),
                mirror,
            ),
            (
                Shape::cylinder(
                    Vec3::new(0.6, 0.12, -1.0),
                    Vec3::new(0.25, 1.0, -0.15),
                    0.35,
                    1.4,
                    true,
                ),
                glass,
            ),
        ];
        for (shape, material) in shapes {
            s.add(shape.unwrap(), material).unwrap();
        }
        s
    }

    #[test]
    fn the_first_segment_skips_only_objects_it_misses() {
        let s = scene();
        let all = Reach::all(&s);
        let mut skipped = 0;
        for position in [Vec3::new(-3.0, 6.0, 2.5), Vec3::new(3.5, 5.0, 1.5)] {
            let light = PointLight::new(position, Rgb::ONE).unwrap();
            let plan: Emission<8> = Emission::plan(&s, &light, 20_000, false);
            let sets = plan.reach(&s, &light);
            for i in 0..plan.count() {
                let (dir, _, _, cone) = plan.photon(&light, i, (0.3, 0.8));
                let first = all.within(sets[cone]);
                skipped += (first != all) as u32;
                let ray = Ray::new(position, dir);
                assert_eq!(
                    first.nearest(&s, &ray),
                    s.intersect(&ray, f32::INFINITY),
                    "{ray:?}"
                );
            }
        }
        assert!(skipped > 30_000, "the cones must skip objects: {skipped}");
    }

    #[test]
    fn every_object_gives_the_scenes_hit() {
        let s = scene();
        let all = Reach::all(&s);
        let mut g = Pcg32::new(5);
        let mut hits = 0;
        for _ in 0..20_000 {
            let o = Vec3::new(g.next_f32(), g.next_f32(), g.next_f32()) * 8.0 - Vec3::splat(4.0);
            let aim = Vec3::new(g.next_f32(), g.next_f32(), g.next_f32()) * 3.0 - Vec3::splat(1.5);
            let Some(dir) = UnitVec3::new(aim - o) else {
                continue;
            };
            let ray = Ray::new(o, dir);
            let hit = s.intersect(&ray, f32::INFINITY);
            hits += hit.is_some() as u32;
            assert_eq!(all.nearest(&s, &ray), hit, "{ray:?}");
        }
        assert!(hits > 10_000, "{hits}");
    }
}

//! Which objects a segment of a photon's path is tested against: the nearest-hit
//! search of the forward pass, narrowed where a test could only miss.

use crate::geometry::{Hit, Ray};
use crate::math::UnitVec3;
#[cfg(feature = "std")]
use crate::math::Vec3;
use crate::scene::Scene;

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
    #[inline(always)]
    pub(crate) fn nearest<const O: usize, const L: usize>(
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
    pub(crate) fn nearest<const O: usize, const L: usize>(
        self,
        scene: &Scene<O, L>,
        ray: &Ray,
    ) -> Option<(Hit, usize)> {
        scene.intersect(ray, f32::INFINITY)
    }
}

/// The objects a photon's segments are tested against: every object ([`Reach::all`]),
/// and for each bounded object `i` the few a segment inside its bounding sphere can
/// meet ([`nearest_inside`](Self::nearest_inside)).
///
/// A segment whose two ends lie in a ball meets only objects that reach into the ball
/// (the ball is convex, so the segment lies in it). For a segment that starts inside
/// object `i` (a photon refracted into a glass ball, or reflected totally inside it)
/// the ball is `i`'s bounding sphere, widened by [`INSIDE_MARGIN`]; an object whose own
/// bounding sphere (or plane) stays farther from it than the margin cannot be hit
/// before the segment's end. So the search over `i`'s set, accepted only when the hit
/// it finds lies in the ball too, is the search over every object, bit for bit; the
/// photons inside glass skip all the other objects' tests (on the two balls, mirror
/// and tube scene, five of its six for most segments inside glass).
#[cfg(feature = "std")]
#[derive(Clone, Debug)]
pub(crate) struct Reaches<const O: usize> {
    /// Every object.
    pub(crate) all: Reach,
    /// Per object, its widened bounding sphere and the objects that reach into it
    /// (`None` for a plane, or when the scene has more objects than a [`Reach`] holds).
    inside: heapless::Vec<Option<Inside>, O>,
}

/// The widened bounding sphere of an object and the objects that reach into it.
#[cfg(feature = "std")]
#[derive(Clone, Copy, Debug)]
struct Inside {
    center: Vec3,
    radius2: f32,
    reach: Reach,
}

/// The margin, relative to an object's bounding radius plus its centre's distance from
/// the origin, by which [`Reaches`] widens bounding spheres and keeps other objects
/// apart from them: far above the rounding of any hit point (about 10⁻⁶ of it).
#[cfg(feature = "std")]
const INSIDE_MARGIN: f32 = 1e-3;

#[cfg(feature = "std")]
impl<const O: usize> Reaches<O> {
    /// Every object of `scene`, and each bounded object's set.
    pub(crate) fn new<const L: usize>(scene: &Scene<O, L>) -> Self {
        let all = Reach::all(scene);
        let objects = scene.objects();
        let spheres = |i: usize| objects[i].shape.bounding_sphere();
        let mut inside = heapless::Vec::new();
        for i in 0..objects.len() {
            let set = spheres(i).filter(|_| objects.len() <= 64).map(|b| {
                let margin = INSIDE_MARGIN * (b.radius + crate::math::max_abs(b.center));
                let radius = b.radius + margin;
                let mut set = 0u64;
                for (j, o) in objects.iter().enumerate() {
                    // Every shape is bounded or a plane.
                    let apart = match spheres(j) {
                        Some(s) => {
                            let gap = radius + s.radius + margin;
                            (s.center - b.center).length_squared() > gap * gap
                        }
                        None => o.shape.as_plane().is_some_and(|p| {
                            p.normal().dot(b.center - p.point()).abs() > radius + margin
                        }),
                    };
                    if !apart {
                        set |= 1 << j;
                    }
                }
                Inside {
                    center: b.center,
                    radius2: radius * radius,
                    reach: all.within(set),
                }
            });
            // Cannot fail: at most O objects.
            let _ = inside.push(set);
        }
        Self { all, inside }
    }

    /// The nearest hit of a segment tested against `reach`, or, when it starts inside
    /// object `i` (`inside`), against what [`nearest_inside`](Self::nearest_inside)
    /// finds it may meet.
    #[inline(always)]
    pub(crate) fn nearest<const L: usize>(
        &self,
        scene: &Scene<O, L>,
        ray: &Ray,
        reach: Reach,
        inside: Option<usize>,
    ) -> Option<(Hit, usize)> {
        match inside {
            Some(i) => self.nearest_inside(scene, ray, i),
            None => reach.nearest(scene, ray),
        }
    }

    /// [`Reach::nearest`] over every object, for a ray that starts inside object `i`
    /// (its origin on or just inside `i`'s surface): the search over `i`'s set when
    /// both the origin and the hit lie in its ball, else over every object.
    #[inline]
    fn nearest_inside<const L: usize>(
        &self,
        scene: &Scene<O, L>,
        ray: &Ray,
        i: usize,
    ) -> Option<(Hit, usize)> {
        if let Some(Some(s)) = self.inside.get(i) {
            let within = |p: Vec3| (p - s.center).length_squared() <= s.radius2;
            if within(ray.origin) {
                match s.reach.nearest(scene, ray) {
                    Some((hit, j)) if within(hit.point) => return Some((hit, j)),
                    _ => {}
                }
            }
        }
        self.all.nearest(scene, ray)
    }
}

/// Whether a ray leaving an object's surface along `dir` goes into it (`normal` the
/// outward normal there): the segment [`Reaches::nearest_inside`] serves.
#[inline]
pub(crate) fn enters(normal: UnitVec3, dir: UnitVec3) -> bool {
    normal.dot(dir.get()) < 0.0
}

/// On a device, every object (see [`Reach`]).
#[cfg(not(feature = "std"))]
#[derive(Clone, Debug)]
pub(crate) struct Reaches<const O: usize> {
    /// Every object.
    pub(crate) all: Reach,
}

#[cfg(not(feature = "std"))]
impl<const O: usize> Reaches<O> {
    /// Every object of `scene`.
    pub(crate) fn new<const L: usize>(scene: &Scene<O, L>) -> Self {
        Self {
            all: Reach::all(scene),
        }
    }

    /// [`Scene::intersect`]`(ray, ∞)`: a device tests every object, inside one or not
    /// (the one search its flash holds).
    #[inline]
    pub(crate) fn nearest<const L: usize>(
        &self,
        scene: &Scene<O, L>,
        ray: &Ray,
        reach: Reach,
        _: Option<usize>,
    ) -> Option<(Hit, usize)> {
        reach.nearest(scene, ray)
    }
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::geometry::Shape;
    use crate::light::PointLight;
    use crate::material::Material;
    use crate::math::{Rgb, Vec3};
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
            let Some(ray) = random_ray(&mut g) else {
                continue;
            };
            let hit = s.intersect(&ray, f32::INFINITY);
            hits += hit.is_some() as u32;
            assert_eq!(all.nearest(&s, &ray), hit, "{ray:?}");
        }
        assert!(hits > 10_000, "{hits}");
    }

    /// A random point in the cube `[-4, 4]³` and a direction towards `[-1.5, 1.5]³`.
    fn random_ray(g: &mut Pcg32) -> Option<Ray> {
        let o = Vec3::new(g.next_f32(), g.next_f32(), g.next_f32()) * 8.0 - Vec3::splat(4.0);
        let aim = Vec3::new(g.next_f32(), g.next_f32(), g.next_f32()) * 3.0 - Vec3::splat(1.5);
        Some(Ray::new(o, UnitVec3::new(aim - o)?))
    }

    #[test]
    fn a_segment_inside_an_object_gives_the_scenes_hit() {
        // The scene's objects apart; then a ball reaching into the first glass ball and
        // a plane through the tube, which their sets must hold.
        let mut overlapping = scene();
        let chrome = Material::mirror(Rgb::splat(0.5)).unwrap();
        let ball = Shape::sphere(Vec3::new(-1.0, 0.75, 0.2), 0.3).unwrap();
        overlapping.add(ball, chrome).unwrap();
        let plane = Shape::plane(Vec3::new(0.6, 0.8, -1.0), Vec3::Z).unwrap();
        overlapping.add(plane, chrome).unwrap();
        for (s, apart) in [(scene(), true), (overlapping, false)] {
            let reaches = Reaches::new(&s);
            let set = |i: usize| reaches.inside[i].map(|x| x.reach);
            let alone = |i: usize| Some(reaches.all.within(1 << i));
            // The balls are alone in theirs (the box's and the tube's bounding spheres
            // overlap each other's); the added ball and plane are in the ones they cross.
            assert_eq!(set(1) == alone(1), apart);
            assert_eq!(set(3), alone(3));
            assert_eq!(set(5).is_some_and(|r| r.planes & 1 << 7 != 0), !apart);
            assert_eq!(set(0), None, "a plane has no inside");
            let mut g = Pcg32::new(9);
            let mut inside = 0;
            for _ in 0..40_000 {
                let Some(ray) = random_ray(&mut g) else {
                    continue;
                };
                let Some((hit, i)) = s.intersect(&ray, f32::INFINITY) else {
                    continue;
                };
                // Into the object, as a refracted or totally reflected photon goes on.
                let Some(d) = UnitVec3::new(
                    Vec3::new(g.next_f32(), g.next_f32(), g.next_f32()) - Vec3::splat(0.5),
                ) else {
                    continue;
                };
                let d = if enters(hit.normal, d) { d } else { -d };
                let inner = Ray::spawn(&hit, d);
                inside += 1;
                let expected = s.intersect(&inner, f32::INFINITY);
                assert_eq!(
                    reaches.nearest_inside(&s, &inner, i),
                    expected,
                    "{inner:?} in {i}"
                );
            }
            assert!(inside > 10_000, "{inside}");
        }
    }
}

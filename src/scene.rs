//! The scene: camera, objects, lights, in fixed-capacity storage.

use heapless::Vec as FixedVec;

use crate::camera::Camera;
use crate::error::Error;
use crate::geometry::{Hit, Ray, Shape};
use crate::light::PointLight;
use crate::material::Material;
use crate::math::Rgb;

/// A shape with its material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Object {
    /// The geometry.
    pub shape: Shape,
    /// How it scatters light.
    pub material: Material,
}

/// A scene holding at most `OBJECTS` objects and `LIGHTS` point lights; both
/// capacities are compiled in, so `size_of::<Scene<O, L>>()` is its whole memory.
#[derive(Clone, Debug)]
pub struct Scene<const OBJECTS: usize, const LIGHTS: usize> {
    camera: Camera,
    objects: FixedVec<Object, OBJECTS>,
    /// Object indices, bounded shapes first, then planes (each group in scene order):
    /// the order [`intersect`](Self::intersect) tries them in.
    order: FixedVec<usize, OBJECTS>,
    lights: FixedVec<PointLight, LIGHTS>,
    background: Rgb,
    ambient: Rgb,
}

impl<const OBJECTS: usize, const LIGHTS: usize> Scene<OBJECTS, LIGHTS> {
    /// An empty scene seen by `camera`, with a black background and no ambient light.
    pub fn new(camera: Camera) -> Self {
        Self {
            camera,
            objects: FixedVec::new(),
            order: FixedVec::new(),
            lights: FixedVec::new(),
            background: Rgb::ZERO,
            ambient: Rgb::ZERO,
        }
    }

    /// Adds an object; an error when the compiled capacity is full.
    pub fn add(&mut self, shape: Shape, material: Material) -> Result<(), Error> {
        let index = self.objects.len();
        self.objects
            .push(Object { shape, material })
            .map_err(|_| Error::Capacity {
                what: "objects",
                requested: OBJECTS + 1,
                capacity: OBJECTS,
            })?;
        // Bounded shapes go before the first plane; cannot fail: one entry per object.
        let at = if shape.is_bounded() {
            let planes = self
                .order
                .iter()
                .filter(|&&i| !self.objects[i].shape.is_bounded());
            self.order.len() - planes.count()
        } else {
            self.order.len()
        };
        let _ = self.order.insert(at, index);
        Ok(())
    }

    /// Adds a light; an error when the compiled capacity is full.
    pub fn add_light(&mut self, light: PointLight) -> Result<(), Error> {
        self.lights.push(light).map_err(|_| Error::Capacity {
            what: "lights",
            requested: LIGHTS + 1,
            capacity: LIGHTS,
        })
    }

    /// Radiance of rays that leave the scene (validated: finite, ≥ 0).
    pub fn set_background(&mut self, background: Rgb) -> Result<(), Error> {
        self.background = background.validate("background")?;
        Ok(())
    }

    /// Ambient light for the `classic` model (validated: finite, ≥ 0).
    pub fn set_ambient(&mut self, ambient: Rgb) -> Result<(), Error> {
        self.ambient = ambient.validate("ambient")?;
        Ok(())
    }

    /// Replaces the camera (for example to change the image size).
    pub fn set_camera(&mut self, camera: Camera) {
        self.camera = camera;
    }

    /// The camera.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The objects.
    pub fn objects(&self) -> &[Object] {
        &self.objects
    }

    /// The lights.
    pub fn lights(&self) -> &[PointLight] {
        &self.lights
    }

    /// Background radiance.
    pub fn background(&self) -> Rgb {
        self.background
    }

    /// Ambient light of the classic model.
    pub fn ambient(&self) -> Rgb {
        self.ambient
    }

    /// `true` when some object can focus light into a caustic; without one the
    /// forward pass is skipped altogether.
    pub fn has_caustic_objects(&self) -> bool {
        self.objects.iter().any(|o| o.material.is_specular())
    }

    /// The nearest hit along `ray` with `t < t_max`, and the index of the object hit
    /// (on an exact tie, the lower index).
    ///
    /// Bounded shapes are tried before unbounded planes: a nearer hit found first
    /// narrows `t_max`, and a plane hit beyond it is then dismissed after its distance,
    /// before its point is built (a ray leaving a box towards the floor, the common
    /// case of a glass object above a plane). Bounded shapes reject cheaply by their
    /// bounding sphere whatever the order.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(Hit, usize)> {
        let mut best: Option<(Hit, usize)> = None;
        // The index of `best` (0 without one: then no index is lower).
        let mut best_index = 0;
        let mut limit = t_max;
        for &i in &self.order {
            // A later index must be strictly nearer; an earlier one wins a tie.
            let reach = if best_index > i {
                next_up(limit)
            } else {
                limit
            };
            if let Some(h) = self.objects[i].shape.intersect(ray, reach) {
                limit = h.t;
                best_index = i;
                best = Some((h, i));
            }
        }
        best
    }

    /// `true` when anything lies along `ray` before `t_max`: the shadow-ray query, an
    /// any-hit test that stops at the first blocker and asks each shape only whether
    /// it blocks ([`Shape::blocks`], no hit point or normal). Every object blocks, glass
    /// and mirrors included (light through them arrives only as caustics).
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.objects.iter().any(|o| o.shape.blocks(ray, t_max))
    }
}

/// The next `f32` above a positive `x` (`+∞` stays): the reach that lets a later
/// object win only when strictly nearer.
#[inline]
pub(crate) fn next_up(x: f32) -> f32 {
    if x < f32::INFINITY {
        f32::from_bits(x.to_bits() + 1)
    } else {
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{UnitVec3, Vec3};

    #[test]
    fn capacity_is_an_error_not_a_truncation() {
        let cam = Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0, 4, 4).unwrap();
        let mut s: Scene<1, 1> = Scene::new(cam);
        let m = Material::diffuse(Rgb::ONE).unwrap();
        s.add(Shape::sphere(Vec3::ZERO, 1.0).unwrap(), m).unwrap();
        assert_eq!(
            s.add(Shape::sphere(Vec3::ZERO, 1.0).unwrap(), m),
            Err(Error::Capacity {
                what: "objects",
                requested: 2,
                capacity: 1
            })
        );
    }

    #[test]
    fn nearest_hit_wins() {
        let cam = Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0, 4, 4).unwrap();
        let mut s: Scene<2, 1> = Scene::new(cam);
        let m = Material::diffuse(Rgb::ONE).unwrap();
        s.add(Shape::sphere(Vec3::new(0.0, 0.0, 10.0), 1.0).unwrap(), m)
            .unwrap();
        s.add(Shape::sphere(Vec3::new(0.0, 0.0, 5.0), 1.0).unwrap(), m)
            .unwrap();
        let r = Ray::new(Vec3::ZERO, UnitVec3::Z);
        let (h, i) = s.intersect(&r, f32::INFINITY).unwrap();
        assert_eq!((h.t, i), (4.0, 1));
        // Planes are tried after bounded shapes, but the order of the scene decides ties
        // and the nearest hit wins.
        let mut t: Scene<3, 1> = Scene::new(cam);
        t.add(Shape::plane(Vec3::new(0.0, 0.0, 4.0), -Vec3::Z).unwrap(), m)
            .unwrap();
        t.add(Shape::sphere(Vec3::new(0.0, 0.0, 5.0), 1.0).unwrap(), m)
            .unwrap();
        t.add(Shape::plane(Vec3::new(0.0, 0.0, 3.0), -Vec3::Z).unwrap(), m)
            .unwrap();
        assert_eq!(
            t.intersect(&r, f32::INFINITY).map(|(h, i)| (h.t, i)),
            Some((3.0, 2))
        );
        assert_eq!(t.intersect(&r, 3.5).map(|(h, i)| (h.t, i)), Some((3.0, 2)));
        let mut tie: Scene<2, 1> = Scene::new(cam);
        tie.add(Shape::plane(Vec3::new(0.0, 0.0, 4.0), -Vec3::Z).unwrap(), m)
            .unwrap();
        tie.add(Shape::sphere(Vec3::new(0.0, 0.0, 5.0), 1.0).unwrap(), m)
            .unwrap();
        assert_eq!(
            tie.intersect(&r, f32::INFINITY).map(|(h, i)| (h.t, i)),
            Some((4.0, 0))
        );
        assert!(s.occluded(&r, 4.5) && !s.occluded(&r, 3.5));
    }
}

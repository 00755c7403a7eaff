//! Tracing one photon through mirrors and glass to where it lands.

use crate::geometry::{Hit, Ray};
use crate::material::{interface, Material};
use crate::math::{reflect, Rgb, UnitVec3};
use crate::sampling::PathSampler;
use crate::scene::Scene;

/// Where a photon came to rest on a surface with a diffuse part.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Landing {
    /// The surface hit (point, normal, error bound).
    pub hit: Hit,
    /// Index of the object it landed on.
    pub object: usize,
    /// Direction of travel.
    pub dir: UnitVec3,
    /// Power, W.
    pub power: Rgb,
}

/// Follows one photon from the light.
///
/// Mirrors multiply its power by their reflectance; at a dielectric, Fresnel
/// reflectance (1 under total internal reflection) chooses reflection or refraction by
/// Russian roulette, so the power stays constant (Jensen 2001, §5.2), drawing on the
/// photon's [`PathSampler`] (its point set's further coordinates); Beer absorption
/// scales it along paths inside glass. A `classic` surface reflects with probability
/// `reflectivity`, transmits with probability `transparency`, and absorbs otherwise.
/// At most `max_depth` specular interactions; the photon is stored at the first surface
/// with a diffuse part that it reaches *from the front* after at least one specular
/// interaction (or at its first hit when `store_direct`), and then ends.
pub(crate) fn trace<const O: usize, const L: usize>(
    scene: &Scene<O, L>,
    mut ray: Ray,
    mut power: Rgb,
    max_depth: u32,
    store_direct: bool,
    rng: &mut PathSampler,
) -> Option<Landing> {
    let mut bounces = 0u32;
    loop {
        let (hit, index) = scene.intersect(&ray, f32::INFINITY)?;
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

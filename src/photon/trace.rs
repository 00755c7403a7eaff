//! Tracing one photon through mirrors and glass to where it lands.

use super::reach::{enters, Reach, Reaches};
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
/// interactions. Its first segment is tested against the objects of `first`, a
/// segment that goes into an object against those [`Reaches`] finds it may meet, the
/// others against all.
pub(crate) fn trace<E, const O: usize, const L: usize>(
    scene: &Scene<O, L>,
    ray: Ray,
    power: Rgb,
    (max_depth, store_direct, split): (u32, bool, bool),
    rng: &mut PathSampler,
    (all, first): (&Reaches<O>, Reach),
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
        if let Some(l) = follow(scene, path, all.all, all, limits, &mut rng, &mut branches) {
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
    all: &Reaches<O>,
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
    // The object the segment starts inside of, if it goes into one.
    let mut inside = None;
    loop {
        let (hit, index) = all.nearest(scene, &ray, reach, inside)?;
        reach = all.all;
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
        inside = enters(hit.normal, dir).then_some(index);
        ray = Ray::spawn(&hit, dir);
    }
}

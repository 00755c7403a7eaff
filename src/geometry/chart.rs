//! The `(u, v)` charts of every shape: where a point lies on its surface. Each shape
//! owns its chart here; the illumination maps lay texels over them.
//!
//! | shape | chart | `u` | `v` | area element |
//! |---|---|---|---|---|
//! | plane | 0: the plane | length along `e1` | length along `e2` | `du·dv` |
//! | sphere | 0: the whole sphere (paper eq. 7, its `z` axis the scene's `y`) | longitude `∈ [0, 2π)` | latitude `∈ [−π/2, π/2]` | `r² cos v du dv` |
//! | box | `2·axis + (normal along +axis)`: each of the 6 faces, in the box's frame | length from the face's corner | length | `du·dv` |
//! | cylinder | 0: the side | angle `∈ [0, 2π)` | height `∈ [0, h]` | `r du dv` |
//! | cylinder | 1: bottom cap, 2: top cap (polar) | angle `∈ [0, 2π)` | radius `∈ [0, r]` | `v du dv` |
//!
//! `(e1, e2)` is [`UnitVec3::basis`] of the plane's normal (of the cylinder's axis for
//! the angles). A sphere's longitude is `atan2(z, x)`: `P(u, v) = c + r·(cos v cos u,
//! sin v, cos v sin u)`.

use core::f32::consts::PI;

use super::{Cuboid, Cylinder, Plane, Shape, Sphere};
use crate::math::{UnitVec3, Vec3};

/// Where a point lies on a shape: the chart, its parameters and the outward normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct SurfacePoint {
    /// The chart (see the module table).
    pub chart: usize,
    /// First parameter.
    pub u: f32,
    /// Second parameter.
    pub v: f32,
    /// Outward normal at the point.
    pub normal: Vec3,
}

impl Shape {
    /// Distance from `x` to the surface (0 on it).
    pub(crate) fn surface_distance(&self, x: Vec3) -> f32 {
        match self {
            Shape::Plane(p) => p.normal().dot(x - p.point()).abs(),
            Shape::Sphere(s) => ((x - s.center()).length() - s.radius()).abs(),
            Shape::Box(b) => {
                let l = b.rotation().transpose() * (x - b.center());
                (l.abs() - b.half_size()).max_element().abs()
            }
            Shape::Cylinder(c) => c.surface_distance(x),
        }
    }

    /// Chart, parameters and outward normal of point `x` (assumed on the surface).
    /// With `n` (the hit's outward normal) the face of a box or the part of a cylinder
    /// is chosen by the normal; without, by the position.
    pub(crate) fn locate(&self, x: Vec3, n: Option<UnitVec3>) -> SurfacePoint {
        match self {
            Shape::Plane(p) => p.locate(x),
            Shape::Sphere(s) => s.locate(x),
            Shape::Box(b) => b.locate(x, n),
            Shape::Cylinder(c) => c.locate(x, n),
        }
    }
}

/// Angle of `(a, b)` in `[0, 2π)`.
#[inline]
fn angle(a: f32, b: f32) -> f32 {
    let t = libm::atan2f(b, a);
    // Rounding may give exactly 2π: a periodic axis wraps it to 0.
    if t < 0.0 {
        t + 2.0 * PI
    } else {
        t
    }
}

impl Plane {
    fn locate(&self, x: Vec3) -> SurfacePoint {
        let (e1, e2) = self.normal().basis();
        let d = x - self.point();
        SurfacePoint {
            chart: 0,
            u: e1.dot(d),
            v: e2.dot(d),
            normal: self.normal().get(),
        }
    }
}

impl Sphere {
    fn locate(&self, x: Vec3) -> SurfacePoint {
        let d = x - self.center();
        let len = d.length();
        let y = if len > 0.0 { d.y / len } else { 0.0 };
        SurfacePoint {
            chart: 0,
            u: angle(d.x, d.z),
            v: libm::asinf(y.clamp(-1.0, 1.0)),
            normal: if len > 0.0 { d / len } else { Vec3::Y },
        }
    }
}

impl Cuboid {
    fn locate(&self, x: Vec3, n: Option<UnitVec3>) -> SurfacePoint {
        let rt = self.rotation().transpose();
        let l = rt * (x - self.center());
        let half = self.half_size();
        let (axis, sign) = match n {
            Some(n) => {
                let nl = rt * n.get();
                let a = argmax(nl.abs().to_array());
                (a, nl[a] >= 0.0)
            }
            None => {
                let a = argmax((l.abs() / half).to_array());
                (a, l[a] >= 0.0)
            }
        };
        let (bx, cx) = ((axis + 1) % 3, (axis + 2) % 3);
        let s = if sign { 1.0 } else { -1.0 };
        SurfacePoint {
            chart: axis * 2 + sign as usize,
            u: l[bx] + half[bx],
            v: l[cx] + half[cx],
            normal: self.rotation().col(axis) * s,
        }
    }
}

fn argmax(a: [f32; 3]) -> usize {
    let mut best = 0;
    for i in 1..3 {
        if a[i] > a[best] {
            best = i;
        }
    }
    best
}

impl Cylinder {
    /// Distances from `x` to the side and the two caps (`(side, bottom, top)`; the caps
    /// at infinity when uncapped), from its height `z` along the axis and radius `rho`.
    fn part_distances(&self, z: f32, rho: f32) -> (f32, f32, f32) {
        let out_z = (-z).max(z - self.height()).max(0.0);
        let side = libm::hypotf(rho - self.radius(), out_z);
        if !self.capped() {
            return (side, f32::INFINITY, f32::INFINITY);
        }
        let out_r = (rho - self.radius()).max(0.0);
        (
            side,
            libm::hypotf(z, out_r),
            libm::hypotf(z - self.height(), out_r),
        )
    }

    fn surface_distance(&self, x: Vec3) -> f32 {
        let rel = x - self.base();
        let z = self.axis().dot(rel);
        let rho = (rel - self.axis().get() * z).length();
        let (side, bottom, top) = self.part_distances(z, rho);
        side.min(bottom.min(top))
    }

    fn locate(&self, x: Vec3, n: Option<UnitVec3>) -> SurfacePoint {
        let (e1, e2) = self.axis().basis();
        let ax = self.axis().get();
        let rel = x - self.base();
        let z = self.axis().dot(rel);
        let (a, b) = (e1.dot(rel), e2.dot(rel));
        let rho = libm::hypotf(a, b);
        let theta = angle(a, b);
        // 0: side, 1: bottom cap, 2: top cap.
        let part = match n {
            _ if !self.capped() => 0,
            Some(n) => {
                let nz = n.dot(ax);
                if nz > 0.5 {
                    2
                } else if nz < -0.5 {
                    1
                } else {
                    0
                }
            }
            None => {
                let (side, bottom, top) = self.part_distances(z, rho);
                if side <= bottom && side <= top {
                    0
                } else if bottom <= top {
                    1
                } else {
                    2
                }
            }
        };
        let radial = if rho > 0.0 {
            (e1.get() * a + e2.get() * b) / rho
        } else {
            e1.get()
        };
        let (v, normal) = match part {
            0 => (z, radial),
            1 => (rho, -ax),
            _ => (rho, ax),
        };
        SurfacePoint {
            chart: part,
            u: theta,
            v,
            normal,
        }
    }
}

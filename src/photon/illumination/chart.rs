//! Texel grids over the `(u, v)` charts of the shapes, and the true area of a texel.
//!
//! The charts live with the shapes (`geometry::chart`, which tabulates them); here each
//! is a rectangle of parameter space with area element `dA = g(v)·du·dv`, `g` a
//! [`Profile`]: `1` on a plane or a box face, `r² cos v` on a sphere (longitude ×
//! latitude), `r` on a cylinder's side (angle × height), `v` on a cap (angle × radius).
//! Angles `u` are periodic; every other coordinate is clamped at the chart's edges.

use crate::geometry::Shape;
use core::f32::consts::PI;

/// How the area element varies along `v`: `dA = g(v)·du·dv`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Profile {
    /// `g(v) = k`.
    Flat(f32),
    /// `g(v) = k·cos v` (a sphere of radius `√k` in longitude/latitude).
    Cos(f32),
    /// `g(v) = v` (a disk in polar coordinates).
    Linear,
}

impl Profile {
    /// `G1(v) = ∫ g`, `G2(v) = ∫ v·g`, in f64.
    fn antiderivatives(self, v: f64) -> (f64, f64) {
        match self {
            Profile::Flat(k) => (k as f64 * v, k as f64 * v * v * 0.5),
            Profile::Cos(k) => {
                let (s, c) = (libm::sin(v), libm::cos(v));
                (k as f64 * s, k as f64 * (v * s + c))
            }
            Profile::Linear => (v * v * 0.5, v * v * v / 3.0),
        }
    }

    /// `∫_a^b w(v)·g(v) dv` for a weight `w` that is 1 (`Flat`), rises linearly from 0
    /// at `a` to 1 at `b` (`Rise`) or falls from 1 at `a` to 0 at `b` (`Fall`).
    fn weighted(self, a: f64, b: f64, w: Weight) -> f64 {
        let (g1a, g2a) = self.antiderivatives(a);
        let (g1b, g2b) = self.antiderivatives(b);
        let h = b - a;
        match w {
            Weight::Flat => g1b - g1a,
            Weight::Rise => (g2b - g2a - a * (g1b - g1a)) / h,
            Weight::Fall => (b * (g1b - g1a) - (g2b - g2a)) / h,
        }
    }
}

#[derive(Clone, Copy)]
enum Weight {
    Flat,
    Rise,
    Fall,
}

/// One chart's grid of `w × h` texels inside the shared texel array.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Grid {
    /// Index of texel (0, 0) in the shared array; row-major.
    pub offset: u32,
    pub w: u32,
    pub h: u32,
    /// Parameter of the chart's lower edges and texel sides: `u = u0 + s·du`.
    pub u0: f32,
    pub du: f32,
    pub v0: f32,
    pub dv: f32,
    pub periodic_u: bool,
    pub profile: Profile,
}

/// The two texels (along one axis) whose centres bracket continuous coordinate `s`
/// (in texel units, centres at `i + ½`), and the weight of the second. Periodic axes
/// wrap; others clamp, giving everything to the edge texel beyond the last centre.
#[inline]
pub(crate) fn pair(s: f32, n: u32, periodic: bool) -> (usize, usize, f32) {
    let n = n as i32;
    let c = s - 0.5;
    let fl = libm::floorf(c);
    let f = c - fl;
    let i0 = fl as i32;
    if periodic {
        let a = i0.rem_euclid(n);
        let b = (i0 + 1).rem_euclid(n);
        (a as usize, b as usize, f)
    } else if i0 < 0 {
        (0, 0, 0.0)
    } else if i0 >= n - 1 {
        let last = (n - 1) as usize;
        (last, last, 0.0)
    } else {
        (i0 as usize, i0 as usize + 1, f)
    }
}

impl Grid {
    /// Texels in this grid.
    pub fn len(&self) -> usize {
        self.w as usize * self.h as usize
    }

    /// Continuous texel coordinates of parameter `(u, v)`.
    #[inline]
    pub fn st(&self, u: f32, v: f32) -> (f32, f32) {
        ((u - self.u0) / self.du, (v - self.v0) / self.dv)
    }

    /// The area that texel row `j` represents per unit of `u`:
    /// `∫ w_j(v)·g(v) dv`, `w_j` the texel's bilinear splat weight along `v` (a tent
    /// between the neighbouring centres, flat from the last centre to a clamped edge).
    pub fn row_integral(&self, j: usize) -> f64 {
        let (v0, dv, h) = (self.v0 as f64, self.dv as f64, self.h as usize);
        let centre = |k: usize| v0 + (k as f64 + 0.5) * dv;
        let p = self.profile;
        let lower = if j == 0 {
            p.weighted(v0, centre(0), Weight::Flat)
        } else {
            p.weighted(centre(j - 1), centre(j), Weight::Rise)
        };
        let upper = if j + 1 == h {
            p.weighted(centre(j), v0 + h as f64 * dv, Weight::Flat)
        } else {
            p.weighted(centre(j), centre(j + 1), Weight::Fall)
        };
        lower + upper
    }

    /// The true surface area texel `(i, j)` represents: the integral over the surface of
    /// its bilinear weight. Along `u` this is `du` for every texel (periodic or
    /// clamped), so the area is `du·row_integral(j)`. The areas of a chart sum to the
    /// chart's area, and a uniform irradiance `E` splats exactly `E·area` into a texel
    /// on average.
    pub fn texel_area(&self, j: usize) -> f64 {
        self.du as f64 * self.row_integral(j)
    }
}

/// The grids of the charts of a bounded shape for `texel` (world length of a texel's
/// side): each chart gets `ceil(extent/texel)` texels along each side (at least one),
/// so texels are at most `texel` long (at the equator of a sphere, the rim of a cap).
/// Offsets are left at 0. `None` for a plane (whose rectangle comes from elsewhere).
pub(crate) fn bounded_grids(shape: &Shape, texel: f32, out: &mut [Grid; 6]) -> Option<usize> {
    let count = |extent: f32| -> u32 { libm::ceilf(extent / texel).clamp(1.0, 1e9) as u32 };
    let grid = |lu: f32, periodic: bool, lv: f32, v0: f32, profile: Profile, su: f32, sv: f32| {
        let (w, h) = (count(su), count(sv));
        Grid {
            offset: 0,
            w,
            h,
            u0: 0.0,
            du: lu / w as f32,
            v0,
            dv: lv / h as f32,
            periodic_u: periodic,
            profile,
        }
    };
    match shape {
        Shape::Plane(_) => None,
        Shape::Sphere(s) => {
            let r = s.radius();
            out[0] = grid(
                2.0 * PI,
                true,
                PI,
                -0.5 * PI,
                Profile::Cos(r * r),
                2.0 * PI * r,
                PI * r,
            );
            Some(1)
        }
        Shape::Box(b) => {
            let half = b.half_size();
            for axis in 0..3 {
                let (bx, cx) = ((axis + 1) % 3, (axis + 2) % 3);
                let (lu, lv) = (2.0 * half[bx], 2.0 * half[cx]);
                let g = grid(lu, false, lv, 0.0, Profile::Flat(1.0), lu, lv);
                out[axis * 2] = g;
                out[axis * 2 + 1] = g;
            }
            Some(6)
        }
        Shape::Cylinder(c) => {
            let (r, h) = (c.radius(), c.height());
            out[0] = grid(2.0 * PI, true, h, 0.0, Profile::Flat(r), 2.0 * PI * r, h);
            if !c.capped() {
                return Some(1);
            }
            let cap = grid(2.0 * PI, true, r, 0.0, Profile::Linear, 2.0 * PI * r, r);
            out[1] = cap;
            out[2] = cap;
            Some(3)
        }
    }
}

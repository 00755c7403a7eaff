//! The secants that bound a grazing pixel's footprints: each sample of its refined
//! grid probed a row ahead ([`Renderer::probe`]), and the distance to the points its
//! neighbours see halved (see `Renderer::grazing_grid`).

use super::differential::{Bounds, Secant};
use super::{Probe, Renderer};
use crate::math::Vec3;
use crate::photon::{CausticStore, GRAZING_VISITS};

/// The largest grid side ([`Renderer::with_sampling`] allows 64, and refinement stops
/// there).
const MAX_SIDE: usize = 64;

/// The probes ([`Renderer::probe`]) of a grazing pixel's `n × n` grid, three rows at a
/// time: the row being sampled and the rows either side, each probed once, a row ahead.
pub(super) struct ProbeRows {
    pixel: (u32, u32),
    n: u32,
    /// Which row each slot holds (row `r` in slot `r % 3`).
    held: [Option<u32>; 3],
    probes: [[Option<Probe>; MAX_SIDE]; 3],
}

impl ProbeRows {
    pub(super) fn new(x: u32, y: u32, n: u32) -> Self {
        Self {
            pixel: (x, y),
            n: n.min(MAX_SIDE as u32),
            held: [None; 3],
            probes: [[None; MAX_SIDE]; 3],
        }
    }

    /// The probe of sub-pixel `(sx, sy)`; `None` outside the grid.
    fn at<S: CausticStore, const O: usize, const L: usize, const D: usize>(
        &mut self,
        r: &Renderer<'_, S, O, L, D>,
        sx: i64,
        sy: i64,
    ) -> Option<Probe> {
        let n = self.n as i64;
        if !(0..n).contains(&sx) || !(0..n).contains(&sy) {
            return None;
        }
        let (row, slot) = (sy as u32, sy as usize % 3);
        if self.held[slot] != Some(row) {
            let (camera, step) = (r.scene.camera(), 1.0 / self.n as f32);
            for (i, p) in self.probes[slot][..self.n as usize].iter_mut().enumerate() {
                let (fx, fy) = ((i as f32 + 0.5) * step, (row as f32 + 0.5) * step);
                *p = r.probe(camera.ray_at(self.pixel.0, self.pixel.1, fx, fy), self.n);
            }
            self.held[slot] = Some(row);
        }
        self.probes[slot][sx as usize]
    }

    /// Sample `(sx, sy)`'s bounds: [`GRAZING_VISITS`], and where its heavy path first
    /// gathers, half-axes of at most half the distance between the points of its
    /// neighbours along each of the image's axes whose paths gather on the same object
    /// at the same depth (central secants; one-sided at the grid's edge or where a
    /// neighbour's path went elsewhere, none without a neighbour).
    pub(super) fn bounds<S: CausticStore, const O: usize, const L: usize, const D: usize>(
        &mut self,
        r: &Renderer<'_, S, O, L, D>,
        sx: u32,
        sy: u32,
    ) -> Bounds {
        let (x, y) = (sx as i64, sy as i64);
        let secant = self.at(r, x, y).map(|p| {
            let mut near = |dx: i64, dy: i64| {
                self.at(r, x + dx, y + dy)
                    .filter(|q| q.depth == p.depth && q.object == p.object)
                    .map(|q| q.point)
            };
            let x_axis = half_secant(p.point, near(-1, 0), near(1, 0));
            let y_axis = half_secant(p.point, near(0, -1), near(0, 1));
            Secant {
                at: p.point,
                half: [x_axis, y_axis],
            }
        });
        Bounds {
            visits: GRAZING_VISITS,
            secant,
        }
    }
}

/// Half a sub-pixel's extent along one axis of the image, from the points its
/// neighbours `before` and `after` along that axis see: `|after − before|/4` (the
/// central difference over two steps, halved), one-sided `|q − p|/2`, unbounded
/// without either.
fn half_secant(p: Vec3, before: Option<Vec3>, after: Option<Vec3>) -> f32 {
    let dist = |a: Vec3, b: Vec3| crate::math::sqrt((a - b).length_squared());
    match (before, after) {
        (Some(b), Some(a)) => 0.25 * dist(a, b),
        (Some(q), None) | (None, Some(q)) => 0.5 * dist(p, q),
        (None, None) => f32::INFINITY,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The central secant halves a neighbour's spacing (two steps over four), the
    /// one-sided one halves one step, and without a neighbour nothing bounds.
    #[test]
    fn a_secant_is_half_the_neighbours_spacing() {
        let p = Vec3::new(1.0, 0.0, 2.0);
        let d = Vec3::new(0.3, 0.0, 0.4); // 0.5 long
        let close = |h: f32, want: f32| (h - want).abs() <= 1e-6;
        assert!(close(half_secant(p, Some(p - d), Some(p + d)), 0.25));
        assert!(close(half_secant(p, Some(p - d), None), 0.25));
        assert!(close(half_secant(p, None, Some(p + d * 2.0)), 0.5));
        assert_eq!(half_secant(p, None, None), f32::INFINITY);
    }

    /// The rows of probes, each probed once and a row ahead, give every sample of a
    /// grazing grid the bounds that probing each neighbour on its own gives — here on
    /// the demo glass sphere, whose floor the camera sees through the ball.
    #[test]
    fn probe_rows_give_each_sample_its_neighbours_secants() {
        let scene: crate::scene::Scene<4, 1> = crate::demo::glass(32, 24).unwrap();
        let r = Renderer::<_, 4, 1, 8>::new(&scene, &crate::photon::NoCaustics, 8).unwrap();
        let (x, y, n) = (16, 11, 8);
        let mut rows = ProbeRows::new(x, y, n);
        let camera = scene.camera();
        let probe = |sx: i64, sy: i64| {
            let inside = (0..n as i64).contains(&sx) && (0..n as i64).contains(&sy);
            let (fx, fy) = ((sx as f32 + 0.5) / n as f32, (sy as f32 + 0.5) / n as f32);
            inside
                .then(|| r.probe(camera.ray_at(x, y, fx, fy), n))
                .flatten()
        };
        let mut bounded = 0;
        for sy in 0..n {
            for sx in 0..n {
                let got = rows.bounds(&r, sx, sy);
                let (i, j) = (sx as i64, sy as i64);
                let want = probe(i, j).map(|p| {
                    let near = |dx, dy| {
                        probe(i + dx, j + dy)
                            .filter(|q| q.depth == p.depth && q.object == p.object)
                            .map(|q| q.point)
                    };
                    let half = [
                        half_secant(p.point, near(-1, 0), near(1, 0)),
                        half_secant(p.point, near(0, -1), near(0, 1)),
                    ];
                    Secant { at: p.point, half }
                });
                assert_eq!(got.secant, want, "sample ({sx}, {sy})");
                assert_eq!(got.visits, GRAZING_VISITS);
                bounded += want.is_some_and(|s| s.half.iter().all(|h| h.is_finite())) as u32;
            }
        }
        assert!(bounded > n * n / 2, "only {bounded} samples bounded");
    }
}

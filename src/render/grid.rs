//! A pixel's grid of samples as its refinement judges it: the estimate, its error by
//! each of the refinement's reasons, and the edges that run between its rows.

use super::PixelEstimate;

/// A pixel's grid estimate, with what its refinement asks of it.
pub(super) struct Grid {
    pub(super) pixel: PixelEstimate,
    /// The checkerboard halves' squared luminance error of the caustic part alone.
    pub(super) caustic2: f32,
    /// The luminance variance of `(m_a − m_b)/2` that the photons of samples widened far
    /// explain (0 on a device's store).
    pub(super) photons: f32,
    /// A sample that grazed glass gathered more than the pixel's value.
    pub(super) grazing: bool,
    /// Every sample saw the same objects along its path (the same signature).
    pub(super) uniform: bool,
    /// The least and the greatest luminance of its samples.
    pub(super) range: (f32, f32),
    /// The squared luminance error of where an edge between its rows or between its
    /// columns lies ([`Lines::aligned2`]; 0 on a device's store).
    pub(super) aligned: f32,
}

impl Grid {
    /// The largest of `e` and the squared errors that the `corners` of luminance
    /// outside the range of this `m × m` grid's samples stand for: each one's distance
    /// from the range times the half sub-pixel around it, `1/(4m²)` of the pixel (see
    /// [`error2`](Self::error2)).
    pub(super) fn corners2(&self, m: u32, corners: [f32; 4], e: f32) -> f32 {
        let w = 1.0 / (4 * m * m) as f32;
        corners.into_iter().fold(e, |e, l| {
            let d = (l - crate::math::clamp(l, self.range.0, self.range.1)) * w;
            crate::math::max(e, d * d)
        })
    }

    /// The squared error of the luminance of this `m × m` grid's pixel, as its
    /// refinement judges it: the checkerboard halves' estimate less what the photons
    /// of samples widened far explain; on the desktop (`corners`: the pixel's corner
    /// luminances) at least each corner's distance from the samples' range times the
    /// half sub-pixel around it, `1/(4m²)` of the pixel — what it saw may lie there,
    /// unsampled; with the `coarser` grid's luminance before it (a grazing pixel)
    /// at least half their difference — halves that alias a sliver alike can agree on a
    /// wrong value twice in a row, two grids of different sides rarely do; and on the
    /// desktop at least the error of an edge that runs between the grid's rows or
    /// columns ([`Lines::aligned2`]), which its halves, each with samples on every row
    /// and column, see alike.
    pub(super) fn error2(&self, m: u32, corners: Option<[f32; 4]>, coarser: Option<f32>) -> f32 {
        let mut e = self.pixel.sampling2.luminance() - self.photons;
        if let Some(c) = corners {
            e = self.corners2(m, c, e);
        }
        if let Some(c) = coarser {
            let d = (self.pixel.radiance.luminance() - c) * 0.5;
            e = crate::math::max(e, d * d);
        }
        if corners.is_some() {
            e = crate::math::max(e, self.aligned);
        }
        e
    }
}

/// The largest grid side whose rows and columns [`Lines`] follows.
const LINES: usize = 16;

/// The rows and the columns of an `n × n` grid (`n ≤` [`LINES`]; none kept otherwise):
/// whether each saw one signature alone, and its samples' luminance summed.
pub(super) struct Lines {
    n: usize,
    rows: [Line; LINES],
    columns: [Line; LINES],
}

/// One row or column of a grid (see [`Lines`]).
#[derive(Clone, Copy, Debug, Default)]
struct Line {
    signature: Option<u32>,
    same: bool,
    sum: f32,
}

impl Line {
    fn add(&mut self, signature: u32, luminance: f32) {
        match self.signature {
            None => (self.signature, self.same) = (Some(signature), true),
            Some(s) => self.same &= s == signature,
        }
        self.sum += luminance;
    }
}

impl Lines {
    pub(super) fn new(n: u32) -> Self {
        Self {
            n: n as usize,
            rows: [Line::default(); LINES],
            columns: [Line::default(); LINES],
        }
    }

    pub(super) fn add(&mut self, sx: u32, sy: u32, signature: u32, luminance: f32) {
        if self.n > LINES {
            return; // a grid too fine to follow: aligned2 reads nothing
        }
        if let (Some(row), Some(column)) = (
            self.rows.get_mut(sy as usize),
            self.columns.get_mut(sx as usize),
        ) {
            row.add(signature, luminance);
            column.add(signature, luminance);
        }
    }

    /// The squared luminance error of an edge that runs between the grid's rows (or
    /// its columns): where every row saw one signature alone but not all the same, the
    /// grid puts the edge on the boundary between two rows, wherever it lies within
    /// the row spacing `1/n` — an error of the step `Δ` between those rows' means
    /// times a uniform offset in `±1/(2n)`, of variance `Δ²/(12n²)`; the largest step
    /// of either direction. The sphere + wall g's floor shadow, nearly along the rows,
    /// read 0.114 against 0.074 on 4×4 grids whose checkerboard halves agreed
    /// (`docs/accuracy.md`, session 31); session 28 found the same edges on the
    /// sphere + wall c. Zero without an edge, or past [`LINES`].
    pub(super) fn aligned2(&self) -> f32 {
        if !(2..=LINES).contains(&self.n) {
            return 0.0;
        }
        let n = self.n as f32;
        let step = |lines: &[Line]| {
            if !lines.iter().all(|l| l.same) {
                return 0.0;
            }
            let steps = lines
                .windows(2)
                .filter(|w| w[0].signature != w[1].signature);
            steps.fold(0.0, |s, w| {
                crate::math::max(s, ((w[0].sum - w[1].sum) / n).abs())
            })
        };
        let [rows, columns] = [&self.rows, &self.columns].map(|l| step(&l[..self.n]));
        let s = crate::math::max(rows, columns);
        s * s / (12.0 * n * n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Rgb;

    /// A 4×4 grid of grey samples reading 1 to 2, halves that differ by `halves`.
    fn grid(halves: f32) -> Grid {
        Grid {
            pixel: PixelEstimate {
                radiance: Rgb::splat(1.5),
                sampling2: Rgb::splat(halves * halves),
                ..PixelEstimate::default()
            },
            photons: 0.0,
            grazing: false,
            uniform: false,
            range: (1.0, 2.0),
            aligned: 0.0,
            caustic2: 0.0,
        }
    }

    /// Each term of the refinement's error estimate is the one its reason gives, and
    /// the estimate is the largest: the halves alone; a corner inside the samples'
    /// range adds nothing; one outside counts its distance from the range times the
    /// `1/(4m²)` of the pixel around it; two grids in a row half their difference.
    #[test]
    fn the_error_estimate_is_the_largest_of_its_reasons() {
        let close = |a: f32, b: f32| (a - b).abs() <= 1e-6 * b.abs().max(1e-12);
        let g = grid(0.01);
        assert!(close(g.error2(4, None, None), 1e-4));
        assert!(close(g.error2(4, Some([1.0, 1.2, 2.0, 1.7]), None), 1e-4));
        // A corner at 10, 8 above the range: (8/64)² on a 4×4 grid, (8/256)² on 8×8.
        let corners = Some([10.0, 1.5, 1.5, 0.5]);
        assert!(close(g.error2(4, corners, None), 0.125 * 0.125));
        assert!(close(g.error2(8, corners, None), 0.03125 * 0.03125));
        // Below the range counts the same way: 0.5 under it gives (0.5/64)², under the
        // halves' 10⁻⁴. A coarser grid at 1.1 against this one's 1.5 gives (0.4/2)².
        assert!(close(g.error2(4, Some([0.5; 4]), None), 1e-4));
        assert!(close(g.error2(4, None, Some(1.1)), 0.04));
        // The largest wins whichever comes first.
        assert!(close(g.error2(4, corners, Some(1.1)), 0.04));
        assert!(close(grid(0.5).error2(4, corners, Some(1.1)), 0.25));
        // An edge between the rows counts on the desktop (with corners) alone.
        let edge = Grid { aligned: 0.3, ..g };
        assert!(close(edge.error2(4, Some([1.5; 4]), None), 0.3));
        assert!(close(edge.error2(4, None, None), 1e-4));
    }

    /// A 4×4 grid whose top two rows saw one thing at luminance 1 and bottom two
    /// another at 0: an edge between rows, a step of 1, variance `1/(12·16)`; the same
    /// turned on its side between columns; an edge that crosses a row (a sample of the
    /// row seeing the other side) or no edge at all: nothing.
    #[test]
    fn an_edge_between_rows_or_columns_has_the_rows_rounding_error() {
        let lines = |side: fn(u32, u32) -> bool| {
            let mut l = Lines::new(4);
            for sy in 0..4 {
                for sx in 0..4 {
                    let lit = side(sx, sy);
                    l.add(sx, sy, lit as u32, if lit { 1.0 } else { 0.0 });
                }
            }
            l.aligned2()
        };
        let want = 1.0 / (12.0 * 16.0);
        assert!((lines(|_, sy| sy < 2) - want).abs() < 1e-7);
        assert!((lines(|sx, _| sx >= 1) - want).abs() < 1e-7);
        assert_eq!(lines(|sx, sy| sx + sy < 3), 0.0);
        assert_eq!(lines(|sx, sy| sy < 2 || (sx, sy) == (0, 2)), 0.0);
        assert_eq!(lines(|_, _| true), 0.0);
        assert_eq!(Lines::new(32).aligned2(), 0.0);
    }
}

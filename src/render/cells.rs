//! The first grid's samples that a supersampled pixel's finer grids take their caustic
//! parts from, where the first grid settled them (see `Renderer::refine`).

#[cfg(feature = "std")]
use crate::math::Rgb;
#[cfg(feature = "std")]
use crate::render::Sample;

/// How a grid's samples use the pixel's first grid (see `Renderer::refine`).
// A device's samples all gather for themselves: it reads no cell.
#[cfg_attr(not(feature = "std"), allow(dead_code))]
pub(super) enum Cells<'c> {
    /// Not at all: each sample gathers its own caustic part.
    Own,
    /// They are the first grid's: each one's caustic part is kept.
    Keep(&'c mut Coarse),
    /// A finer grid's: a sample that sees the same paths (the same signature) as the
    /// first grid's sample in whose cell it lies takes that one's caustic part.
    Take(&'c Coarse),
}

/// The largest first grid side whose samples [`Coarse`] keeps.
#[cfg(feature = "std")]
const COARSE: usize = 16;

/// The first grid's samples' signatures, caustic parts and splits, row by row (on the
/// desktop: 7 KiB that a device's stack is spared).
#[cfg(feature = "std")]
pub(super) struct Coarse {
    /// The first grid's side.
    n: u32,
    cells: [(u32, Rgb, Rgb); COARSE * COARSE],
}

#[cfg(feature = "std")]
impl Coarse {
    /// Room for an `n × n` first grid (none past [`COARSE`]).
    pub(super) fn new(n: u32) -> Self {
        Self {
            n,
            cells: [(0, Rgb::ZERO, Rgb::ZERO); COARSE * COARSE],
        }
    }

    /// Keeps sample `(sx, sy)` of the first grid.
    pub(super) fn keep(&mut self, sx: u32, sy: u32, s: &Sample) {
        let n = self.n;
        if (n as usize) <= COARSE {
            if let Some(c) = self.cells.get_mut((sy * n + sx) as usize) {
                *c = (s.signature, s.caustic, s.split);
            }
        }
    }

    /// The kept sample whose cell holds sample `(sx, sy)` of an `m × m` grid (`m` a
    /// multiple of the first grid's side): `⌊sx·n/m⌋`, whose cell `[cx/n, (cx+1)/n)`
    /// holds the sample's centre `(sx + ½)/m`.
    pub(super) fn cell(&self, sx: u32, sy: u32, m: u32) -> Option<(u32, Rgb, Rgb)> {
        let n = self.n;
        if (n as usize) > COARSE || n == 0 || m % n != 0 {
            return None;
        }
        let (cx, cy) = (sx * n / m, sy * n / m);
        self.cells.get((cy * n + cx) as usize).copied()
    }
}

/// On a device nothing is kept.
#[cfg(not(feature = "std"))]
pub(super) struct Coarse;

#[cfg(not(feature = "std"))]
impl Coarse {
    pub(super) fn new(_: u32) -> Self {
        Self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every sample of a finer grid takes the kept sample of the first-grid cell that
    /// holds its centre (brute force over the sub-pixel positions), and nothing is
    /// taken from grids whose side is not a multiple of the first's.
    #[cfg(feature = "std")]
    #[test]
    fn a_finer_sample_takes_the_cell_that_holds_it() {
        let n = 4;
        let mut c = Coarse::new(n);
        for sy in 0..n {
            for sx in 0..n {
                let s = Sample {
                    signature: sy * n + sx,
                    caustic: Rgb::splat(sx as f32),
                    ..Sample::default()
                };
                c.keep(sx, sy, &s);
            }
        }
        for m in [8, 16, 32] {
            for sy in 0..m {
                for sx in 0..m {
                    let centre = |s: u32| (s as f32 + 0.5) / m as f32;
                    let (cx, cy) = (
                        (centre(sx) * n as f32) as u32,
                        (centre(sy) * n as f32) as u32,
                    );
                    let (signature, caustic, _) = c.cell(sx, sy, m).unwrap();
                    assert_eq!((signature, caustic), (cy * n + cx, Rgb::splat(cx as f32)));
                }
            }
        }
        assert_eq!(c.cell(0, 0, 6), None);
        assert_eq!(
            Coarse::new(COARSE as u32 + 1).cell(0, 0, 2 * COARSE as u32 + 2),
            None
        );
    }
}

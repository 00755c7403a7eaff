//! A display that is a byte stream: RGB565 pixels, little-endian, row-major.
//!
//! This is what a device sends down a wire (an SPI panel's RAM write, a semihosted
//! file, a UART) and what the host tests compare: one `DrawTarget` for all of them,
//! so the firmware, `tests/device.rs` and `tests/simulator.rs` share the encoding
//! (each used to carry its own copy). Pixels must arrive in stream order, which
//! [`DisplaySink`](super::DisplaySink) guarantees (whole rows, top to bottom); anything
//! else is an error, never a silent seek. One row of `W` pixels is buffered; each full
//! row goes to the writer in one call and into the stream's FNV-1a checksum.

use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::geometry::{OriginDimensions, Point, Size};
use embedded_graphics_core::pixelcolor::{IntoStorage, Rgb565};
use embedded_graphics_core::primitives::Rectangle;
use embedded_graphics_core::Pixel;

use crate::error::Error;

/// FNV-1a, 32 bits (Fowler, Noll, Vo): `h = (h ⊕ byte)·16777619` from
/// `h = 2166136261`. The checksum a device prints for the bytes it streamed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fnv1a(u32);

impl Default for Fnv1a {
    fn default() -> Self {
        Self::new()
    }
}

impl Fnv1a {
    /// The hash of no bytes.
    pub const fn new() -> Self {
        Self(0x811c_9dc5)
    }

    /// Continues the hash with `bytes`.
    pub fn update(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u32).wrapping_mul(0x0100_0193);
        }
    }

    /// The hash of `bytes`.
    pub fn of(bytes: &[u8]) -> u32 {
        let mut h = Self::new();
        h.update(bytes);
        h.0
    }

    /// The hash so far.
    pub fn value(&self) -> u32 {
        self.0
    }
}

/// Why a pixel did not reach the stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StreamError<E> {
    /// The writer failed.
    Write(E),
    /// A pixel arrived out of stream order (or outside the display): where it was.
    OutOfOrder {
        /// Its column.
        x: i32,
        /// Its row.
        y: i32,
    },
}

/// An RGB565 display of `width × height` (`width ≤ W`) that streams its pixels as
/// little-endian `u16`s, one row per call of `write`.
#[derive(Debug)]
pub struct Rgb565Stream<F, const W: usize> {
    write: F,
    size: Size,
    /// The next pixel's position.
    col: u32,
    row: u32,
    hash: Fnv1a,
    buf: [[u8; 2]; W],
}

impl<F, E, const W: usize> Rgb565Stream<F, W>
where
    F: FnMut(&[u8]) -> Result<(), E>,
{
    /// A stream of `width × height` pixels into `write`; an error when `width`
    /// exceeds the row buffer `W` or either side is zero.
    pub fn new(width: u32, height: u32, write: F) -> Result<Self, Error> {
        if width == 0 || height == 0 {
            return Err(Error::NotPositive {
                what: "display size",
                value: 0.0,
            });
        }
        if width as usize > W {
            return Err(Error::Capacity {
                what: "display width (row buffer)",
                requested: width as usize,
                capacity: W,
            });
        }
        Ok(Self {
            write,
            size: Size::new(width, height),
            col: 0,
            row: 0,
            hash: Fnv1a::new(),
            buf: [[0; 2]; W],
        })
    }

    /// Pixels streamed so far (whole rows only).
    pub fn pixels(&self) -> u32 {
        self.row * self.size.width
    }

    /// `true` once every pixel has been streamed.
    pub fn is_complete(&self) -> bool {
        self.row == self.size.height
    }

    /// FNV-1a of the bytes streamed so far.
    pub fn hash(&self) -> u32 {
        self.hash.value()
    }

    /// The writer back.
    pub fn into_writer(self) -> F {
        self.write
    }

    /// Sends the buffered row and starts the next.
    fn flush_row(&mut self) -> Result<(), StreamError<E>> {
        let bytes = self.buf[..self.size.width as usize].as_flattened();
        (self.write)(bytes).map_err(StreamError::Write)?;
        self.hash.update(bytes);
        self.col = 0;
        self.row += 1;
        Ok(())
    }

    #[inline]
    fn push(&mut self, p: Point, c: Rgb565) -> Result<(), StreamError<E>> {
        if p.x != self.col as i32 || p.y != self.row as i32 || self.row >= self.size.height {
            return Err(StreamError::OutOfOrder { x: p.x, y: p.y });
        }
        self.buf[self.col as usize] = c.into_storage().to_le_bytes();
        self.col += 1;
        if self.col == self.size.width {
            self.flush_row()?;
        }
        Ok(())
    }
}

impl<F, const W: usize> OriginDimensions for Rgb565Stream<F, W> {
    fn size(&self) -> Size {
        self.size
    }
}

impl<F, E, const W: usize> DrawTarget for Rgb565Stream<F, W>
where
    F: FnMut(&[u8]) -> Result<(), E>,
{
    type Color = Rgb565;
    type Error = StreamError<E>;

    fn draw_iter<I>(&mut self, pixels: I) -> Result<(), Self::Error>
    where
        I: IntoIterator<Item = Pixel<Rgb565>>,
    {
        pixels
            .into_iter()
            .try_for_each(|Pixel(p, c)| self.push(p, c))
    }

    fn fill_contiguous<I>(&mut self, area: &Rectangle, colors: I) -> Result<(), Self::Error>
    where
        I: IntoIterator<Item = Rgb565>,
    {
        // The common case, a whole row at the stream's position (what `DisplaySink`
        // sends): no per-pixel position checks.
        let w = self.size.width;
        let whole_row = area.top_left == Point::new(0, self.row as i32)
            && self.col == 0
            && area.size == Size::new(w, 1)
            && self.row < self.size.height;
        if whole_row {
            let mut n = 0;
            for (slot, c) in self.buf[..w as usize].iter_mut().zip(colors) {
                *slot = c.into_storage().to_le_bytes();
                n += 1;
            }
            if n < w {
                self.col = n; // the iterator ran short: a partial row, as `push` leaves it
                return Ok(());
            }
            return self.flush_row();
        }
        let columns = area.columns();
        let points = area
            .rows()
            .flat_map(move |y| columns.clone().map(move |x| Point::new(x, y)));
        points.zip(colors).try_for_each(|(p, c)| self.push(p, c))
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;
    use embedded_graphics_core::pixelcolor::RgbColor;

    #[test]
    fn rows_in_order_become_little_endian_bytes() {
        let mut out = Vec::new();
        let mut s: Rgb565Stream<_, 4> = Rgb565Stream::new(3, 2, |b: &[u8]| {
            out.push(b.to_vec());
            Ok::<_, ()>(())
        })
        .unwrap();
        let row = [Rgb565::RED, Rgb565::GREEN, Rgb565::BLUE];
        for y in 0..2 {
            s.fill_contiguous(&Rectangle::new(Point::new(0, y), Size::new(3, 1)), row)
                .unwrap();
        }
        assert!(s.is_complete() && s.pixels() == 6);
        let hash = s.hash();
        // Red 0xf800, green 0x07e0, blue 0x001f, low byte first.
        let bytes = [0x00, 0xf8, 0xe0, 0x07, 0x1f, 0x00];
        assert_eq!(out, [bytes.to_vec(), bytes.to_vec()]);
        assert_eq!(hash, Fnv1a::of(&[bytes, bytes].concat()));
    }

    #[test]
    fn out_of_order_pixels_and_narrow_buffers_are_errors() {
        let mut s: Rgb565Stream<_, 4> =
            Rgb565Stream::new(4, 2, |_: &[u8]| Ok::<_, ()>(())).unwrap();
        let skip = s.draw_iter([Pixel(Point::new(1, 0), Rgb565::RED)]);
        assert_eq!(skip, Err(StreamError::OutOfOrder { x: 1, y: 0 }));
        let area = Rectangle::new(Point::new(0, 0), Size::new(4, 3));
        let past_the_end = s.fill_contiguous(&area, core::iter::repeat(Rgb565::RED));
        assert_eq!(past_the_end, Err(StreamError::OutOfOrder { x: 0, y: 2 }));
        assert!(Rgb565Stream::<_, 4>::new(5, 1, |_: &[u8]| Ok::<_, ()>(())).is_err());
        // The writer's error comes back as it is.
        let mut failing: Rgb565Stream<_, 1> =
            Rgb565Stream::new(1, 1, |_: &[u8]| Err("full")).unwrap();
        assert_eq!(
            failing.draw_iter([Pixel(Point::zero(), Rgb565::RED)]),
            Err(StreamError::Write("full"))
        );
        // FNV-1a's published test vector.
        assert_eq!(Fnv1a::of(b"a"), 0xe40c_292c);
    }
}

//! Rows to any `embedded-graphics` display.

use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::geometry::{Point, Size};
use embedded_graphics_core::pixelcolor::Rgb888;
use embedded_graphics_core::primitives::Rectangle;

use super::ToneMap;
use crate::math::Rgb;

/// Optional ordered dithering before a display's colour quantisation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Dither {
    /// None: each pixel is converted on its own (the default).
    #[default]
    Off,
    /// A 4×4 Bayer matrix on the 8-bit sRGB values, scaled to the step of a 5/6-bit
    /// (RGB565) channel: breaks up the banding of smooth gradients on small displays.
    Bayer565,
}

const BAYER4: [[i8; 4]; 4] = [[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]];

/// Draws rendered rows onto a `DrawTarget`: each row is tone mapped, converted to the
/// display's colour through `Rgb888`, and sent with one `fill_contiguous` on a
/// one-pixel-high rectangle. Needs no frame buffer. The display's own error is returned
/// unchanged.
///
/// ```
/// use caustic::raster::{DisplaySink, Dither, ToneMap};
/// use caustic::math::Rgb;
/// use embedded_graphics_core::{draw_target::DrawTarget, geometry::{OriginDimensions, Size}, Pixel, pixelcolor::Rgb565};
///
/// /// A display that only counts pixels.
/// struct Counter(usize);
/// impl OriginDimensions for Counter { fn size(&self) -> Size { Size::new(4, 2) } }
/// impl DrawTarget for Counter {
///     type Color = Rgb565;
///     type Error = core::convert::Infallible;
///     fn draw_iter<I: IntoIterator<Item = Pixel<Rgb565>>>(&mut self, px: I) -> Result<(), Self::Error> {
///         self.0 += px.into_iter().count();
///         Ok(())
///     }
/// }
/// let mut display = Counter(0);
/// let mut sink = DisplaySink::new(&mut display, ToneMap::default(), Dither::Off);
/// sink.draw_row(0, &[Rgb::ONE; 4]).unwrap();
/// sink.draw_row(1, &[Rgb::ZERO; 4]).unwrap();
/// assert_eq!(display.0, 8);
/// ```
#[derive(Debug)]
pub struct DisplaySink<'d, D> {
    display: &'d mut D,
    tone: ToneMap,
    dither: Dither,
}

impl<'d, D> DisplaySink<'d, D>
where
    D: DrawTarget,
    D::Color: From<Rgb888>,
{
    /// A sink drawing onto `display` with `tone` mapping.
    pub fn new(display: &'d mut D, tone: ToneMap, dither: Dither) -> Self {
        Self {
            display,
            tone,
            dither,
        }
    }

    /// Draws `row` as display row `y`, from column 0: radiance (`Rgb`), or any pixel
    /// that gives one (a [`PixelEstimate`](crate::render::PixelEstimate) draws its value).
    pub fn draw_row<P: Copy>(&mut self, y: u32, row: &[P]) -> Result<(), D::Error>
    where
        Rgb: From<P>,
    {
        let area = Rectangle::new(Point::new(0, y as i32), Size::new(row.len() as u32, 1));
        let (tone, dither) = (self.tone, self.dither);
        let colors = row.iter().enumerate().map(move |(x, &c)| {
            let [r, g, b] = tone.srgb8(Rgb::from(c));
            let [r, g, b] = match dither {
                Dither::Off => [r, g, b],
                Dither::Bayer565 => {
                    let t = BAYER4[y as usize % 4][x % 4] as i32; // 0..15
                                                                  // Offsets in (−½, ½) of a quantisation step: 8 levels for 5 bits, 4 for 6.
                    let off = |v: u8, step: i32| {
                        (v as i32 + ((2 * t - 15) * step) / 32).clamp(0, 255) as u8
                    };
                    [off(r, 8), off(g, 4), off(b, 8)]
                }
            };
            D::Color::from(Rgb888::new(r, g, b))
        });
        self.display.fill_contiguous(&area, colors)
    }

    /// Gives the display back.
    pub fn into_inner(self) -> &'d mut D {
        self.display
    }
}

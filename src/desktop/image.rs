//! Images on disk: PNG (through tiny-skia) for looking, PFM and OpenEXR (linear float,
//! through the `exr` crate) for measuring, and the error metrics used to compare two
//! renders.

use std::fs;
use std::io::{self, Write};
use std::path::Path;
use std::string::{String, ToString};
use std::vec::Vec;
use std::{format, vec};

use crate::math::Rgb;
use crate::raster::ToneMap;

/// The sample type of an OpenEXR file.
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ExrPrecision {
    /// 16-bit half floats (about 3 decimal digits, up to 65504).
    Half,
    /// 32-bit floats: the renderer's values exactly.
    #[default]
    Float,
}

/// An image file format, chosen by the file name's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// `.png`: 8-bit sRGB, tone mapped.
    Png,
    /// `.pfm`: linear float RGB.
    Pfm,
    /// `.exr`: linear OpenEXR RGB.
    Exr(ExrPrecision),
}

impl Format {
    /// The format of `path` by its extension (any case): `.png`, `.pfm` or `.exr`
    /// (with `exr` samples); an error naming the path otherwise, and for `-` (this
    /// program writes files, not standard output).
    pub fn of(path: &Path, exr: ExrPrecision) -> Result<Self, String> {
        if path.as_os_str() == "-" {
            return Err("-: writing to standard output is not supported; give a file name ending in .png, .pfm or .exr".into());
        }
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(Format::Png),
            Some("pfm") => Ok(Format::Pfm),
            Some("exr") => Ok(Format::Exr(exr)),
            _ => Err(format!(
                "{}: unknown image type (the name must end in .png, .pfm or .exr)",
                path.display()
            )),
        }
    }
}

/// Checks that `path` can be written, before any work: opens it for writing (creating
/// it, not truncating it), and removes it again if it did not exist.
pub fn check_writable(path: &Path) -> io::Result<()> {
    let existed = path.exists();
    fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(false)
        .open(path)?;
    if !existed {
        fs::remove_file(path)?;
    }
    Ok(())
}

/// A linear-radiance image, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` pixels, row-major from the top-left.
    pub pixels: Vec<Rgb>,
}

impl Image {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: std::vec![Rgb::ZERO; width as usize * height as usize],
        }
    }

    /// Row `y`.
    pub fn row(&self, y: u32) -> &[Rgb] {
        let w = self.width as usize;
        &self.pixels[y as usize * w..(y as usize + 1) * w]
    }

    /// The image averaged over `f × f` blocks (a box filter; edge blocks that do not fit
    /// are dropped). Comparing binned images measures error at a coarser resolution,
    /// where a caustic's fold — a curve on which irradiance diverges, so that one pixel
    /// centre's value depends on the kernel — integrates to a finite value.
    pub fn binned(&self, f: u32) -> Image {
        let f = f.max(1);
        let (w, h) = (self.width / f, self.height / f);
        let mut out = Image::new(w, h);
        let inv = 1.0 / (f * f) as f32;
        for y in 0..h {
            for x in 0..w {
                let mut sum = Rgb::ZERO;
                for dy in 0..f {
                    for dx in 0..f {
                        sum += self.pixels[((y * f + dy) * self.width + x * f + dx) as usize];
                    }
                }
                out.pixels[(y * w + x) as usize] = sum * inv;
            }
        }
        out
    }

    /// The pixels' bytes as 8-bit sRGB RGBA, tone mapped.
    pub fn to_rgba8(&self, tone: &ToneMap) -> Vec<u8> {
        let mut out = vec![0; self.pixels.len() * 4];
        self.write_rgba8(tone, &mut out);
        out
    }

    /// [`to_rgba8`](Self::to_rgba8) into `out`, four bytes a pixel (as many pixels as
    /// both hold): no list built a byte at a time, as a `flat_map` would (2.6 ms of a
    /// 320×240 PNG, perf).
    fn write_rgba8(&self, tone: &ToneMap, out: &mut [u8]) {
        for (px, &c) in out.chunks_exact_mut(4).zip(&self.pixels) {
            let [r, g, b] = tone.srgb8(c);
            px.copy_from_slice(&[r, g, b, 255]);
        }
    }

    /// Writes an 8-bit sRGB PNG.
    pub fn write_png(&self, path: &Path, tone: &ToneMap) -> io::Result<()> {
        let mut pixmap = tiny_skia::Pixmap::new(self.width, self.height)
            .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "empty image"))?;
        self.write_rgba8(tone, pixmap.data_mut());
        pixmap
            .save_png(path)
            .map_err(|e| io::Error::other(e.to_string()))
    }

    /// Writes the image as `format`: PNG through `tone`, PFM or OpenEXR linear.
    pub fn write(&self, path: &Path, format: Format, tone: &ToneMap) -> io::Result<()> {
        match format {
            Format::Png => self.write_png(path, tone),
            Format::Pfm => self.write_pfm(path),
            Format::Exr(p) => self.write_exr(path, p),
        }
    }

    /// Writes an OpenEXR file of R, G, B channels (linear radiance) with `precision`
    /// samples, single-threaded.
    pub fn write_exr(&self, path: &Path, precision: ExrPrecision) -> io::Result<()> {
        use exr::prelude::{f16, Image as Exr, SpecificChannels, Vec2, WritableImage};
        let size = (self.width as usize, self.height as usize);
        let at = |x: usize, y: usize| self.pixels[y * size.0 + x];
        let result = match precision {
            ExrPrecision::Float => Exr::from_channels(
                size,
                SpecificChannels::rgb(|Vec2(x, y)| {
                    let c = at(x, y);
                    (c.r, c.g, c.b)
                }),
            )
            .write()
            .non_parallel()
            .to_file(path),
            ExrPrecision::Half => Exr::from_channels(
                size,
                SpecificChannels::rgb(|Vec2(x, y)| {
                    let c = at(x, y);
                    (f16::from_f32(c.r), f16::from_f32(c.g), f16::from_f32(c.b))
                }),
            )
            .write()
            .non_parallel()
            .to_file(path),
        };
        result.map_err(exr_io)
    }

    /// Reads the first RGB(A) layer of an OpenEXR file as float (alpha is dropped).
    pub fn read_exr(path: &Path) -> io::Result<Image> {
        use exr::prelude::*;
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .rgba_channels(
                |size, _| (size.width(), vec![Rgb::ZERO; size.area()]),
                |(w, px): &mut (usize, Vec<Rgb>),
                 Vec2(x, y),
                 (r, g, b, _): (f32, f32, f32, f32)| {
                    px[y * *w + x] = Rgb::new(r, g, b);
                },
            )
            .first_valid_layer()
            .all_attributes()
            .non_parallel()
            .from_file(path)
            .map_err(exr_io)?;
        let size = image.layer_data.size;
        let (_, pixels) = image.layer_data.channel_data.pixels;
        Ok(Self {
            width: size.width() as u32,
            height: size.height() as u32,
            pixels,
        })
    }

    /// Reads a PFM or an OpenEXR file (told apart by their first bytes); every error
    /// names the file.
    pub fn read(path: &Path) -> io::Result<Image> {
        let named = |e: io::Error| io::Error::new(e.kind(), format!("{}: {e}", path.display()));
        let mut magic = [0u8; 4];
        let n =
            io::Read::read(&mut fs::File::open(path).map_err(named)?, &mut magic).map_err(named)?;
        if n == 4 && magic == [0x76, 0x2f, 0x31, 0x01] {
            Self::read_exr(path).map_err(named)
        } else if magic.starts_with(b"PF") {
            Self::read_pfm(path).map_err(|e| match e.kind() {
                io::ErrorKind::InvalidData => e,
                _ => named(e),
            })
        } else {
            Err(named(io::Error::new(
                io::ErrorKind::InvalidData,
                "neither a PFM nor an OpenEXR file",
            )))
        }
    }

    /// Writes a PFM: `PF`, the size, `-1.0` (little-endian), then float RGB rows from
    /// the bottom to the top.
    pub fn write_pfm(&self, path: &Path) -> io::Result<()> {
        let mut out = Vec::with_capacity(self.pixels.len() * 12 + 32);
        write!(out, "PF\n{} {}\n-1.0\n", self.width, self.height)?;
        for y in (0..self.height).rev() {
            for c in self.row(y) {
                for v in c.to_array() {
                    out.extend_from_slice(&v.to_le_bytes());
                }
            }
        }
        fs::write(path, out)
    }

    /// Reads a colour PFM of either byte order.
    pub fn read_pfm(path: &Path) -> io::Result<Image> {
        let bytes = fs::read(path)?;
        let bad = |m: &str| {
            io::Error::new(
                io::ErrorKind::InvalidData,
                std::format!("{}: {m}", path.display()),
            )
        };
        // Three whitespace-separated header tokens after "PF", then one whitespace byte.
        let mut tokens: Vec<String> = Vec::new();
        let mut i = 0;
        while tokens.len() < 4 {
            while i < bytes.len() && bytes[i].is_ascii_whitespace() {
                i += 1;
            }
            let start = i;
            while i < bytes.len() && !bytes[i].is_ascii_whitespace() {
                i += 1;
            }
            if start == i {
                return Err(bad("truncated header"));
            }
            tokens.push(String::from_utf8_lossy(&bytes[start..i]).into_owned());
        }
        i += 1;
        if tokens[0] != "PF" {
            return Err(bad("not a colour PFM (expected PF)"));
        }
        let parse = |s: &str| s.parse::<u32>().map_err(|_| bad("bad size"));
        let (w, h) = (parse(&tokens[1])?, parse(&tokens[2])?);
        let scale: f32 = tokens[3].parse().map_err(|_| bad("bad scale"))?;
        let n = w as usize * h as usize;
        let data = bytes
            .get(i..i + n * 12)
            .ok_or_else(|| bad("truncated data"))?;
        let mut img = Image::new(w, h);
        for (k, chunk) in data.chunks_exact(4).enumerate() {
            let b: [u8; 4] = chunk.try_into().map_err(|_| bad("truncated data"))?;
            let v = if scale < 0.0 {
                f32::from_le_bytes(b)
            } else {
                f32::from_be_bytes(b)
            };
            let (p, ch) = (k / 3, k % 3);
            let (x, y_from_bottom) = (p % w as usize, p / w as usize);
            let px = &mut img.pixels[(h as usize - 1 - y_from_bottom) * w as usize + x];
            match ch {
                0 => px.r = v,
                1 => px.g = v,
                _ => px.b = v,
            }
        }
        Ok(img)
    }
}

/// An `exr` error as an I/O error.
fn exr_io(e: exr::error::Error) -> io::Error {
    match e {
        exr::error::Error::Io(e) => e,
        e => io::Error::new(io::ErrorKind::InvalidData, e.to_string()),
    }
}

/// How far an image is from a reference. In JSON (serde), a ratio that is not finite
/// (a black reference) is `null`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ImageError {
    /// `√mean((a − b)²) / mean(b)` over all channels of the pixels compared.
    pub rel_rmse: f64,
    /// `mean|a − b| / mean(b)`.
    pub rel_mae: f64,
    /// Pixels compared.
    pub pixels: usize,
}

/// Compares `a` against the reference `b` over the pixels where `mask` (if given) is
/// true. `None` when the sizes differ or no pixel is selected.
pub fn compare(a: &Image, b: &Image, mask: Option<&[bool]>) -> Option<ImageError> {
    if (a.width, a.height) != (b.width, b.height) {
        return None;
    }
    let (mut se, mut ae, mut sum, mut n) = (0.0f64, 0.0f64, 0.0f64, 0usize);
    for (i, (pa, pb)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        if mask.is_some_and(|m| !m[i]) {
            continue;
        }
        for (x, y) in pa.to_array().into_iter().zip(pb.to_array()) {
            let d = x as f64 - y as f64;
            se += d * d;
            ae += d.abs();
            sum += y as f64;
        }
        n += 1;
    }
    if n == 0 {
        return None;
    }
    let count = (3 * n) as f64;
    let mean = sum / count;
    Some(ImageError {
        rel_rmse: (se / count).sqrt() / mean,
        rel_mae: ae / count / mean,
        pixels: n,
    })
}

/// The pixels where `img`'s luminance exceeds `fraction` of its 99.9th percentile: the
/// caustic-region mask when `img` is the caustic part of a reference.
pub fn mask_above(img: &Image, fraction: f32) -> Vec<bool> {
    let mut lum: Vec<f32> = img.pixels.iter().map(|p| p.luminance()).collect();
    let mut sorted = lum.clone();
    sorted.sort_by(f32::total_cmp);
    let p999 = sorted
        .get((sorted.len() as f64 * 0.999) as usize)
        .copied()
        .unwrap_or(0.0);
    let t = fraction * p999;
    lum.iter_mut().map(|l| *l > t && *l > 0.0).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pfm_round_trips_with_rows_bottom_to_top() {
        let mut img = Image::new(3, 2);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            *p = Rgb::new(i as f32, -0.5 * i as f32, 1e-7 * i as f32);
        }
        let dir = std::env::temp_dir().join(std::format!("caustic-pfm-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.pfm");
        img.write_pfm(&path).unwrap();
        let bytes = fs::read(&path).unwrap();
        assert!(bytes.starts_with(b"PF\n3 2\n-1.0\n"));
        // The first pixel in the file is the bottom-left one: index 3 in our top-down order.
        assert_eq!(f32::from_le_bytes(bytes[12..16].try_into().unwrap()), 3.0);
        assert_eq!(Image::read_pfm(&path).unwrap(), img);
        fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn metrics_match_hand_computation() {
        let mut a = Image::new(2, 1);
        let mut b = Image::new(2, 1);
        b.pixels = std::vec![Rgb::splat(1.0), Rgb::splat(3.0)];
        a.pixels = std::vec![Rgb::splat(2.0), Rgb::splat(3.0)];
        let e = compare(&a, &b, None).unwrap();
        // mean b = 2, errors (1,1,1,0,0,0): rmse = √(1/2), mae = 1/2.
        assert!((e.rel_rmse - 0.5f64.sqrt() / 2.0).abs() < 1e-12);
        assert!((e.rel_mae - 0.25).abs() < 1e-12);
        let e = compare(&a, &b, Some(&[false, true])).unwrap();
        assert_eq!((e.rel_rmse, e.pixels), (0.0, 1));
        assert!(compare(&a, &Image::new(1, 1), None).is_none());
    }
}

//! The Cortex-M4F firmware's image (`examples/cortex-m4`), rendered on the host through
//! the same path, and compared with the device's bytes bit for bit.
//!
//! The scene, settings, seed, gather size `K`, path stack `DEPTH`, tone map and dither
//! are the firmware's; the display is an in-memory RGB565 `DrawTarget` instead of a file
//! written through semihosting. `tools/device/run.sh` runs the firmware under QEMU and
//! then this test with
//! - `CAUSTIC_DEVICE_RGB565`: the device's file (little-endian RGB565, row-major);
//! - `CAUSTIC_DEVICE_FNV1A`: the hash from the firmware's `PASS` line.
//!
//! Without them the comparison is skipped (and said so) and only the host-side
//! properties are checked. `cargo test --test device -- --nocapture` also prints the
//! `size_of` values of the device budget.

use std::mem::size_of;

use caustic::demo;
use caustic::math::Rgb;
use caustic::photon::{KdStore, Photon, PhotonMap};
use caustic::raster::{DisplaySink, Dither, ToneMap};
use caustic::render::Renderer;
use caustic::scene::Scene;
use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::geometry::{OriginDimensions, Size};
use embedded_graphics_core::pixelcolor::{IntoStorage, Rgb565};
use embedded_graphics_core::Pixel;

// Mirrors of the firmware's constants (examples/cortex-m4/src/main.rs).
const WIDTH: u32 = 160;
const HEIGHT: u32 = 120;
const SEED: u64 = 0;
const K: usize = 32;
const DEPTH: usize = 8;
const PHOTONS: usize = demo::DEVICE_PHOTONS as usize;

/// An RGB565 display in memory, laid out as the device's file; it counts the writes
/// to each pixel and refuses pixels outside it.
struct Memory565 {
    size: Size,
    bytes: Vec<u8>,
    writes: Vec<u32>,
}

impl Memory565 {
    fn new(width: u32, height: u32) -> Self {
        let n = (width * height) as usize;
        Self {
            size: Size::new(width, height),
            bytes: vec![0; 2 * n],
            writes: vec![0; n],
        }
    }
}

impl OriginDimensions for Memory565 {
    fn size(&self) -> Size {
        self.size
    }
}

impl DrawTarget for Memory565 {
    type Color = Rgb565;
    type Error = core::convert::Infallible;

    fn draw_iter<I: IntoIterator<Item = Pixel<Rgb565>>>(
        &mut self,
        pixels: I,
    ) -> Result<(), Self::Error> {
        let (w, h) = (self.size.width as i32, self.size.height as i32);
        for Pixel(p, c) in pixels {
            assert!(
                (0..w).contains(&p.x) && (0..h).contains(&p.y),
                "pixel {p:?} outside the {w}x{h} display"
            );
            let i = (p.y * w + p.x) as usize;
            self.bytes[2 * i..2 * i + 2].copy_from_slice(&c.into_storage().to_le_bytes());
            self.writes[i] += 1;
        }
        Ok(())
    }
}

/// FNV-1a, 32 bits: the firmware's checksum.
fn fnv1a(bytes: &[u8]) -> u32 {
    bytes.iter().fold(0x811c_9dc5u32, |h, &b| {
        (h ^ b as u32).wrapping_mul(0x0100_0193)
    })
}

/// The firmware's render, on the host: RGB565 bytes, rows handed to the sink, and
/// photons stored.
fn render_like_the_device() -> (Memory565, Vec<u32>, usize) {
    let scene = demo::fig6::<2, 1>(WIDTH, HEIGHT).unwrap();
    let settings = demo::device_settings().unwrap();
    let mut map: Box<PhotonMap<PHOTONS>> = Box::new(PhotonMap::new());
    let forward = map.build(&scene, &settings, SEED).unwrap();
    let store = map.store::<K>(&settings).unwrap();
    let renderer: Renderer<_, 2, 1, DEPTH> =
        Renderer::new(&scene, &store, settings.max_depth()).unwrap();
    let mut display = Memory565::new(WIDTH, HEIGHT);
    let mut rows = Vec::new();
    let mut row = [Rgb::ZERO; WIDTH as usize];
    {
        let mut sink = DisplaySink::new(&mut display, ToneMap::default(), Dither::Off);
        renderer
            .rows(&mut row, |y, pixels| {
                rows.push(y);
                sink.draw_row(y, pixels)
            })
            .unwrap();
    }
    (display, rows, forward.stored)
}

#[test]
fn device_image_is_the_host_image_bit_for_bit() {
    let (display, rows, stored) = render_like_the_device();
    assert_eq!(
        rows,
        (0..HEIGHT).collect::<Vec<_>>(),
        "rows top to bottom, once each"
    );
    assert!(
        display.writes.iter().all(|&n| n == 1),
        "every pixel written exactly once"
    );
    assert!(stored > 0, "the cube makes caustic photons");
    let hash = fnv1a(&display.bytes);
    println!("host: {WIDTH}x{HEIGHT} RGB565, {stored} photons stored, fnv1a=0x{hash:08x}");

    if let Ok(expected) = std::env::var("CAUSTIC_DEVICE_FNV1A") {
        let expected = u32::from_str_radix(expected.trim().trim_start_matches("0x"), 16)
            .expect("CAUSTIC_DEVICE_FNV1A is a hex u32");
        assert_eq!(
            hash, expected,
            "the host's hash against the firmware's PASS line"
        );
    }
    match std::env::var_os("CAUSTIC_DEVICE_RGB565") {
        None => println!("CAUSTIC_DEVICE_RGB565 not set: skipped the comparison with the device"),
        Some(path) => {
            let device = std::fs::read(&path)
                .unwrap_or_else(|e| panic!("reading {}: {e}", path.to_string_lossy()));
            assert_eq!(device.len(), display.bytes.len(), "device file length");
            let differing: Vec<usize> = (0..display.writes.len())
                .filter(|&i| device[2 * i..2 * i + 2] != display.bytes[2 * i..2 * i + 2])
                .collect();
            if let Some(&i) = differing.first() {
                let px = |b: &[u8]| u16::from_le_bytes([b[2 * i], b[2 * i + 1]]);
                panic!(
                    "{} of {} pixels differ; first at ({}, {}): device {:#06x}, host {:#06x}",
                    differing.len(),
                    display.writes.len(),
                    i % WIDTH as usize,
                    i / WIDTH as usize,
                    px(&device),
                    px(&display.bytes),
                );
            }
            println!(
                "device file {} is bit-identical to the host render ({} bytes)",
                path.to_string_lossy(),
                device.len()
            );
        }
    }
}

#[test]
fn device_budget_sizes() {
    let sizes = [
        ("Photon", size_of::<Photon>()),
        ("PhotonMap<2048>", size_of::<PhotonMap<PHOTONS>>()),
        ("Scene<2,1>", size_of::<Scene<2, 1>>()),
        ("KdStore<32>", size_of::<KdStore<'static, K>>()),
        ("Rgb row [Rgb; 160]", size_of::<[Rgb; WIDTH as usize]>()),
    ];
    for (what, bytes) in sizes {
        println!("size_of {what}: {bytes} bytes");
    }
    assert_eq!(size_of::<Photon>(), 20);
    // The map is its photons and a few words: it fits the 64 KiB static budget.
    assert!(size_of::<PhotonMap<PHOTONS>>() <= 20 * PHOTONS + 16);
}

//! caustic on a Cortex-M4F: the paper's Fig. 6 at 160 × 120, under QEMU (`mps2-an386`).
//!
//! The forward pass fills a photon map that lives in a `static` (not on the stack); the
//! backward pass renders one row at a time into a 160-pixel buffer, and each row goes
//! through `caustic::raster::DisplaySink` onto [`HostFile`], an embedded-graphics
//! `DrawTarget<Color = Rgb565>` that writes the pixels as little-endian `u16`s into a
//! file on the host through semihosting. No frame buffer exists on the device.
//!
//! Output (semihosting stdout): the photon and ray counts, the stack's high-water mark,
//! and `PASS fnv1a=0x…`, the FNV-1a hash of the RGB565 bytes in file order. QEMU exits
//! with 0 on success and 1 from a panic or a HardFault.
//!
//! The output path is the second word of the semihosting command line
//! (`-semihosting-config enable=on,target=native,arg=caustic,arg=PATH`); without one the
//! file is `fig6.rgb565` in QEMU's working directory.
//!
//! `caustic_mark_*` are empty functions the run script's QEMU plugin recognises by
//! address to count the instructions of each phase.

#![no_std]
#![no_main]

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicBool, Ordering};

use caustic::demo;
use caustic::math::Rgb;
use caustic::photon::PhotonMap;
use caustic::raster::{DisplaySink, Dither, ToneMap};
use caustic::render::{Renderer, RowsError};
use cortex_m_rt::{entry, exception, ExceptionFrame};
use cortex_m_semihosting::{debug, hprintln, nr, syscall, syscall1};
use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::geometry::{OriginDimensions, Size};
use embedded_graphics_core::pixelcolor::{IntoStorage, Rgb565};
use embedded_graphics_core::primitives::Rectangle;
use embedded_graphics_core::Pixel;

/// Image size (the host test `tests/device.rs` uses the same).
const WIDTH: u32 = 160;
/// Image size.
const HEIGHT: u32 = 120;
/// Seed of the forward pass (mirrored in `tests/device.rs`).
const SEED: u64 = 0;
/// Photons per estimate the gather can hold.
const K: usize = 32;
/// Path stack entries of the backward pass.
const DEPTH: usize = 8;
/// Photon map capacity.
const PHOTONS: usize = demo::DEVICE_PHOTONS as usize;
/// Output file when the command line names none.
const DEFAULT_PATH: &[u8] = b"fig6.rgb565";

type Map = PhotonMap<PHOTONS>;

/// The photon map's storage: a `static`, so its 40 KiB are in `.bss`, counted by the
/// linker, and never on the stack.
struct MapCell(UnsafeCell<Map>);

// SAFETY: the map is only reached through `take_map`, which hands out its one `&mut`
// once (guarded by `MAP_TAKEN`); nothing else touches `MAP`.
#[allow(unsafe_code)]
unsafe impl Sync for MapCell {}

static MAP: MapCell = MapCell(UnsafeCell::new(Map::new()));
static MAP_TAKEN: AtomicBool = AtomicBool::new(false);

/// The photon map, exclusively; `None` after the first call.
fn take_map() -> Option<&'static mut Map> {
    if MAP_TAKEN.swap(true, Ordering::AcqRel) {
        return None;
    }
    // SAFETY: the flag above makes this the only reference ever created to `MAP`'s
    // contents, and `MAP` is private to this module.
    #[allow(unsafe_code)]
    Some(unsafe { &mut *MAP.0.get() })
}

/// FNV-1a, 32 bits.
#[derive(Clone, Copy)]
struct Fnv1a(u32);

impl Fnv1a {
    const fn new() -> Self {
        Self(0x811c_9dc5)
    }
    fn update(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u32).wrapping_mul(0x0100_0193);
        }
    }
}

/// A semihosting call failed: which one.
#[derive(Clone, Copy, Debug)]
struct HostIoError(&'static str);

/// A display that is a file on the host: pixel `(x, y)` is the little-endian RGB565
/// `u16` at byte `2·(y·width + x)`. Each run of pixels within a row is one
/// `SYS_SEEK` + `SYS_WRITE`, so any drawing order works; `DisplaySink` draws whole rows
/// top to bottom, which makes the file a plain row-major image and `hash` its FNV-1a.
struct HostFile {
    fd: usize,
    size: Size,
    /// Pixels written.
    written: u32,
    /// Where the last run ended (bytes), to skip redundant seeks.
    pos: usize,
    /// FNV-1a of the bytes in the order they were written.
    hash: Fnv1a,
    /// One row of bytes at most: the only image memory on the device.
    buf: [u8; 2 * WIDTH as usize],
}

impl HostFile {
    /// Creates (truncates) `path` on the host; `path` ends with a NUL byte.
    fn create(path: &[u8], size: Size) -> Result<Self, HostIoError> {
        debug_assert_eq!(path.last(), Some(&0));
        if size.width > WIDTH {
            return Err(HostIoError("display wider than the row buffer"));
        }
        // SAFETY: SYS_OPEN reads `len` bytes of the NUL-terminated name at `ptr`,
        // which lives across the call.
        #[allow(unsafe_code)]
        let fd = unsafe {
            syscall!(
                OPEN,
                path.as_ptr(),
                nr::open::W_TRUNC_BINARY,
                path.len() - 1
            )
        };
        if fd as isize == -1 {
            return Err(HostIoError("SYS_OPEN"));
        }
        Ok(Self {
            fd,
            size,
            written: 0,
            pos: 0,
            hash: Fnv1a::new(),
            buf: [0; 2 * WIDTH as usize],
        })
    }

    /// Writes `bytes` at byte offset `at`.
    fn write_at(&mut self, at: usize, n: usize) -> Result<(), HostIoError> {
        if at != self.pos {
            // SAFETY: SYS_SEEK takes a handle and an absolute offset, no memory.
            #[allow(unsafe_code)]
            let r = unsafe { syscall!(SEEK, self.fd, at) };
            if r != 0 {
                return Err(HostIoError("SYS_SEEK"));
            }
        }
        let bytes = &self.buf[..n];
        // SAFETY: SYS_WRITE reads `len` bytes at `ptr`, a live borrow of `self.buf`.
        #[allow(unsafe_code)]
        let left = unsafe { syscall!(WRITE, self.fd, bytes.as_ptr(), bytes.len()) };
        if left != 0 {
            return Err(HostIoError("SYS_WRITE"));
        }
        self.hash.update(bytes);
        self.pos = at + n;
        Ok(())
    }

    fn close(self) -> Result<(u32, u32), HostIoError> {
        // SAFETY: SYS_CLOSE takes a handle only.
        #[allow(unsafe_code)]
        let r = unsafe { syscall!(CLOSE, self.fd) };
        if r != 0 {
            return Err(HostIoError("SYS_CLOSE"));
        }
        Ok((self.written, self.hash.0))
    }
}

impl OriginDimensions for HostFile {
    fn size(&self) -> Size {
        self.size
    }
}

impl DrawTarget for HostFile {
    type Color = Rgb565;
    type Error = HostIoError;

    fn draw_iter<I>(&mut self, pixels: I) -> Result<(), Self::Error>
    where
        I: IntoIterator<Item = Pixel<Self::Color>>,
    {
        // Slow path (one write per pixel); DisplaySink never takes it.
        let (w, h) = (self.size.width as i32, self.size.height as i32);
        for Pixel(p, c) in pixels {
            if (0..w).contains(&p.x) && (0..h).contains(&p.y) {
                self.buf[..2].copy_from_slice(&c.into_storage().to_le_bytes());
                self.write_at(2 * (p.y * w + p.x) as usize, 2)?;
                self.written += 1;
            }
        }
        Ok(())
    }

    fn fill_contiguous<I>(&mut self, area: &Rectangle, colors: I) -> Result<(), Self::Error>
    where
        I: IntoIterator<Item = Self::Color>,
    {
        let (w, h) = (self.size.width as i32, self.size.height as i32);
        let mut colors = colors.into_iter();
        let x0 = area.top_left.x;
        for y in area.top_left.y..area.top_left.y + area.size.height as i32 {
            // The visible part of this row of the area: columns [lo, hi).
            let (lo, hi) = (x0.max(0), (x0 + area.size.width as i32).min(w));
            let visible = (0..h).contains(&y) && lo < hi;
            let mut n = 0;
            for x in x0..x0 + area.size.width as i32 {
                let Some(c) = colors.next() else { break };
                if visible && (lo..hi).contains(&x) {
                    self.buf[n..n + 2].copy_from_slice(&c.into_storage().to_le_bytes());
                    n += 2;
                }
            }
            if n > 0 {
                self.write_at(2 * (y * w + lo) as usize, n)?;
                self.written += (n / 2) as u32;
            }
        }
        Ok(())
    }
}

/// The output path from the semihosting command line (`PROGRAM PATH`), NUL-terminated
/// in `buf`; the default when there is no second word.
fn output_path(buf: &mut [u8; 256]) -> &[u8] {
    let mut block = [buf.as_mut_ptr() as usize, buf.len()];
    // SAFETY: SYS_GET_CMDLINE writes at most `block[1]` bytes (NUL included) into `buf`
    // and the length into `block[1]`; both live across the call.
    #[allow(unsafe_code)]
    let r = unsafe { syscall1!(GET_CMDLINE, block.as_mut_ptr()) };
    let line: &[u8] = if r == 0 {
        &buf[..block[1].min(buf.len())]
    } else {
        &[]
    };
    let mut words = line
        .split(|&b| b == b' ' || b == 0)
        .filter(|w| !w.is_empty());
    let path = words.nth(1).unwrap_or(DEFAULT_PATH);
    let mut out = [0u8; 256];
    let n = path.len().min(255);
    out[..n].copy_from_slice(&path[..n]);
    *buf = out;
    &buf[..n + 1]
}

/// Bytes of stack ever used: the painted words `_stack_end..` that are still painted
/// lie below the deepest point the stack reached.
fn stack_high_water() -> (usize, usize) {
    extern "C" {
        static _stack_end: u32;
        static _stack_start: u32;
    }
    let start = core::ptr::addr_of!(_stack_end) as usize;
    let top = core::ptr::addr_of!(_stack_start) as usize;
    let mut p = start;
    while p < top {
        // SAFETY: `_stack_end.._stack_start` is RAM reserved for the stack (cortex-m-rt's
        // linker script); reading a word of it, aligned, is always defined.
        #[allow(unsafe_code)]
        let v = unsafe { core::ptr::read_volatile(p as *const u32) };
        if v != cortex_m_rt::STACK_PAINT_VALUE {
            break;
        }
        p += 4;
    }
    (top - p, top - start)
}

macro_rules! marker {
    ($name:ident, $n:expr) => {
        /// Phase marker for the instruction-count plugin: does nothing, is never inlined.
        #[inline(never)]
        #[no_mangle]
        extern "C" fn $name() {
            core::hint::black_box($n);
        }
    };
}
marker!(caustic_mark_photons_begin, 1u32);
marker!(caustic_mark_photons_end, 2u32);
marker!(caustic_mark_render_begin, 3u32);
marker!(caustic_mark_render_end, 4u32);

/// Stops with a failure. The core's `Error` is not formatted: its `Debug`/`Display`
/// print `f32` fields, and float formatting alone is about 16 KiB of flash. The host
/// test (`tests/device.rs`) runs the same code and shows the error's text.
fn fail(what: &str) -> ! {
    hprintln!("FAIL {}", what);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::bkpt();
    }
}

#[entry]
fn main() -> ! {
    hprintln!(
        "caustic on Cortex-M4F: Fig. 6, {}x{}, seed {}",
        WIDTH,
        HEIGHT,
        SEED
    );
    let mut path_buf = [0u8; 256];
    let path = output_path(&mut path_buf);
    hprintln!(
        "output: {}",
        core::str::from_utf8(&path[..path.len() - 1]).unwrap_or("?")
    );

    let scene = demo::fig6::<2, 1>(WIDTH, HEIGHT).unwrap_or_else(|_| fail("scene"));
    let settings = demo::device_settings().unwrap_or_else(|_| fail("settings"));
    let map = take_map().unwrap_or_else(|| fail("photon map taken twice"));

    caustic_mark_photons_begin();
    let forward = map
        .build(&scene, &settings, SEED)
        .unwrap_or_else(|_| fail("forward pass"));
    caustic_mark_photons_end();
    hprintln!(
        "photons: {} emitted, {} stored (capacity {})",
        forward.emitted,
        forward.stored,
        PHOTONS
    );

    let store = map.store::<K>(&settings).unwrap_or_else(|_| fail("store"));
    let renderer: Renderer<_, 2, 1, DEPTH> =
        Renderer::new(&scene, &store, settings.max_depth()).unwrap_or_else(|_| fail("renderer"));
    let mut display =
        HostFile::create(path, Size::new(WIDTH, HEIGHT)).unwrap_or_else(|e| fail(e.0));
    let mut row = [Rgb::ZERO; WIDTH as usize];

    caustic_mark_render_begin();
    let rays = {
        let mut sink = DisplaySink::new(&mut display, ToneMap::default(), Dither::Off);
        renderer.rows(&mut row, |y, pixels| sink.draw_row(y, pixels))
    };
    caustic_mark_render_end();
    let rays = rays.unwrap_or_else(|e| match e {
        RowsError::Sink(e) => fail(e.0),
        RowsError::Render(_) => fail("row buffer"),
    });

    let (pixels, hash) = display.close().unwrap_or_else(|e| fail(e.0));
    hprintln!("rays: {} eye, {} shadow", rays.eye, rays.shadow);
    let (stack, stack_region) = stack_high_water();
    hprintln!(
        "stack high-water: {} bytes (of {} reserved)",
        stack,
        stack_region
    );
    if pixels != WIDTH * HEIGHT {
        fail("not every pixel was written");
    }
    hprintln!(
        "PASS fnv1a=0x{:08x} pixels={} stack={}",
        hash,
        pixels,
        stack
    );
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::bkpt();
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("PANIC {}", info);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::bkpt();
    }
}

#[exception]
#[allow(unsafe_code)]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    hprintln!("HARDFAULT {:?}", frame);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::bkpt();
    }
}

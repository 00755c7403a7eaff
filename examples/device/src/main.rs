//! caustic on a microcontroller: the paper's Fig. 6 at 160 × 120 under QEMU, one
//! source for four instruction sets (Cortex-M4F `mps2-an386`, Cortex-M3 `mps2-an385`,
//! Cortex-M33 `mps2-an505`, RV32IMAC `virt`); only the reset code and the semihosting
//! trap differ (`arm.rs`, `riscv.rs`, `semihosting.rs`).
//!
//! Every capacity is `caustic::budget::FIG6` (with `--features glass`, the physical
//! scene `caustic::demo::glass` and `caustic::budget::GLASS`): the forward pass fills a
//! `DeviceMap<{ BUDGET.stored }, { BUDGET.splats }>` that lives in a `static` (in `.bss`, not on the
//! stack); the backward pass renders one row at a time into a 160-pixel buffer (also
//! static: the stack holds only the path stack, the gather and the call frames), and
//! each row goes through `caustic::raster::DisplaySink` onto a
//! `caustic::raster::Rgb565Stream` whose bytes (little-endian RGB565, row-major) are
//! appended to a file on the host by semihosting. No frame buffer exists on the device.
//!
//! Output (semihosting stdout): the photon and ray counts, with `--features
//! error-estimate` the render's estimate of its own error (`error_estimate rel_rmse=…
//! rel_rmse_caustic=…`: the rows are `caustic::render::PixelEstimate`s, tallied as the
//! desktop tallies them, printed by `caustic::budget::ErrorFigure` with integer
//! arithmetic), the stack's high-water mark, and `PASS fnv1a=0x…`, the FNV-1a of the
//! RGB565 bytes. QEMU exits with 0 on success
//! and 1 on any failure, panic or fault. The output path is the second word of the
//! semihosting command line (`arg=caustic,arg=PATH`), else `fig6.rgb565` (`glass.rgb565`).
//!
//! `caustic_mark_*` are empty functions the run script's QEMU plugin recognises by
//! address to count the instructions of each phase.

#![no_std]
#![no_main]

mod semihosting;

#[cfg(target_arch = "arm")]
mod arm;
#[cfg(target_arch = "arm")]
use arm as platform;
#[cfg(target_arch = "riscv32")]
mod riscv;
#[cfg(target_arch = "riscv32")]
use riscv as platform;

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicBool, Ordering};

use caustic::budget::DeviceMap;
use caustic::raster::{DisplaySink, Dither, Rgb565Stream, ToneMap};
use caustic::render::Renderer;
use estimate::{Pixel, Tally};
use semihosting::Part::{Dec, Hex, Text};
use semihosting::{say, HostFile};

/// The scene: Fig. 6 by default; `--features glass` builds the physical scene.
#[cfg(not(feature = "glass"))]
mod scene {
    pub use caustic::budget::{FIG6 as BUDGET, FIG6_LIGHTS as LIGHTS, FIG6_OBJECTS as OBJECTS};
    pub use caustic::demo::fig6 as build;
    pub const NAME: &str = "Fig. 6";
    pub const FILE: &[u8] = b"fig6.rgb565";
}
/// The scene: the glass sphere, the mirror and the floor (`demo::glass`).
#[cfg(feature = "glass")]
mod scene {
    pub use caustic::budget::{GLASS as BUDGET, GLASS_LIGHTS as LIGHTS, GLASS_OBJECTS as OBJECTS};
    pub use caustic::demo::glass as build;
    pub const NAME: &str = "glass sphere and mirror";
    pub const FILE: &[u8] = b"glass.rgb565";
}
use scene::{BUDGET, LIGHTS, OBJECTS};

/// The target this firmware was built for (set by build.rs).
const TARGET: &str = env!("CAUSTIC_FIRMWARE_TARGET");
/// Row length, pixels.
const WIDTH: usize = BUDGET.width as usize;

/// The render's estimate of its own error (`--features error-estimate`): rows of
/// `PixelEstimate`s (radiance, caustic part, error terms) tallied row by row. It costs
/// Fig. 6 on the Cortex-M4F about 5 KiB of flash (soft-float `f64` sums and ratio,
/// digits) and 2 M instructions, more than its budget leaves: the glass firmwares carry
/// it (tools/device/run.sh).
#[cfg(feature = "error-estimate")]
mod estimate {
    use crate::hprintln;
    use caustic::budget::ErrorFigure;
    use caustic::math::Rgb;
    use caustic::render::{ErrorTally, PixelEstimate};

    /// A row's pixel: radiance with its caustic part and error terms.
    pub type Pixel = PixelEstimate;
    /// The pixel a row starts as.
    pub const BLANK: Pixel = PixelEstimate {
        radiance: Rgb::ZERO,
        caustic: Rgb::ZERO,
        split: Rgb::ZERO,
        sampling2: Rgb::ZERO,
    };

    /// The tally of every finished row.
    #[derive(Default)]
    pub struct Tally(ErrorTally);

    impl Tally {
        /// Adds a finished row (splats included).
        pub fn add(&mut self, row: &[Pixel]) {
            self.0.add_row(row);
        }

        /// Prints the estimate, as the host test prints it.
        pub fn report(&self) {
            hprintln!("error_estimate {}", ErrorFigure(self.0));
        }
    }
}
/// Without the error estimate: rows of radiance, nothing tallied.
#[cfg(not(feature = "error-estimate"))]
mod estimate {
    use caustic::math::Rgb;

    /// A row's pixel: linear radiance.
    pub type Pixel = Rgb;
    /// The pixel a row starts as.
    pub const BLANK: Pixel = Rgb::ZERO;

    /// Nothing to tally.
    #[derive(Default)]
    pub struct Tally;

    impl Tally {
        /// Nothing to add.
        pub fn add(&mut self, _: &[Pixel]) {}
        /// Nothing to print.
        pub fn report(&self) {}
    }
}

/// What the render keeps outside the stack: the photon map (in `.bss`, counted by
/// the linker), the row of pixels, and the output path.
struct Statics {
    map: DeviceMap<{ BUDGET.stored }, { BUDGET.splats }>,
    row: [Pixel; WIDTH],
    path: [u8; 256],
}

struct StaticsCell(UnsafeCell<Statics>);

// SAFETY: the contents are only reached through `take_statics`, which hands out their
// one `&mut` once (guarded by `TAKEN`); nothing else touches `STATICS`.
#[allow(unsafe_code)]
unsafe impl Sync for StaticsCell {}

static STATICS: StaticsCell = StaticsCell(UnsafeCell::new(Statics {
    map: DeviceMap::new(),
    row: [estimate::BLANK; WIDTH],
    path: [0; 256],
}));
static TAKEN: AtomicBool = AtomicBool::new(false);

/// The statics, exclusively; `None` after the first call.
fn take_statics() -> Option<&'static mut Statics> {
    // A load and a store, not `swap`: the firmware is single-threaded, and RV32
    // without the A extension has no atomic swap.
    if TAKEN.load(Ordering::Acquire) {
        return None;
    }
    TAKEN.store(true, Ordering::Release);
    // SAFETY: the flag above makes this the only reference ever created to
    // `STATICS`' contents (one thread, no interrupts), and it is private to this module.
    #[allow(unsafe_code)]
    Some(unsafe { &mut *STATICS.0.get() })
}

/// Bytes of stack ever used, and reserved: the painted words from `_stack_end` up
/// that are still painted lie below the deepest point the stack reached.
fn stack_high_water() -> (usize, usize) {
    extern "C" {
        static _stack_end: u32;
        static _stack_start: u32;
    }
    let start = core::ptr::addr_of!(_stack_end) as usize;
    let top = core::ptr::addr_of!(_stack_start) as usize;
    let mut p = start;
    while p < top {
        // SAFETY: `_stack_end.._stack_start` is RAM reserved for the stack (linker
        // script); reading an aligned word of it is always defined.
        #[allow(unsafe_code)]
        let v = unsafe { core::ptr::read_volatile(p as *const u32) };
        if v != platform::STACK_PAINT {
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

/// A count for printing, as `u32`: formatting a `u64` links a 64-bit division
/// (1.1 KiB of flash). A device render's counts stay far below 2³² (the ray budget
/// bounds a pixel's rays); a larger one would print as `u32::MAX`, never wrapped.
fn count(n: u64) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}
// The seed is printed as a `u32` (see `count`).
const _: () = assert!(BUDGET.seed >> 32 == 0);

/// Stops with a failure. The core's `Error` is not formatted: its `Display` prints
/// `f32` fields, and float formatting alone is about 16 KiB of flash. The host test
/// (`tests/device.rs`) runs the same code and shows the error's text.
fn fail(what: &str) -> ! {
    say(&[Text("FAIL "), Text(what), Text("\n")]);
    semihosting::exit(false)
}

/// The whole run; called by the platform's reset code.
pub fn run() -> ! {
    say(&[
        Text("caustic on "),
        Text(TARGET),
        Text(": "),
        Text(scene::NAME),
        Text(", "),
        Dec(BUDGET.width),
        Text("x"),
        Dec(BUDGET.height),
        Text(", seed "),
        Dec(BUDGET.seed as u32),
        Text("\n"),
    ]);
    let Statics { map, row, path } = take_statics().unwrap_or_else(|| fail("statics taken twice"));
    let path = semihosting::output_path(path, scene::FILE);

    let scene = scene::build::<OBJECTS, LIGHTS>(BUDGET.width, BUDGET.height)
        .unwrap_or_else(|_| fail("scene"));
    let settings = BUDGET.settings().unwrap_or_else(|_| fail("settings"));

    caustic_mark_photons_begin();
    let forward = map.build(&scene, &settings, BUDGET.seed);
    caustic_mark_photons_end();
    let forward = forward.unwrap_or_else(|_| fail("forward pass: over budget"));
    say(&[
        Text("photons: "),
        Dec(count(forward.emitted)),
        Text(" emitted, "),
        Dec(forward.stored as u32),
        Text(" stored (capacity "),
        Dec(BUDGET.stored as u32),
        Text("), "),
        Dec(map.splats().len() as u32),
        Text(" seen by the eye (capacity "),
        Dec(BUDGET.splats as u32),
        Text(")\n"),
    ]);

    let store = map
        .store::<{ BUDGET.k }>(&settings)
        .unwrap_or_else(|_| fail("store"));
    let renderer: Renderer<_, OBJECTS, LIGHTS, { BUDGET.depth }> = map.with_splats(
        Renderer::new(&scene, &store, settings.max_depth()).unwrap_or_else(|_| fail("renderer")),
    );
    let mut file = HostFile::create(path).unwrap_or_else(|e| fail(e));
    let mut stream =
        Rgb565Stream::<_, WIDTH>::new(BUDGET.width, BUDGET.height, |b: &[u8]| file.write(b))
            .unwrap_or_else(|_| fail("display"));

    // A unit struct without the error estimate, not with it: one constructor for both.
    #[allow(clippy::default_constructed_unit_structs)]
    let mut tally = Tally::default();
    caustic_mark_render_begin();
    let rays = {
        let mut sink = DisplaySink::new(&mut stream, ToneMap::default(), Dither::Off);
        renderer.rows(row, |y, pixels| {
            tally.add(pixels);
            sink.draw_row(y, pixels)
        })
    };
    caustic_mark_render_end();
    let rays = rays.unwrap_or_else(|_| fail("writing the image"));

    let (pixels, hash, complete) = (stream.pixels(), stream.hash(), stream.is_complete());
    let _ = stream.into_writer(); // gives `file` back
    file.close().unwrap_or_else(|e| fail(e));
    say(&[
        Text("rays: "),
        Dec(count(rays.eye)),
        Text(" eye, "),
        Dec(count(rays.shadow)),
        Text(" shadow\n"),
    ]);
    tally.report();
    let (stack, reserved) = stack_high_water();
    say(&[
        Text("stack high-water: "),
        Dec(stack as u32),
        Text(" bytes (of "),
        Dec(reserved as u32),
        Text(" reserved)\n"),
    ]);
    if !complete {
        fail("not every pixel was written");
    }
    say(&[
        Text("PASS fnv1a=0x"),
        Hex(hash),
        Text(" pixels="),
        Dec(pixels),
        Text(" stack="),
        Dec(stack as u32),
        Text("\n"),
    ]);
    semihosting::exit(true)
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    match info.location() {
        Some(l) => say(&[
            Text("PANIC at "),
            Text(l.file()),
            Text(":"),
            Dec(l.line()),
            Text("\n"),
        ]),
        None => say(&[Text("PANIC\n")]),
    }
    semihosting::exit(false)
}

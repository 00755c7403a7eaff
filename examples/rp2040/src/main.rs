//! caustic on a Raspberry Pi Pico (RP2040, Cortex-M0+, no FPU) with an ST7789 SPI
//! display: the paper's Fig. 6 at 160 × 120, every capacity from
//! `caustic::budget::FIG6`, the same core and the same rows as the QEMU firmwares
//! (`examples/device`), drawn on the panel row by row as the renderer produces them.
//!
//! Wiring (Pico GPIO, SPI0): SCK 18, MOSI 19, CS 17, DC 16, RST 21, backlight 20;
//! a 240 × 240 ST7789 (the image sits in its top-left corner). The on-board LED
//! (GPIO 25) lights while rendering and goes dark when the image is complete; it
//! blinks if anything fails.

#![no_std]
#![no_main]

use core::cell::UnsafeCell;

use caustic::budget::{DeviceMap, FIG6, FIG6_LIGHTS, FIG6_OBJECTS};
use caustic::demo;
use caustic::math::Rgb;
use caustic::raster::{DisplaySink, Dither, ToneMap};
use caustic::render::Renderer;
use embedded_hal::delay::DelayNs;
use embedded_hal::digital::OutputPin;
use embedded_hal_bus::spi::ExclusiveDevice;
use mipidsi::interface::SpiInterface;
use mipidsi::models::ST7789;
use mipidsi::options::ColorInversion;
use mipidsi::Builder;
use rp2040_hal::fugit::RateExtU32;
use rp2040_hal::{self as hal, pac, Clock};

/// The second-stage bootloader for the Pico's W25Q080 flash.
#[link_section = ".boot2"]
#[used]
pub static BOOT2: [u8; 256] = rp2040_boot2::BOOT_LOADER_W25Q080;

/// The Pico's crystal.
const XTAL_HZ: u32 = 12_000_000;
/// Row length, pixels.
const WIDTH: usize = FIG6.width as usize;

/// The photon map and the row: statics, not on the stack.
struct Statics {
    map: DeviceMap<{ FIG6.stored }, { FIG6.splats }>,
    row: [Rgb; WIDTH],
}

struct StaticsCell(UnsafeCell<Statics>);

// SAFETY: reached only through `main`'s single `&mut`, taken once before anything
// else runs (one core is used, no interrupts are enabled).
#[allow(unsafe_code)]
unsafe impl Sync for StaticsCell {}

static STATICS: StaticsCell = StaticsCell(UnsafeCell::new(Statics {
    map: DeviceMap::new(),
    row: [Rgb::ZERO; WIDTH],
}));

/// Blinks the LED forever: something failed.
fn fail(led: &mut impl OutputPin, delay: &mut impl DelayNs) -> ! {
    loop {
        let _ = led.set_high();
        delay.delay_ms(100);
        let _ = led.set_low();
        delay.delay_ms(100);
    }
}

#[hal::entry]
fn main() -> ! {
    let mut pac = pac::Peripherals::take().unwrap();
    let mut watchdog = hal::Watchdog::new(pac.WATCHDOG);
    let Ok(clocks) = hal::clocks::init_clocks_and_plls(
        XTAL_HZ,
        pac.XOSC,
        pac.CLOCKS,
        pac.PLL_SYS,
        pac.PLL_USB,
        &mut pac.RESETS,
        &mut watchdog,
    ) else {
        panic!("clocks");
    };
    let sio = hal::Sio::new(pac.SIO);
    let pins = hal::gpio::Pins::new(
        pac.IO_BANK0,
        pac.PADS_BANK0,
        sio.gpio_bank0,
        &mut pac.RESETS,
    );
    let mut timer = hal::Timer::new(pac.TIMER, &mut pac.RESETS, &clocks);
    let mut led = pins.gpio25.into_push_pull_output();
    let _ = led.set_high();

    // The display on SPI0 at 62.5 MHz.
    let sck = pins.gpio18.into_function::<hal::gpio::FunctionSpi>();
    let mosi = pins.gpio19.into_function::<hal::gpio::FunctionSpi>();
    let spi = hal::spi::Spi::<_, _, _, 8>::new(pac.SPI0, (mosi, sck)).init(
        &mut pac.RESETS,
        clocks.peripheral_clock.freq(),
        62_500_000u32.Hz(),
        embedded_hal::spi::MODE_3,
    );
    let cs = pins.gpio17.into_push_pull_output();
    let dc = pins.gpio16.into_push_pull_output();
    let rst = pins.gpio21.into_push_pull_output();
    let mut backlight = pins.gpio20.into_push_pull_output();
    // Both cannot fail: the RP2040's GPIO and SPI errors are `Infallible`.
    let Ok(device) = ExclusiveDevice::new(spi, cs, timer);
    let mut buffer = [0u8; 2 * WIDTH];
    let interface = SpiInterface::new(device, dc, &mut buffer);
    let Ok(mut display) = Builder::new(ST7789, interface)
        .display_size(240, 240)
        .invert_colors(ColorInversion::Inverted)
        .reset_pin(rst)
        .init(&mut timer);
    let _ = backlight.set_high();

    // SAFETY: the only reference to the statics, taken once (see `StaticsCell`).
    #[allow(unsafe_code)]
    let Statics { map, row } = unsafe { &mut *STATICS.0.get() };
    let Ok(scene) = demo::fig6::<FIG6_OBJECTS, FIG6_LIGHTS>(FIG6.width, FIG6.height) else {
        fail(&mut led, &mut timer)
    };
    let Ok(settings) = FIG6.settings() else {
        fail(&mut led, &mut timer)
    };
    if map.build(&scene, &settings, FIG6.seed).is_err() {
        fail(&mut led, &mut timer)
    }
    let Ok(store) = map.store::<{ FIG6.k }>(&settings) else {
        fail(&mut led, &mut timer)
    };
    let Ok(renderer) = Renderer::<_, FIG6_OBJECTS, FIG6_LIGHTS, { FIG6.depth }>::new(
        &scene,
        &store,
        settings.max_depth(),
    ) else {
        fail(&mut led, &mut timer)
    };
    let renderer = map.with_splats(renderer);
    let drawn = {
        let mut sink = DisplaySink::new(&mut display, ToneMap::default(), Dither::Off);
        renderer.rows(row, |y, pixels| sink.draw_row(y, pixels))
    };
    if drawn.is_err() {
        fail(&mut led, &mut timer)
    }
    let _ = led.set_low();
    loop {
        cortex_m::asm::wfi();
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {
        core::hint::spin_loop();
    }
}

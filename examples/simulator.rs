//! The desktop simulator: watch a device render on the desktop.
//!
//! Builds the scene in code exactly as the device firmware does
//! ([`caustic::demo::fig6`] with [`caustic::budget::FIG6`]: 2 048 photons,
//! K = 32, path stack of 8, seed 0, [`ToneMap::default`], no dithering), renders it row
//! by row through the library's `DrawTarget` adapter ([`DisplaySink`]) onto an
//! `embedded-graphics-simulator` [`SimulatorDisplay`] of the device's 160×120 RGB565
//! panel, and saves the display as a PNG. The test `tests/simulator.rs` checks that
//! these pixels equal, bit for bit, the little-endian RGB565 byte stream the firmware
//! sends to its panel.
//!
//! ```text
//! cargo run --release --example simulator -- -o out/sim.png
//! ```
//!
//! Headless by default: no SDL, no window, nothing but the PNG.
//!
//! Options:
//!
//! | flag | meaning | default |
//! |---|---|---|
//! | `--width W`, `--height H` | display size in pixels (the camera is resized to it) | 160 × 120 |
//! | `--color rgb565\|rgb888` | the display's colour format | `rgb565` |
//! | `--dither off\|bayer` | 4×4 Bayer dithering before RGB565 quantisation (RGB565 is **not** dithered unless asked; the device is not) | `off` |
//! | `--scene FILE.json` | a scene file instead of the built-in Fig. 6 scene | built-in |
//! | `--photons N`, `--k K`, `--radius R`, `--max-depth D`, `--gather nearest\|radius`, `--emit cones\|sphere`, `--cone-filter K`, `--seed S` | the photon flags of `caustic render`, the same definitions ([`caustic::desktop::cli::PhotonArgs`]) and checks | the device's budget (or the file's `photons` block), seed 0 |
//! | `--scale N` | each display pixel as N×N PNG pixels | 1 |
//! | `-o OUT.png` | where to write the PNG | `out/simulator.png` |
//! | `--window` | also show rows in a window as they are produced (needs SDL, below) | off |
//!
//! A scene file is loaded with the desktop capacities
//! ([`caustic::desktop::MAX_OBJECTS`] objects, [`caustic::desktop::MAX_LIGHTS`] lights,
//! gather K ≤ [`caustic::desktop::MAX_GATHER`], path stack
//! [`caustic::desktop::MAX_DEPTH`]), which are larger than a device build's; its
//! `photons` block is used (one pass: `passes` is ignored, as on a device) except where
//! a photon flag replaces one of its keys (the others, such as `gather`, stay), and its
//! `image` size is replaced by the display size. With the built-in scene the device's
//! capacities hold: `--k` ≤ 32 and `--max-depth` ≤ 8.
//!
//! # A window
//!
//! `--window` opens an SDL window in which rows appear as they are produced, then
//! waits until it is closed. The simulator is a dev-dependency without its SDL
//! backend (so that the default build and CI need no SDL); to get the window, install
//! SDL2's development files (Debian/Ubuntu: `apt-get install libsdl2-dev`) and enable
//! the backend for one run:
//!
//! ```text
//! cargo run --release --example simulator \
//!     --features embedded-graphics-simulator/with-sdl -- --window
//! ```
//!
//! (Checked on Debian 12 under Xvfb.) In the window each row is presented as it
//! leaves the renderer, at most 60 rows a second (the simulator's frame limiter), so
//! the picture builds up top to bottom as on the panel. Without the backend
//! `--window` shows nothing; the PNG is written either way.

use std::error::Error;
use std::path::{Path, PathBuf};
use std::time::Instant;

use caustic::desktop::cli::PhotonArgs;
use caustic::desktop::settings::{Given, SettingsInput};
use caustic::desktop::{self, MAX_DEPTH, MAX_GATHER, MAX_LIGHTS, MAX_OBJECTS};
use caustic::math::Rgb;
use caustic::photon::{self, KdTree, Photon, PhotonSettings};
use caustic::raster::{DisplaySink, Dither, ToneMap};
use caustic::render::Renderer;
use caustic::scene::Scene;
use caustic::{budget, demo};
use clap::error::ErrorKind;
use clap::{Parser, ValueEnum};
use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::geometry::Size;
use embedded_graphics_core::pixelcolor::{BinaryColor, PixelColor, Rgb565, Rgb888};
use embedded_graphics_simulator::{OutputSettingsBuilder, SimulatorDisplay, Window};

/// Gather capacity K of the device build.
pub const DEVICE_GATHER: usize = budget::FIG6.k;
/// Path stack DEPTH of the device build.
pub const DEVICE_DEPTH: usize = budget::FIG6.depth;
/// Objects of the device build's scene type.
pub const DEVICE_OBJECTS: usize = budget::FIG6_OBJECTS;
/// Lights of the device build's scene type.
pub const DEVICE_LIGHTS: usize = budget::FIG6_LIGHTS;

/// The display's colour format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ColorFormat {
    /// 16-bit RGB565, as on the device.
    Rgb565,
    /// 24-bit RGB888.
    Rgb888,
}

/// `--dither off|bayer`.
fn dither(s: &str) -> Result<Dither, String> {
    match s {
        "off" | "none" => Ok(Dither::Off),
        "bayer" => Ok(Dither::Bayer565),
        _ => Err(format!("expected off or bayer, not {s:?}")),
    }
}

/// The command line: the display's flags, and the photon flags of `caustic render`
/// ([`PhotonArgs`], the same definitions).
#[derive(Parser, Clone, Debug, PartialEq)]
#[command(
    name = "simulator",
    allow_negative_numbers = true,
    about = "Renders the device's scene (paper Fig. 6, device budget) onto a simulated \
             160x120 RGB565 display and writes it as a PNG. RGB565 is not dithered \
             unless --dither bayer is given. --window needs the simulator's SDL \
             backend: see the docs in examples/simulator.rs."
)]
pub struct Options {
    /// Display width in pixels (the camera is resized to it)
    #[arg(long, value_name = "W", default_value_t = 160,
          value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub width: u32,
    /// Display height in pixels
    #[arg(long, value_name = "H", default_value_t = 120,
          value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub height: u32,
    /// The display's colour format
    #[arg(long, value_enum, default_value_t = ColorFormat::Rgb565)]
    pub color: ColorFormat,
    /// 4×4 Bayer dithering before RGB565 quantisation (off or bayer; the device does not dither)
    #[arg(long, value_name = "off|bayer", default_value = "off", value_parser = dither)]
    pub dither: Dither,
    /// A scene file instead of the built-in Fig. 6 scene [default: built-in]
    #[arg(long, value_name = "FILE.json")]
    pub scene: Option<PathBuf>,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub budget: PhotonArgs,
    /// Each display pixel as N×N PNG pixels
    #[arg(long, value_name = "N", default_value_t = 1,
          value_parser = clap::value_parser!(u32).range(1..=16))]
    pub scale: u32,
    /// Where to write the PNG
    #[arg(
        short = 'o',
        long = "out",
        visible_alias = "output",
        value_name = "OUT.png",
        default_value = "out/simulator.png"
    )]
    pub out: PathBuf,
    /// Also show rows in a window as they are produced (needs SDL)
    #[arg(long)]
    pub window: bool,
}

impl Default for Options {
    /// The device: 160×120 RGB565, undithered, built-in scene, its budget, seed 0 (the
    /// command line's defaults).
    fn default() -> Self {
        Self::parse_from(["simulator"])
    }
}

impl Options {
    /// Parses the arguments after the program name. `Ok(None)` for `--help` or
    /// `--version`.
    pub fn parse<I: IntoIterator<Item = String>>(args: I) -> Result<Option<Self>, String> {
        let args = std::iter::once("simulator".to_string()).chain(args);
        let o = match Self::try_parse_from(args) {
            Ok(o) => o,
            Err(e) if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) => {
                return Ok(None)
            }
            Err(e) => return Err(e.to_string()),
        };
        if o.dither == Dither::Bayer565 && o.color != ColorFormat::Rgb565 {
            return Err(
                "--dither bayer is scaled to RGB565 steps: use it with --color rgb565".into(),
            );
        }
        Ok(Some(o))
    }
}

/// What a render did.
#[derive(Clone, Copy, Debug, Default)]
pub struct Stats {
    /// Photons emitted over all lights.
    pub emitted: u64,
    /// Photons stored in the map.
    pub stored: usize,
    /// Rows drawn.
    pub rows: u32,
    /// Eye and shadow rays traced.
    pub rays: u64,
}

/// Renders the scene `opts` asks for onto `display` (any size ≥ the image) through
/// [`DisplaySink`], calling `after_row(y, display)` once row `y` is on it.
pub fn render<D>(
    opts: &Options,
    display: &mut D,
    after_row: &mut dyn FnMut(u32, &D),
) -> Result<Stats, Box<dyn Error>>
where
    D: DrawTarget,
    D::Color: From<Rgb888>,
    D::Error: std::fmt::Debug,
{
    let (tone, dither) = (ToneMap::default(), opts.dither);
    let mut sink = |y: u32, pixels: &[Rgb]| -> Result<(), Box<dyn Error>> {
        DisplaySink::new(&mut *display, tone, dither)
            .draw_row(y, pixels)
            .map_err(|e| format!("display error at row {y}: {e:?}"))?;
        after_row(y, display);
        Ok(())
    };
    let seed = opts.budget.seed;
    match &opts.scene {
        None => {
            let scene = demo::fig6::<DEVICE_OBJECTS, DEVICE_LIGHTS>(opts.width, opts.height)?;
            let device = SettingsInput::of(&budget::FIG6.settings()?);
            let input = device.overridden_by(&opts.budget.input());
            let settings = opts.budget.finish(input.validate(&scene)?.photons);
            draw::<DEVICE_OBJECTS, DEVICE_LIGHTS, DEVICE_GATHER, DEVICE_DEPTH>(
                &scene, &settings, seed, &mut sink,
            )
        }
        Some(path) => {
            // The display's size replaces the file's image size.
            let flags = SettingsInput {
                width: Some(Given::flag(opts.width)),
                height: Some(Given::flag(opts.height)),
                ..opts.budget.input()
            };
            let loaded = desktop::load_scene(path)?.with_overrides(&flags)?;
            if loaded.passes > 1 {
                eprintln!(
                    "note: rendering one photon pass, as a device does (the file asks for {})",
                    loaded.passes
                );
            }
            let settings = opts.budget.finish(loaded.photons);
            draw::<MAX_OBJECTS, MAX_LIGHTS, MAX_GATHER, MAX_DEPTH>(
                &loaded.scene,
                &settings,
                seed,
                &mut sink,
            )
        }
    }
}

/// The device's pipeline with the photon array on the heap (any `--photons`): the
/// same forward pass ([`photon::shoot_with_splats`], pass 0, then [`photon::balance`]) as
/// `PhotonMap::build`, a gather of `K`, a path stack of `DEPTH`, one row buffer whose
/// rows go to `sink(y, pixels)`.
fn draw<const O: usize, const L: usize, const K: usize, const DEPTH: usize>(
    scene: &Scene<O, L>,
    settings: &PhotonSettings,
    seed: u64,
    mut sink: impl FnMut(u32, &[Rgb]) -> Result<(), Box<dyn Error>>,
) -> Result<Stats, Box<dyn Error>> {
    let needed = photon::photons_needed(scene, settings);
    if needed > desktop::MAX_PHOTONS {
        return Err(format!(
            "{needed} photons exceed the desktop capacity {}",
            desktop::MAX_PHOTONS
        )
        .into());
    }
    let mut photons = vec![Photon::ZERO; needed];
    let mut splats = Vec::new();
    let forward = photon::shoot_with_splats(scene, settings, seed, 0, &mut photons, &mut splats)?;
    photons.truncate(forward.stored);
    photon::balance(&mut photons);
    let store = photon::store_over::<K>(
        KdTree::from_balanced(&photons),
        forward.power_unit,
        settings,
    )?;
    let renderer: Renderer<'_, _, O, L, DEPTH> =
        Renderer::new(scene, &store, settings.max_depth())?;
    // As the device (`budget::DeviceMap::with_splats`): caustics seen directly are
    // light-traced when the settings splat.
    let renderer = if settings.camera_splats() {
        renderer.with_splats(&splats)
    } else {
        renderer
    };

    let mut row = vec![Rgb::ZERO; scene.camera().width() as usize];
    let count = renderer
        .rows(&mut row, |y, pixels| sink(y, pixels))
        .map_err(|e| e.to_string())?;
    Ok(Stats {
        emitted: forward.emitted,
        stored: forward.stored,
        rows: scene.camera().height(),
        rays: count.eye + count.shadow,
    })
}

/// Renders onto a `SimulatorDisplay<C>`, optionally shown in a window, and saves it.
fn simulate<C>(opts: &Options) -> Result<Stats, Box<dyn Error>>
where
    C: PixelColor + From<BinaryColor> + From<Rgb888> + Into<Rgb888>,
{
    let mut display = SimulatorDisplay::<C>::new(Size::new(opts.width, opts.height));
    let output = OutputSettingsBuilder::new().scale(opts.scale).build();
    let mut window = opts
        .window
        .then(|| Window::new("caustic: device simulator", &output));
    let stats = render(opts, &mut display, &mut |_y, d| {
        if let Some(w) = window.as_mut() {
            w.update(d);
        }
    })?;
    save(&display, opts.scale, &opts.out)?;
    if let Some(w) = window.as_mut() {
        eprintln!("close the window to exit");
        w.show_static(&display);
    }
    Ok(stats)
}

/// Writes `display` as a PNG, `scale` PNG pixels per display pixel.
pub fn save<C>(display: &SimulatorDisplay<C>, scale: u32, out: &Path) -> Result<(), Box<dyn Error>>
where
    C: PixelColor + Into<Rgb888>,
{
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let settings = OutputSettingsBuilder::new().scale(scale).build();
    display
        .to_rgb_output_image(&settings)
        .save_png(out)
        .map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    Ok(())
}

fn main() {
    let opts = match Options::parse(std::env::args().skip(1)) {
        Ok(Some(o)) => o,
        Ok(None) => {
            // clap prints the help or the version itself.
            let _ = Options::try_parse().map_err(|e| e.exit());
            return;
        }
        Err(e) => {
            eprintln!("simulator: {e}");
            std::process::exit(2);
        }
    };
    let t = Instant::now();
    let result = match opts.color {
        ColorFormat::Rgb565 => simulate::<Rgb565>(&opts),
        ColorFormat::Rgb888 => simulate::<Rgb888>(&opts),
    };
    match result {
        Ok(s) => eprintln!(
            "{}×{} {:?}{}: {} photons stored of {} emitted, {} rays, {:.0} ms; wrote {}",
            opts.width,
            opts.height,
            opts.color,
            if opts.dither == Dither::Off {
                ""
            } else {
                " (Bayer dithered)"
            },
            s.stored,
            s.emitted,
            s.rays,
            t.elapsed().as_secs_f64() * 1e3,
            opts.out.display(),
        ),
        Err(e) => {
            eprintln!("simulator: {e}");
            std::process::exit(1);
        }
    }
}

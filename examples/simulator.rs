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
//! | `--photons N` | photons per light | 2 048 (or the file's `photons.count`) |
//! | `--seed S` | forward-pass seed | 0 |
//! | `--scale N` | each display pixel as N×N PNG pixels | 1 |
//! | `-o OUT.png` | where to write the PNG | `out/simulator.png` |
//! | `--window` | also show rows in a window as they are produced (needs SDL, below) | off |
//!
//! A scene file is loaded with the desktop capacities
//! ([`caustic::desktop::MAX_OBJECTS`] objects, [`caustic::desktop::MAX_LIGHTS`] lights,
//! gather K ≤ [`caustic::desktop::MAX_GATHER`], path stack
//! [`caustic::desktop::MAX_DEPTH`]), which are larger than a device build's; its
//! `photons` block is used (one pass: `passes` is ignored, as on a device) except for
//! `--photons`, and its `image` size is replaced by the display size.
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

use caustic::desktop::{self, MAX_DEPTH, MAX_GATHER, MAX_LIGHTS, MAX_OBJECTS};
use caustic::math::Rgb;
use caustic::photon::{self, KdTree, Photon, PhotonSettings};
use caustic::raster::{DisplaySink, Dither, ToneMap};
use caustic::render::Renderer;
use caustic::scene::Scene;
use caustic::{budget, demo};
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
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorFormat {
    /// 16-bit RGB565, as on the device.
    Rgb565,
    /// 24-bit RGB888.
    Rgb888,
}

/// The command line.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Display width in pixels.
    pub width: u32,
    /// Display height in pixels.
    pub height: u32,
    /// Colour format.
    pub color: ColorFormat,
    /// Dithering before quantisation.
    pub dither: Dither,
    /// A scene file instead of the built-in scene.
    pub scene: Option<PathBuf>,
    /// Photons per light, overriding the scene's budget.
    pub photons: Option<u32>,
    /// Forward-pass seed.
    pub seed: u64,
    /// PNG pixels per display pixel.
    pub scale: u32,
    /// The PNG's path.
    pub out: PathBuf,
    /// Show an SDL window.
    pub window: bool,
}

impl Default for Options {
    /// The device: 160×120 RGB565, undithered, built-in scene, its budget, seed 0.
    fn default() -> Self {
        Self {
            width: 160,
            height: 120,
            color: ColorFormat::Rgb565,
            dither: Dither::Off,
            scene: None,
            photons: None,
            seed: 0,
            scale: 1,
            out: PathBuf::from("out/simulator.png"),
            window: false,
        }
    }
}

const USAGE: &str = "\
usage: simulator [--width W] [--height H] [--color rgb565|rgb888] [--dither off|bayer]
                 [--scene FILE.json] [--photons N] [--seed S] [--scale N] [-o OUT.png]
                 [--window]

Renders the device's scene (paper Fig. 6, device budget) onto a simulated
160x120 RGB565 display and writes it as a PNG (default out/simulator.png).
RGB565 is not dithered unless --dither bayer is given.
--window needs the simulator's SDL backend: see the docs in examples/simulator.rs.";

fn number<T: std::str::FromStr>(flag: &str, v: &str) -> Result<T, String> {
    v.parse()
        .map_err(|_| format!("{flag}: not a valid number: {v:?}"))
}

impl Options {
    /// Parses the arguments after the program name. `Ok(None)` for `--help`.
    pub fn parse<I: IntoIterator<Item = String>>(args: I) -> Result<Option<Self>, String> {
        let mut o = Self::default();
        let mut args = args.into_iter();
        while let Some(arg) = args.next() {
            let (flag, inline) = match arg.split_once('=') {
                Some((f, v)) if f.starts_with("--") => (f.to_string(), Some(v.to_string())),
                _ => (arg, None),
            };
            if matches!(flag.as_str(), "-h" | "--help") {
                return Ok(None);
            }
            if flag == "--window" {
                o.window = true;
                continue;
            }
            const VALUED: [&str; 11] = [
                "--width",
                "--height",
                "--color",
                "--dither",
                "--scene",
                "--photons",
                "--seed",
                "--scale",
                "-o",
                "--out",
                "--output",
            ];
            if !VALUED.contains(&flag.as_str()) {
                return Err(format!("unknown argument {flag:?}"));
            }
            let Some(value) = inline.or_else(|| args.next()) else {
                return Err(format!("{flag}: missing value"));
            };
            match flag.as_str() {
                "--width" => o.width = number(&flag, &value)?,
                "--height" => o.height = number(&flag, &value)?,
                "--color" => {
                    o.color = match value.as_str() {
                        "rgb565" => ColorFormat::Rgb565,
                        "rgb888" => ColorFormat::Rgb888,
                        _ => {
                            return Err(format!(
                                "--color: expected rgb565 or rgb888, not {value:?}"
                            ))
                        }
                    }
                }
                "--dither" => {
                    o.dither = match value.as_str() {
                        "off" | "none" => Dither::Off,
                        "bayer" => Dither::Bayer565,
                        _ => return Err(format!("--dither: expected off or bayer, not {value:?}")),
                    }
                }
                "--scene" => o.scene = Some(PathBuf::from(value)),
                "--photons" => o.photons = Some(number(&flag, &value)?),
                "--seed" => o.seed = number(&flag, &value)?,
                "--scale" => o.scale = number(&flag, &value)?,
                "-o" | "--out" | "--output" => o.out = PathBuf::from(value),
                _ => unreachable!("{flag} is in VALUED"),
            }
        }
        if o.width == 0 || o.height == 0 {
            return Err("--width and --height must be positive".into());
        }
        if !(1..=16).contains(&o.scale) {
            return Err("--scale must lie in 1..=16".into());
        }
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
    let tone = ToneMap::default();
    match &opts.scene {
        None => {
            let scene = demo::fig6::<DEVICE_OBJECTS, DEVICE_LIGHTS>(opts.width, opts.height)?;
            let device = budget::FIG6.settings()?;
            let settings = with_count(&device, opts.photons)?;
            draw::<_, DEVICE_OBJECTS, DEVICE_LIGHTS, DEVICE_GATHER, DEVICE_DEPTH>(
                &scene,
                &settings,
                opts.seed,
                tone,
                opts.dither,
                display,
                after_row,
            )
        }
        Some(path) => {
            let mut loaded = desktop::load_scene(path)?;
            if loaded.passes > 1 {
                eprintln!(
                    "note: rendering one photon pass, as a device does (the file asks for {})",
                    loaded.passes
                );
            }
            let camera = loaded.scene.camera().with_size(opts.width, opts.height)?;
            loaded.scene.set_camera(camera);
            let settings = with_count(&loaded.photons, opts.photons)?;
            draw::<_, MAX_OBJECTS, MAX_LIGHTS, MAX_GATHER, MAX_DEPTH>(
                &loaded.scene,
                &settings,
                opts.seed,
                tone,
                opts.dither,
                display,
                after_row,
            )
        }
    }
}

/// `settings` with another photon count.
fn with_count(
    settings: &PhotonSettings,
    count: Option<u32>,
) -> Result<PhotonSettings, caustic::Error> {
    let Some(count) = count else {
        return Ok(*settings);
    };
    Ok(PhotonSettings::new(
        count,
        settings.k(),
        settings.max_radius(),
        settings.max_depth(),
    )?
    .with_cone_filter(settings.cone_filter()))
}

/// The device's pipeline with the photon array on the heap (any `--photons`): the
/// same forward pass ([`photon::shoot`], pass 0, then [`photon::balance`]) as
/// `PhotonMap::build`, a gather of `K`, a path stack of `DEPTH`, one row buffer.
fn draw<D, const O: usize, const L: usize, const K: usize, const DEPTH: usize>(
    scene: &Scene<O, L>,
    settings: &PhotonSettings,
    seed: u64,
    tone: ToneMap,
    dither: Dither,
    display: &mut D,
    after_row: &mut dyn FnMut(u32, &D),
) -> Result<Stats, Box<dyn Error>>
where
    D: DrawTarget,
    D::Color: From<Rgb888>,
    D::Error: std::fmt::Debug,
{
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
        .rows(&mut row, |y, pixels| {
            DisplaySink::new(&mut *display, tone, dither)
                .draw_row(y, pixels)
                .map_err(|e| format!("display error at row {y}: {e:?}"))?;
            after_row(y, display);
            Ok::<_, Box<dyn Error>>(())
        })
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
            println!("{USAGE}");
            return;
        }
        Err(e) => {
            eprintln!("simulator: {e}\n\n{USAGE}");
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

//! The desktop simulator (`examples/simulator.rs`) shows exactly what the device shows.
//!
//! The example's own code is compiled in here, and its pixels are compared with those
//! of the firmware's pipeline (`examples/device`, every capacity from
//! `caustic::budget::FIG6`, `DisplaySink` onto the library's `Rgb565Stream`), which
//! `tests/support` runs on the host.
#![cfg(feature = "std")]

mod support;

#[path = "../examples/simulator.rs"]
#[allow(dead_code)]
mod simulator;

use caustic::budget::FIG6;
use caustic::raster::{Dither, ToneMap};
use embedded_graphics_core::draw_target::DrawTarget;
use embedded_graphics_core::geometry::{OriginDimensions, Point, Size};
use embedded_graphics_core::pixelcolor::{PixelColor, Rgb565, Rgb888, RgbColor};
use embedded_graphics_core::Pixel;
use embedded_graphics_simulator::SimulatorDisplay;
use simulator::{ColorFormat, Options};

const W: u32 = FIG6.width;
const H: u32 = FIG6.height;

/// The simulator's display after rendering `opts`; also checks that `after_row` saw
/// each row once, top to bottom.
fn simulate<C>(opts: &Options) -> SimulatorDisplay<C>
where
    C: PixelColor + From<embedded_graphics_core::pixelcolor::BinaryColor> + From<Rgb888>,
{
    let mut display = SimulatorDisplay::<C>::new(Size::new(opts.width, opts.height));
    let mut seen = Vec::new();
    let stats = simulator::render(opts, &mut display, &mut |y, _| seen.push(y)).unwrap();
    assert_eq!(seen, (0..opts.height).collect::<Vec<_>>());
    assert_eq!(stats.rows, opts.height);
    display
}

/// A display that counts how often each pixel is drawn, and where out of bounds.
struct Counter<C> {
    size: Size,
    count: Vec<u32>,
    last: Vec<Option<C>>,
    outside: usize,
}

impl<C: PixelColor> Counter<C> {
    fn new(size: Size) -> Self {
        let n = (size.width * size.height) as usize;
        Self {
            size,
            count: vec![0; n],
            last: vec![None; n],
            outside: 0,
        }
    }
}

impl<C: PixelColor> OriginDimensions for Counter<C> {
    fn size(&self) -> Size {
        self.size
    }
}

impl<C: PixelColor> DrawTarget for Counter<C> {
    type Color = C;
    type Error = core::convert::Infallible;

    fn draw_iter<I: IntoIterator<Item = Pixel<C>>>(
        &mut self,
        pixels: I,
    ) -> Result<(), Self::Error> {
        let (w, h) = (self.size.width as i32, self.size.height as i32);
        for Pixel(p, c) in pixels {
            if (0..w).contains(&p.x) && (0..h).contains(&p.y) {
                let i = (p.y * w + p.x) as usize;
                self.count[i] += 1;
                self.last[i] = Some(c);
            } else {
                self.outside += 1;
            }
        }
        Ok(())
    }
}

fn pixels<C: PixelColor>(d: &SimulatorDisplay<C>) -> Vec<C> {
    let s = d.size();
    (0..s.height as i32)
        .flat_map(|y| (0..s.width as i32).map(move |x| d.get_pixel(Point::new(x, y))))
        .collect()
}

/// The defaults are the device: 160×120 RGB565, undithered, built-in scene, seed 0.
#[test]
fn defaults_are_the_device() {
    let o = Options::parse(Vec::<String>::new()).unwrap().unwrap();
    assert_eq!((o.width, o.height), (W, H));
    assert_eq!(
        (o.color, o.dither, o.budget.seed),
        (ColorFormat::Rgb565, Dither::Off, 0)
    );
    assert_eq!((o.scene.as_ref(), o.budget.count), (None, None));
}

/// The headline: the simulator's RGB565 pixels are the device's byte stream, bit for bit.
#[test]
fn simulator_shows_exactly_what_the_device_streams() {
    // The stream refuses pixels out of order: completing it means one pass, in order.
    let support::device::Streamed {
        bytes: device,
        hash,
        ..
    } = support::device::fig6_stream();
    println!("device stream fnv1a=0x{hash:08x}");

    let display = simulate::<Rgb565>(&Options::default());
    let shown = display.to_le_bytes();
    assert_eq!(shown.len(), device.len());
    if let Some(i) = shown.iter().zip(&device).position(|(a, b)| a != b) {
        let p = i / 2;
        panic!(
            "pixel ({}, {}) differs: simulator {:02x?}, device {:02x?}",
            p % W as usize,
            p / W as usize,
            &shown[2 * p..2 * p + 2],
            &device[2 * p..2 * p + 2]
        );
    }
    // Not a blank frame: the cube, its caustic and the grey field are all there.
    let distinct: std::collections::HashSet<_> = pixels(&display).into_iter().collect();
    assert!(distinct.len() > 50, "{} colours", distinct.len());
}

/// Every pixel of the display is drawn exactly once, none outside it, at the device
/// size, at another size, in both colour formats, and for a scene file.
#[test]
fn every_pixel_is_drawn_exactly_once() {
    let scene = format!("{}/scenes/fig6.json", env!("CARGO_MANIFEST_DIR"));
    let args = |a: &[&str]| {
        Options::parse(a.iter().map(|s| s.to_string()))
            .unwrap()
            .unwrap()
    };
    for opts in [
        Options::default(),
        args(&[
            "--width",
            "37",
            "--height",
            "23",
            "--photons",
            "500",
            "--seed",
            "3",
        ]),
        args(&[
            "--width=64",
            "--height=48",
            "--scene",
            &scene,
            "--photons",
            "1000",
        ]),
    ] {
        let size = Size::new(opts.width, opts.height);
        let mut d565 = Counter::<Rgb565>::new(size);
        simulator::render(&opts, &mut d565, &mut |_, _| {}).unwrap();
        let mut d888 = Counter::<Rgb888>::new(size);
        simulator::render(&opts, &mut d888, &mut |_, _| {}).unwrap();
        for (name, count, outside) in [
            ("rgb565", &d565.count, d565.outside),
            ("rgb888", &d888.count, d888.outside),
        ] {
            assert_eq!(outside, 0, "{name} {opts:?}");
            if let Some(i) = count.iter().position(|&n| n != 1) {
                panic!("{name} {opts:?}: pixel {i} drawn {} times", count[i]);
            }
        }
        // The same colours whichever format: RGB565 is RGB888 quantised.
        for (a, b) in d565.last.iter().zip(&d888.last) {
            assert_eq!(*a, b.map(Rgb565::from));
        }
    }
}

/// `--color rgb888` shows the tone-mapped 8-bit sRGB of the rows, exactly.
#[test]
fn rgb888_is_the_tone_mapped_srgb_of_the_rows() {
    let tone = ToneMap::default();
    let mut want = Vec::new();
    support::device::fig6_rows(|_, row| want.extend(row.iter().map(|&c| tone.srgb8(c))));
    let opts = Options {
        color: ColorFormat::Rgb888,
        ..Options::default()
    };
    let got: Vec<[u8; 3]> = pixels(&simulate::<Rgb888>(&opts))
        .into_iter()
        .map(|c| [c.r(), c.g(), c.b()])
        .collect();
    assert_eq!(got.len(), want.len());
    assert!(
        got == want,
        "RGB888 pixels differ from ToneMap::srgb8 of the rows"
    );
}

/// `--dither bayer` changes pixels, but none by more than one RGB565 step per channel.
#[test]
fn dithering_stays_within_one_rgb565_step() {
    let plain = pixels(&simulate::<Rgb565>(&Options::default()));
    let opts = Options::parse(["--dither", "bayer"].map(String::from))
        .unwrap()
        .unwrap();
    assert_eq!(opts.dither, Dither::Bayer565);
    let dithered = pixels(&simulate::<Rgb565>(&opts));
    let mut changed = 0;
    for (i, (a, b)) in plain.iter().zip(&dithered).enumerate() {
        let steps = [
            a.r().abs_diff(b.r()),
            a.g().abs_diff(b.g()),
            a.b().abs_diff(b.b()),
        ];
        assert!(steps.iter().all(|&s| s <= 1), "pixel {i}: {a:?} vs {b:?}");
        changed += (a != b) as usize;
    }
    // The field's smooth gradient is where banding shows: dithering must touch it.
    assert!(changed > plain.len() / 10, "only {changed} pixels changed");
}

/// Bad command lines are refused with a message, `--help` is not an error.
#[test]
fn the_command_line_is_checked() {
    let parse = |a: &[&str]| Options::parse(a.iter().map(|s| s.to_string()));
    assert_eq!(parse(&["--help"]), Ok(None));
    for bad in [
        &["--bogus"][..],
        &["--width"],
        &["--width", "0"],
        &["--height", "-3"],
        &["--color", "rgb666"],
        &["--dither", "floyd"],
        &["--dither", "bayer", "--color", "rgb888"],
        &["--photons", "many"],
        &["--scale", "0"],
        &["stray"],
    ] {
        assert!(parse(bad).is_err(), "{bad:?} accepted");
    }
    let o = parse(&[
        "-o",
        "x/y.png",
        "--color",
        "rgb888",
        "--seed",
        "9",
        "--photons",
        "100",
    ])
    .unwrap()
    .unwrap();
    assert_eq!(o.out, std::path::PathBuf::from("x/y.png"));
    assert_eq!(
        (o.color, o.budget.seed, o.budget.count),
        (ColorFormat::Rgb888, 9, Some(100))
    );
}

/// `--photons` replaces only the scene file's photon count: its gather choice stays.
/// With `--photons 20000` the glass sphere (which gathers every photon within its
/// radius) shows the pixels of the same file with `"count": 20000`, and not those of
/// the k-nearest gather.
#[test]
fn photons_flag_keeps_the_scenes_gather() {
    let text = std::fs::read_to_string(format!(
        "{}/scenes/glass_sphere.json",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let dir = std::env::temp_dir().join(format!("caustic-sim-gather-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = |name: &str, edit: &dyn Fn(&mut serde_json::Value)| {
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        // Few photons per estimate, so that the k nearest differ from all in the radius.
        v["photons"]["k"] = 2.into();
        edit(&mut v);
        let path = dir.join(name);
        std::fs::write(&path, v.to_string()).unwrap();
        path.to_str().unwrap().to_string()
    };
    let original = file("original.json", &|_| {});
    let counted = file("counted.json", &|v| v["photons"]["count"] = 20_000.into());
    let nearest = file("nearest.json", &|v| {
        v["photons"]["count"] = 20_000.into();
        v["photons"]["gather"] = "nearest".into();
    });
    // Without camera splats the store gathers at every diffuse hit, so the gather
    // choice shows wherever the caustic is (with them, only behind the glass).
    let show = |args: &[&str]| {
        let mut all = vec!["--width", "64", "--height", "48", "--no-splat", "--scene"];
        all.extend_from_slice(args);
        let opts = Options::parse(all.iter().map(|s| s.to_string()))
            .unwrap()
            .unwrap();
        pixels(&simulate::<Rgb565>(&opts))
    };
    let flagged = show(&[&original, "--photons", "20000"]);
    assert!(
        flagged == show(&[&counted]),
        "--photons changed more than the count"
    );
    assert!(
        flagged != show(&[&nearest]),
        "the gather choice makes no difference"
    );
    std::fs::remove_dir_all(dir).ok();
}

//! `caustic`: render a scene file to PNG/PFM, or compare two PFM images.
//!
//! ```text
//! caustic render SCENE.json -o OUT.png [--pfm OUT.pfm] [--width W] [--height H]
//!                [--photons N] [--k K] [--radius R] [--max-depth D] [--passes P]
//!                [--alpha A] [--cone-filter K] [--seed S] [--threads T]
//!                [--exposure E] [--supersample S] [--sampling adaptive|centre|grid]
//!                [--splat on|off] [--emit cones|sphere] [--gather nearest|radius]
//!                [--stats] [--quiet]
//!                [--store kd|illum] [--texel-size S]
//! caustic compare A.pfm REFERENCE.pfm [--mask M.pfm] [--mask-fraction F] [--bin B]
//! ```
//! Exit status: 0 on success, 2 on bad input (scene, flags, files), 1 otherwise.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use caustic::desktop::image::{compare, mask_above, Image};
use caustic::desktop::run::render_illumination;
use caustic::desktop::scene_file::StoreChoice;
use caustic::desktop::{load_scene, render, RenderOptions, RenderStats};
use caustic::photon::{ConeFilter, MapStats, PhotonSettings};
use caustic::raster::ToneMap;
use caustic::render::Sampling;

const USAGE: &str = "usage:
  caustic render SCENE.json -o OUT.png [--pfm OUT.pfm] [--width W] [--height H]
                 [--photons N] [--k K] [--radius R] [--max-depth D] [--passes P]
                 [--alpha A] [--cone-filter K] [--seed S] [--threads T]
                 [--exposure E] [--supersample S] [--sampling adaptive|centre|grid]
                 [--splat on|off] [--emit cones|sphere] [--gather nearest|radius]
                 [--stats] [--quiet]
                 [--store kd|illum] [--texel-size S]
  caustic compare A.pfm REFERENCE.pfm [--mask M.pfm] [--mask-fraction F] [--bin B]";

/// A failure and its exit status.
struct Failure {
    code: u8,
    message: String,
}

fn bad_input(message: impl Into<String>) -> Failure {
    Failure {
        code: 2,
        message: message.into(),
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("render") => cmd_render(&args[1..]),
        Some("compare") => cmd_compare(&args[1..]),
        Some("-h" | "--help" | "help") => {
            println!("{USAGE}");
            Ok(())
        }
        _ => Err(bad_input(USAGE)),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("caustic: {}", f.message);
            ExitCode::from(f.code)
        }
    }
}

/// Flags as `--name value` pairs and bare switches, after positional arguments.
struct Flags<'a> {
    args: &'a [String],
    used: Vec<bool>,
}

impl<'a> Flags<'a> {
    fn new(args: &'a [String]) -> Self {
        Self {
            args,
            used: vec![false; args.len()],
        }
    }

    fn switch(&mut self, name: &str) -> bool {
        match self.args.iter().position(|a| a == name) {
            Some(i) => {
                self.used[i] = true;
                true
            }
            None => false,
        }
    }

    fn value<T: std::str::FromStr>(&mut self, names: &[&str]) -> Result<Option<T>, Failure> {
        let Some(i) = self.args.iter().position(|a| names.contains(&a.as_str())) else {
            return Ok(None);
        };
        self.used[i] = true;
        let v = self
            .args
            .get(i + 1)
            .ok_or_else(|| bad_input(format!("{} needs a value", names[0])))?;
        self.used[i + 1] = true;
        v.parse()
            .map(Some)
            .map_err(|_| bad_input(format!("{}: cannot parse \"{v}\"", names[0])))
    }

    /// The positional arguments left, or an error naming an unknown flag.
    fn positional(self) -> Result<Vec<&'a String>, Failure> {
        let mut out = Vec::new();
        for (a, used) in self.args.iter().zip(self.used) {
            if used {
                continue;
            }
            if a.starts_with("--") || (a.starts_with('-') && a.len() > 1) {
                return Err(bad_input(format!("unknown option {a}\n{USAGE}")));
            }
            out.push(a);
        }
        Ok(out)
    }
}

fn cmd_render(args: &[String]) -> Result<(), Failure> {
    let t0 = Instant::now();
    let mut f = Flags::new(args);
    let out: Option<PathBuf> = f.value(&["-o", "--output"])?;
    let pfm: Option<PathBuf> = f.value(&["--pfm"])?;
    let width: Option<u32> = f.value(&["--width"])?;
    let height: Option<u32> = f.value(&["--height"])?;
    let photons: Option<u32> = f.value(&["--photons"])?;
    let k: Option<u32> = f.value(&["--k"])?;
    let radius: Option<f32> = f.value(&["--radius"])?;
    let max_depth: Option<u32> = f.value(&["--max-depth"])?;
    let passes: Option<u32> = f.value(&["--passes"])?;
    let alpha: Option<f32> = f.value(&["--alpha"])?;
    let cone: Option<f32> = f.value(&["--cone-filter"])?;
    let seed: u64 = f.value(&["--seed"])?.unwrap_or(0);
    let threads: Option<usize> = f.value(&["--threads"])?;
    let exposure: f32 = f.value(&["--exposure"])?.unwrap_or(1.0);
    let supersample: Option<u32> = f.value(&["--supersample"])?;
    let sampling: Option<String> = f.value(&["--sampling"])?;
    let splat: Option<String> = f.value(&["--splat"])?;
    let emit: Option<String> = f.value(&["--emit"])?;
    let gather: Option<String> = f.value(&["--gather"])?;
    let store: Option<String> = f.value(&["--store"])?;
    let texel_size: Option<f32> = f.value(&["--texel-size"])?;
    let want_stats = f.switch("--stats");
    let quiet = f.switch("--quiet");
    let pos = f.positional()?;
    let [scene_path] = pos.as_slice() else {
        return Err(bad_input(format!("render takes one scene file\n{USAGE}")));
    };
    if out.is_none() && pfm.is_none() {
        return Err(bad_input("render needs -o OUT.png and/or --pfm OUT.pfm"));
    }
    let tone = ToneMap::new(exposure).map_err(|e| bad_input(format!("--exposure: {e}")))?;

    let loaded =
        load_scene(scene_path.as_ref()).map_err(|e| bad_input(format!("{scene_path}: {e}")))?;
    let mut scene = loaded.scene;
    if width.is_some() || height.is_some() {
        let c = scene.camera();
        let (w, h) = (width.unwrap_or(c.width()), height.unwrap_or(c.height()));
        scene.set_camera(
            c.with_size(w, h)
                .map_err(|e| bad_input(format!("--width/--height: {e}")))?,
        );
    }
    let p = loaded.photons;
    let settings = PhotonSettings::new(
        photons.unwrap_or(p.count()),
        k.unwrap_or(p.k()),
        radius.unwrap_or(p.max_radius()),
        max_depth.unwrap_or(p.max_depth()),
    )
    .map_err(|e| bad_input(format!("photon flags: {e}")))?;
    let cone = match cone {
        Some(kc) => {
            Some(ConeFilter::new(kc).ok_or_else(|| bad_input("--cone-filter must be ≥ 1"))?)
        }
        None => None,
    };
    let fixed_radius = match gather.as_deref() {
        None => p.fixed_radius(),
        Some("nearest") => false,
        Some("radius") => true,
        Some(other) => {
            return Err(bad_input(format!(
                "--gather takes nearest or radius, not {other}"
            )))
        }
    };
    let full_sphere = match emit.as_deref() {
        None | Some("cones") => false,
        Some("sphere") => true,
        Some(other) => {
            return Err(bad_input(format!(
                "--emit takes cones or sphere, not {other}"
            )))
        }
    };
    let splat = match splat.as_deref() {
        None | Some("on") => true,
        Some("off") => false,
        Some(other) => return Err(bad_input(format!("--splat takes on or off, not {other}"))),
    };
    let refine = supersample.unwrap_or(caustic::render::REFINE);
    let sampling = match sampling.as_deref() {
        None if supersample.is_some() => Sampling::Grid(refine),
        None | Some("adaptive") => Sampling::Adaptive(refine),
        Some("centre") | Some("center") => Sampling::Centre,
        Some("grid") => Sampling::Grid(refine),
        Some(other) => {
            return Err(bad_input(format!(
                "--sampling takes adaptive, centre or grid, not {other}"
            )))
        }
    };
    let settings = settings
        .with_cone_filter(cone)
        .with_full_sphere(full_sphere)
        .with_fixed_radius(fixed_radius)
        .with_camera_splats(splat);
    let alpha = alpha.unwrap_or(loaded.alpha);
    if !(alpha > 0.0 && alpha < 1.0) {
        return Err(bad_input("--alpha must lie in (0, 1)"));
    }
    let opts = RenderOptions {
        seed,
        threads: threads
            .unwrap_or_else(caustic::desktop::run::available_threads)
            .max(1),
        progress: !quiet,
        passes: passes.unwrap_or(loaded.passes).max(1),
        alpha,
        sampling,
    };
    let parse_ms = t0.elapsed().as_secs_f64() * 1e3;
    // The caustic store: --store, else the scene file's; illumination maps take
    // --texel-size, else the file's texel_size, else 0.05.
    let file_texel = match loaded.caustic_store {
        StoreChoice::IlluminationMap { texel_size } => Some(texel_size),
        StoreChoice::KdTree => None,
    };
    let illum = match store.as_deref() {
        Some("kd") => None,
        Some("illum") => Some(texel_size.or(file_texel).unwrap_or(0.05)),
        Some(other) => return Err(bad_input(format!("--store: \"{other}\" (kd or illum)"))),
        None => file_texel.map(|t| texel_size.unwrap_or(t)),
    };
    if illum.is_none() && texel_size.is_some() {
        return Err(bad_input("--texel-size needs --store illum"));
    }
    let (image, stats, map_stats) = match illum {
        None => render(&scene, &settings, &opts).map(|(i, s)| (i, s, None)),
        Some(t) => {
            render_illumination(&scene, &settings, &opts, t).map(|(i, s, m)| (i, s, Some((t, m))))
        }
    }
    .map_err(|e| bad_input(e.to_string()))?;
    let t_write = Instant::now();
    if let Some(path) = &out {
        image.write_png(path, &tone).map_err(|e| Failure {
            code: 1,
            message: format!("{}: {e}", path.display()),
        })?;
    }
    if let Some(path) = &pfm {
        image.write_pfm(path).map_err(|e| Failure {
            code: 1,
            message: format!("{}: {e}", path.display()),
        })?;
    }
    let write_ms = t_write.elapsed().as_secs_f64() * 1e3;
    if want_stats {
        println!(
            "{}",
            illum_json(
                stats_json(&stats, parse_ms, write_ms, t0.elapsed().as_secs_f64() * 1e3),
                map_stats
            )
        );
    }
    Ok(())
}

/// Adds `"store"` (and the illumination maps' texels and dropped photons) to the stats.
fn illum_json(mut json: String, maps: Option<(f32, MapStats)>) -> String {
    json.pop(); // the closing brace
    match maps {
        None => json += ",\"store\":\"kd\"}",
        Some((t, m)) => {
            json += &format!(
                concat!(
                    ",\"store\":\"illum\",\"illumination\":{{\"texel_size\":{},\"texels\":{},",
                    "\"bytes\":{},\"objects\":{},\"dropped_photons\":{}}}}}"
                ),
                t,
                m.texels,
                m.texels * std::mem::size_of::<caustic::math::Rgb>(),
                m.mapped_objects,
                m.dropped_photons
            )
        }
    }
    json
}

fn stats_json(s: &RenderStats, parse_ms: f64, write_ms: f64, total_ms: f64) -> String {
    format!(
        concat!(
            "{{\"width\":{},\"height\":{},\"threads\":{},\"passes\":{},",
            "\"time_ms\":{{\"parse\":{:.3},\"emit\":{:.3},\"balance\":{:.3},\"render\":{:.3},",
            "\"gather_cpu\":{:.3},\"write\":{:.3},\"total\":{:.3}}},",
            "\"rays\":{{\"eye\":{},\"shadow\":{},\"refined_pixels\":{}}},",
            "\"photons\":{{\"emitted\":{},\"stored\":{},\"splatted\":{}}}}}"
        ),
        s.width,
        s.height,
        s.threads,
        s.passes,
        parse_ms,
        s.emit_ms,
        s.balance_ms,
        s.render_ms,
        s.gather_cpu_ms,
        write_ms,
        total_ms,
        s.rays.eye,
        s.rays.shadow,
        s.rays.refined,
        s.photons_emitted,
        s.photons_stored,
        s.photons_splatted
    )
}

fn cmd_compare(args: &[String]) -> Result<(), Failure> {
    let mut f = Flags::new(args);
    let mask_path: Option<PathBuf> = f.value(&["--mask"])?;
    let fraction: f32 = f.value(&["--mask-fraction"])?.unwrap_or(0.1);
    let bin: u32 = f.value(&["--bin"])?.unwrap_or(1);
    let pos = f.positional()?;
    let [a, b] = pos.as_slice() else {
        return Err(bad_input(format!("compare takes two PFM files\n{USAGE}")));
    };
    let read = |p: &String| Image::read_pfm(p.as_ref()).map_err(|e| bad_input(e.to_string()));
    let (a, b) = (read(a)?.binned(bin), read(b)?.binned(bin));
    if (a.width, a.height) != (b.width, b.height) {
        return Err(bad_input(format!(
            "sizes differ: {}×{} vs {}×{}",
            a.width, a.height, b.width, b.height
        )));
    }
    let full = compare(&a, &b, None).ok_or_else(|| bad_input("empty images"))?;
    let mut json = format!(
        "{{\"rel_rmse\":{:.6},\"rel_mae\":{:.6},\"pixels\":{}",
        full.rel_rmse, full.rel_mae, full.pixels
    );
    if let Some(m) = mask_path {
        let m = Image::read_pfm(&m)
            .map_err(|e| bad_input(e.to_string()))?
            .binned(bin);
        if (m.width, m.height) != (a.width, a.height) {
            return Err(bad_input("the mask's size differs from the images'"));
        }
        let mask = mask_above(&m, fraction);
        match compare(&a, &b, Some(&mask)) {
            Some(e) => {
                json += &format!(
                    ",\"mask\":{{\"rel_rmse\":{:.6},\"rel_mae\":{:.6},\"pixels\":{}}}",
                    e.rel_rmse, e.rel_mae, e.pixels
                )
            }
            None => json += ",\"mask\":null",
        }
    }
    println!("{json}}}");
    Ok(())
}

//! `caustic render`: every check before any work, then the render, the files and the
//! statistics.

use std::path::{Path, PathBuf};
use std::time::Instant;

use caustic::desktop::cli::RenderArgs;
use caustic::desktop::image::{check_writable, Format, Image};
use caustic::desktop::run::render_illumination;
use caustic::desktop::{
    load_scene, render_with_error, ErrorEstimate, LoadedScene, RenderStats, Rendered, SceneError,
    StoreChoice,
};
use caustic::photon::MapStats;
use caustic::raster::ToneMap;
use serde::Serialize;

use crate::{bad_input, Failure};

/// The files to write and their formats, each checked writable before any work.
fn outputs(args: &RenderArgs) -> Result<Vec<(PathBuf, Format)>, Failure> {
    let mut out = Vec::new();
    if let Some(p) = &args.output {
        let f = Format::of(p, args.exr_precision).map_err(|e| bad_input(format!("-o {e}")))?;
        out.push((p.clone(), f));
    }
    if let Some(p) = &args.pfm {
        out.push((p.clone(), Format::Pfm));
    }
    if out.is_empty() {
        return Err(bad_input(
            "render needs -o FILE (.png, .pfm or .exr) and/or --pfm FILE.pfm",
        ));
    }
    let error_map = args.error_map.iter().map(|p| (p.clone(), Format::Pfm));
    for (p, _) in out.iter().cloned().chain(error_map) {
        check_writable(&p).map_err(|e| bad_input(format!("{}: cannot write: {e}", p.display())))?;
    }
    Ok(out)
}

/// A settings error: a flag's stands alone, a JSON path's is prefixed with the file.
fn settings_error(scene: &Path, e: SceneError) -> Failure {
    if e.path.starts_with('-') {
        bad_input(e.to_string())
    } else {
        bad_input(format!("{}: {e}", scene.display()))
    }
}

/// The scene file with the flags laid over it, validated.
fn scene(args: &RenderArgs) -> Result<LoadedScene, Failure> {
    let loaded = load_scene(&args.scene).map_err(|e| settings_error(&args.scene, e))?;
    loaded
        .with_overrides(&args.input())
        .map_err(|e| settings_error(&args.scene, e))
}

pub fn run(args: &RenderArgs) -> Result<(), Failure> {
    let t0 = Instant::now();
    let outputs = outputs(args)?;
    let tone = ToneMap::new(args.exposure).map_err(|e| bad_input(format!("--exposure: {e}")))?;
    let loaded = scene(args)?;
    let settings = args.photons.finish(loaded.photons);
    let opts = args.options(&loaded);
    let parse_ms = ms(t0);
    let (rendered, maps) = match loaded.caustic_store {
        StoreChoice::KdTree => {
            render_with_error(&loaded.scene, &settings, &opts).map(|r| (r, None))
        }
        StoreChoice::IlluminationMap { texel_size: t } => {
            render_illumination(&loaded.scene, &settings, &opts, t).map(|(r, m)| (r, Some((t, m))))
        }
    }
    .map_err(|e| bad_input(e.to_string()))?;
    let Rendered {
        image,
        error,
        stats,
    } = rendered;
    let t_write = Instant::now();
    write(&image, &outputs, &tone)?;
    if let Some(path) = &args.error_map {
        error.write(path, Format::Pfm, &tone).map_err(|e| Failure {
            code: 1,
            message: format!("{}: {e}", path.display()),
        })?;
    }
    if let Some(target) = stats.error.target {
        let reached = stats.error.rel_rmse.unwrap_or(0.0);
        let why = if stats.error.reached == Some(true) {
            "reached"
        } else if stats.error.time_limited {
            "time limit"
        } else {
            "pass limit"
        };
        eprintln!(
            "target error {target}: estimated relative RMSE {reached:.4} after {} passes ({why})",
            stats.passes
        );
    }
    if args.stats {
        let times = Times {
            parse: parse_ms,
            emit: stats.emit_ms,
            balance: stats.balance_ms,
            render: stats.render_ms,
            gather_cpu: stats.gather_cpu_ms,
            write: ms(t_write),
            total: ms(t0),
        };
        let json = serde_json::to_string(&Stats::new(&stats, times, maps))
            .map_err(|e| bad_input(format!("cannot write JSON: {e}")))?;
        println!("{json}");
    }
    Ok(())
}

fn write(image: &Image, outputs: &[(PathBuf, Format)], tone: &ToneMap) -> Result<(), Failure> {
    for (path, format) in outputs {
        image.write(path, *format, tone).map_err(|e| Failure {
            code: 1,
            message: format!("{}: {e}", path.display()),
        })?;
    }
    Ok(())
}

fn ms(since: Instant) -> f64 {
    since.elapsed().as_secs_f64() * 1e3
}

/// `--stats`: one JSON object. Non-finite numbers would be written as `null`.
#[derive(Serialize)]
struct Stats {
    width: u32,
    height: u32,
    threads: usize,
    passes: u32,
    time_ms: Times,
    rays: Rays,
    photons: Photons,
    store: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    illumination: Option<Maps>,
    error_estimate: ErrorEstimate,
}

/// Milliseconds per phase (`gather_cpu` summed over threads).
#[derive(Serialize)]
struct Times {
    parse: f64,
    emit: f64,
    balance: f64,
    render: f64,
    gather_cpu: f64,
    write: f64,
    total: f64,
}

#[derive(Serialize)]
struct Rays {
    eye: u64,
    shadow: u64,
    /// Pixels whose corners disagreed and were supersampled.
    refined_pixels: u64,
    /// Gathers whose photons were averaged over a patch widened far past their own.
    widened_gathers: u64,
}

#[derive(Serialize)]
struct Photons {
    emitted: u64,
    stored: u64,
    /// Photons the camera sees directly, light-traced into their pixels.
    splatted: u64,
}

/// What the illumination maps held.
#[derive(Serialize)]
struct Maps {
    texel_size: f32,
    texels: usize,
    bytes: usize,
    objects: usize,
    dropped_photons: u64,
    /// The most texels the maps may hold.
    texel_budget: usize,
    /// Texels the layout would have needed at the asked texel size.
    requested_texels: f64,
    /// Objects whose texels were made coarser to fit the budget.
    coarsened_objects: usize,
    /// The coarsest texel side chosen, scene units.
    largest_texel: f32,
}

impl Stats {
    fn new(s: &RenderStats, time_ms: Times, maps: Option<(f32, MapStats)>) -> Self {
        Self {
            width: s.width,
            height: s.height,
            threads: s.threads,
            passes: s.passes,
            time_ms,
            rays: Rays {
                eye: s.rays.eye,
                shadow: s.rays.shadow,
                refined_pixels: s.rays.refined,
                widened_gathers: s.rays.widened,
            },
            photons: Photons {
                emitted: s.photons_emitted,
                stored: s.photons_stored,
                splatted: s.photons_splatted,
            },
            store: if maps.is_some() { "illum" } else { "kd" },
            illumination: maps.map(|(t, m)| Maps {
                texel_size: t,
                texels: m.texels,
                bytes: m.texels * std::mem::size_of::<caustic::math::Rgb>(),
                objects: m.mapped_objects,
                dropped_photons: m.dropped_photons,
                texel_budget: m.texel_budget,
                requested_texels: m.requested_texels,
                coarsened_objects: m.coarsened_objects,
                largest_texel: m.largest_texel,
            }),
            error_estimate: s.error,
        }
    }
}

//! The command-line arguments of `caustic` and of the simulator example (feature
//! `cli`), as [`clap`] derive structs, so that both programs define each flag once.
//!
//! A flag that a scene file can also set (`--photons`, `--k`, `--passes`, …) becomes a
//! [`SettingsInput`] value from [`Source::Flag`](super::settings::Source::Flag) and is
//! checked by the same validation as the file's key ([`SettingsInput::validate`]):
//! `--passes 0` and `"passes": 0` fail alike, each error naming the flag or the JSON
//! path. Flags of the command line alone (`--threads`, `--supersample`, `--exposure`,
//! …) are checked by clap as they are parsed. Usage errors exit with status 2.

// clap's derives expect the std prelude; this crate is `no_std` with `extern crate std`.
use std::prelude::rust_2021::*;

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use super::image::ExrPrecision;
use super::run::{available_threads, RenderOptions};
use super::settings::{Gather, Given, PhotonInput, SettingsInput, StoreKind};
use super::LoadedScene;
use crate::photon::{ConeFilter, PhotonSettings};
use crate::render::{Sampling, REFINE};

/// How photons leave a point light (`--emit`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum Emit {
    /// Through projection maps: only towards the objects that make caustics.
    #[default]
    Cones,
    /// Over the whole sphere, as the paper does (to measure what the maps save).
    Sphere,
}

/// How each pixel's area is sampled (`--sampling`): see [`Sampling`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum SamplingArg {
    /// The four corners, averaged where they agree; an S×S grid where they do not.
    #[default]
    Adaptive,
    /// One ray through the pixel centre (the paper; a point estimate of the pixel).
    Centre,
    /// An S×S grid of rays in every pixel.
    Grid,
}

/// A number that must be positive and finite.
fn positive_f32(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(v),
        Ok(v) => Err(std::format!("must be a positive number (got {v})")),
        Err(e) => Err(e.to_string()),
    }
}

/// A number of seconds that must be positive and finite.
fn positive_f64(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(v),
        Ok(v) => Err(std::format!("must be a positive number (got {v})")),
        Err(e) => Err(e.to_string()),
    }
}

/// Jensen's cone filter constant, ≥ 1.
fn cone_filter(s: &str) -> Result<ConeFilter, String> {
    let k: f32 = s
        .parse()
        .map_err(|e: core::num::ParseFloatError| e.to_string())?;
    ConeFilter::new(k).ok_or_else(|| std::format!("must be a number ≥ 1 (got {k})"))
}

/// The photon budget and the estimate: the flags `caustic render` and the simulator
/// share. Unset values come from the scene file (or the built-in scene).
#[derive(Args, Clone, Debug, Default, PartialEq)]
pub struct PhotonArgs {
    /// Photons emitted per light [default: the scene's photons.count, else 100000]
    #[arg(long = "photons", value_name = "N")]
    pub count: Option<u32>,
    /// Photons gathered per estimate, 1..=1024 [default: the scene's photons.k, else 64]
    #[arg(long, value_name = "K")]
    pub k: Option<u32>,
    /// Gather radius bound, scene units [default: the scene's photons.max_radius, else 1/40 of the largest caustic object]
    #[arg(long, value_name = "R")]
    pub radius: Option<f32>,
    /// Specular interactions per path, ≤ 32 [default: the scene's photons.max_depth, else 8]
    #[arg(long, value_name = "D")]
    pub max_depth: Option<u32>,
    /// How the kd-tree estimate gathers [default: the scene's photons.gather, else nearest]
    #[arg(long, value_enum, value_name = "HOW")]
    pub gather: Option<Gather>,
    /// How photons leave a light [default: cones]
    #[arg(long, value_enum, value_name = "HOW")]
    pub emit: Option<Emit>,
    /// Jensen's cone filter with constant K ≥ 1 (e.g. 1.1) [default: off]
    #[arg(long, value_name = "K", value_parser = cone_filter)]
    pub cone_filter: Option<ConeFilter>,
    /// Seed of the forward pass
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// Gather at every diffuse hit, as the paper does, instead of light-tracing the caustics the camera sees directly into their pixels
    #[arg(long)]
    pub no_splat: bool,
}

impl PhotonArgs {
    /// The values given as flags, for [`SettingsInput::overridden_by`].
    pub fn input(&self) -> SettingsInput {
        SettingsInput {
            photons: PhotonInput {
                count: self.count.map(Given::flag),
                k: self.k.map(Given::flag),
                max_radius: self.radius.map(Given::flag),
                max_depth: self.max_depth.map(Given::flag),
                gather: self.gather.map(Given::flag),
            },
            ..SettingsInput::default()
        }
    }

    /// Validated `settings` with the flags no scene file sets: the cone filter and the
    /// emission.
    pub fn finish(&self, settings: PhotonSettings) -> PhotonSettings {
        settings
            .with_cone_filter(self.cone_filter.or(settings.cone_filter()))
            .with_full_sphere(self.emit == Some(Emit::Sphere))
            .with_camera_splats(!self.no_splat)
    }
}

/// `caustic render`: everything but the outputs' writing.
#[derive(Args, Clone, Debug, PartialEq)]
pub struct RenderArgs {
    /// The scene file (JSON; see docs/scene-format.md)
    #[arg(value_name = "SCENE.json")]
    pub scene: PathBuf,
    /// Output image, by extension: .png (8-bit sRGB), .pfm or .exr (linear radiance); `-` is refused
    #[arg(short = 'o', long = "output", value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Also write linear radiance as PFM [default: none]
    #[arg(long, value_name = "FILE.pfm")]
    pub pfm: Option<PathBuf>,
    /// Sample type of .exr output
    #[arg(long = "exr", value_enum, value_name = "TYPE", default_value_t = ExrPrecision::Float)]
    pub exr_precision: ExrPrecision,
    /// Image width in pixels [default: the scene's image.width, else 320]
    #[arg(long, value_name = "W")]
    pub width: Option<u32>,
    /// Image height in pixels [default: the scene's image.height, else 240]
    #[arg(long, value_name = "H")]
    pub height: Option<u32>,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub photons: PhotonArgs,
    /// Progressive passes (Knaus & Zwicker 2011), ≥ 1 [default: the scene's photons.passes, else 1]
    #[arg(long, value_name = "P")]
    pub passes: Option<u32>,
    /// Radius shrink exponent of the passes, in (0, 1) [default: the scene's photons.alpha, else 0.6667]
    #[arg(long, value_name = "A")]
    pub alpha: Option<f32>,
    /// Caustic store [default: the scene's photons.caustic_store, else kd]
    #[arg(long, value_enum, value_name = "STORE")]
    pub store: Option<StoreKind>,
    /// Texel side of the illumination maps, scene units [default: the scene's texel_size, else 0.05]
    #[arg(long, value_name = "S")]
    pub texel_size: Option<f32>,
    /// Cap on rays (eye and shadow) per camera ray, ≥ 2 [default: the scene's image.max_rays_per_sample, else 256]
    #[arg(long, value_name = "N")]
    pub max_rays: Option<u32>,
    /// How each pixel's area is sampled
    #[arg(long, value_enum, value_name = "HOW", default_value_t = SamplingArg::Adaptive)]
    pub sampling: SamplingArg,
    /// Side of the sub-pixel grid (S×S rays) of --sampling adaptive and grid, 1..=64
    #[arg(long, value_name = "S", default_value_t = REFINE,
          value_parser = clap::value_parser!(u32).range(1..=64))]
    pub supersample: u32,
    /// Worker threads, ≥ 1 [default: all cores]
    #[arg(long, value_name = "T", value_parser = clap::value_parser!(u64).range(1..=4096))]
    pub threads: Option<u64>,
    /// Exposure of the PNG's tone map, > 0
    #[arg(long, value_name = "E", default_value_t = 1.0, value_parser = positive_f32)]
    pub exposure: f32,
    /// Write the per-pixel estimated error as PFM [default: none]
    #[arg(long, value_name = "FILE.pfm")]
    pub error_map: Option<PathBuf>,
    /// Render passes until the estimated relative RMSE is at most E, > 0 (instead of --photons/--passes)
    #[arg(long, value_name = "E", value_parser = positive_f32,
          conflicts_with_all = ["count", "passes"])]
    pub target_error: Option<f32>,
    /// With --target-error: stop after S seconds, > 0 [default: none]
    #[arg(long, value_name = "S", value_parser = positive_f64, requires = "target_error")]
    pub time_limit: Option<f64>,
    /// Print one JSON object of statistics (times, rays, photons) on stdout
    #[arg(long)]
    pub stats: bool,
    /// No progress bar (it is hidden anyway when stderr is not a terminal)
    #[arg(long, short = 'q')]
    pub quiet: bool,
}

impl RenderArgs {
    /// The flags that a scene file can also set, for [`LoadedScene::with_overrides`].
    pub fn input(&self) -> SettingsInput {
        SettingsInput {
            width: self.width.map(Given::flag),
            height: self.height.map(Given::flag),
            passes: self.passes.map(Given::flag),
            alpha: self.alpha.map(Given::flag),
            store: self.store.map(Given::flag),
            texel_size: self.texel_size.map(Given::flag),
            max_rays: self.max_rays.map(Given::flag),
            ..self.photons.input()
        }
    }

    /// The options of a render of `loaded` (after [`LoadedScene::with_overrides`]).
    pub fn options(&self, loaded: &LoadedScene) -> RenderOptions {
        RenderOptions {
            seed: self.photons.seed,
            threads: self.threads.map_or_else(available_threads, |t| t as usize),
            progress: !self.quiet,
            passes: loaded.passes,
            alpha: loaded.alpha,
            sampling: match self.sampling {
                SamplingArg::Adaptive => Sampling::Adaptive(self.supersample),
                SamplingArg::Centre => Sampling::Centre,
                SamplingArg::Grid => Sampling::Grid(self.supersample),
            },
            max_rays_per_sample: loaded.max_rays_per_sample,
            error_map: self.error_map.clone(),
            target_error: self.target_error,
            time_limit: self.time_limit,
            time_gathers: self.stats,
        }
    }
}

/// `caustic compare`: how far an image is from a reference.
#[derive(Args, Clone, Debug, PartialEq)]
pub struct CompareArgs {
    /// The image to measure (PFM or OpenEXR)
    #[arg(value_name = "IMAGE")]
    pub image: PathBuf,
    /// The reference (PFM or OpenEXR)
    #[arg(value_name = "REFERENCE")]
    pub reference: PathBuf,
    /// Also measure inside a mask: the pixels where this image's luminance exceeds --mask-fraction of its 99.9th percentile [default: none]
    #[arg(long, value_name = "M.pfm")]
    pub mask: Option<PathBuf>,
    /// The mask's threshold, as a fraction of its 99.9th percentile
    #[arg(long, value_name = "F", default_value_t = 0.1)]
    pub mask_fraction: f32,
    /// Compare B×B-binned images (box filter), ≥ 1
    #[arg(long, value_name = "B", default_value_t = 1,
          value_parser = clap::value_parser!(u32).range(1..))]
    pub bin: u32,
}

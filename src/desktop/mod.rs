//! The desktop side (feature `std`): scene files ([`scene_file`]) and the settings
//! they share with the command line ([`settings`], one validation for both), images on
//! disk ([`image`]: PNG, PFM, OpenEXR), threads and progress ([`run`], [`rows`]), and with
//! feature `cli` the command-line arguments of `caustic` and the examples ([`cli`]).
//!
//! It is thin on purpose: everything that decides a pixel's value lives in the no_std
//! core; this module reads files, allocates the photon array on the heap, splits rows
//! among threads, and writes files. Tests, benches and the `caustic` program all come
//! through here, so they run the very same core as the device.

#[cfg(feature = "cli")]
#[cfg_attr(docsrs, doc(cfg(feature = "cli")))]
pub mod cli;
pub mod image;
pub mod photons;
pub mod progress;
pub mod rows;
pub mod run;
pub mod scene_file;
pub mod settings;

pub use image::Image;
pub use run::{render, render_with_error, ErrorEstimate, RenderOptions, RenderStats, Rendered};
pub use scene_file::{load_scene, parse_scene, LoadedScene, SceneError};
pub use settings::{SettingsInput, StoreChoice};

use crate::scene::Scene;

/// Most objects a scene file may hold on the desktop.
pub const MAX_OBJECTS: usize = 64;
/// Most lights a scene file may hold on the desktop.
pub const MAX_LIGHTS: usize = 16;
/// Deepest specular path on the desktop (the path stack's size).
pub const MAX_DEPTH: usize = 32;
/// Most photons one estimate may gather on the desktop.
pub const MAX_GATHER: usize = 1024;
/// Most photons one forward pass may store on the desktop (20 bytes each).
pub const MAX_PHOTONS: usize = 1 << 25;

/// The scene type of the desktop tools.
pub type DesktopScene = Scene<MAX_OBJECTS, MAX_LIGHTS>;

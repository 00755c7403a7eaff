//! The settings a scene file and the command line share — the image size, the photon
//! budget and estimate, the passes, the caustic store, the cap on eye rays — and their
//! one validation.
//!
//! A value passes the same checks and gets the same message whether a JSON key or a
//! flag gave it; only its location differs (`photons.passes: must be at least 1` or
//! `--passes: must be at least 1`). The scene parser reads a file's values into a
//! [`SettingsInput`] and validates it; the `caustic` program lays its flags over the
//! file's input ([`SettingsInput::overridden_by`]) and validates the result again.

use std::format;
use std::string::{String, ToString};

use super::scene_file::SceneError;
use super::{MAX_DEPTH, MAX_GATHER};
use crate::camera::Camera;
use crate::photon::PhotonSettings;
use crate::scene::Scene;
use crate::Error;

/// A setting that a scene file and a flag can both give.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Key {
    /// `image.width`, `--width`.
    Width,
    /// `image.height`, `--height`.
    Height,
    /// `photons.count`, `--photons`.
    Count,
    /// `photons.k`, `--k`.
    K,
    /// `photons.max_radius`, `--radius`.
    MaxRadius,
    /// `photons.max_depth`, `--max-depth`.
    MaxDepth,
    /// `photons.passes`, `--passes`.
    Passes,
    /// `photons.alpha`, `--alpha`.
    Alpha,
    /// `photons.gather`, `--gather`.
    Gather,
    /// `photons.caustic_store.type`, `--store`.
    Store,
    /// `photons.caustic_store.texel_size`, `--texel-size`.
    TexelSize,
    /// `image.max_rays_per_sample`, `--max-rays`.
    MaxRays,
}

impl Key {
    /// The key's JSON path in a scene file.
    pub const fn json_path(self) -> &'static str {
        match self {
            Key::Width => "image.width",
            Key::Height => "image.height",
            Key::Count => "photons.count",
            Key::K => "photons.k",
            Key::MaxRadius => "photons.max_radius",
            Key::MaxDepth => "photons.max_depth",
            Key::Passes => "photons.passes",
            Key::Alpha => "photons.alpha",
            Key::Gather => "photons.gather",
            Key::Store => "photons.caustic_store.type",
            Key::TexelSize => "photons.caustic_store.texel_size",
            Key::MaxRays => "image.max_rays_per_sample",
        }
    }

    /// The key's flag on the command line.
    pub const fn flag(self) -> &'static str {
        match self {
            Key::Width => "--width",
            Key::Height => "--height",
            Key::Count => "--photons",
            Key::K => "--k",
            Key::MaxRadius => "--radius",
            Key::MaxDepth => "--max-depth",
            Key::Passes => "--passes",
            Key::Alpha => "--alpha",
            Key::Gather => "--gather",
            Key::Store => "--store",
            Key::TexelSize => "--texel-size",
            Key::MaxRays => "--max-rays",
        }
    }
}

/// Where a value was given.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// A scene file (or a program's built-in scene).
    File,
    /// A flag on the command line.
    Flag,
}

/// A value and where it was given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Given<T> {
    /// The value.
    pub value: T,
    /// Where it was given.
    pub source: Source,
}

impl<T> Given<T> {
    /// A value from a scene file.
    pub fn file(value: T) -> Self {
        Self {
            value,
            source: Source::File,
        }
    }

    /// A value from a flag.
    pub fn flag(value: T) -> Self {
        Self {
            value,
            source: Source::Flag,
        }
    }
}

/// A key's location as its source names it: the flag or the JSON path.
fn location(key: Key, source: Source) -> &'static str {
    match source {
        Source::File => key.json_path(),
        Source::Flag => key.flag(),
    }
}

/// An error at `key` as given by `source`.
fn key_err(key: Key, source: Source, message: impl Into<String>) -> SceneError {
    SceneError {
        path: location(key, source).to_string(),
        message: message.into(),
    }
}

/// What is wrong with a value, without the core's name for it (the location names it).
pub(crate) fn problem(e: &Error) -> String {
    match *e {
        Error::NotFinite { .. } => "must be a finite number".to_string(),
        Error::NotPositive { value, .. } => format!("must be positive (got {value})"),
        Error::OutOfRange {
            value, min, max, ..
        } => format!("must lie in [{min}, {max}] (got {value})"),
        Error::Capacity {
            requested,
            capacity,
            ..
        } => format!("{requested} requested but the compiled capacity is {capacity}"),
        _ => e.to_string(),
    }
}

/// How a kd-tree estimate gathers photons (`photons.gather`, `--gather`).
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Gather {
    /// The k nearest photons within the radius.
    #[default]
    Nearest,
    /// Every photon within the radius.
    Radius,
}

/// Which caustic store (`photons.caustic_store.type`, `--store`).
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StoreKind {
    /// The photon kd-tree (`kd_tree` in a file).
    #[default]
    Kd,
    /// Arvo's illumination maps (`illumination_map` in a file).
    Illum,
}

/// Which caustic store renders the caustics, validated.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum StoreChoice {
    /// `{ "type": "kd_tree" }`: the photon kd-tree and its k-nearest estimate (default).
    #[default]
    KdTree,
    /// `{ "type": "illumination_map", "texel_size": s }`: Arvo's illumination maps with
    /// texels of side `s` scene units (the paper's "scale").
    IlluminationMap {
        /// World length of a texel's side, > 0.
        texel_size: f32,
    },
}

/// Default photons per light.
pub const DEFAULT_COUNT: u32 = 100_000;
/// Default photons per estimate.
pub const DEFAULT_K: u32 = 64;
/// Default specular interactions per path.
pub const DEFAULT_MAX_DEPTH: u32 = 8;
/// Default progressive passes.
pub const DEFAULT_PASSES: u32 = 1;
/// Default radius shrink exponent α of the passes.
pub const DEFAULT_ALPHA: f32 = 2.0 / 3.0;
/// Default texel side of `--store illum` when neither flag nor file gives one.
pub const DEFAULT_TEXEL_SIZE: f32 = 0.05;

/// The shared settings before validation: each value if given, and where.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SettingsInput {
    /// Image width in pixels.
    pub width: Option<Given<u32>>,
    /// Image height in pixels.
    pub height: Option<Given<u32>>,
    /// The photon budget and estimate.
    pub photons: PhotonInput,
    /// Progressive passes.
    pub passes: Option<Given<u32>>,
    /// Radius shrink exponent of the passes.
    pub alpha: Option<Given<f32>>,
    /// The caustic store.
    pub store: Option<Given<StoreKind>>,
    /// The illumination maps' texel side.
    pub texel_size: Option<Given<f32>>,
    /// The cap on rays per camera ray.
    pub max_rays: Option<Given<u32>>,
}

/// The settings of [`PhotonSettings::new`] and its gather before validation: each value
/// if given, and where.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhotonInput {
    /// Photons emitted per light.
    pub count: Option<Given<u32>>,
    /// Photons per estimate.
    pub k: Option<Given<u32>>,
    /// Gather radius bound.
    pub max_radius: Option<Given<f32>>,
    /// Specular interactions per path.
    pub max_depth: Option<Given<u32>>,
    /// How the kd-tree estimate gathers.
    pub gather: Option<Given<Gather>>,
}

/// The shared settings, validated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// The camera at the image size asked for.
    pub camera: Camera,
    /// The photon budget and estimate (no cone filter, projection-map emission).
    pub photons: PhotonSettings,
    /// Progressive passes, ≥ 1.
    pub passes: u32,
    /// Radius shrink exponent, in (0, 1).
    pub alpha: f32,
    /// The caustic store.
    pub caustic_store: StoreChoice,
    /// The cap on rays (eye and shadow) per camera ray, if any.
    pub max_rays_per_sample: Option<u32>,
}

impl SettingsInput {
    /// The values of `settings` as if a file had given them (a program's built-in scene).
    pub fn of(settings: &PhotonSettings) -> Self {
        Self {
            photons: PhotonInput::of(settings),
            ..Self::default()
        }
    }

    /// `self` with every value that `over` gives replaced by it.
    pub fn overridden_by(&self, over: &SettingsInput) -> Self {
        Self {
            width: over.width.or(self.width),
            height: over.height.or(self.height),
            photons: self.photons.overridden_by(&over.photons),
            passes: over.passes.or(self.passes),
            alpha: over.alpha.or(self.alpha),
            store: over.store.or(self.store),
            texel_size: over.texel_size.or(self.texel_size),
            max_rays: over.max_rays.or(self.max_rays),
        }
    }

    /// Validates the settings for `scene`: its camera resized to `width × height` (when
    /// they differ from it), defaults for what is not given (the gather radius from
    /// [`default_radius`]), every value checked against the core's constructors and the
    /// desktop's capacities. An error names the flag or the JSON path of the value.
    pub fn validate<const O: usize, const L: usize>(
        &self,
        scene: &Scene<O, L>,
    ) -> Result<Settings, SceneError> {
        Ok(Settings {
            camera: self.camera(scene.camera())?,
            photons: self.photons.validate(|| default_radius(scene))?,
            passes: self.passes()?,
            alpha: self.alpha()?,
            caustic_store: self.store()?,
            max_rays_per_sample: self.max_rays()?,
        })
    }

    fn camera(&self, camera: &Camera) -> Result<Camera, SceneError> {
        let w = self.width.map_or(camera.width(), |g| g.value);
        let h = self.height.map_or(camera.height(), |g| g.value);
        if (w, h) == (camera.width(), camera.height()) {
            return Ok(*camera);
        }
        camera.with_size(w, h).map_err(|e| {
            let (key, given) = match e {
                Error::OutOfRange {
                    what: "image height",
                    ..
                } => (Key::Height, self.height),
                _ => (Key::Width, self.width),
            };
            key_err(key, given.map_or(Source::File, |g| g.source), problem(&e))
        })
    }

    fn passes(&self) -> Result<u32, SceneError> {
        match self.passes {
            None => Ok(DEFAULT_PASSES),
            Some(g) if g.value == 0 => Err(key_err(Key::Passes, g.source, "must be at least 1")),
            Some(g) => Ok(g.value),
        }
    }

    fn alpha(&self) -> Result<f32, SceneError> {
        match self.alpha {
            None => Ok(DEFAULT_ALPHA),
            Some(g) if !(g.value > 0.0 && g.value < 1.0) => Err(key_err(
                Key::Alpha,
                g.source,
                format!("must lie in (0, 1) (got {})", g.value),
            )),
            Some(g) => Ok(g.value),
        }
    }

    /// The store: `--store`/`type`, with `--texel-size`/`texel_size` (default
    /// [`DEFAULT_TEXEL_SIZE`]) for illumination maps; a texel size given by a flag
    /// for the kd-tree is an error, one left in the file is ignored.
    fn store(&self) -> Result<StoreChoice, SceneError> {
        match (self.store.map(|g| g.value), self.texel_size) {
            (Some(StoreKind::Illum), t) => {
                let t = t.unwrap_or(Given::file(DEFAULT_TEXEL_SIZE));
                if !(t.value > 0.0 && t.value.is_finite()) {
                    return Err(key_err(
                        Key::TexelSize,
                        t.source,
                        format!("must be a positive number (got {})", t.value),
                    ));
                }
                Ok(StoreChoice::IlluminationMap {
                    texel_size: t.value,
                })
            }
            (_, Some(t)) if t.source == Source::Flag => Err(key_err(
                Key::TexelSize,
                Source::Flag,
                "needs the illumination maps (--store illum)",
            )),
            _ => Ok(StoreChoice::KdTree),
        }
    }

    fn max_rays(&self) -> Result<Option<u32>, SceneError> {
        match self.max_rays {
            Some(g) if g.value == 0 => Err(key_err(Key::MaxRays, g.source, "must be at least 1")),
            g => Ok(g.map(|g| g.value)),
        }
    }
}

impl PhotonInput {
    /// The values of `settings` as if a file had given them.
    fn of(settings: &PhotonSettings) -> Self {
        let gather = if settings.fixed_radius() {
            Gather::Radius
        } else {
            Gather::Nearest
        };
        Self {
            count: Some(Given::file(settings.count())),
            k: Some(Given::file(settings.k())),
            max_radius: Some(Given::file(settings.max_radius())),
            max_depth: Some(Given::file(settings.max_depth())),
            gather: Some(Given::file(gather)),
        }
    }

    /// `self` with every value that `over` gives replaced by it.
    fn overridden_by(&self, over: &PhotonInput) -> Self {
        Self {
            count: over.count.or(self.count),
            k: over.k.or(self.k),
            max_radius: over.max_radius.or(self.max_radius),
            max_depth: over.max_depth.or(self.max_depth),
            gather: over.gather.or(self.gather),
        }
    }

    /// Validates the values against the core's constructor and the desktop's
    /// capacities, with `default_radius` when no radius is given.
    fn validate(&self, default_radius: impl FnOnce() -> f32) -> Result<PhotonSettings, SceneError> {
        let value = |g: Option<Given<u32>>, default: u32| g.map_or(default, |g| g.value);
        let source = |g: Option<Given<u32>>| g.map_or(Source::File, |g| g.source);
        let k = value(self.k, DEFAULT_K);
        let max_depth = value(self.max_depth, DEFAULT_MAX_DEPTH);
        let radius = self.max_radius.map_or_else(default_radius, |g| g.value);
        let settings = PhotonSettings::new(value(self.count, DEFAULT_COUNT), k, radius, max_depth)
            .map_err(|e| {
                // The core's labels of `PhotonSettings::new`, matched exactly.
                let (key, src) = match e {
                    Error::NotPositive {
                        what: "photons.k", ..
                    } => (Key::K, source(self.k)),
                    Error::OutOfRange {
                        what: "photons.max_depth",
                        ..
                    } => (Key::MaxDepth, source(self.max_depth)),
                    _ => (
                        Key::MaxRadius,
                        self.max_radius.map_or(Source::File, |g| g.source),
                    ),
                };
                key_err(key, src, problem(&e))
            })?;
        if k as usize > MAX_GATHER {
            return Err(key_err(
                Key::K,
                source(self.k),
                format!("{k} exceeds the gather capacity {MAX_GATHER}"),
            ));
        }
        if max_depth as usize > MAX_DEPTH {
            return Err(key_err(
                Key::MaxDepth,
                source(self.max_depth),
                format!("{max_depth} exceeds the path stack capacity {MAX_DEPTH}"),
            ));
        }
        let fixed = self.gather.is_some_and(|g| g.value == Gather::Radius);
        Ok(settings.with_fixed_radius(fixed))
    }
}

/// A gather radius for scenes that give none: a fortieth of the largest caustic
/// object's bounding radius (scales with the scene), or 1/100 of the camera's distance
/// from the origin when there is no bounded caustic object.
pub fn default_radius<const O: usize, const L: usize>(scene: &Scene<O, L>) -> f32 {
    let r = scene
        .objects()
        .iter()
        .filter(|o| o.material.is_specular())
        .filter_map(|o| o.shape.bounding_sphere())
        .map(|b| b.radius)
        .fold(0.0, f32::max);
    if r > 0.0 {
        r / 40.0
    } else {
        let d = scene.camera().position().length();
        if d > 0.0 {
            0.01 * d
        } else {
            0.01
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    fn scene() -> Scene<1, 1> {
        let camera = Camera::new(Vec3::new(0.0, 1.0, 5.0), Vec3::ZERO, Vec3::Y, 40.0, 32, 24);
        Scene::new(camera.unwrap())
    }

    /// A flag and the file's key fail the same check with the same message; only the
    /// location differs.
    #[test]
    fn a_flag_and_a_key_get_the_same_message() {
        fn g<T>(value: T, source: Source) -> Option<Given<T>> {
            Some(Given { value, source })
        }
        let cases: [fn(&mut SettingsInput, Source); 9] = [
            |s, src| s.passes = g(0, src),
            |s, src| s.photons.k = g(0, src),
            |s, src| s.photons.k = g(5000, src),
            |s, src| s.photons.max_depth = g(40, src),
            |s, src| s.photons.max_depth = g(999, src),
            |s, src| {
                s.photons.max_radius = Some(Given {
                    value: -1.0,
                    source: src,
                })
            },
            |s, src| {
                s.alpha = Some(Given {
                    value: 1.0,
                    source: src,
                })
            },
            |s, src| s.width = g(0, src),
            |s, src| s.max_rays = g(0, src),
        ];
        for (i, set) in cases.into_iter().enumerate() {
            let (mut file, mut flag) = (SettingsInput::default(), SettingsInput::default());
            set(&mut file, Source::File);
            set(&mut flag, Source::Flag);
            let a = file.validate(&scene()).expect_err("file");
            let b = flag.validate(&scene()).expect_err("flag");
            assert_eq!(a.message, b.message, "case {i}");
            assert!(
                a.path.contains('.') && b.path.starts_with("--"),
                "{a} / {b}"
            );
        }
    }

    /// A flag replaces the file's value and keeps the rest (the gather choice
    /// survives `--photons`).
    #[test]
    fn flags_override_only_what_they_give() {
        let file = SettingsInput {
            photons: PhotonInput {
                count: Some(Given::file(10)),
                gather: Some(Given::file(Gather::Radius)),
                max_radius: Some(Given::file(0.5)),
                ..PhotonInput::default()
            },
            ..SettingsInput::default()
        };
        let flags = SettingsInput {
            photons: PhotonInput {
                count: Some(Given::flag(20)),
                ..PhotonInput::default()
            },
            ..SettingsInput::default()
        };
        let s = file.overridden_by(&flags).validate(&scene()).unwrap();
        assert_eq!(s.photons.count(), 20);
        assert!(s.photons.fixed_radius());
        assert_eq!(s.photons.max_radius(), 0.5);
        assert_eq!((s.passes, s.caustic_store), (1, StoreChoice::KdTree));
    }

    #[test]
    fn texel_size_needs_the_maps_only_when_a_flag_gives_it() {
        let t = |source| SettingsInput {
            texel_size: Some(Given { value: 0.1, source }),
            ..SettingsInput::default()
        };
        let e = t(Source::Flag).validate(&scene()).unwrap_err();
        assert_eq!(e.path, "--texel-size");
        assert_eq!(t(Source::File).store(), Ok(StoreChoice::KdTree));
        let illum = SettingsInput {
            store: Some(Given::flag(StoreKind::Illum)),
            ..SettingsInput::default()
        };
        assert_eq!(
            illum.store(),
            Ok(StoreChoice::IlluminationMap {
                texel_size: DEFAULT_TEXEL_SIZE
            })
        );
    }
}

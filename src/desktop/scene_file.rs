//! Scene files: JSON as in `shared/scene-format.md`, parsed with serde and validated
//! by the core's constructors. Every error names its JSON path and the problem.

use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;
use std::string::{String, ToString};
use std::vec::Vec;
use std::{format, fs};

use serde::de::DeserializeOwned;
use serde::Deserialize;
use serde_json::Value;

use super::{DesktopScene, MAX_LIGHTS, MAX_OBJECTS};
use crate::camera::Camera;
use crate::geometry::Shape;
use crate::light::PointLight;
use crate::material::{Classic, Material};
use crate::math::{Rgb, Vec3};
use crate::photon::PhotonSettings;
use crate::Error;

/// A problem with a scene file: where (a JSON path such as `objects[2].radius`, or
/// the file) and what.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneError {
    /// JSON path of the offending value (empty for the whole document).
    pub path: String,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.path.is_empty() {
            write!(f, "{}", self.message)
        } else {
            write!(f, "{}: {}", self.path, self.message)
        }
    }
}

impl std::error::Error for SceneError {}

fn err(path: impl Into<String>, message: impl Into<String>) -> SceneError {
    SceneError {
        path: path.into(),
        message: message.into(),
    }
}

/// The path of a core error: `base.field` when the error names one of `fields`.
fn core_err(base: &str, e: Error, fields: &[&str]) -> SceneError {
    let what = match e {
        Error::NotFinite { what }
        | Error::NotPositive { what, .. }
        | Error::OutOfRange { what, .. }
        | Error::Degenerate { what }
        | Error::Capacity { what, .. } => what,
    };
    // The first field (in the caller's order of preference) that the message names.
    let field = fields.iter().find(|f| what.contains(*f));
    let path = match field {
        Some(f) if base.is_empty() => f.to_string(),
        Some(f) => format!("{base}.{f}"),
        None => base.to_string(),
    };
    err(path, e.to_string())
}

/// Deserializes `value` as `T`, reporting the full path below `base`.
fn typed<T: DeserializeOwned>(value: &Value, base: &str) -> Result<T, SceneError> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let inner = e.path().to_string();
        let path = match (base.is_empty(), inner.as_str()) {
            (_, ".") => base.to_string(),
            (true, p) => p.to_string(),
            (false, p) if p.starts_with('[') => format!("{base}{p}"),
            (false, p) => format!("{base}.{p}"),
        };
        err(path, e.into_inner().to_string())
    })
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileDoc {
    camera: CameraDef,
    image: Option<ImageDef>,
    background: Option<[f32; 3]>,
    ambient: Option<[f32; 3]>,
    lights: Vec<Value>,
    materials: BTreeMap<String, Value>,
    objects: Vec<Value>,
    photons: Option<PhotonsDef>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraDef {
    position: [f32; 3],
    look_at: [f32; 3],
    up: Option<[f32; 3]>,
    fov_y_deg: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ImageDef {
    width: u32,
    height: u32,
}

/// The scene's `photons` block, all optional.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhotonsDef {
    /// Photons emitted per light.
    pub count: Option<u32>,
    /// Photons per estimate.
    pub k: Option<u32>,
    /// Gather radius bound.
    pub max_radius: Option<f32>,
    /// Specular interactions per path.
    pub max_depth: Option<u32>,
    /// Progressive passes.
    pub passes: Option<u32>,
    /// Radius shrink exponent.
    pub alpha: Option<f32>,
    /// Which caustic store.
    pub caustic_store: Option<Value>,
    /// How the kd-tree estimate gathers photons: `"nearest"` (the k nearest within
    /// `max_radius`, the default) or `"radius"` (every photon within `max_radius`).
    pub gather: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PointLightDef {
    #[serde(rename = "type")]
    _type: String,
    position: [f32; 3],
    intensity: [f32; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DiffuseDef {
    #[serde(rename = "type")]
    _type: String,
    albedo: [f32; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MirrorDef {
    #[serde(rename = "type")]
    _type: String,
    reflectance: Option<[f32; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DielectricDef {
    #[serde(rename = "type")]
    _type: String,
    ior: f32,
    absorption: Option<[f32; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ClassicDef {
    #[serde(rename = "type")]
    _type: String,
    color: [f32; 3],
    ambient: f32,
    diffuse: f32,
    specular: f32,
    shininess: f32,
    reflectivity: f32,
    transparency: f32,
    ior: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PlaneDef {
    #[serde(rename = "type")]
    _type: String,
    point: [f32; 3],
    normal: [f32; 3],
    material: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SphereDef {
    #[serde(rename = "type")]
    _type: String,
    center: [f32; 3],
    radius: f32,
    material: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxDef {
    #[serde(rename = "type")]
    _type: String,
    center: [f32; 3],
    size: [f32; 3],
    rotation_deg: Option<[f32; 3]>,
    material: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CylinderDef {
    #[serde(rename = "type")]
    _type: String,
    base: [f32; 3],
    axis: [f32; 3],
    radius: f32,
    height: f32,
    capped: Option<bool>,
    material: String,
}

/// A scene file, read and validated.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// The scene (camera sized by the file's `image`, default 320×240).
    pub scene: DesktopScene,
    /// The `photons` block, merged with defaults.
    pub photons: PhotonSettings,
    /// Progressive passes (default 1).
    pub passes: u32,
    /// Radius shrink exponent for passes (default 2/3).
    pub alpha: f32,
    /// The caustic store (`photons.caustic_store`), default the kd-tree.
    pub caustic_store: StoreChoice,
}

/// Which caustic store renders the caustics (`photons.caustic_store`).
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

/// The type tag of a JSON object, or an error at `path.type`.
fn type_of<'v>(v: &'v Value, path: &str, allowed: &[&str]) -> Result<&'v str, SceneError> {
    let Some(obj) = v.as_object() else {
        return Err(err(path, "expected an object"));
    };
    match obj.get("type").and_then(Value::as_str) {
        Some(t) if allowed.contains(&t) => Ok(t),
        Some(t) => Err(err(
            format!("{path}.type"),
            format!(
                "unknown type \"{t}\" (expected one of: {})",
                allowed.join(", ")
            ),
        )),
        None => Err(err(format!("{path}.type"), "missing field `type`")),
    }
}

fn v3(a: [f32; 3]) -> Vec3 {
    Vec3::from_array(a)
}

/// Parses and validates a scene from JSON text.
pub fn parse_scene(text: &str) -> Result<LoadedScene, SceneError> {
    let value: Value =
        serde_json::from_str(text).map_err(|e| err("", format!("invalid JSON: {e}")))?;
    let doc: FileDoc = typed(&value, "")?;

    let (w, h) = doc
        .image
        .as_ref()
        .map_or((320, 240), |i| (i.width, i.height));
    let c = &doc.camera;
    let camera = Camera::new(
        v3(c.position),
        v3(c.look_at),
        v3(c.up.unwrap_or([0.0, 1.0, 0.0])),
        c.fov_y_deg,
        w,
        h,
    )
    .map_err(|e| {
        let path = match e {
            Error::OutOfRange {
                what: "image width" | "image height",
                ..
            } => "image",
            _ => "camera",
        };
        core_err(path, e, &["look_at", "position", "up", "fov_y_deg"])
    })?;
    let mut scene = DesktopScene::new(camera);
    if let Some(b) = doc.background {
        scene
            .set_background(Rgb::from_array(b))
            .map_err(|e| core_err("background", e, &[]))?;
    }
    if let Some(a) = doc.ambient {
        scene
            .set_ambient(Rgb::from_array(a))
            .map_err(|e| core_err("ambient", e, &[]))?;
    }

    if doc.lights.len() > MAX_LIGHTS {
        return Err(err(
            "lights",
            format!(
                "{} lights, at most {MAX_LIGHTS} are supported",
                doc.lights.len()
            ),
        ));
    }
    for (i, v) in doc.lights.iter().enumerate() {
        let path = format!("lights[{i}]");
        type_of(v, &path, &["point"])?;
        let l: PointLightDef = typed(v, &path)?;
        let light = PointLight::new(v3(l.position), Rgb::from_array(l.intensity))
            .map_err(|e| core_err(&path, e, &["position", "intensity"]))?;
        scene
            .add_light(light)
            .map_err(|e| core_err(&path, e, &[]))?;
    }

    let mut materials = BTreeMap::new();
    for (name, v) in &doc.materials {
        let path = format!("materials.{name}");
        let fields = [
            "albedo",
            "reflectance",
            "ior",
            "absorption",
            "color",
            "ambient",
            "diffuse",
            "specular",
            "shininess",
            "reflectivity",
            "transparency",
        ];
        let m = match type_of(v, &path, &["diffuse", "mirror", "dielectric", "classic"])? {
            "diffuse" => Material::diffuse(Rgb::from_array(typed::<DiffuseDef>(v, &path)?.albedo)),
            "mirror" => Material::mirror(Rgb::from_array(
                typed::<MirrorDef>(v, &path)?
                    .reflectance
                    .unwrap_or([1.0; 3]),
            )),
            "dielectric" => {
                let d: DielectricDef = typed(v, &path)?;
                Material::dielectric(d.ior, Rgb::from_array(d.absorption.unwrap_or([0.0; 3])))
            }
            _ => {
                let d: ClassicDef = typed(v, &path)?;
                Material::classic(Classic::new(
                    Rgb::from_array(d.color),
                    d.ambient,
                    d.diffuse,
                    d.specular,
                    d.shininess,
                    d.reflectivity,
                    d.transparency,
                    d.ior,
                ))
            }
        }
        .map_err(|e| {
            // "reflectivity + transparency" names two fields: point at the second.
            core_err(&path, e, &fields)
        })?;
        materials.insert(name.clone(), m);
    }

    if doc.objects.len() > MAX_OBJECTS {
        return Err(err(
            "objects",
            format!(
                "{} objects, at most {MAX_OBJECTS} are supported",
                doc.objects.len()
            ),
        ));
    }
    for (i, v) in doc.objects.iter().enumerate() {
        let path = format!("objects[{i}]");
        let (shape, material) = match type_of(v, &path, &["plane", "sphere", "box", "cylinder"])? {
            "plane" => {
                let d: PlaneDef = typed(v, &path)?;
                (Shape::plane(v3(d.point), v3(d.normal)), d.material)
            }
            "sphere" => {
                let d: SphereDef = typed(v, &path)?;
                (Shape::sphere(v3(d.center), d.radius), d.material)
            }
            "box" => {
                let d: BoxDef = typed(v, &path)?;
                (
                    Shape::cuboid(
                        v3(d.center),
                        v3(d.size),
                        v3(d.rotation_deg.unwrap_or([0.0; 3])),
                    ),
                    d.material,
                )
            }
            _ => {
                let d: CylinderDef = typed(v, &path)?;
                (
                    Shape::cylinder(
                        v3(d.base),
                        v3(d.axis),
                        d.radius,
                        d.height,
                        d.capped.unwrap_or(true),
                    ),
                    d.material,
                )
            }
        };
        let shape = shape.map_err(|e| {
            core_err(
                &path,
                e,
                &[
                    "center",
                    "radius",
                    "size",
                    "rotation_deg",
                    "point",
                    "normal",
                    "base",
                    "axis",
                    "height",
                ],
            )
        })?;
        let Some(&m) = materials.get(&material) else {
            let known: Vec<&str> = materials.keys().map(String::as_str).collect();
            return Err(err(
                format!("{path}.material"),
                format!(
                    "unknown material \"{material}\" (defined: {})",
                    known.join(", ")
                ),
            ));
        };
        scene.add(shape, m).map_err(|e| core_err(&path, e, &[]))?;
    }

    let p = doc.photons.unwrap_or_default();
    let max_radius = p.max_radius.unwrap_or_else(|| default_radius(&scene));
    let photons = PhotonSettings::new(
        p.count.unwrap_or(DEFAULT_COUNT),
        p.k.unwrap_or(DEFAULT_K),
        max_radius,
        p.max_depth.unwrap_or(DEFAULT_MAX_DEPTH),
    )
    .map_err(|e| core_err("photons", e, &["k", "max_radius", "max_depth", "count"]))?;
    if photons.k() as usize > super::MAX_GATHER {
        return Err(err(
            "photons.k",
            format!(
                "{} exceeds the gather capacity {}",
                photons.k(),
                super::MAX_GATHER
            ),
        ));
    }
    if photons.max_depth() as usize > super::MAX_DEPTH {
        return Err(err(
            "photons.max_depth",
            format!("exceeds the path stack capacity {}", super::MAX_DEPTH),
        ));
    }
    let photons = match p.gather.as_deref() {
        None | Some("nearest") => photons,
        Some("radius") => photons.with_fixed_radius(true),
        Some(other) => {
            return Err(err(
                "photons.gather",
                format!("unknown gather \"{other}\" (expected nearest or radius)"),
            ));
        }
    };
    let passes = p.passes.unwrap_or(1);
    if passes == 0 {
        return Err(err("photons.passes", "must be at least 1"));
    }
    let alpha = p.alpha.unwrap_or(2.0 / 3.0);
    if !(alpha > 0.0 && alpha < 1.0) {
        return Err(err(
            "photons.alpha",
            format!("must lie in (0, 1) (got {alpha})"),
        ));
    }
    let mut caustic_store = StoreChoice::KdTree;
    if let Some(store) = &p.caustic_store {
        let path = "photons.caustic_store";
        match type_of(store, path, &["kd_tree", "illumination_map"])? {
            "kd_tree" if store.as_object().is_some_and(|o| o.len() == 1) => {}
            "kd_tree" => return Err(err(path, "kd_tree takes no other field")),
            _ => {
                let o = store
                    .as_object()
                    .ok_or_else(|| err(path, "expected an object"))?;
                if let Some(k) = o.keys().find(|k| *k != "type" && *k != "texel_size") {
                    return Err(err(
                        format!("{path}.{k}"),
                        "unknown field (illumination_map takes texel_size)",
                    ));
                }
                let t = o
                    .get("texel_size")
                    .ok_or_else(|| err(format!("{path}.texel_size"), "missing field `texel_size`"))?
                    .as_f64()
                    .filter(|t| t.is_finite() && *t > 0.0 && (*t as f32) > 0.0)
                    .ok_or_else(|| {
                        err(format!("{path}.texel_size"), "must be a positive number")
                    })?;
                caustic_store = StoreChoice::IlluminationMap {
                    texel_size: t as f32,
                };
            }
        }
    }
    Ok(LoadedScene {
        scene,
        photons,
        passes,
        alpha,
        caustic_store,
    })
}

/// A gather radius for scenes that give none: a fortieth of the largest caustic
/// object's bounding radius (scales with the scene), or 1/100 of the camera's distance
/// to its look-at point when there is no bounded caustic object.
fn default_radius(scene: &DesktopScene) -> f32 {
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
        // Scales with the scene: a hundredth of the camera's distance from the origin.
        let d = scene.camera().position().length();
        if d > 0.0 {
            0.01 * d
        } else {
            0.01
        }
    }
}

/// Reads and validates a scene file; I/O errors name the file.
pub fn load_scene(path: &Path) -> Result<LoadedScene, SceneError> {
    let text = fs::read_to_string(path)
        .map_err(|e| err("", format!("cannot read {}: {e}", path.display())))?;
    parse_scene(&text)
}

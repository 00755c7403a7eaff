//! Scene files: JSON as in `shared/scene-format.md`, parsed with serde and validated
//! by the core's constructors (the shared settings by [`super::settings`]). Every error
//! names its JSON path and the problem.

use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;
use std::string::{String, ToString};
use std::vec::Vec;
use std::{format, fs};

use serde::de::DeserializeOwned;
use serde::Deserialize;
use serde_json::Value;

use super::settings::{Gather, Given, Key, PhotonInput, SettingsInput, StoreKind};
use super::{DesktopScene, MAX_LIGHTS, MAX_OBJECTS};
use crate::camera::Camera;
use crate::geometry::Shape;
use crate::light::PointLight;
use crate::material::{Classic, Material};
use crate::math::{Rgb, Vec3};
use crate::photon::PhotonSettings;
use crate::Error;

pub use super::settings::{StoreChoice, DEFAULT_COUNT, DEFAULT_K, DEFAULT_MAX_DEPTH};

/// A problem with a scene file or a flag: where (a JSON path such as
/// `objects[2].radius`, a flag such as `--passes`, or the file) and what.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneError {
    /// JSON path or flag of the offending value (empty for the whole document).
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

/// Locates a core error: `base.field` for the field whose core label is `what` in
/// `fields` (the constructor's labels and the JSON fields they name, matched exactly),
/// else `base`.
fn core_err(base: &str, e: Error, fields: &[(&str, &str)]) -> SceneError {
    let what = match e {
        Error::NotFinite { what }
        | Error::NotPositive { what, .. }
        | Error::OutOfRange { what, .. }
        | Error::Degenerate { what }
        | Error::Capacity { what, .. } => what,
        _ => "",
    };
    let path = match fields.iter().find(|(label, _)| *label == what) {
        Some((_, f)) if base.is_empty() => f.to_string(),
        Some((_, f)) => format!("{base}.{f}"),
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
    max_rays_per_sample: Option<u32>,
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

/// The typed objects of the scene format (`{"type": …, fields}`), one line each: a
/// struct of the fields that also takes the `type` key (its value is checked first, by
/// [`type_of`]) and refuses any other key.
macro_rules! typed_objects {
    ($($name:ident { $($field:ident: $ty:ty),* $(,)? })*) => {$(
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct $name {
            #[serde(rename = "type")]
            _type: String,
            $($field: $ty,)*
        }
    )*};
}

typed_objects! {
    PointLightDef { position: [f32; 3], intensity: [f32; 3] }
    DiffuseDef { albedo: [f32; 3] }
    MirrorDef { reflectance: Option<[f32; 3]> }
    DielectricDef { ior: f32, absorption: Option<[f32; 3]> }
    ClassicDef {
        color: [f32; 3], ambient: f32, diffuse: f32, specular: f32, shininess: f32,
        reflectivity: f32, transparency: f32, ior: f32,
    }
    PlaneDef { point: [f32; 3], normal: [f32; 3], material: String }
    SphereDef { center: [f32; 3], radius: f32, material: String }
    BoxDef { center: [f32; 3], size: [f32; 3], rotation_deg: Option<[f32; 3]>, material: String }
    CylinderDef {
        base: [f32; 3], axis: [f32; 3], radius: f32, height: f32, capped: Option<bool>,
        material: String,
    }
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
    /// The cap on rays per camera ray (`image.max_rays_per_sample`), if any.
    pub max_rays_per_sample: Option<u32>,
    /// The file's shared settings as written, for flags to override
    /// ([`LoadedScene::with_overrides`]).
    pub input: SettingsInput,
}

impl LoadedScene {
    /// The scene with `flags` laid over the file's settings, all validated again
    /// (the same checks and messages as the file's keys, naming the flags).
    pub fn with_overrides(mut self, flags: &SettingsInput) -> Result<Self, SceneError> {
        let input = self.input.overridden_by(flags);
        let s = input.validate(&self.scene)?;
        self.scene.set_camera(s.camera);
        self.input = input;
        self.photons = s.photons;
        self.passes = s.passes;
        self.alpha = s.alpha;
        self.caustic_store = s.caustic_store;
        self.max_rays_per_sample = s.max_rays_per_sample;
        Ok(self)
    }
}

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

/// The list `key` (`lights`, `objects`) holds at most `max` entries.
fn at_most(list: &[Value], max: usize, key: &str) -> Result<(), SceneError> {
    if list.len() > max {
        let message = format!("{} {key}, at most {max} are supported", list.len());
        return Err(err(key, message));
    }
    Ok(())
}

fn v3(a: [f32; 3]) -> Vec3 {
    Vec3::from_array(a)
}

/// Parses and validates a scene from JSON text.
pub fn parse_scene(text: &str) -> Result<LoadedScene, SceneError> {
    let value: Value =
        serde_json::from_str(text).map_err(|e| err("", format!("invalid JSON: {e}")))?;
    let doc: FileDoc = typed(&value, "")?;
    let mut scene = DesktopScene::new(camera(&doc.camera, doc.image.as_ref())?);
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
    add_lights(&mut scene, &doc.lights)?;
    let materials = materials(&doc.materials)?;
    add_objects(&mut scene, &doc.objects, &materials)?;
    let input = settings_input(doc.image.as_ref(), doc.photons.unwrap_or_default())?;
    let settings = input.validate(&scene)?;
    Ok(LoadedScene {
        scene,
        photons: settings.photons,
        passes: settings.passes,
        alpha: settings.alpha,
        caustic_store: settings.caustic_store,
        max_rays_per_sample: settings.max_rays_per_sample,
        input,
    })
}

/// The camera at the file's image size (default 320×240).
fn camera(c: &CameraDef, image: Option<&ImageDef>) -> Result<Camera, SceneError> {
    let (w, h) = image.map_or((320, 240), |i| (i.width, i.height));
    let up = c.up.unwrap_or([0.0, 1.0, 0.0]);
    Camera::new(v3(c.position), v3(c.look_at), v3(up), c.fov_y_deg, w, h).map_err(|e| match e {
        Error::OutOfRange {
            what: what @ ("image width" | "image height"),
            ..
        } => {
            let key = if what == "image width" {
                Key::Width
            } else {
                Key::Height
            };
            err(key.json_path(), super::settings::problem(&e))
        }
        _ => core_err(
            "camera",
            e,
            &[
                ("camera position", "position"),
                ("camera look_at", "look_at"),
                ("camera look_at − position", "look_at"),
                ("camera up", "up"),
                ("camera forward × up", "up"),
                ("camera fov_y_deg", "fov_y_deg"),
            ],
        ),
    })
}

fn add_lights(scene: &mut DesktopScene, lights: &[Value]) -> Result<(), SceneError> {
    at_most(lights, MAX_LIGHTS, "lights")?;
    for (i, v) in lights.iter().enumerate() {
        let path = format!("lights[{i}]");
        type_of(v, &path, &["point"])?;
        let l: PointLightDef = typed(v, &path)?;
        let fields = [
            ("light position", "position"),
            ("light intensity", "intensity"),
        ];
        let light = PointLight::new(v3(l.position), Rgb::from_array(l.intensity))
            .map_err(|e| core_err(&path, e, &fields))?;
        scene
            .add_light(light)
            .map_err(|e| core_err(&path, e, &[]))?;
    }
    Ok(())
}

/// The core's labels of the material constructors and the fields they name.
const MATERIAL_FIELDS: [(&str, &str); 12] = [
    ("albedo", "albedo"),
    ("reflectance", "reflectance"),
    ("ior", "ior"),
    ("absorption", "absorption"),
    ("color", "color"),
    ("ambient", "ambient"),
    ("diffuse", "diffuse"),
    ("specular", "specular"),
    ("shininess", "shininess"),
    ("reflectivity", "reflectivity"),
    ("transparency", "transparency"),
    ("reflectivity + transparency", "reflectivity"),
];

fn materials(defs: &BTreeMap<String, Value>) -> Result<BTreeMap<String, Material>, SceneError> {
    let mut materials = BTreeMap::new();
    for (name, v) in defs {
        let path = format!("materials.{name}");
        let m = match type_of(v, &path, &["diffuse", "mirror", "dielectric", "classic"])? {
            "diffuse" => Material::diffuse(Rgb::from_array(typed::<DiffuseDef>(v, &path)?.albedo)),
            "mirror" => {
                let d: MirrorDef = typed(v, &path)?;
                Material::mirror(Rgb::from_array(d.reflectance.unwrap_or([1.0; 3])))
            }
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
        .map_err(|e| core_err(&path, e, &MATERIAL_FIELDS))?;
        materials.insert(name.clone(), m);
    }
    Ok(materials)
}

/// The core's labels of the shape constructors and the fields they name.
const SHAPE_FIELDS: [(&str, &str); 11] = [
    ("plane point", "point"),
    ("plane normal", "normal"),
    ("sphere center", "center"),
    ("sphere radius", "radius"),
    ("box center", "center"),
    ("box size", "size"),
    ("box rotation_deg", "rotation_deg"),
    ("cylinder base", "base"),
    ("cylinder axis", "axis"),
    ("cylinder radius", "radius"),
    ("cylinder height", "height"),
];

/// The shape of object `v` and the name of its material.
fn shape(v: &Value, path: &str) -> Result<(Shape, String), SceneError> {
    let (shape, material) = match type_of(v, path, &["plane", "sphere", "box", "cylinder"])? {
        "plane" => {
            let d: PlaneDef = typed(v, path)?;
            (Shape::plane(v3(d.point), v3(d.normal)), d.material)
        }
        "sphere" => {
            let d: SphereDef = typed(v, path)?;
            (Shape::sphere(v3(d.center), d.radius), d.material)
        }
        "box" => {
            let d: BoxDef = typed(v, path)?;
            let rotation = v3(d.rotation_deg.unwrap_or([0.0; 3]));
            (
                Shape::cuboid(v3(d.center), v3(d.size), rotation),
                d.material,
            )
        }
        _ => {
            let d: CylinderDef = typed(v, path)?;
            let capped = d.capped.unwrap_or(true);
            let (base, axis) = (v3(d.base), v3(d.axis));
            let shape = Shape::cylinder(base, axis, d.radius, d.height, capped);
            (shape, d.material)
        }
    };
    let shape = shape.map_err(|e| core_err(path, e, &SHAPE_FIELDS))?;
    Ok((shape, material))
}

fn add_objects(
    scene: &mut DesktopScene,
    objects: &[Value],
    materials: &BTreeMap<String, Material>,
) -> Result<(), SceneError> {
    at_most(objects, MAX_OBJECTS, "objects")?;
    for (i, v) in objects.iter().enumerate() {
        let path = format!("objects[{i}]");
        let (shape, material) = shape(v, &path)?;
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
    Ok(())
}

/// The file's shared settings as written (checked by [`SettingsInput::validate`]).
fn settings_input(image: Option<&ImageDef>, p: PhotonsDef) -> Result<SettingsInput, SceneError> {
    let gather = match p.gather.as_deref() {
        None => None,
        Some("nearest") => Some(Gather::Nearest),
        Some("radius") => Some(Gather::Radius),
        Some(other) => {
            return Err(err(
                "photons.gather",
                format!("unknown gather \"{other}\" (expected nearest or radius)"),
            ));
        }
    };
    let (store, texel_size) = match &p.caustic_store {
        None => (None, None),
        Some(v) => caustic_store(v)?,
    };
    Ok(SettingsInput {
        width: image.map(|i| Given::file(i.width)),
        height: image.map(|i| Given::file(i.height)),
        photons: PhotonInput {
            count: p.count.map(Given::file),
            k: p.k.map(Given::file),
            max_radius: p.max_radius.map(Given::file),
            max_depth: p.max_depth.map(Given::file),
            gather: gather.map(Given::file),
        },
        passes: p.passes.map(Given::file),
        alpha: p.alpha.map(Given::file),
        store: store.map(Given::file),
        texel_size: texel_size.map(Given::file),
        max_rays: image.and_then(|i| i.max_rays_per_sample).map(Given::file),
    })
}

/// `photons.caustic_store`: its type and, for illumination maps, its texel size.
fn caustic_store(store: &Value) -> Result<(Option<StoreKind>, Option<f32>), SceneError> {
    let path = "photons.caustic_store";
    match type_of(store, path, &["kd_tree", "illumination_map"])? {
        "kd_tree" if store.as_object().is_some_and(|o| o.len() == 1) => {
            Ok((Some(StoreKind::Kd), None))
        }
        "kd_tree" => Err(err(path, "kd_tree takes no other field")),
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
                .ok_or_else(|| err(format!("{path}.texel_size"), "must be a positive number"))?;
            // Checked, as `--texel-size` is, by the settings' validation.
            Ok((Some(StoreKind::Illum), Some(t as f32)))
        }
    }
}

/// Reads and validates a scene file; I/O errors name the file.
pub fn load_scene(path: &Path) -> Result<LoadedScene, SceneError> {
    let text = fs::read_to_string(path)
        .map_err(|e| err("", format!("cannot read {}: {e}", path.display())))?;
    parse_scene(&text)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The labels in the tables are the ones the core emits: a value the core rejects
    /// lands at its own field's path (a renamed label would land at the object's).
    #[test]
    fn each_core_label_maps_to_its_field() {
        let scene = |camera: &str, light: &str, object: &str| {
            format!(
                r#"{{"camera": {{"position": {camera}, "look_at": [0, 0, 0], "fov_y_deg": 40}},
                "lights": [{{"type": "point", "position": {light}, "intensity": [1, 1, 1]}}],
                "materials": {{"m": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}},
                "objects": [{object}]}}"#
            )
        };
        let (cam, light, big) = ("[0, 1, 5]", "[0, 5, 0]", "[1e300, 0, 0]");
        let sphere = r#"{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}"#;
        let cases = [
            (scene(big, light, sphere), "camera.position"),
            (scene(cam, big, sphere), "lights[0].position"),
            (
                r#"{"type": "plane", "point": [1e300, 0, 0], "normal": [0, 1, 0], "material": "m"}"#
                    .to_string(),
                "objects[0].point",
            ),
            (sphere.replace("[0, 0, 0]", big), "objects[0].center"),
            (
                r#"{"type": "box", "center": [0, 0, 0], "size": [1, 1, 1], "rotation_deg": [1e300, 0, 0], "material": "m"}"#
                    .to_string(),
                "objects[0].rotation_deg",
            ),
            (
                r#"{"type": "box", "center": [1e300, 0, 0], "size": [1, 1, 1], "material": "m"}"#
                    .to_string(),
                "objects[0].center",
            ),
            (cylinder("[1e300, 0, 0]", "1", "1"), "objects[0].base"),
            (cylinder("[0, 0, 0]", "0", "1"), "objects[0].radius"),
            (cylinder("[0, 0, 0]", "1", "0"), "objects[0].height"),
        ];
        for (i, (text, path)) in cases.into_iter().enumerate() {
            let text = if text.starts_with("{\"camera") {
                text
            } else {
                scene(cam, light, &text)
            };
            let e = parse_scene(&text).expect_err(path);
            assert_eq!(e.path, path, "case {i}: {e}");
        }
    }

    fn cylinder(base: &str, radius: &str, height: &str) -> String {
        format!(
            r#"{{"type": "cylinder", "base": {base}, "axis": [0, 1, 0], "radius": {radius},
            "height": {height}, "material": "m"}}"#
        )
    }
}

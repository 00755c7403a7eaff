//! Scenes built to be slow or to break things (issue 16), as scene-file JSON, so that
//! the same scenes go through the parser, the library and the `caustic` program.
//!
//! Six kinds, chosen by the seed:
//! 0. **deep classic trees**: overlapping classic objects both reflective and
//!    transparent (every hit forks) inside a reflective classic room, `max_depth` 30;
//! 1. **many overlapping glass objects** (12–40) over a floor, `max_depth` 30;
//! 2. **the camera inside glass**, nested in more glass;
//! 3. **lights inside objects**: in glass, in a closed diffuse box, in a mirror box;
//! 4. **grazing planes**: planes through the camera or a light, nearly parallel to the
//!    view, duplicated, and two facing mirrors (a hall of mirrors);
//! 5. **illumination maps** with a tiny texel over scattered photons, and gathers as
//!    large as the budget allows.
//!
//! Each at 16×12 with 1–4 lights, up to 20 000 photons per light and 1–3 passes.

use serde_json::{json, Value};

use super::Rng;

fn v3(rng: &mut Rng, e: f32) -> Value {
    let v = rng.v(e);
    json!([v.x, v.y, v.z])
}

fn rgb(rng: &mut Rng, max: f32) -> Value {
    let c = rng.rgb(max);
    json!([c.r, c.g, c.b])
}

/// A classic material whose hits all fork: `reflectivity + transparency` near 1.
fn forking_classic(rng: &mut Rng) -> Value {
    let r = rng.range(0.2, 0.8);
    json!({"type": "classic", "color": rgb(rng, 1.0), "ambient": rng.f(), "diffuse": rng.f(),
           "specular": rng.f(), "shininess": rng.range(1.0, 100.0).round(),
           "reflectivity": r, "transparency": (1.0 - r) * rng.range(0.9, 1.0),
           "ior": rng.range(1.0, 2.5)})
}

fn glass(rng: &mut Rng) -> Value {
    let absorption = if rng.chance(0.5) {
        json!([0, 0, 0])
    } else {
        rgb(rng, 2.0)
    };
    json!({"type": "dielectric", "ior": rng.range(1.05, 2.6), "absorption": absorption})
}

/// A random bounded shape near the origin (spheres, boxes, cylinders) of size ~`s`.
fn blob(rng: &mut Rng, s: f32, material: &str) -> Value {
    let c = v3(rng, s);
    match rng.below(3) {
        0 => json!({"type": "sphere", "center": c, "radius": rng.range(0.2, 1.0) * s,
                    "material": material}),
        1 => json!({"type": "box", "center": c,
                    "size": [rng.range(0.2, 1.5) * s, rng.range(0.2, 1.5) * s, rng.range(0.2, 1.5) * s],
                    "rotation_deg": v3(rng, 180.0), "material": material}),
        _ => json!({"type": "cylinder", "base": c, "axis": v3(rng, 1.0),
                    "radius": rng.range(0.1, 0.8) * s, "height": rng.range(0.2, 2.0) * s,
                    "capped": rng.chance(0.7), "material": material}),
    }
}

fn light(position: Value, rng: &mut Rng) -> Value {
    json!({"type": "point", "position": position, "intensity": rgb(rng, 80.0)})
}

/// The parts of a scene a kind builds on.
struct Parts {
    camera: Value,
    objects: Vec<Value>,
    lights: Vec<Value>,
    store: Value,
    /// `(k, max_radius)` of the gather.
    gather: (u64, f32),
}

/// Kind 0: forking classic objects inside a reflective classic room.
fn deep_classic_trees(rng: &mut Rng, p: &mut Parts) {
    for _ in 0..4 + rng.below(10) {
        p.objects.push(blob(rng, 1.0, "fork"));
    }
    p.objects.push(
        json!({"type": "box", "center": [0, 0, 0], "size": [14, 14, 14],
                          "material": "room"}),
    );
    p.lights.push(light(v3(rng, 3.0), rng));
}

/// Kind 1: 12–40 overlapping glass objects of two indices.
fn overlapping_glass(rng: &mut Rng, p: &mut Parts) {
    for i in 0..12 + rng.below(29) {
        let m = if i % 2 == 0 { "glass" } else { "glass2" };
        p.objects.push(blob(rng, 1.2, m));
    }
}

/// Kind 2: the camera inside three nested glass spheres, among forking objects.
fn camera_in_glass(rng: &mut Rng, p: &mut Parts) {
    let at = v3(rng, 0.5);
    p.camera["position"] = at.clone();
    p.camera["look_at"] = v3(rng, 3.0);
    for r in [0.8, 1.6, 3.0] {
        p.objects
            .push(json!({"type": "sphere", "center": at, "radius": r,
                              "material": "glass"}));
    }
    for _ in 0..4 {
        p.objects.push(blob(rng, 1.5, "fork"));
    }
}

/// Kind 3: lights inside glass, a closed diffuse box, a mirror box, and on a sphere.
fn lights_in_objects(rng: &mut Rng, p: &mut Parts) {
    p.objects
        .push(json!({"type": "sphere", "center": [0, 0, 0], "radius": 1.0,
                          "material": "glass"}));
    p.objects.push(
        json!({"type": "box", "center": [2.5, 0, 0], "size": [1, 1, 1],
                          "material": "floor"}),
    );
    p.objects.push(
        json!({"type": "box", "center": [-2.5, 0, 0], "size": [1.2, 1.2, 1.2],
                          "material": "mirror"}),
    );
    p.lights = vec![
        light(json!([0.1, 0.2, 0.0]), rng),
        light(json!([2.5, 0.1, 0.0]), rng),
        light(json!([-2.5, 0.0, 0.1]), rng),
        light(json!([0.0, 1.0, 0.0]), rng),
    ];
}

/// Kind 4: planes through the camera and the light, a grazing glass plane twice, and
/// two facing mirrors.
fn grazing_planes(rng: &mut Rng, p: &mut Parts) {
    p.objects
        .push(json!({"type": "plane", "point": [0.0, 1.5, 6.0],
                          "normal": [0.0, 1.0, 1e-4], "material": "floor"}));
    p.objects
        .push(json!({"type": "plane", "point": [2.0, 5.0, 3.0],
                          "normal": v3(rng, 1.0), "material": "fork"}));
    let grazing = json!({"type": "plane", "point": [0.0, 1.4999, 0.0],
                         "normal": [0.0, 1.0, 1e-6], "material": "glass"});
    p.objects.push(grazing.clone());
    p.objects.push(grazing);
    p.objects.push(
        json!({"type": "plane", "point": [-4, 0, 0], "normal": [1, 0, 0],
                          "material": "mirror"}),
    );
    p.objects.push(
        json!({"type": "plane", "point": [4, 0, 0], "normal": [-1, 0, 0],
                          "material": "mirror"}),
    );
    p.objects.push(blob(rng, 1.0, "glass"));
}

/// Kind 5: glass before a wall, illumination maps with a tiny texel, the largest gather.
fn tiny_texels(rng: &mut Rng, p: &mut Parts) {
    for _ in 0..3 + rng.below(6) {
        p.objects.push(blob(rng, 1.0, "glass"));
    }
    p.objects.push(
        json!({"type": "plane", "point": [0, 0, -3], "normal": [0, 0, 1],
                          "material": "floor"}),
    );
    p.store = json!({"type": "illumination_map", "texel_size": rng.range(1e-4, 1e-2)});
    p.gather = (1024, 10.0);
}

/// Hostile scene number `seed` as scene-file JSON (see the module documentation).
pub fn hostile_scene(seed: u64) -> Value {
    let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ 0x486f_7374);
    let kind = seed % 6;
    let camera = json!({"position": [0.0, 1.5, 6.0], "look_at": [0.0, 0.3, 0.0],
                        "fov_y_deg": rng.range(20.0, 120.0)});
    let mut materials = json!({
        "floor": {"type": "diffuse", "albedo": rgb(&mut rng, 1.0)},
        "mirror": {"type": "mirror", "reflectance": [1.0, 1.0, 1.0]},
        "fork": forking_classic(&mut rng),
        "room": forking_classic(&mut rng),
        "glass": glass(&mut rng),
        "glass2": glass(&mut rng),
    });
    let mut p = Parts {
        camera,
        objects: vec![
            json!({"type": "plane", "point": [0, -1.5, 0], "normal": [0, 1, 0],
                             "material": "floor"}),
        ],
        lights: vec![light(json!([2.0, 5.0, 3.0]), &mut rng)],
        store: json!({"type": "kd_tree"}),
        gather: (1 + rng.below(128), rng.range(0.01, 0.5)),
    };
    let build = [
        deep_classic_trees,
        overlapping_glass,
        camera_in_glass,
        lights_in_objects,
        grazing_planes,
        tiny_texels,
    ];
    build[kind as usize](&mut rng, &mut p);
    for _ in 0..rng.below(3) {
        p.lights.push(light(v3(&mut rng, 4.0), &mut rng));
    }
    if rng.chance(0.3) {
        materials["glass"]["ior"] = json!(1.0);
    }
    json!({
        "camera": p.camera,
        "image": {"width": 16, "height": 12},
        "background": rgb(&mut rng, 0.5),
        "ambient": rgb(&mut rng, 0.3),
        "lights": p.lights,
        "materials": materials,
        "objects": p.objects,
        "photons": {
            "count": 1000 + rng.below(19_001), "k": p.gather.0, "max_radius": p.gather.1,
            "max_depth": 30, "passes": if kind == 5 { 1 } else { 1 + rng.below(3) },
            "caustic_store": p.store
        }
    })
}

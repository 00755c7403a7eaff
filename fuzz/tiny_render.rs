// Shared by `fuzz/fuzz_targets/parse_scene.rs` and `tests/fuzz_corpus.rs` (by
// `include!`): parse a scene; if it parses, render it tiny and check every pixel.

/// Parses `text`; when it parses, renders it at 4×3 with at most 256 photons per light
/// and two passes, on one thread, and panics on a non-finite or negative pixel. Returns
/// whether it parsed and rendered. Errors of the parser or of the render are fine (they
/// are the clear errors a user sees); panics are not.
#[allow(dead_code)]
pub fn tiny_render(text: &str) -> bool {
    let Ok(mut loaded) = caustic::desktop::parse_scene(text) else {
        return false;
    };
    let Ok(camera) = loaded.scene.camera().with_size(4, 3) else {
        return false;
    };
    loaded.scene.set_camera(camera);
    let p = loaded.photons;
    let Ok(settings) =
        caustic::photon::PhotonSettings::new(p.count().min(256), p.k(), p.max_radius(), p.max_depth())
    else {
        return false;
    };
    let opts = caustic::desktop::RenderOptions {
        seed: 1,
        threads: 1,
        passes: loaded.passes.min(2),
        alpha: loaded.alpha,
        ..caustic::desktop::RenderOptions::default()
    };
    let Ok((image, _stats)) = caustic::desktop::render(&loaded.scene, &settings, &opts) else {
        return false;
    };
    for (i, px) in image.pixels.iter().enumerate() {
        assert!(
            px.is_finite() && px.min_channel() >= 0.0,
            "pixel {i} is {px:?}"
        );
    }
    true
}

//! Replays the fuzzer's seed corpus (`fuzz/corpus/parse_scene/`) as an ordinary test:
//! every file is parsed; whatever parses is rendered tiny (4×3, ≤ 256 photons per light)
//! and every pixel must be finite and non-negative; nothing may panic.
//!
//! A corpus a long `cargo fuzz run` grew is replayed by the fuzzer itself:
//! `cargo fuzz run parse_scene <dir> -- -runs=0`.

include!("../fuzz/tiny_render.rs");

fn replay(dir: &std::path::Path) -> (usize, usize) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    let mut rendered = 0;
    for path in &entries {
        let bytes = std::fs::read(path).unwrap();
        let Ok(text) = std::str::from_utf8(&bytes) else {
            continue;
        };
        let ok = std::panic::catch_unwind(|| tiny_render(text))
            .unwrap_or_else(|_| panic!("{} panics", path.display()));
        rendered += ok as usize;
    }
    (entries.len(), rendered)
}

/// Every file of the seed corpus parses and renders, or fails cleanly; the valid seeds
/// (the example scenes and the small hand-written ones) render, each by name.
#[test]
fn seed_corpus_parses_or_fails_cleanly() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus/parse_scene");
    let (files, rendered) = replay(&dir);
    println!("{files} corpus files, {rendered} rendered");
    assert!(files >= 8, "the seed corpus is missing");
    for name in [
        "fig6.json",
        "glass_sphere.json",
        "tube.json",
        "two_balls.json",
        "minimal.json",
        "classic_inside.json",
    ] {
        let text = std::fs::read_to_string(dir.join(name)).unwrap();
        assert!(tiny_render(&text), "{name} must parse and render");
    }
    assert!(rendered >= 6, "only {rendered} of {files} rendered");
}

/// Every bad seed gets an error that names its JSON path.
#[test]
fn broken_seeds_get_clear_errors() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus/parse_scene");
    for (name, path) in [
        ("broken_type.json", "lights[0].type"),
        ("truncated.json", ""),
        // Found by the fuzzer: its square underflows, and the estimate divided by zero.
        ("subnormal_max_radius.json", "photons.max_radius"),
        // Found by the fuzzer: 2·10³¹ W/sr overflowed a gather's scale, and 0·∞ gave NaN.
        ("huge_intensity.json", "lights[0].intensity"),
    ] {
        let text = std::fs::read_to_string(dir.join(name)).unwrap();
        let e = caustic::desktop::parse_scene(&text).unwrap_err();
        assert_eq!(e.path, path, "{name}: {e}");
        assert!(!e.message.is_empty());
    }
}

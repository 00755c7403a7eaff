//! The `caustic` program as a user meets it: help, version, suggestions, flag checks
//! that match the scene file's, outputs by extension checked before any work, JSON.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn caustic(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_caustic"))
        .args(args)
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn scene() -> String {
    format!("{}/scenes/glass_sphere.json", env!("CARGO_MANIFEST_DIR"))
}

/// A fresh directory for one test's files.
fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("caustic-cli-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A small, fast render of the glass sphere with extra flags.
fn small_render(extra: &[&str]) -> Output {
    let sc = scene();
    let mut args = vec!["render", &sc, "--width=40", "--height", "30"];
    args.extend_from_slice(&["--photons", "5000", "--quiet"]);
    args.extend_from_slice(extra);
    caustic(&args)
}

#[test]
fn help_and_version_exit_0_and_describe_every_flag() {
    let v = caustic(&["--version"]);
    assert_eq!(v.status.code(), Some(0));
    let text = String::from_utf8_lossy(&v.stdout);
    assert!(text.contains(env!("CARGO_PKG_VERSION")), "{text}");
    assert_eq!(caustic(&["-V"]).status.code(), Some(0));

    let render_flags = [
        "--output",
        "--pfm",
        "--exr",
        "--width",
        "--height",
        "--photons",
        "--k",
        "--radius",
        "--max-depth",
        "--gather",
        "--emit",
        "--cone-filter",
        "--seed",
        "--passes",
        "--alpha",
        "--store",
        "--texel-size",
        "--max-rays",
        "--supersample",
        "--threads",
        "--exposure",
        "--error-map",
        "--target-error",
        "--time-limit",
        "--stats",
        "--quiet",
    ];
    let compare_flags = ["--mask", "--mask-fraction", "--bin"];
    for (cmd, flags) in [
        ("render", &render_flags[..]),
        ("compare", &compare_flags[..]),
    ] {
        for help in ["--help", "-h"] {
            let o = caustic(&[cmd, help]);
            assert_eq!(o.status.code(), Some(0), "{cmd} {help}: {}", stderr(&o));
            let text = String::from_utf8_lossy(&o.stdout);
            for flag in flags {
                // The flag, then its one-line description on the same line or the next.
                let at = text
                    .find(&format!("{flag} "))
                    .or_else(|| text.find(&format!("{flag}\n")))
                    .unwrap_or_else(|| panic!("{cmd} {help} lacks {flag}:\n{text}"));
                let after: String = text[at..].lines().take(2).collect();
                assert!(after.len() > flag.len() + 12, "{flag} has no description");
            }
        }
    }
    // The defaults are stated in the help.
    let text = String::from_utf8_lossy(&caustic(&["render", "--help"]).stdout).into_owned();
    for default in [
        "else 100000",
        "else 64",
        "all cores",
        "[default: 1]",
        "[default: 0]",
    ] {
        assert!(text.contains(default), "no {default:?} in render --help");
    }
}

#[test]
fn usage_errors_exit_2_with_a_suggestion() {
    let sc = scene();
    let o = caustic(&["render", &sc, "--widht", "80", "-o", "x.png"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--width"), "{}", stderr(&o));
    let o = caustic(&["rendr"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("render"), "{}", stderr(&o));
    assert_eq!(caustic(&[]).status.code(), Some(2));
    let o = caustic(&["render", &sc, "--gather", "knn", "-o", "x.png"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("nearest"),
        "the values are listed: {}",
        stderr(&o)
    );
    let o = caustic(&["render", &sc, "--target-error", "0.02", "--passes", "4"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--target-error"), "{}", stderr(&o));
}

/// A flag and the same key in a scene file fail the same check with the same message;
/// the flag's error names the flag, the file's the JSON path.
#[test]
fn bad_flag_values_name_the_flag_and_match_the_files_message() {
    let d = dir("values");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(scene()).unwrap()).unwrap();
    let cases = [
        ("--passes", "0", "passes", serde_json::json!(0)),
        ("--k", "5000", "k", serde_json::json!(5000)),
        ("--k", "0", "k", serde_json::json!(0)),
        ("--radius", "-1", "max_radius", serde_json::json!(-1.0)),
        ("--max-depth", "40", "max_depth", serde_json::json!(40)),
        ("--alpha", "1.5", "alpha", serde_json::json!(1.5)),
    ];
    for (flag, value, key, json) in cases {
        let out = d.join("x.png");
        let o = small_render(&[flag, value, "-o", s(&out)]);
        assert_eq!(o.status.code(), Some(2), "{flag} {value}");
        let by_flag = stderr(&o);
        let prefix = format!("caustic: {flag}: ");
        assert!(by_flag.starts_with(&prefix), "{by_flag}");

        let mut edited = v.clone();
        edited["photons"][key] = json;
        let file = d.join(format!("{key}.json"));
        std::fs::write(&file, edited.to_string()).unwrap();
        let o = caustic(&["render", s(&file), "-o", s(&out), "--quiet"]);
        assert_eq!(o.status.code(), Some(2), "\"{key}\": {value}");
        let by_file = stderr(&o);
        let at = format!("photons.{key}: ");
        let message =
            &by_file[by_file.find(&at).unwrap_or_else(|| panic!("{by_file}")) + at.len()..];
        assert_eq!(&by_flag[prefix.len()..], message, "{flag} vs photons.{key}");
        assert!(!out.exists());
    }
    let o = small_render(&["--threads", "0", "-o", s(&d.join("x.png"))]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--threads"), "{}", stderr(&o));
    v["image"]["max_rays_per_sample"] = serde_json::json!(0);
    let file = d.join("rays.json");
    std::fs::write(&file, v.to_string()).unwrap();
    let o = caustic(&["render", s(&file), "-o", s(&d.join("x.png"))]);
    assert!(stderr(&o).contains("image.max_rays_per_sample: must be at least 1"));
    let o = small_render(&["--max-rays", "0", "-o", s(&d.join("x.png"))]);
    assert!(stderr(&o).contains("--max-rays: must be at least 1"));
    std::fs::remove_dir_all(d).ok();
}

/// An unwritable output or an unknown extension fails before any work: with a budget
/// of four billion photons per light the program still exits at once with status 2,
/// writes no file (not even the good one beside it) and prints no statistics.
#[test]
fn bad_outputs_fail_before_any_work() {
    let d = dir("outputs");
    let good = d.join("good.pfm");
    for bad in ["/nonexistent/a.png", "-", "x.jpg", s(&d)] {
        let sc = scene();
        let args = [
            "render",
            &sc,
            "--photons",
            "4000000000",
            "--stats",
            "--pfm",
            s(&good),
        ];
        let mut args = args.to_vec();
        args.extend_from_slice(&["-o", bad]);
        let o = caustic(&args);
        assert_eq!(o.status.code(), Some(2), "-o {bad}: {}", stderr(&o));
        assert!(o.stdout.is_empty(), "statistics printed for -o {bad}");
        assert!(!good.exists(), "-o {bad}: an output was written");
        let e = stderr(&o);
        assert!(e.contains(bad), "the error names {bad}: {e}");
    }
    assert!(!Path::new("/nonexistent/a.png").exists());
    let o = small_render(&[
        "-o",
        s(&d.join("x.png")),
        "--error-map",
        "/nonexistent/e.pfm",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!d.join("x.png").exists());
    std::fs::remove_dir_all(d).ok();
}

/// `-o x.exr` writes OpenEXR that `compare` reads as identical to the PFM of the same
/// render; half floats differ by their rounding only.
#[test]
fn exr_round_trips_against_pfm_under_compare() {
    let d = dir("exr");
    let (exr, half, pfm) = (d.join("x.exr"), d.join("h.exr"), d.join("x.pfm"));
    let o = small_render(&["-o", s(&exr), "--pfm", s(&pfm), "--stats"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let stats: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(stats["width"].as_u64(), Some(40));
    assert_eq!(stats["store"].as_str(), Some("kd"));
    assert!(stats["time_ms"]["total"].as_f64().unwrap() > 0.0);
    assert!(std::fs::read(&exr)
        .unwrap()
        .starts_with(&[0x76, 0x2f, 0x31, 0x01]));
    let c = caustic(&["compare", s(&exr), s(&pfm)]);
    assert!(c.status.success(), "{}", stderr(&c));
    let c: serde_json::Value = serde_json::from_slice(&c.stdout).unwrap();
    assert_eq!(
        (c["rel_rmse"].as_f64(), c["rel_mae"].as_f64()),
        (Some(0.0), Some(0.0))
    );
    assert_eq!(c["pixels"].as_u64(), Some(1200));

    let o = small_render(&["-o", s(&half), "--exr", "half"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let c = caustic(&["compare", s(&half), s(&pfm)]);
    let c: serde_json::Value = serde_json::from_slice(&c.stdout).unwrap();
    let e = c["rel_rmse"].as_f64().unwrap();
    // Half floats keep 11 significant bits: a relative error of at most 2^-11 each.
    assert!(e > 0.0 && e < 1.0 / 2048.0, "half rel_rmse {e}");
    std::fs::remove_dir_all(d).ok();
}

/// `compare` names a file it cannot read, and a black reference gives `null`, not NaN.
#[test]
fn compare_names_unreadable_files_and_writes_json() {
    let d = dir("compare");
    let black = d.join("black.pfm");
    caustic::desktop::Image::new(4, 3)
        .write_pfm(&black)
        .unwrap();
    let o = caustic(&["compare", s(&black), s(&black)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let c: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(c["rel_rmse"].is_null() && c["rel_mae"].is_null(), "{c}");
    assert_eq!(c["pixels"].as_u64(), Some(12));
    let missing = d.join("nope.pfm");
    let o = caustic(&["compare", s(&missing), s(&black)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains(s(&missing)), "{}", stderr(&o));
    let text = d.join("text.pfm");
    std::fs::write(&text, "not an image").unwrap();
    let o = caustic(&["compare", s(&black), s(&text)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains(s(&text)), "{}", stderr(&o));
    std::fs::remove_dir_all(d).ok();
}

#[test]
fn completions_for_bash_zsh_and_fish() {
    for shell in ["bash", "zsh", "fish"] {
        let o = caustic(&["completions", shell]);
        assert_eq!(o.status.code(), Some(0), "{shell}");
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(
            text.contains("--photons") && text.contains("render"),
            "{shell}"
        );
    }
    assert_eq!(caustic(&["completions", "tcsh"]).status.code(), Some(2));
}

/// A flag replaces only its own key: `--photons` on a scene that gathers by radius
/// renders the bits of the same scene with that `count`, not those of k-nearest.
#[test]
fn a_flag_replaces_only_its_key() {
    let d = dir("override");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(scene()).unwrap()).unwrap();
    // Few photons per estimate, so that the k nearest differ from all within the radius.
    v["photons"]["k"] = 2.into();
    let write = |name: &str, count: u32, gather: &str| {
        let mut v = v.clone();
        v["photons"]["count"] = count.into();
        v["photons"]["gather"] = gather.into();
        let p = d.join(name);
        std::fs::write(&p, v.to_string()).unwrap();
        p
    };
    let original = write("original.json", 500_000, "radius");
    let radius = write("radius.json", 5000, "radius");
    let nearest = write("nearest.json", 5000, "nearest");
    let render = |sc: &Path, extra: &[&str], out: &Path| {
        let mut args = vec![
            "render",
            s(sc),
            "--width",
            "40",
            "--height",
            "30",
            "--quiet",
            // The paper's gather at every diffuse hit, so that the gather choice shows
            // (with splats the gathers behind glass take every photon in a footprint).
            "--no-splat",
        ];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--pfm", s(out)]);
        let o = caustic(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        std::fs::read(out).unwrap()
    };
    let flagged = render(&original, &["--photons", "5000"], &d.join("a.pfm"));
    assert!(flagged == render(&radius, &[], &d.join("b.pfm")));
    assert!(flagged != render(&nearest, &[], &d.join("c.pfm")));
    std::fs::remove_dir_all(d).ok();
}

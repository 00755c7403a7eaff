//! The device firmware's image (`examples/device`), rendered on the host through the
//! same path, against a committed hash, and against the device's own bytes when
//! `tools/device/run.sh` hands them over.
//!
//! The scene, budget (`caustic::budget::FIG6`), tone map and dither are the
//! firmware's, and so is the display: the library's `Rgb565Stream`. `run.sh` runs the
//! firmware under QEMU on four instruction sets, then this test with, per scene
//! (`FIG6`, `GLASS`),
//! - `CAUSTIC_DEVICE_<SCENE>_RGB565`: a device's file (little-endian RGB565, row-major);
//! - `CAUSTIC_DEVICE_<SCENE>_FNV1A`: the hash from the firmware's `PASS` line;
//! - `CAUSTIC_DEVICE_<SCENE>_ERROR`: the firmware's error estimate, the words after
//!   `error_estimate` (firmwares built with `--features error-estimate`: the glass ones).
//!
//! The committed hash is what every firmware printed (`PASS fnv1a=…`) when it was
//! last changed: `cargo test` alone therefore checks the host against the device.
//! `cargo test --test device -- --nocapture` also prints the `size_of` values.

mod support;

use std::mem::size_of;

use caustic::budget::{DeviceMap, DeviceMemory, FIG6, FIG6_LIGHTS, FIG6_OBJECTS, GLASS};
use caustic::math::Rgb;
use caustic::photon::{KdStore, Photon};
use caustic::raster::Fnv1a;
use caustic::scene::Scene;

/// FNV-1a of Fig. 6's RGB565 bytes as the four firmwares (Cortex-M4F, M3, M33,
/// RV32IMAC) streamed them under QEMU (tools/device/run.sh).
const FIG6_FNV1A: u32 = 0x3354_54b1;
/// FNV-1a of the glass scene's bytes (`demo::glass`, `budget::GLASS`), as the four
/// firmwares built with `--features glass` streamed them.
const GLASS_FNV1A: u32 = 0x4166_70b5;
/// The render's estimate of its own error, as the glass firmwares print it (and as a
/// Fig. 6 firmware built with `--features error-estimate` would).
const FIG6_ERROR: &str = "rel_rmse=0.0950 rel_rmse_caustic=0.3942";
/// The same for the glass scene.
const GLASS_ERROR: &str = "rel_rmse=0.2521 rel_rmse_caustic=0.3607";

/// Checks a host stream of scene `tag` (`FIG6`, `GLASS`): rows in order, the
/// committed hash and error estimate, and, when run.sh hands them over, the device's
/// bytes (`CAUSTIC_DEVICE_<TAG>_RGB565`), hash (`CAUSTIC_DEVICE_<TAG>_FNV1A`) and
/// printed error estimate (`CAUSTIC_DEVICE_<TAG>_ERROR`).
fn check_against_the_device(
    tag: &str,
    s: &support::device::Streamed,
    height: u32,
    committed: (u32, &str),
) {
    let (committed, committed_error) = committed;
    assert_eq!(
        s.rows,
        (0..height).collect::<Vec<_>>(),
        "rows top to bottom, once each"
    );
    assert_eq!(s.hash, Fnv1a::of(&s.bytes));
    assert!(s.forward.stored > 0, "caustic photons land");
    println!(
        "host {tag}: {} bytes RGB565, {} photons stored of {} emitted, fnv1a=0x{:08x}",
        s.bytes.len(),
        s.forward.stored,
        s.forward.emitted,
        s.hash
    );
    assert_eq!(
        s.hash, committed,
        "{tag}: the host render is not the committed device image (if the renderer changed \
         on purpose, run tools/device/run.sh and commit the hash every firmware prints)"
    );
    println!("host {tag}: error_estimate {}", s.error);
    assert_eq!(
        s.error, committed_error,
        "{tag}: the host's error estimate is not the committed one"
    );
    if let Ok(device) = std::env::var(format!("CAUSTIC_DEVICE_{tag}_ERROR")) {
        assert_eq!(
            device.trim(),
            s.error,
            "{tag}: the firmware's error estimate against the host's"
        );
        println!("{tag}: the device's error estimate is the host's: {device}");
    }
    if let Ok(expected) = std::env::var(format!("CAUSTIC_DEVICE_{tag}_FNV1A")) {
        let expected = u32::from_str_radix(expected.trim().trim_start_matches("0x"), 16)
            .expect("the device hash is a hex u32");
        assert_eq!(
            s.hash, expected,
            "{tag}: the host's hash against the firmware's PASS line"
        );
    }
    let Some(path) = std::env::var_os(format!("CAUSTIC_DEVICE_{tag}_RGB565")) else {
        println!("{tag}: no device file given: compared with the committed hash only");
        return;
    };
    let device =
        std::fs::read(&path).unwrap_or_else(|e| panic!("reading {}: {e}", path.to_string_lossy()));
    assert_eq!(device.len(), s.bytes.len(), "{tag}: device file length");
    let width = s.bytes.len() / 2 / height as usize;
    let differing: Vec<usize> = (0..s.bytes.len() / 2)
        .filter(|&i| device[2 * i..2 * i + 2] != s.bytes[2 * i..2 * i + 2])
        .collect();
    if let Some(&i) = differing.first() {
        let px = |b: &[u8]| u16::from_le_bytes([b[2 * i], b[2 * i + 1]]);
        panic!(
            "{tag}: {} of {} pixels differ; first at ({}, {}): device {:#06x}, host {:#06x}",
            differing.len(),
            s.bytes.len() / 2,
            i % width,
            i / width,
            px(&device),
            px(&s.bytes),
        );
    }
    println!(
        "{tag}: device file {} is bit-identical to the host render ({} bytes)",
        path.to_string_lossy(),
        device.len()
    );
}

#[test]
fn device_image_is_the_host_image_bit_for_bit() {
    check_against_the_device(
        "FIG6",
        &support::device::fig6_stream(),
        FIG6.height,
        (FIG6_FNV1A, FIG6_ERROR),
    );
}

/// The physical scene: a dielectric sphere (Fresnel, Beer absorption), a mirror and a
/// diffuse floor, with the desktop's default estimator (light-traced caustics where
/// the eye sees them, gathers behind the glass).
#[test]
fn glass_scene_on_the_device_is_the_host_image_bit_for_bit() {
    let s = support::device::glass_stream();
    check_against_the_device("GLASS", &s, GLASS.height, (GLASS_FNV1A, GLASS_ERROR));
    // Not a blank frame: the floor, the sphere, its caustic and the mirror.
    let mut colours: Vec<&[u8]> = s.bytes.chunks(2).collect();
    colours.sort_unstable();
    colours.dedup();
    assert!(colours.len() > 100, "{} colours", colours.len());
}

#[test]
fn device_budget_sizes() {
    type Memory = DeviceMemory<
        FIG6_OBJECTS,
        FIG6_LIGHTS,
        { FIG6.stored },
        { FIG6.splats },
        { FIG6.width as usize },
    >;
    let sizes = [
        ("Photon", size_of::<Photon>()),
        (
            "DeviceMap<FIG6.stored, FIG6.splats>",
            size_of::<DeviceMap<{ FIG6.stored }, { FIG6.splats }>>(),
        ),
        ("Scene<2,1>", size_of::<Scene<FIG6_OBJECTS, FIG6_LIGHTS>>()),
        ("KdStore<FIG6.k>", size_of::<KdStore<'static, { FIG6.k }>>()),
        (
            "row [Rgb; FIG6.width]",
            size_of::<[Rgb; FIG6.width as usize]>(),
        ),
        ("DeviceMemory (scene + map + row)", size_of::<Memory>()),
    ];
    for (what, bytes) in sizes {
        println!("size_of {what}: {bytes} bytes");
    }
    assert_eq!(size_of::<Photon>(), 16);
    // The map is its photons, its splats and a few words, sized to what is stored, not
    // to what is emitted.
    let map = size_of::<DeviceMap<{ FIG6.stored }, { FIG6.splats }>>();
    assert!(map <= 16 * (FIG6.stored + FIG6.splats) + 32, "{map}");
    assert!(FIG6.stored < FIG6.emitted as usize / 3);
}

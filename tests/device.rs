//! The device firmware's image (`examples/device`), rendered on the host through the
//! same path, against a committed hash, and against the device's own bytes when
//! `tools/device/run.sh` hands them over.
//!
//! The scene, budget (`caustic::budget::FIG6`), tone map and dither are the
//! firmware's, and so is the display: the library's `Rgb565Stream`. `run.sh` runs the
//! firmware under QEMU on four instruction sets, then this test with
//! - `CAUSTIC_DEVICE_RGB565`: a device's file (little-endian RGB565, row-major);
//! - `CAUSTIC_DEVICE_FNV1A`: the hash from the firmware's `PASS` line.
//!
//! The committed hash is what every firmware printed (`PASS fnv1a=…`) when it was
//! last changed: `cargo test` alone therefore checks the host against the device.
//! `cargo test --test device -- --nocapture` also prints the `size_of` values.

mod support;

use std::mem::size_of;

use caustic::budget::{DeviceMap, DeviceMemory, FIG6, FIG6_LIGHTS, FIG6_OBJECTS};
use caustic::math::Rgb;
use caustic::photon::{KdStore, Photon};
use caustic::raster::Fnv1a;
use caustic::scene::Scene;

/// FNV-1a of Fig. 6's RGB565 bytes as the four firmwares (Cortex-M4F, M3, M33,
/// RV32IMAC) streamed them under QEMU (tools/device/run.sh).
const FIG6_FNV1A: u32 = 0xc8f3_1be2;

#[test]
fn device_image_is_the_host_image_bit_for_bit() {
    let (bytes, hash, forward, rows) = support::fig6_stream();
    assert_eq!(
        rows,
        (0..FIG6.height).collect::<Vec<_>>(),
        "rows top to bottom, once each"
    );
    assert_eq!(bytes.len(), 2 * (FIG6.width * FIG6.height) as usize);
    assert_eq!(hash, Fnv1a::of(&bytes));
    assert!(forward.stored > 0, "the cube makes caustic photons");
    println!(
        "host: {}x{} RGB565, {} photons stored of {} emitted, fnv1a=0x{hash:08x}",
        FIG6.width, FIG6.height, forward.stored, forward.emitted
    );
    assert_eq!(
        hash, FIG6_FNV1A,
        "the host render is not the committed device image (if the renderer changed on \
         purpose, run tools/device/run.sh and commit the hash every firmware prints)"
    );

    if let Ok(expected) = std::env::var("CAUSTIC_DEVICE_FNV1A") {
        let expected = u32::from_str_radix(expected.trim().trim_start_matches("0x"), 16)
            .expect("CAUSTIC_DEVICE_FNV1A is a hex u32");
        assert_eq!(
            hash, expected,
            "the host's hash against the firmware's PASS line"
        );
    }
    let Some(path) = std::env::var_os("CAUSTIC_DEVICE_RGB565") else {
        println!("CAUSTIC_DEVICE_RGB565 not set: compared with the committed hash only");
        return;
    };
    let device =
        std::fs::read(&path).unwrap_or_else(|e| panic!("reading {}: {e}", path.to_string_lossy()));
    assert_eq!(device.len(), bytes.len(), "device file length");
    let differing: Vec<usize> = (0..bytes.len() / 2)
        .filter(|&i| device[2 * i..2 * i + 2] != bytes[2 * i..2 * i + 2])
        .collect();
    if let Some(&i) = differing.first() {
        let px = |b: &[u8]| u16::from_le_bytes([b[2 * i], b[2 * i + 1]]);
        panic!(
            "{} of {} pixels differ; first at ({}, {}): device {:#06x}, host {:#06x}",
            differing.len(),
            bytes.len() / 2,
            i % FIG6.width as usize,
            i / FIG6.width as usize,
            px(&device),
            px(&bytes),
        );
    }
    println!(
        "device file {} is bit-identical to the host render ({} bytes)",
        path.to_string_lossy(),
        device.len()
    );
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

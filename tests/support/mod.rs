//! What the device tests share: the firmware's pipeline on the host
//! (`examples/device/src/main.rs`, every capacity from `caustic::budget::FIG6`) and
//! its byte stream through the library's own `Rgb565Stream`.
#![allow(dead_code)] // each test file uses a part

use caustic::budget::{DeviceMap, FIG6, FIG6_LIGHTS, FIG6_OBJECTS};
use caustic::demo;
use caustic::math::Rgb;
use caustic::photon::ForwardStats;
use caustic::raster::{DisplaySink, Dither, Rgb565Stream, ToneMap};
use caustic::render::Renderer;

/// The firmware's render of Fig. 6, calling `sink(y, row)` for each row in order.
pub fn fig6_rows(mut sink: impl FnMut(u32, &[Rgb])) -> ForwardStats {
    let scene = demo::fig6::<FIG6_OBJECTS, FIG6_LIGHTS>(FIG6.width, FIG6.height).unwrap();
    let settings = FIG6.settings().unwrap();
    let mut map: Box<DeviceMap<{ FIG6.stored }, { FIG6.splats }>> = Box::default();
    let forward = map.build(&scene, &settings, FIG6.seed).unwrap();
    let store = map.store::<{ FIG6.k }>(&settings).unwrap();
    let renderer: Renderer<_, FIG6_OBJECTS, FIG6_LIGHTS, { FIG6.depth }> =
        map.with_splats(Renderer::new(&scene, &store, settings.max_depth()).unwrap());
    let mut row = [Rgb::ZERO; FIG6.width as usize];
    renderer
        .rows(&mut row, |y, pixels| {
            sink(y, pixels);
            Ok::<_, ()>(())
        })
        .unwrap();
    forward
}

/// The firmware's byte stream (little-endian RGB565, row-major) and its FNV-1a, as
/// the firmware makes them: `DisplaySink` (default tone map, no dither) onto an
/// `Rgb565Stream`. Also the forward pass's statistics and the rows in the order the
/// renderer handed them out.
pub fn fig6_stream() -> (Vec<u8>, u32, ForwardStats, Vec<u32>) {
    let mut bytes = Vec::new();
    let mut order = Vec::new();
    let mut stream =
        Rgb565Stream::<_, { FIG6.width as usize }>::new(FIG6.width, FIG6.height, |b: &[u8]| {
            bytes.extend_from_slice(b);
            Ok::<_, ()>(())
        })
        .unwrap();
    let forward = {
        let mut sink = DisplaySink::new(&mut stream, ToneMap::default(), Dither::Off);
        fig6_rows(|y, pixels| {
            order.push(y);
            sink.draw_row(y, pixels).unwrap();
        })
    };
    assert!(stream.is_complete(), "every pixel streamed");
    let hash = stream.hash();
    let _ = stream.into_writer(); // gives `bytes` back
    (bytes, hash, forward, order)
}

//! What the device tests share: the firmware's pipeline on the host
//! (`examples/device/src/main.rs`, every capacity from a `caustic::budget` constant)
//! and its byte stream through the library's own `Rgb565Stream`.

use caustic::budget::{
    DeviceBudget, DeviceMap, ErrorFigure, FIG6, FIG6_LIGHTS, FIG6_OBJECTS, GLASS, GLASS_LIGHTS,
    GLASS_OBJECTS,
};
use caustic::demo;
use caustic::math::Rgb;
use caustic::photon::ForwardStats;
use caustic::raster::{DisplaySink, Dither, Rgb565Stream, ToneMap};
use caustic::render::{ErrorTally, PixelEstimate, Renderer, RowPixel};
use caustic::scene::Scene;

/// What a device streams for one scene: its bytes (little-endian RGB565, row-major),
/// their FNV-1a, the render's error estimate as the firmware prints it (`rel_rmse=…
/// rel_rmse_caustic=…`, `caustic::budget::ErrorFigure`), the forward pass's
/// statistics, and the rows in the order they came.
pub struct Streamed {
    pub bytes: Vec<u8>,
    pub hash: u32,
    pub error: String,
    pub forward: ForwardStats,
    pub rows: Vec<u32>,
}

/// The firmware's render of `scene` with `budget` (whose capacities are the const
/// parameters: objects, lights, stored photons, splats, width, K, depth) into rows of
/// `T` (radiance, or pixels with their error estimates), calling `sink(y, row)` for
/// each row in order.
pub fn rows<
    T: RowPixel + Copy + Default,
    const O: usize,
    const L: usize,
    const N: usize,
    const S: usize,
    const W: usize,
    const K: usize,
    const D: usize,
>(
    budget: &DeviceBudget,
    scene: &Scene<O, L>,
    mut sink: impl FnMut(u32, &[T]),
) -> ForwardStats {
    let settings = budget.settings().unwrap();
    let mut map: Box<DeviceMap<N, S>> = Box::default();
    let forward = map.build(scene, &settings, budget.seed).unwrap();
    let store = map.store::<K>(&settings).unwrap();
    let renderer: Renderer<_, O, L, D> =
        map.with_splats(Renderer::new(scene, &store, settings.max_depth()).unwrap());
    let mut row = [T::default(); W];
    renderer
        .rows(&mut row, |y, pixels| {
            sink(y, pixels);
            Ok::<_, ()>(())
        })
        .unwrap();
    forward
}

/// The firmware's byte stream for `scene`, as the firmware makes it: `DisplaySink`
/// (default tone map, no dither) onto an `Rgb565Stream`, with the error estimate the
/// firmware built with `--features error-estimate` prints (its rows are
/// `PixelEstimate`s; their radiance, and so the bytes, are the same either way).
pub fn stream<
    const O: usize,
    const L: usize,
    const N: usize,
    const S: usize,
    const W: usize,
    const K: usize,
    const D: usize,
>(
    budget: &DeviceBudget,
    scene: &Scene<O, L>,
) -> Streamed {
    let mut bytes = Vec::new();
    let mut order = Vec::new();
    let mut stream = Rgb565Stream::<_, W>::new(budget.width, budget.height, |b: &[u8]| {
        bytes.extend_from_slice(b);
        Ok::<_, ()>(())
    })
    .unwrap();
    let mut tally = ErrorTally::default();
    let forward = {
        let mut sink = DisplaySink::new(&mut stream, ToneMap::default(), Dither::Off);
        rows::<PixelEstimate, O, L, N, S, W, K, D>(budget, scene, |y, pixels| {
            order.push(y);
            tally.add_row(pixels);
            sink.draw_row(y, pixels).unwrap();
        })
    };
    assert!(stream.is_complete(), "every pixel streamed");
    let hash = stream.hash();
    let _ = stream.into_writer(); // gives `bytes` back
    Streamed {
        bytes,
        hash,
        error: ErrorFigure(tally).to_string(),
        forward,
        rows: order,
    }
}

/// Fig. 6 with `budget::FIG6`, row by row.
pub fn fig6_rows(sink: impl FnMut(u32, &[Rgb])) -> ForwardStats {
    let scene = demo::fig6(FIG6.width, FIG6.height).unwrap();
    rows::<
        Rgb,
        FIG6_OBJECTS,
        FIG6_LIGHTS,
        { FIG6.stored },
        { FIG6.splats },
        { FIG6.width as usize },
        { FIG6.k },
        { FIG6.depth },
    >(&FIG6, &scene, sink)
}

/// Fig. 6's device stream.
pub fn fig6_stream() -> Streamed {
    let scene = demo::fig6(FIG6.width, FIG6.height).unwrap();
    stream::<
        FIG6_OBJECTS,
        FIG6_LIGHTS,
        { FIG6.stored },
        { FIG6.splats },
        { FIG6.width as usize },
        { FIG6.k },
        { FIG6.depth },
    >(&FIG6, &scene)
}

/// The glass scene's device stream (`demo::glass` with `budget::GLASS`).
pub fn glass_stream() -> Streamed {
    let scene = demo::glass(GLASS.width, GLASS.height).unwrap();
    stream::<
        GLASS_OBJECTS,
        GLASS_LIGHTS,
        { GLASS.stored },
        { GLASS.splats },
        { GLASS.width as usize },
        { GLASS.k },
        { GLASS.depth },
    >(&GLASS, &scene)
}

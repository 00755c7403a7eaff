#!/usr/bin/env python3
"""Calibration of caustic's own error estimate (issue 13): estimated against measured.

Renders each scene (three the defaults were tuned on, three held out) with the release
`caustic` binary at several photon budgets, reads `--stats`' `error_estimate`, measures the
true error against the committed pixel-area reference (tests/data/NAME.ref*.pfm) and writes
docs/error_calibration.csv and docs/error_calibration.svg (log-log scatter, y = x and the
factor-2 band).

Measured error: relative RMSE sqrt(mean((a-b)^2))/mean(b) over pixels and channels, of the
full image and of the caustic region (reference caustic part >= 10 % of the reference
luminance, Rec. 709). The reference has noise of its own (NAME.ref.json: that of the committed
mean of its seeds, from their spread); the render and the reference are independent,
so E[measured^2] = true^2 + ref_noise^2, and the column `true` is sqrt(max(measured^2 -
ref_noise^2, 0)). The ratio estimated / true is what must lie within a factor 2.

Each scene's photons block is replaced by a plain one (count N, k 64, max_radius 0.25, the
file's max_depth): no estimator hint. Usage (from the repository root, after
`cargo build --release`):

    tools/reference/.venv/bin/python tools/reference/calibration.py [--size 320x240]
        [--photons 25000,100000,400000,1600000] [--out docs/error_calibration] [--own-noise]

--own-noise renders every point a second time with seed 1 and adds the render's own
seed-to-seed noise (columns own_noise_full, own_noise_caustic): what the error estimate's
photon part estimates, measured without any reference, and a floor under the measured error
that no better reference can lower.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))

# (reference name, scene file, role)
SCENES = [
    ("glass_sphere", "scenes/glass_sphere.json", "tuning"),
    ("two_balls", "scenes/two_balls.json", "tuning"),
    ("tube", "scenes/tube.json", "tuning"),
    ("sphere_wall", "scenes/heldout/sphere_wall.json", "held out"),
    ("tilted_cube", "scenes/heldout/tilted_cube.json", "held out"),
    ("balls_mirror_tube", "scenes/heldout/balls_mirror_tube.json", "held out"),
]


def read_pfm(path):
    """PFM as float64 (H, W, 3), top row first."""
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF", path
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        a = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4").reshape(h, w, 3)
    return a[::-1].astype(np.float64)


def binned(a, b):
    """b x b box average: exact for pixel-area averages."""
    if b == 1:
        return a
    h, w = a.shape[:2]
    return a.reshape(h // b, b, w // b, b, 3).mean(axis=(1, 3))


def lum(a):
    return a @ np.array([0.2126, 0.7152, 0.0722])


def rel_rmse(a, b, mask):
    return float(np.sqrt(((a[mask] - b[mask]) ** 2).mean()) / b[mask].mean())


def reference(name, width):
    """Full image, caustic region and the reference's own noise (full, caustic) at `width`."""
    data = os.path.join(REPO, "tests", "data")
    full = read_pfm(os.path.join(data, f"{name}.ref.pfm"))
    caustic = read_pfm(os.path.join(data, f"{name}.ref.caustic.pfm"))
    b = full.shape[1] // width
    if b * width != full.shape[1]:
        raise SystemExit(f"calibration: width {width} does not divide the reference's {full.shape[1]}")
    full, caustic = binned(full, b), binned(caustic, b)
    region = (lum(full) > 0) & (lum(caustic) >= 0.1 * lum(full))
    noise = json.load(open(os.path.join(data, f"{name}.ref.json")))["noise"]
    if b == 1:
        ref_noise = (noise["mean_of_seeds_rel_rmse_full"], noise["mean_of_seeds_rel_rmse_caustic_region"])
    elif b == 2:
        ref_noise = (noise["mean_of_seeds_rel_rmse_full_2x2"], noise["mean_of_seeds_rel_rmse_caustic_region_2x2"])
    else:
        raise SystemExit("calibration: the reference noise is known at 1x1 and 2x2 bins only")
    return full, region, ref_noise


def render(scene_path, photons, width, height, binary, seed=0):
    """Render with a plain photons block and forward-pass `seed` (caustic's default is 0);
    return (image, error_estimate, seconds)."""
    js = json.load(open(os.path.join(REPO, scene_path)))
    depth = js.get("photons", {}).get("max_depth", 8)
    js["photons"] = {"count": photons, "k": 64, "max_radius": 0.25, "max_depth": depth}
    with tempfile.TemporaryDirectory() as tmp:
        scene = os.path.join(tmp, "scene.json")
        out = os.path.join(tmp, "out.pfm")
        with open(scene, "w") as f:
            json.dump(js, f)
        cmd = [binary, "render", scene, "-o", out, "--quiet", "--stats", "--seed", str(seed),
               "--width", str(width), "--height", str(height)]
        t0 = time.time()
        stats = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
        seconds = time.time() - t0
        return read_pfm(out), stats["error_estimate"], seconds


def own_noise(a, b, ref, mask):
    """The render's own noise from two independent seeds a, b: sqrt(mean((a-b)^2)/2) over the
    mask, relative to the reference's mean there (the rel. RMSE one render has against its
    expectation; needs no reference beyond the normalisation)."""
    return float(np.sqrt(((a[mask] - b[mask]) ** 2).mean() / 2) / ref[mask].mean())


def true_error(measured, ref_noise):
    return math.sqrt(max(measured ** 2 - ref_noise ** 2, 0.0))


def measure(args):
    rows = []
    for name, path, role in SCENES:
        ref, region, (noise_full, noise_caustic) = reference(name, args.width)
        for n in args.photons:
            img, est, seconds = render(path, n, args.width, args.height, args.binary)
            mf, mc = rel_rmse(img, ref, np.ones(region.shape, bool)), rel_rmse(img, ref, region)
            row = dict(scene=name, role=role, photons=n, seconds=round(seconds, 3),
                       estimated_full=est["rel_rmse"], measured_full=mf, ref_noise_full=noise_full,
                       true_full=true_error(mf, noise_full),
                       estimated_caustic=est["rel_rmse_caustic"], measured_caustic=mc,
                       ref_noise_caustic=noise_caustic, true_caustic=true_error(mc, noise_caustic))
            if args.own_noise:
                other, _, _ = render(path, n, args.width, args.height, args.binary, seed=1)
                every = np.ones(region.shape, bool)
                row.update(own_noise_full=own_noise(img, other, ref, every),
                           own_noise_caustic=own_noise(img, other, ref, region))
                print(f"{name:>18} {n:>8}: own noise (seeds 0, 1) full {row['own_noise_full']:.4f} "
                      f"caustic {row['own_noise_caustic']:.4f}", flush=True)
            rows.append(row)
            print(f"{name:>18} {n:>8}: full est {row['estimated_full']:.4f} true {row['true_full']:.4f} "
                  f"(measured {mf:.4f}); caustic est {fmt(row['estimated_caustic'])} true "
                  f"{row['true_caustic']:.4f} (measured {mc:.4f}); {seconds:.2f} s", flush=True)
    return rows


def fmt(x):
    return "-" if x is None else f"{x:.4f}"


def write_csv(rows, path):
    keys = list(rows[0].keys())
    with open(path, "w") as f:
        f.write(",".join(keys) + "\n")
        for r in rows:
            f.write(",".join("" if r[k] is None else (f"{r[k]:.6g}" if isinstance(r[k], float) else str(r[k]))
                             for k in keys) + "\n")


def points(rows):
    """(scene, kind, estimated, true) for every pair that has both numbers."""
    out = []
    for r in rows:
        for kind in ("full", "caustic"):
            e, t = r[f"estimated_{kind}"], r[f"true_{kind}"]
            if e is not None and e > 0 and t > 0:
                out.append((r["scene"], kind, e, t))
    return out


def within_factor_2(rows):
    pts = points(rows)
    return sum(1 for _, _, e, t in pts if 0.5 <= e / t <= 2.0), len(pts)


COLOURS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b"]


def write_svg(rows, path, title):
    pts = points(rows)
    lo = 10 ** math.floor(math.log10(min(min(e, t) for _, _, e, t in pts)))
    hi = 10 ** math.ceil(math.log10(max(max(e, t) for _, _, e, t in pts)))
    size, m = 460, 60

    def xy(x, y):
        fx = (math.log10(x) - math.log10(lo)) / (math.log10(hi) - math.log10(lo))
        fy = (math.log10(y) - math.log10(lo)) / (math.log10(hi) - math.log10(lo))
        return m + fx * size, m + (1 - fy) * size

    s = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{size + 2 * m + 170}" height="{size + 2 * m}" '
         f'font-family="sans-serif" font-size="12">',
         '<rect width="100%" height="100%" fill="white"/>',
         f'<text x="{m}" y="{m - 25}" font-size="14">{title}</text>']
    d = lo
    while d <= hi * 1.0001:
        for k in range(1, 10):
            v = d * k
            if v > hi * 1.0001:
                break
            x0, y0 = xy(v, lo)
            _, y1 = xy(lo, v)
            w = "#bbb" if k == 1 else "#eee"
            s.append(f'<line x1="{x0:.1f}" y1="{m}" x2="{x0:.1f}" y2="{m + size}" stroke="{w}"/>')
            s.append(f'<line x1="{m}" y1="{y1:.1f}" x2="{m + size}" y2="{y1:.1f}" stroke="{w}"/>')
            if k == 1:
                s.append(f'<text x="{x0:.1f}" y="{m + size + 16}" text-anchor="middle">{v:g}</text>')
                s.append(f'<text x="{m - 6}" y="{y1 + 4:.1f}" text-anchor="end">{v:g}</text>')
        d *= 10
    for f, dash in ((1.0, ""), (2.0, ' stroke-dasharray="6,4"'), (0.5, ' stroke-dasharray="6,4"')):
        a, b = (lo, lo * f) if f >= 1 else (lo / f, lo)
        c, e = (hi / f, hi) if f >= 1 else (hi, hi * f)
        (x0, y0), (x1, y1) = xy(a, b), xy(c, e)
        s.append(f'<line x1="{x0:.1f}" y1="{y0:.1f}" x2="{x1:.1f}" y2="{y1:.1f}" stroke="black"{dash}/>')
    s.append(f'<rect x="{m}" y="{m}" width="{size}" height="{size}" fill="none" stroke="black"/>')
    s.append(f'<text x="{m + size / 2}" y="{m + size + 40}" text-anchor="middle">measured error, '
             f'reference noise subtracted (rel. RMSE)</text>')
    s.append(f'<text transform="translate({m - 45},{m + size / 2}) rotate(-90)" text-anchor="middle">'
             f'estimated error (--stats error_estimate)</text>')
    names = [n for n, _, _ in SCENES]
    for scene, kind, e, t in pts:
        x, y = xy(t, e)
        c = COLOURS[names.index(scene) % len(COLOURS)]
        if kind == "full":
            s.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="4.5" fill="{c}"/>')
        else:
            s.append(f'<rect x="{x - 4:.1f}" y="{y - 4:.1f}" width="8" height="8" fill="none" '
                     f'stroke="{c}" stroke-width="2"/>')
    lx = m + size + 20
    for i, (name, _, role) in enumerate(SCENES):
        y = m + 10 + 18 * i
        s.append(f'<circle cx="{lx}" cy="{y}" r="4.5" fill="{COLOURS[i]}"/>')
        s.append(f'<text x="{lx + 10}" y="{y + 4}">{name} ({role})</text>')
    y = m + 10 + 18 * len(SCENES) + 10
    s.append(f'<circle cx="{lx}" cy="{y}" r="4.5" fill="gray"/><text x="{lx + 10}" y="{y + 4}">full image</text>')
    s.append(f'<rect x="{lx - 4}" y="{y + 14}" width="8" height="8" fill="none" stroke="gray" stroke-width="2"/>'
             f'<text x="{lx + 10}" y="{y + 22}">caustic region</text>')
    s.append(f'<text x="{lx}" y="{y + 44}">solid: y = x</text><text x="{lx}" y="{y + 60}">dashed: factor 2</text>')
    s.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(s) + "\n")


def main(argv):
    ap = argparse.ArgumentParser(prog="calibration.py")
    ap.add_argument("--size", default="320x240")
    ap.add_argument("--photons", default="25000,100000,400000,1600000")
    ap.add_argument("--out", default=os.path.join(REPO, "docs", "error_calibration"))
    ap.add_argument("--binary", default=os.path.join(os.environ.get("CARGO_TARGET_DIR", os.path.join(REPO, "target")),
                                                     "release", "caustic"))
    ap.add_argument("--own-noise", action="store_true",
                    help="also render seed 1 and report the render's own seed-to-seed noise")
    args = ap.parse_args(argv)
    args.width, args.height = map(int, args.size.split("x"))
    args.photons = [int(x) for x in args.photons.split(",")]
    commit = subprocess.run(["git", "-C", REPO, "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    rows = measure(args)
    write_csv(rows, args.out + ".csv")
    ok, total = within_factor_2(rows)
    write_svg(rows, args.out + ".svg",
              f"caustic's error estimate vs measured, {args.width}x{args.height}, commit {commit}: "
              f"{ok}/{total} within 2x")
    print(f"{ok} of {total} estimates within a factor 2 of the true error; wrote {args.out}.csv/.svg")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

#!/usr/bin/env python3
"""caustic against Mitsuba 3's `ptracer`, in one run, on the wall-less glass sphere (issue 12).

Both render scenes/glass_sphere.json at 320x240 at increasing budgets (caustic: photons per
light, plain photons block k 64 / max_radius 0.25, default estimator, all cores; ptracer: spp
in passes of 64, all cores); each image's relative RMSE sqrt(mean((a-b)^2))/mean(b) over the
**caustic floor** (pixels that see the floor directly, not through or at the sphere: none of
4x4 sub-pixel rays in it or its 8 neighbours hits a sphere; and whose reference caustic part is >= 10 % of the
reference luminance) is measured against the committed pixel-area reference
(tests/data/glass_sphere.ref*.pfm), and the time each needs to reach 5 % is interpolated
log-log between the two budgets around it. Budgets double until the error is below 5 %;
ptracer's also stop before their total time would pass --max-seconds (150), and its time to
5 % is then extrapolated along its measured convergence (log-log least squares of error against
spp over its last three runs; an unbiased light tracer converges as spp^-1/2), at those
runs' seconds per spp.

Matching transport: ptracer also computes floor light that the glass refocuses onto the floor
(L D S+ D E and deeper), which the contract leaves out (tools/reference/README.md). That part
is quadratic and higher in the floor albedo rho, so it is measured once, before the race, by
ptracer itself with common random numbers: extra = 2 f(rho) - 4 f(rho/2) (same seeds, paths
identical, the rho-linear part cancels path by path), and ptracer's target is reference +
extra. The extra part's own noise (from its two halves of passes) and the reference's (from
its two seeds, when /tmp/caustic-reference/glass_sphere.s{1,2}.pfm are there) are subtracted
in quadrature from the measured errors: true^2 = measured^2 - noise^2.

Times: caustic's is the whole process (`caustic render`, parse to PFM written), the median
of 3 runs; ptracer's is its render calls only (scene loaded and kernels compiled by an
untimed 1-spp warm-up), one run. Writes docs/race_ptracer.md.

Usage: tools/reference/run --race [--max-seconds 150] [--extra-spp 512] [--out docs/race_ptracer.md]
"""
import argparse
import json
import math
import os
import subprocess
import sys
import time

import numpy as np

import calibration as C
import ptracer as PT
import reference as R

SCENE = "scenes/glass_sphere.json"
REF = "glass_sphere"
TARGET = 0.05
W, H = 320, 240
CACHE = os.path.join(C.REPO, "out", "race")


def camera_rays(js, sub):
    """Unit directions of sub x sub rays per pixel, shape (H, W, sub*sub, 3), and the eye."""
    cam = js["camera"]
    eye = np.array(cam["position"], float)
    fwd = np.array(cam["look_at"], float) - eye
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, np.array(cam.get("up", [0, 1, 0]), float))
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    t = math.tan(math.radians(cam["fov_y_deg"]) / 2)
    o = (np.arange(sub) + 0.5) / sub
    xs = (np.arange(W)[:, None] + o[None, :]).reshape(-1)  # W*sub
    ys = (np.arange(H)[:, None] + o[None, :]).reshape(-1)
    u = (2 * xs / W - 1) * t * W / H
    v = (1 - 2 * ys / H) * t
    d = fwd + u[None, :, None] * right + v[:, None, None] * up  # (H*sub, W*sub, 3)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    d = d.reshape(H, sub, W, sub, 3).transpose(0, 2, 1, 3, 4).reshape(H, W, sub * sub, 3)
    return eye, d


def floor_mask(js, sub=4):
    """Pixels none of whose sub x sub rays, nor their neighbours', hits a sphere (the scene's
    only other shapes are planes: the glass sphere scene)."""
    if any(o["type"] not in ("sphere", "plane") for o in js["objects"]):
        raise SystemExit("race.py: only spheres and planes")
    eye, d = camera_rays(js, sub)
    hit = np.zeros(d.shape[:3], bool)
    for o in js["objects"]:
        if o["type"] == "sphere":
            oc = eye - np.array(o["center"], float)
            b = d @ oc
            disc = b * b - (oc @ oc - o["radius"] ** 2)
            hit |= (disc >= 0) & (-b + np.sqrt(np.maximum(disc, 0)) > 0)
    near = hit.any(axis=-1)
    grown = near.copy()  # and their 8 neighbours: random sub-pixel samples find thin slivers
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            grown |= np.roll(np.roll(near, dy, axis=0), dx, axis=1)
    return ~grown


def reference():
    ref = C.read_pfm(os.path.join(C.REPO, "tests", "data", f"{REF}.ref.pfm"))
    caustic = C.read_pfm(os.path.join(C.REPO, "tests", "data", f"{REF}.ref.caustic.pfm"))
    js = json.load(open(os.path.join(C.REPO, SCENE)))
    region = floor_mask(js) & (C.lum(ref) > 0) & (C.lum(caustic) >= 0.1 * C.lum(ref))
    return js, ref, region


def reference_noise(ref, region, prefix):
    """The committed mean's own noise in the region: half the seed pair's rel. RMSE,
    if both seeds are at `prefix`.s{1,2}.pfm and their mean is the committed image."""
    try:
        a, b = C.read_pfm(prefix + ".s1.pfm"), C.read_pfm(prefix + ".s2.pfm")
    except OSError:
        return None
    if np.abs(0.5 * (a + b) - ref).max() > 1e-4 * ref.max():
        return None
    return 0.5 * C.rel_rmse(a, b, region) * b[region].mean() / ref[region].mean()


def ptracer_image(scene, spp, seed0, per_pass=64):
    """Mean of spp/per_pass ptracer passes with seeds seed0, seed0+1, ...; (image, seconds,
    per-pass images)."""
    import mitsuba as mi
    n = max(1, spp // per_pass)
    passes = []
    t0 = time.time()
    for k in range(n):
        passes.append(np.array(mi.render(scene, spp=min(spp, per_pass), seed=seed0 + k), dtype=np.float64)[..., :3])
    return np.mean(passes, axis=0), time.time() - t0, passes


def extra_transport(js, spp, region, ref, saved):
    """ptracer's transport beyond the contract: 2 f(rho) - 4 f(rho/2) with common random
    numbers, and its noise in the region relative to the reference's mean there. From
    `saved` (ptracer.py's renders, SAVED/pt_s{1,2}_a{1.0,0.5}_N.pfm: two seeds, noise from
    their difference) if there, else rendered at `spp` (noise from its even and odd passes)
    and cached under out/race."""
    for n in (4096, 2048, 1024, 512):
        files = {(s, a): os.path.join(saved, f"pt_s{s}_a{a}_{n}.pfm") for s in (1, 2) for a in ("1.0", "0.5")}
        if all(os.path.exists(f) for f in files.values()):
            e = [2 * R.read_pfm(files[(s, "1.0")]) - 4 * R.read_pfm(files[(s, "0.5")]) for s in (1, 2)]
            return extra_info(0.5 * (e[0] + e[1]), e, region, ref, f"2 seeds x {n} spp ({saved})", 0.0)
    os.makedirs(CACHE, exist_ok=True)
    path = os.path.join(CACHE, f"extra_{spp}.pfm")
    if os.path.exists(path) and os.path.exists(path + ".json"):
        return R.read_pfm(path), json.load(open(path + ".json"))
    scenes = {s: PT.mitsuba_scene(js, W, H, s, 10, "ptracer") for s in (1.0, 0.5)}
    runs = {s: ptracer_image(scenes[s], spp, 1_000_000) for s in (1.0, 0.5)}
    halves = [2 * np.mean(runs[1.0][2][h::2], axis=0) - 4 * np.mean(runs[0.5][2][h::2], axis=0) for h in (0, 1)]
    extra, info = extra_info(2 * runs[1.0][0] - 4 * runs[0.5][0], halves, region, ref, f"{spp} spp",
                             runs[1.0][1] + runs[0.5][1])
    R.write_pfm(path, extra.reshape(-1, 3), W, H)
    json.dump(info, open(path + ".json", "w"))
    return extra, info


def extra_info(extra, halves, region, ref, source, seconds):
    """The mean of two independent halves has half their difference's RMS as its noise."""
    d = (halves[0] - halves[1])[region]
    return extra, dict(source=source, seconds=seconds,
                       noise=float(0.5 * np.sqrt((d ** 2).mean()) / ref[region].mean()),
                       share=float(extra[region].sum() / ref[region].sum()))


def true_error(measured, noise):
    return math.sqrt(max(measured ** 2 - noise ** 2, 0.0))


def race_caustic(ref, region, noise, binary, counts):
    rows = []
    for n in counts:
        runs = [C.render(SCENE, n, W, H, binary) for _ in range(3)]
        img = runs[0][0]
        t = float(np.median([r[2] for r in runs]))
        m = C.rel_rmse(img, ref, region)
        rows.append(dict(budget=f"{n} photons", n=n, seconds=t, measured=m, true=true_error(m, noise)))
        print(f"caustic {n:>8} photons: {t:6.2f} s, caustic floor {m:.4f} (true {rows[-1]['true']:.4f})", flush=True)
        if rows[-1]["true"] < TARGET:
            break
    return rows


def race_ptracer(js, target, region, noise, max_spp, max_seconds):
    import mitsuba as mi
    scene = PT.mitsuba_scene(js, W, H, 1.0, 10, "ptracer")
    mi.render(scene, spp=1, seed=0)  # load and compile: not timed
    rows, spp = [], 16
    while spp <= max_spp and sum(r["seconds"] for r in rows) * 2 < max_seconds:
        img, t, _ = ptracer_image(scene, spp, 1)
        m = C.rel_rmse(img, target, region)
        rows.append(dict(budget=f"{spp} spp", n=spp, seconds=t, measured=m, true=true_error(m, noise)))
        print(f"ptracer {spp:>5} spp: {t:6.2f} s, caustic floor {m:.4f} (true {rows[-1]['true']:.4f})", flush=True)
        if rows[-1]["true"] < TARGET:
            break
        spp *= 2
    return rows


def time_to(rows, target=TARGET):
    """Seconds to reach `target`: log-log between the two runs around it; else extrapolated
    along the least-squares line of log error against log budget over the last three runs
    (the convergence rate, measured on budgets, which timing noise does not disturb), at
    those runs' seconds per unit of budget (then marked, with the rate)."""
    pts = [(math.log(r["seconds"]), math.log(r["true"])) for r in rows if r["true"] > 0]
    lt = math.log(target)
    for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
        if e0 >= lt > e1:
            return math.exp(t0 + (lt - e0) / (e1 - e0) * (t1 - t0)), ""
    last = [(math.log(r["n"]), math.log(r["true"])) for r in rows[-3:]]
    mn, me = sum(n for n, _ in last) / len(last), sum(e for _, e in last) / len(last)
    slope = sum((n - mn) * (e - me) for n, e in last) / sum((n - mn) ** 2 for n, _ in last)
    if slope >= 0:
        return float("nan"), " (not reached, not decreasing)"
    budget = math.exp(mn + (lt - me) / slope)
    timed = rows[-3:]
    per_unit = sum(r["seconds"] for r in timed) / sum(r["n"] for r in timed)
    return budget * per_unit, (f" (extrapolated: error ∝ budget^{slope:.2f} over the last 3 runs, "
                               f"{budget:.0f} at their mean {per_unit * 1000:.1f} ms each)")


def write_md(path, args, cau, pt, info, ref_noise, region, load):
    commit = subprocess.run(["git", "-C", C.REPO, "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    tc, nc = time_to(cau)
    tp, npt = time_to(pt)
    noise = "not known (seed images absent), not subtracted" if ref_noise is None else f"{ref_noise:.4f}"
    lines = [
        "# caustic against Mitsuba 3 `ptracer` on the wall-less glass sphere",
        "",
        f"Generated by `tools/reference/run --race` (tools/reference/race.py) at commit {commit}, "
        f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; load average {load[0]} before, {load[1]} after "
        "(the 2 cores are shared: timings are noisy).",
        "",
        f"Scene `{SCENE}`, {W}x{H}; error = relative RMSE over the **caustic floor** ({int(region.sum())} px: "
        "the floor seen directly, no 4x4 sub-pixel ray of the pixel or its neighbours on the sphere, where the reference caustic is "
        ">= 10 % of the reference luminance) against `tests/data/glass_sphere.ref.pfm` (pixel-area). "
        "`true` = sqrt(measured² − noise²) with the reference's own noise there "
        f"({noise}); for ptracer also the noise of the extra transport (below). caustic: plain photons block "
        "(k 64, max_radius 0.25), default estimator, whole-process time, median of 3. ptracer: Mitsuba 3.9.1 "
        "`llvm_ad_rgb`, max_depth 10, passes of 64 spp (fewer below 64), render calls only (its scene load "
        "and kernel compilation excluded), one run.",
        "",
        "ptracer also computes floor light refocused onto the floor (L D S+ D E), which the contract leaves "
        "out; its target is the reference plus that part, measured before the race by ptracer itself with "
        f"common random numbers, 2·f(ρ) − 4·f(ρ/2) from {info['source']}: {100 * info['share']:.1f} % of the "
        f"region's sum, noise {info['noise']:.4f} relative (not timed in the race).",
        "",
        "| renderer | budget | time (s) | caustic-floor rel. RMSE measured | true |",
        "|---|---|---:|---:|---:|",
    ]
    for name, rows in (("caustic", cau), ("ptracer", pt)):
        for r in rows:
            lines.append(f"| {name} | {r['budget']} | {r['seconds']:.2f} | {r['measured']:.4f} | {r['true']:.4f} |")
    lines += ["", f"**Time to {TARGET:.0%} caustic-floor error** (log-log interpolation): caustic "
              f"{tc:.2f} s{nc}, ptracer {tp:.1f} s{npt}: **ratio {tp / tc:.0f}×** (issue 12's bar: ≥ 20×).", ""]
    with open(path, "w") as f:
        f.write("\n".join(lines))
    print("\n".join(lines[-2:]))


def main(argv):
    ap = argparse.ArgumentParser(prog="race.py")
    ap.add_argument("--extra-spp", type=int, default=512)
    ap.add_argument("--max-spp", type=int, default=8192)
    ap.add_argument("--max-seconds", type=float, default=150,
                    help="start no ptracer run whose time (about 2x the last) would pass this total")
    ap.add_argument("--extra-from", default="/tmp/caustic-reference/ptracer",
                    help="ptracer.py's saved renders (pt_s{1,2}_a{1.0,0.5}_N.pfm) for the extra transport")
    ap.add_argument("--photons", default="12500,25000,50000,100000,200000,400000,800000,1600000")
    ap.add_argument("--ref-seeds", default="/tmp/caustic-reference/glass_sphere",
                    help="prefix of the reference's two seed images (PREFIX.s1.pfm, PREFIX.s2.pfm), for its noise")
    ap.add_argument("--out", default=os.path.join(C.REPO, "docs", "race_ptracer.md"))
    ap.add_argument("--binary", default=os.path.join(os.environ.get("CARGO_TARGET_DIR", os.path.join(C.REPO, "target")),
                                                     "release", "caustic"))
    args = ap.parse_args(argv)
    if args.extra_spp < 128:
        ap.error("--extra-spp: at least 128 (two halves of 64-spp passes)")
    load0 = os.getloadavg()[0]
    js, ref, region = reference()
    ref_noise = reference_noise(ref, region, args.ref_seeds)
    R.init_mitsuba()
    extra, info = extra_transport(js, args.extra_spp, region, ref, args.extra_from)
    print(f"extra transport: {100 * info['share']:.1f} % of the region, noise {info['noise']:.4f}; "
          f"reference noise {ref_noise}", flush=True)
    rn = ref_noise or 0.0
    cau = race_caustic(ref, region, rn, args.binary, [int(x) for x in args.photons.split(",")])
    pt = race_ptracer(js, ref + extra, region, math.hypot(rn, info["noise"]), args.max_spp, args.max_seconds)
    write_md(args.out, args, cau, pt, info, ref_noise, region, (f"{load0:.1f}", f"{os.getloadavg()[0]:.1f}"))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

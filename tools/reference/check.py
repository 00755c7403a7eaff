#!/usr/bin/env python3
"""Self-checks of the reference renderer (run as `tools/reference/run --check [...]`).

1. Analytic scenes (pixel-centre rays): a diffuse floor under a point light (radiance
   rho*I*cos/(pi d^2) per pixel), and the same floor with a diffuse sphere (shading +
   shadow computed here with closed-form ray/sphere/plane intersections, independently of
   reference.py's Geometry).
2. Noise of a reference (--pair PREFIX1 PREFIX2, two seeds rendered with
   `run SCENE -o PREFIX.pfm --parts-prefix PREFIX --json PREFIX.json`): relative RMSE
   between the seeds, full image and caustic region; --json writes it with both runs'
   statistics (tests/data/NAME.ref.json).
The comparison with Mitsuba's ptracer is ptracer.py (`run --ptracer`).
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np

import pixel
import reference as R
from metrics import binned, caustic_mask, rel_rmse

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))


# ----------------------------------------------------------------------------- check 1
def analytic_scene(with_sphere):
    js = {
        "camera": {"position": [0, 4, 7], "look_at": [0, 0.6, 0], "up": [0, 1, 0], "fov_y_deg": 40},
        "background": [0.01, 0.02, 0.03],
        "lights": [{"type": "point", "position": [-3, 6, -2], "intensity": [60, 45, 30]}],
        "materials": {"floor": {"type": "diffuse", "albedo": [0.8, 0.6, 0.4]},
                      "ball": {"type": "diffuse", "albedo": [0.3, 0.5, 0.7]}},
        "objects": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "material": "floor"}],
    }
    if with_sphere:
        js["objects"].append({"type": "sphere", "center": [0, 1, 0], "radius": 1.0, "material": "ball"})
    return js


def analytic_image(js, W, H):
    cam = js["camera"]
    pos = np.array(cam["position"], float)
    fwd = np.array(cam["look_at"], float) - pos
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, cam["up"])
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    hh = math.tan(math.radians(cam["fov_y_deg"]) / 2)
    hw = hh * W / H
    img = np.zeros((H, W, 3))
    L = js["lights"][0]
    lp, I = np.array(L["position"], float), np.array(L["intensity"], float)
    mats = js["materials"]
    sph = [o for o in js["objects"] if o["type"] == "sphere"]

    def sphere_t(o, d, c, r):
        oc = o - c
        b = oc @ d
        cc = oc @ oc - r * r
        disc = b * b - cc
        if disc < 0:
            return math.inf
        s = math.sqrt(disc)
        for t in (-b - s, -b + s):
            if t > 1e-7:
                return t
        return math.inf

    for y in range(H):
        for x in range(W):
            u = (2 * (x + 0.5) / W - 1) * hw
            v = (1 - 2 * (y + 0.5) / H) * hh
            d = fwd + u * right + v * up
            d /= np.linalg.norm(d)
            tp = -pos[1] / d[1] if d[1] < 0 else math.inf
            ts = sphere_t(pos, d, np.array(sph[0]["center"], float), sph[0]["radius"]) if sph else math.inf
            if not math.isfinite(min(tp, ts)):
                img[y, x] = js["background"]
                continue
            if ts < tp:
                p = pos + ts * d
                n = (p - np.array(sph[0]["center"])) / sph[0]["radius"]
                rho = np.array(mats["ball"]["albedo"])
            else:
                p = pos + tp * d
                n = np.array([0.0, 1.0, 0.0])
                rho = np.array(mats["floor"]["albedo"])
            l = lp - p
            dist = np.linalg.norm(l)
            l /= dist
            cos = n @ l
            if cos <= 0:
                continue
            if sph and ts >= tp and sphere_t(p, l, np.array(sph[0]["center"], float), sph[0]["radius"]) < dist:
                continue  # floor point in the sphere's shadow
            img[y, x] = rho * I * cos / (math.pi * dist * dist)
    return img


def check_analytic(W, H):
    rows = []
    for with_sphere in (False, True):
        js = analytic_scene(with_sphere)
        scene = R.parse_scene(js)
        full, parts, _, _ = pixel.render(scene, W, H, 1000, 1, 0.003, quiet=True, centre=True)
        full = full.reshape(H, W, 3)
        ref = analytic_image(js, W, H)
        err = np.abs(full - ref) / np.maximum(ref, 1e-6)
        lit = ref.max(axis=2) > 1e-4
        bad = (err > 1e-4).any(axis=2)
        rows.append(("floor + diffuse sphere" if with_sphere else "floor only",
                     float(err[lit].max()) if not with_sphere else float(np.median(err[lit])),
                     int(bad.sum()), W * H, float(np.abs(parts["caustic"]).max())))
    return rows


# ----------------------------------------------------------------------------- noise
def load_prefix(prefix):
    out = {"full": R.read_pfm(prefix + ".pfm")}
    for k in ("caustic", "splat", "gather", "gather2", "direct_seen", "direct_through", "background"):
        f = f"{prefix}.{k}.pfm"
        if os.path.exists(f):
            out[k] = R.read_pfm(f)
    return out


def compare_pair(A, B):
    """Relative RMSE between two seeds, full image and caustic region (one image's own
    noise is that / sqrt(2)); also per part, and over 2x2 bins."""
    mask = caustic_mask(0.5 * (A["caustic"] + B["caustic"]), 0.5 * (A["full"] + B["full"]))
    res = dict(caustic_px=int(mask.sum()),
               pair_rel_rmse_full=rel_rmse(A["full"], B["full"]),
               pair_rel_rmse_caustic_region=rel_rmse(A["full"], B["full"], mask),
               pair_rel_rmse_caustic_part_in_region=rel_rmse(A["caustic"], B["caustic"], mask))
    m2 = binned(mask[..., None].astype(float), 2)[..., 0] > 0.5
    res["pair_rel_rmse_full_2x2"] = rel_rmse(binned(A["full"], 2), binned(B["full"], 2))
    res["pair_rel_rmse_caustic_region_2x2"] = rel_rmse(binned(A["full"], 2), binned(B["full"], 2), m2)
    if "gather2" in A and "gather2" in B:
        # kernel bias of the gather: bias(r) ~ D (edges, bias ~ r) or D/3 (smooth, ~ r^2),
        # D = gather(2r) - gather(r) on the same vertices and photons, mean of both seeds
        D = 0.5 * ((A["gather2"] - A["gather"]) + (B["gather2"] - B["gather"]))
        full = 0.5 * (A["full"] + B["full"])
        res["gather_2r_minus_r_rel_rms_full"] = float(np.sqrt((D ** 2).mean()) / full.mean())
        res["gather_2r_minus_r_rel_rms_caustic_region"] = float(np.sqrt((D[mask] ** 2).mean()) / full[mask].mean())
        res["gather_2r_minus_r_rel_sum"] = float(D.sum() / full.sum())
    for k in ("direct_seen", "direct_through", "splat", "gather"):
        if k in A and k in B:
            res[f"sum_{k}"] = float(0.5 * (A[k] + B[k]).sum() / (0.5 * (A["full"] + B["full"])).sum())
    return res


def mean_of_seeds(runs):
    """The mean of n renders (seeds) of one scene, full image and caustic part, and its
    own noise: per pixel the seeds' sample variance (n - 1) over n, as relative RMSE
    sqrt(mean var/n) / mean over the image and over the caustic region, per pixel and
    over 2x2 bins. For two seeds each is the pair's relative RMSE / 2."""
    n = len(runs)
    full = np.stack([r["full"] for r in runs])
    caustic = np.stack([r["caustic"] for r in runs])
    mf, mc = full.mean(axis=0), caustic.mean(axis=0)
    mask = caustic_mask(mc, mf)
    m2 = binned(mask[..., None].astype(float), 2)[..., 0] > 0.5
    bins = np.stack([binned(f, 2) for f in full])

    def rel(stack, region):
        var = stack.var(axis=0, ddof=1) / n
        mean = stack.mean(axis=0)
        if region is None:
            return float(np.sqrt(var.mean()) / mean.mean())
        return float(np.sqrt(var[region].mean()) / mean[region].mean())

    noise = dict(seeds=n,
                 mean_of_seeds_rel_rmse_full=rel(full, None),
                 mean_of_seeds_rel_rmse_caustic_region=rel(full, mask),
                 mean_of_seeds_rel_rmse_full_2x2=rel(bins, None),
                 mean_of_seeds_rel_rmse_caustic_region_2x2=rel(bins, m2),
                 mean_of_seeds_caustic_px=int(mask.sum()))
    return mf, mc, noise


def main(argv):
    ap = argparse.ArgumentParser(prog="run --check")
    ap.add_argument("--width", type=int, default=160)
    ap.add_argument("--height", type=int, default=120)
    ap.add_argument("--pair", nargs="+", metavar="PREFIX",
                    help="noise between renders (seeds) of one scene: two or more; the pair "
                         "figures are of the first two, the mean's noise of all")
    ap.add_argument("--json", help="with --pair: write the noise figures and the runs' statistics (PREFIX.json) here")
    ap.add_argument("--mean-to", metavar="PREFIX",
                    help="with --pair: write the mean of the seeds as PREFIX.pfm and PREFIX.caustic.pfm")
    ap.add_argument("--skip-analytic", action="store_true")
    args = ap.parse_args(argv)
    W, H = args.width, args.height
    if not args.skip_analytic:
        t0 = time.time()
        rows = check_analytic(W, H)
        print(f"check 1, analytic scenes ({W}x{H}, pixel-centre rays, {time.time() - t0:.1f}s):")
        print(f"  {'scene':<24} {'rel err':>10} {'px >1e-4':>9} {'of':>6} {'max caustic':>12}")
        for name, e, nbad, n, mc in rows:
            tag = "(max)" if name == "floor only" else "(median)"
            print(f"  {name:<24} {e:>10.2e} {nbad:>9d} {n:>6d} {mc:>12.1e}   rel err {tag}")
    if args.pair:
        if len(args.pair) < 2:
            ap.error("--pair: at least two renders")
        renders = [load_prefix(p) for p in args.pair]
        res = compare_pair(renders[0], renders[1])
        mean_full, mean_caustic, noise = mean_of_seeds(renders)
        res.update(noise)
        print(json.dumps(res, indent=1))
        if args.mean_to:
            H, W = mean_full.shape[:2]
            for suffix, m in (("", mean_full), (".caustic", mean_caustic)):
                R.write_pfm(f"{args.mean_to}{suffix}.pfm", m.reshape(-1, 3), W, H)
        if args.json:
            runs = []
            for p in args.pair:
                if os.path.exists(p + ".json"):
                    with open(p + ".json") as f:
                        runs.append(json.load(f))
            with open(args.json, "w") as f:
                json.dump(dict(noise=res, runs=runs), f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

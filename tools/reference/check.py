#!/usr/bin/env python3
"""Self-checks of the reference renderer (run as `tools/reference/run --check [...]`).

1. Analytic scenes: a diffuse floor under a point light (radiance rho*I*cos/(pi d^2) per
   pixel), and the same floor with a diffuse sphere (shading + shadow computed here with
   closed-form ray/sphere/plane intersections, independently of reference.py's Geometry).
2. Caustics seen directly (L S+ D E) are estimated twice, by the photon gather at the eye
   vertices and by splatting photons onto the pinhole: the two must agree within noise.
3. Noise of the reference itself: relative RMSE between two seeds, full image and
   caustic region.

Either renders two seeds itself (--scene, --photons) or reads existing renders
(--pair PREFIX1 PREFIX2, each PREFIX.pfm plus PREFIX.<part>.pfm as written by
`run SCENE -o PREFIX.pfm --parts-prefix PREFIX`).
"""
import argparse
import math
import os
import sys
import time

import numpy as np

import reference as R

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))


def lum(a):
    return a.mean(axis=-1)


def rel_rmse(a, b, mask=None):
    """sqrt(mean |a-b|^2) / mean((a+b)/2), over the mask (all channels)."""
    if mask is None:
        mask = np.ones(a.shape[:2], bool)
    d = (a - b)[mask]
    m = (0.5 * (a + b))[mask].mean()
    return float(np.sqrt((d ** 2).mean()) / m) if m > 0 else float("nan")


def caustic_mask(caustic, direct):
    """Caustic region: caustic radiance > 25 % of the median directly lit radiance."""
    dl = lum(direct)
    ref = np.median(dl[dl > 0]) if (dl > 0).any() else 1.0
    return lum(caustic) > 0.25 * ref


def bin2(a):
    H, W = a.shape[:2]
    return a[: H // 2 * 2, : W // 2 * 2].reshape(H // 2, 2, W // 2, 2, -1).mean(axis=(1, 3))


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
        full, parts, _ = R.render(scene, W, H, 1000, 1, 0.015, quiet=True)
        full = full.reshape(H, W, 3)
        ref = analytic_image(js, W, H)
        err = np.abs(full - ref) / np.maximum(ref, 1e-6)
        lit = ref.max(axis=2) > 1e-4
        bad = (err > 1e-4).any(axis=2)
        rows.append(("floor + diffuse sphere" if with_sphere else "floor only",
                     float(err[lit].max()) if not with_sphere else float(np.median(err[lit])),
                     int(bad.sum()), W * H, float(np.abs(parts["caustic"]).max())))
    return rows


# ----------------------------------------------------------------------------- checks 2, 3
def load_prefix(prefix):
    out = {"full": R.read_pfm(prefix + ".pfm")}
    for k in ("direct", "caustic", "background", "caustic_direct_seen", "splat"):
        f = f"{prefix}.{k}.pfm"
        if os.path.exists(f):
            out[k] = R.read_pfm(f)
    return out


def compare_pair(A, B):
    mask = caustic_mask(0.5 * (A["caustic"] + B["caustic"]), 0.5 * (A["direct"] + B["direct"]))
    res = dict(mask_pixels=int(mask.sum()))
    res["noise_full_pair"] = rel_rmse(A["full"], B["full"])
    res["noise_caustic_pair"] = rel_rmse(A["full"], B["full"], mask)
    res["noise_causticpart_pair"] = rel_rmse(A["caustic"], B["caustic"], mask)
    if "splat" in A and "splat" in B:
        g = 0.5 * (A["caustic_direct_seen"] + B["caustic_direct_seen"])
        s = 0.5 * (A["splat"] + B["splat"])
        # region where the caustic is seen directly (not through glass)
        m2 = caustic_mask(g, 0.5 * (A["direct"] + B["direct"]))
        res["splat_mask_pixels"] = int(m2.sum())
        res["sum_ratio_splat_over_gather"] = float(s[m2].sum() / g[m2].sum())
        res["rmse_splat_vs_gather"] = rel_rmse(s, g, m2)
        res["noise_gather_pair"] = rel_rmse(A["caustic_direct_seen"], B["caustic_direct_seen"], m2)
        res["noise_splat_pair"] = rel_rmse(A["splat"], B["splat"], m2)
        m2b = bin2(m2[..., None].astype(float))[..., 0] > 0.5
        res["rmse_splat_vs_gather_2x2"] = rel_rmse(bin2(s), bin2(g), m2b)
        res["noise_gather_pair_2x2"] = rel_rmse(bin2(A["caustic_direct_seen"]), bin2(B["caustic_direct_seen"]), m2b)
        res["noise_splat_pair_2x2"] = rel_rmse(bin2(A["splat"]), bin2(B["splat"]), m2b)
    return res


def print_pair(name, res, splat_check=True):
    print(f"\n[{name}]")
    print(f"  caustic region: {res['mask_pixels']} px (caustic part > 25% of median direct radiance)")
    print("  check 3, noise of the reference (relative RMSE between two seeds; one image's own")
    print("  noise is that / sqrt(2)):")
    print(f"    {'full image':<34} {res['noise_full_pair']:.4f}")
    print(f"    {'caustic region, full image':<34} {res['noise_caustic_pair']:.4f}")
    print(f"    {'caustic region, caustic part':<34} {res['noise_causticpart_pair']:.4f}")
    if splat_check and "rmse_splat_vs_gather" in res:
        print(f"  check 2, caustics seen directly, region {res['splat_mask_pixels']} px (seed-averaged images):")
        print(f"    {'sum(splat) / sum(gather)':<34} {res['sum_ratio_splat_over_gather']:.4f}")
        print(f"    {'':<34} {'per pixel':>10} {'2x2 bins':>10}")
        print(f"    {'rel RMSE splat vs gather':<34} {res['rmse_splat_vs_gather']:>10.4f} {res['rmse_splat_vs_gather_2x2']:>10.4f}")
        print(f"    {'gather seed-pair rel RMSE':<34} {res['noise_gather_pair']:>10.4f} {res['noise_gather_pair_2x2']:>10.4f}")
        print(f"    {'splat seed-pair rel RMSE':<34} {res['noise_splat_pair']:>10.4f} {res['noise_splat_pair_2x2']:>10.4f}")
        # expected difference of the two seed-averaged estimates if unbiased: each average has
        # variance pair^2/4, so |s-g| ~ sqrt(pair_g^2 + pair_s^2)/2
        exp = 0.5 * math.hypot(res["noise_gather_pair"], res["noise_splat_pair"])
        exp2 = 0.5 * math.hypot(res["noise_gather_pair_2x2"], res["noise_splat_pair_2x2"])
        print(f"    {'expected from noise alone':<34} {exp:>10.4f} {exp2:>10.4f}")


def main(argv):
    ap = argparse.ArgumentParser(prog="run --check")
    ap.add_argument("--scene", default=os.path.join(REPO, "scenes", "glass_sphere.json"))
    ap.add_argument("--photons", type=int, default=20_000_000)
    ap.add_argument("--radius", type=float, default=0.015)
    ap.add_argument("--width", type=int, default=160)
    ap.add_argument("--height", type=int, default=120)
    ap.add_argument("--pair", nargs=2, metavar="PREFIX", help="compare two existing renders instead of rendering")
    ap.add_argument("--skip-analytic", action="store_true")
    ap.add_argument("--supersample", type=int, default=4,
                    help="K x K eye rays per pixel for the self-rendered pair (so that the gather, too, is a pixel-area average)")
    ap.add_argument("--splat-check", action="store_true", help="with --pair: also compare splat vs gather (renders made with --supersample > 1)")
    args = ap.parse_args(argv)
    W, H = args.width, args.height
    if not args.skip_analytic:
        t0 = time.time()
        rows = check_analytic(W, H)
        print(f"check 1, analytic scenes ({W}x{H}, {time.time() - t0:.1f}s):")
        print(f"  {'scene':<24} {'rel err':>10} {'px >1e-4':>9} {'of':>6} {'max caustic':>12}")
        for name, e, nbad, n, mc in rows:
            tag = "(max)" if name == "floor only" else "(median)"
            print(f"  {name:<24} {e:>10.2e} {nbad:>9d} {n:>6d} {mc:>12.1e}   rel err {tag}")
    if args.pair:
        A, B = load_prefix(args.pair[0]), load_prefix(args.pair[1])
        # check 2 needs pixel-area averages on both sides (--supersample > 1): with one ray
        # per pixel the gather is a point sample at the pixel centre, the splat an average.
        print_pair(f"{args.pair[0]} vs {args.pair[1]}", compare_pair(A, B), splat_check=args.splat_check)
        return 0
    scene = R.load_scene(args.scene)
    imgs = []
    for seed in (1, 2):
        t0 = time.time()
        full, parts, st = R.render(scene, W, H, args.photons, seed, args.radius, quiet=True, ss=args.supersample)
        d = {k: v.reshape(H, W, 3) for k, v in parts.items()}
        d["full"] = full.reshape(H, W, 3)
        imgs.append(d)
        print(f"rendered {os.path.basename(args.scene)} seed {seed}: {args.photons} photons, "
              f"{args.supersample}x{args.supersample} eye rays per pixel, "
              f"{time.time() - t0:.0f}s", flush=True)
    print_pair(f"{os.path.basename(args.scene)}, {args.photons} photons, r={args.radius}, "
               f"supersample {args.supersample}", compare_pair(*imgs))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

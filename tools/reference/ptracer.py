#!/usr/bin/env python3
"""Validation of the reference against Mitsuba 3's own integrators (`run --ptracer`).

`--integrator ptracer` (default): Mitsuba's light tracer cannot see anything through glass or
in a mirror from a pinhole (a specular chain to a point camera has probability zero), so it
estimates exactly the part of the image seen directly: L D E and L S+ D E (compared with the
reference's direct_seen + splat), plus transport the contract leaves out (floor light that
glass refocuses onto the floor, L D S+ D E, and deeper).
`--integrator path`: Mitsuba's path tracer sees through glass but cannot carry a point
light's caustics; its L D S* E is compared with direct_seen + direct_through.

With the floor the only diffuse surface, the contract's part is linear in the floor albedo
rho and the rest is O(rho^2): f(rho) = a rho + b rho^2 + c rho^3 + ...  so
4 f(rho/2) - f(rho) = a rho - c rho^3 / 2. Both albedos are rendered with the same seed
(common random numbers; rr_depth > max_depth, so the paths are identical and the rho^2
term cancels path by path), each at seeds 1 and 2 for the noise. Mitsuba's max_depth
counts segments: 10 = L S^8 D E, the contract's longest path seen directly.

Usage: run --ptracer SCENE.json REF_PREFIX [--ref2 REF_PREFIX2] [--integrator path] [--spp N]
  REF_PREFIX: a reference render's --parts-prefix; --ref2 the other seed's (its noise is
  included in expected_from_noise). Figures per pixel and over 4x4 and 8x8 bins.
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np

import reference as R
from metrics import binned, caustic_mask, rel_rmse


def mitsuba_scene(js, W, H, albedo_scale, max_depth, integrator="ptracer"):
    import mitsuba as mi
    T = mi.ScalarTransform4f
    cam = js["camera"]
    d = {"type": "scene",
         "integrator": {"type": integrator, "max_depth": max_depth, "rr_depth": max_depth + 1,
                        "hide_emitters": True},
         "sensor": {"type": "perspective", "fov": cam["fov_y_deg"], "fov_axis": "y",
                    "to_world": T().look_at(origin=cam["position"], target=cam["look_at"], up=cam.get("up", [0, 1, 0])),
                    "film": {"type": "hdrfilm", "width": W, "height": H, "rfilter": {"type": "box"},
                             "pixel_format": "rgb", "component_format": "float32"},
                    "sampler": {"type": "independent"}}}
    mats = {}
    for name, m in js["materials"].items():
        if m["type"] == "diffuse":
            mats[name] = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [albedo_scale * x for x in m["albedo"]]}}
        elif m["type"] == "dielectric":
            if any(m.get("absorption", [0, 0, 0])):
                raise SystemExit("ptracer.py: absorbing dielectrics are not converted")
            mats[name] = {"type": "dielectric", "int_ior": m["ior"], "ext_ior": 1.0}
        elif m["type"] == "mirror":
            mats[name] = {"type": "conductor", "material": "none",
                          "specular_reflectance": {"type": "rgb", "value": m.get("reflectance", [1, 1, 1])}}
        else:
            raise SystemExit(f"ptracer.py: material type {m['type']} not converted")
    for i, o in enumerate(js["objects"]):
        if o["type"] == "sphere":
            d[f"o{i}"] = {"type": "sphere", "center": o["center"], "radius": o["radius"], "bsdf": mats[o["material"]]}
        elif o["type"] == "plane":
            M = np.eye(4)
            M[:3, :3] = R.frame_z_to(np.array(o["normal"], float)) * 1000.0
            M[:3, 3] = o["point"]
            d[f"o{i}"] = {"type": "rectangle", "to_world": T(M.tolist()), "bsdf": mats[o["material"]]}
        else:
            raise SystemExit(f"ptracer.py: object type {o['type']} not converted")
    for i, L in enumerate(js["lights"]):
        d[f"l{i}"] = {"type": "point", "position": L["position"], "intensity": {"type": "rgb", "value": L["intensity"]}}
    return mi.load_dict(d)


def render_pt(js, W, H, scale, spp, seed, max_depth, integrator, per_pass=64):
    import mitsuba as mi
    scene = mitsuba_scene(js, W, H, scale, max_depth, integrator)
    acc = np.zeros((H, W, 3))
    n = max(1, spp // per_pass)
    for k in range(n):
        img = mi.render(scene, spp=per_pass, seed=seed * 100003 + k)
        acc += np.array(img, dtype=np.float64)[..., :3]
    return acc / n


def main(argv):
    ap = argparse.ArgumentParser(prog="ptracer.py")
    ap.add_argument("scene")
    ap.add_argument("ref_prefix")
    ap.add_argument("--ref2", help="second-seed prefix of the reference (its own noise)")
    ap.add_argument("--spp", type=int, default=4096)
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=240)
    ap.add_argument("--max-depth", type=int, default=10,
                    help="Mitsuba max_depth (segments): 10 = L S^8 D E, the contract's longest path seen directly")
    ap.add_argument("--out", default="/tmp/caustic-reference/ptracer")
    ap.add_argument("--json")
    ap.add_argument("--integrator", choices=("ptracer", "path"), default="ptracer",
                    help="path: Mitsuba's path tracer, which sees through glass but cannot carry point-light "
                         "caustics; compared with the reference's direct_seen + direct_through (L D S* E)")
    args = ap.parse_args(argv)
    R.init_mitsuba()
    js = json.load(open(args.scene))
    W, H = args.width, args.height
    os.makedirs(args.out, exist_ok=True)
    imgs, times = {}, {}
    for seed in (1, 2):
        for scale in (1.0, 0.5):
            key = f"s{seed}_a{scale}"
            tag = "pt" if args.integrator == "ptracer" else args.integrator
            path = os.path.join(args.out, f"{tag}_{key}_{args.spp}.pfm")
            if os.path.exists(path):
                imgs[key] = R.read_pfm(path)
                continue
            t0 = time.time()
            imgs[key] = render_pt(js, W, H, scale, args.spp, seed, args.max_depth, args.integrator)
            times[key] = time.time() - t0
            R.write_pfm(path, imgs[key].reshape(-1, 3), W, H)
            R.log(f"ptracer {key}: {args.spp} spp, {times[key]:.0f}s")
    lin = {s: 4 * imgs[f"s{s}_a0.5"] - imgs[f"s{s}_a1.0"] for s in (1, 2)}
    rho = {s: imgs[f"s{s}_a1.0"] for s in (1, 2)}
    other = "splat" if args.integrator == "ptracer" else "direct_through"
    ref = R.read_pfm(args.ref_prefix + ".direct_seen.pfm") + R.read_pfm(f"{args.ref_prefix}.{other}.pfm")
    splat = R.read_pfm(f"{args.ref_prefix}.{other}.pfm")
    ref2 = None
    if args.ref2:
        ref2 = R.read_pfm(args.ref2 + ".direct_seen.pfm") + R.read_pfm(f"{args.ref2}.{other}.pfm")
        splat = 0.5 * (splat + R.read_pfm(f"{args.ref2}.{other}.pfm"))
    refm = ref if ref2 is None else 0.5 * (ref + ref2)
    mask = caustic_mask(splat, refm)
    res = dict(integrator=args.integrator, compared_parts=["direct_seen", other], region=f"{other} >= 10% of the pixel",
               spp=args.spp, max_depth=args.max_depth, caustic_px=int(mask.sum()), seconds=times)
    for b in (1, 4, 8):
        m = binned(mask[..., None].astype(float), b)[..., 0] > 0.5
        L = {s: binned(lin[s], b) for s in (1, 2)}
        P = {s: binned(rho[s], b) for s in (1, 2)}
        Rm = binned(refm, b)
        la, pa = 0.5 * (L[1] + L[2]), 0.5 * (P[1] + P[2])
        row = {}
        for name, mk in (("full", None), ("region", m)):
            lin_pair = rel_rmse(L[1], L[2], mk)
            r = dict(mitsuba_lin_pair=lin_pair, mitsuba_rho_pair=rel_rmse(P[1], P[2], mk),
                     ref_vs_lin=rel_rmse(Rm, la, mk), ref_vs_rho=rel_rmse(Rm, pa, mk),
                     sum_lin_over_ref=float(la[mk if mk is not None else ...].sum() / Rm[mk if mk is not None else ...].sum()),
                     sum_rho_over_ref=float(pa[mk if mk is not None else ...].sum() / Rm[mk if mk is not None else ...].sum()))
            exp2 = lin_pair ** 2 / 4
            if ref2 is not None:
                ref_pair = rel_rmse(binned(ref, b), binned(ref2, b), mk)
                r["ref_pair"] = ref_pair
                exp2 += ref_pair ** 2 / 4
            r["expected_from_noise"] = math.sqrt(exp2)
            row[name] = r
        res[f"bin{b}"] = row
    print(json.dumps(res, indent=1))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(res, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

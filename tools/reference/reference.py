#!/usr/bin/env python3
"""Independent reference renderer for caustic scenes (see README.md).

Pixel-area averages (box filter) of exactly the light transport of the scene contract:
  * direct         L D S* E     random sub-pixel eye samples (pixel.py), adaptive per pixel;
  * caustic, seen directly  L S+ D E   light tracing: every photon deposit connected to the
                                pinhole and added to the pixel it projects into (Splat);
  * caustic, seen through glass / in a mirror  L S+ D S+ E   the eye samples gather the
                                photon map with a disk far below a pixel's footprint (pixel.py);
  * background     rays that leave the scene.
This file holds the scene parser, the ray queries, the optics, the camera, the photon
tracer and the splat; pixel.py the eye sampling and the gather; check.py and ptracer.py
the checks.

Ray queries use Mitsuba 3 (llvm_ad_rgb) for spheres, boxes, cylinders and their caps.
Infinite planes are intersected analytically in float64 (a finite Mitsuba rectangle large
enough to stand for an infinite plane loses too much float32 precision); ties between a
plane and another surface at the same distance go to the plane (see README).
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np

EPS = 1e-4  # ray-origin offset along the geometric normal (scene units)


def log(*a):
    print(*a, file=sys.stderr, flush=True)


# ----------------------------------------------------------------------------- scene
class SceneError(Exception):
    pass


def _vec(v, path, n=3):
    if not isinstance(v, (list, tuple)) or len(v) != n or not all(isinstance(x, (int, float)) for x in v):
        raise SceneError(f"{path}: expected an array of {n} numbers")
    return np.array(v, dtype=np.float64)


def _num(v, path):
    if not isinstance(v, (int, float)) or isinstance(v, bool):
        raise SceneError(f"{path}: expected a number")
    return float(v)


def _keys(d, path, required, optional=()):
    if not isinstance(d, dict):
        raise SceneError(f"{path}: expected an object")
    for k in d:
        if k not in required and k not in optional:
            raise SceneError(f"{path}.{k}: unknown key")
    for k in required:
        if k not in d:
            raise SceneError(f"{path}.{k}: missing")


def _normalize(v):
    return v / np.linalg.norm(v)


def rot_xyz(deg):
    rx, ry, rz = np.radians(deg)
    cx, sx, cy, sy, cz, sz = math.cos(rx), math.sin(rx), math.cos(ry), math.sin(ry), math.cos(rz), math.sin(rz)
    Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def frame_z_to(n):
    """Rotation matrix whose third column is n (unit)."""
    n = _normalize(n)
    a = np.array([1.0, 0, 0]) if abs(n[0]) < 0.9 else np.array([0, 1.0, 0])
    t = _normalize(np.cross(a, n))
    b = np.cross(n, t)
    return np.stack([t, b, n], axis=1)


def parse_scene(js):
    _keys(js, "scene", ["camera", "lights", "materials", "objects"],
          ["image", "background", "ambient", "photons"])
    cam = js["camera"]
    _keys(cam, "camera", ["position", "look_at", "fov_y_deg"], ["up"])
    camera = dict(position=_vec(cam["position"], "camera.position"),
                  look_at=_vec(cam["look_at"], "camera.look_at"),
                  up=_vec(cam.get("up", [0, 1, 0]), "camera.up"),
                  fov=_num(cam["fov_y_deg"], "camera.fov_y_deg"))
    if "image" in js:
        _keys(js["image"], "image", [], ["width", "height"])
    bg = _vec(js.get("background", [0, 0, 0]), "background")
    if "ambient" in js:
        _vec(js["ambient"], "ambient")
    lights = []
    for i, l in enumerate(js["lights"]):
        p = f"lights[{i}]"
        _keys(l, p, ["type", "position", "intensity"])
        if l["type"] != "point":
            raise SceneError(f"{p}.type: expected \"point\"")
        lights.append(dict(position=_vec(l["position"], p + ".position"),
                           intensity=_vec(l["intensity"], p + ".intensity")))
    mats = {}
    for name, m in js["materials"].items():
        p = f"materials.{name}"
        if not isinstance(m, dict) or "type" not in m:
            raise SceneError(f"{p}.type: missing")
        t = m["type"]
        if t == "diffuse":
            _keys(m, p, ["type", "albedo"])
            mats[name] = dict(type="diffuse", albedo=_vec(m["albedo"], p + ".albedo"))
        elif t == "mirror":
            _keys(m, p, ["type"], ["reflectance"])
            mats[name] = dict(type="mirror", reflectance=_vec(m.get("reflectance", [1, 1, 1]), p + ".reflectance"))
        elif t == "dielectric":
            _keys(m, p, ["type", "ior"], ["absorption"])
            mats[name] = dict(type="dielectric", ior=_num(m["ior"], p + ".ior"),
                              absorption=_vec(m.get("absorption", [0, 0, 0]), p + ".absorption"))
        elif t == "classic":
            raise SceneError(f"{p}.type: \"classic\" is the seed paper's non-physical coefficient model; "
                             "the reference renderer supports only the physical materials "
                             "diffuse, mirror and dielectric")
        else:
            raise SceneError(f"{p}.type: expected diffuse, mirror or dielectric, got {t!r}")
    objs = []
    for i, o in enumerate(js["objects"]):
        p = f"objects[{i}]"
        if not isinstance(o, dict) or "type" not in o:
            raise SceneError(f"{p}.type: missing")
        t = o["type"]
        if t == "sphere":
            _keys(o, p, ["type", "center", "radius", "material"])
            ob = dict(center=_vec(o["center"], p + ".center"), radius=_num(o["radius"], p + ".radius"))
        elif t == "box":
            _keys(o, p, ["type", "center", "size", "material"], ["rotation_deg"])
            ob = dict(center=_vec(o["center"], p + ".center"), size=_vec(o["size"], p + ".size"),
                      R=rot_xyz(_vec(o.get("rotation_deg", [0, 0, 0]), p + ".rotation_deg")))
        elif t == "cylinder":
            _keys(o, p, ["type", "base", "axis", "radius", "height", "material"], ["capped"])
            ob = dict(base=_vec(o["base"], p + ".base"), axis=_normalize(_vec(o["axis"], p + ".axis")),
                      radius=_num(o["radius"], p + ".radius"), height=_num(o["height"], p + ".height"),
                      capped=bool(o.get("capped", True)))
        elif t == "plane":
            _keys(o, p, ["type", "point", "normal", "material"])
            ob = dict(point=_vec(o["point"], p + ".point"), normal=_normalize(_vec(o["normal"], p + ".normal")))
        else:
            raise SceneError(f"{p}.type: expected sphere, box, cylinder or plane, got {t!r}")
        if o["material"] not in mats:
            raise SceneError(f"{p}.material: unknown material {o['material']!r}")
        ob["type"] = t
        ob["mat"] = mats[o["material"]]
        objs.append(ob)
    ph = js.get("photons", {})
    _keys(ph, "photons", [], ["count", "k", "max_radius", "max_depth", "passes", "alpha", "caustic_store", "gather"])
    max_depth = int(ph.get("max_depth", 8))
    return dict(camera=camera, background=bg, lights=lights, objects=objs, max_depth=max_depth)


# ----------------------------------------------------------------------------- geometry
class Geometry:
    """Closest-hit and occlusion queries; Mitsuba for bounded shapes, analytic planes."""

    def __init__(self, scene):
        import mitsuba as mi
        import drjit as dr
        self.mi, self.dr = mi, dr
        self.objs = scene["objects"]
        T = mi.ScalarTransform4f
        d = {"type": "scene"}
        self.planes = []
        names = {}
        for i, o in enumerate(self.objs):
            if o["type"] == "plane":
                self.planes.append(i)
            elif o["type"] == "sphere":
                d[f"o{i}"] = {"type": "sphere", "center": o["center"].tolist(), "radius": o["radius"]}
                names[f"o{i}"] = (i, 0)
            elif o["type"] == "box":
                M = np.eye(4)
                M[:3, :3] = o["R"] @ np.diag(o["size"] / 2)
                M[:3, 3] = o["center"]
                d[f"o{i}"] = {"type": "cube", "to_world": T(M.tolist())}
                names[f"o{i}"] = (i, 0)
            elif o["type"] == "cylinder":
                b, a, r, h = o["base"], o["axis"], o["radius"], o["height"]
                d[f"o{i}"] = {"type": "cylinder", "p0": b.tolist(), "p1": (b + h * a).tolist(), "radius": r}
                names[f"o{i}"] = (i, 0)
                if o["capped"]:
                    for part, c, n in ((1, b, -a), (2, b + h * a, a)):
                        M = np.eye(4)
                        M[:3, :3] = frame_z_to(n) * r
                        M[:3, 3] = c
                        d[f"o{i}c{part}"] = {"type": "disk", "to_world": T(M.tolist())}
                        names[f"o{i}c{part}"] = (i, part)
        self.has_mi = len(d) > 1
        if self.has_mi:
            self.scene = mi.load_dict(d)
            ids = dr.reinterpret_array(mi.UInt32, self.scene.shapes_dr()).numpy()
            lut_size = int(ids.max()) + 1
            self.lut_obj = np.full(lut_size, -1, np.int64)
            self.lut_part = np.zeros(lut_size, np.int64)
            for sid, sh in zip(ids, self.scene.shapes()):
                i, part = names[sh.id()]
                self.lut_obj[sid] = i
                self.lut_part[sid] = part

    def _ray(self, o, d, maxt=None):
        mi = self.mi
        f = lambda a: mi.Float(np.ascontiguousarray(a, dtype=np.float32))
        ray = mi.Ray3f(mi.Point3f(f(o[:, 0]), f(o[:, 1]), f(o[:, 2])), mi.Vector3f(f(d[:, 0]), f(d[:, 1]), f(d[:, 2])))
        if maxt is not None:
            ray.maxt = f(maxt)
        return ray

    def _planes_t(self, o, d):
        """(n, nplanes) analytic plane distances, inf where no hit in front."""
        out = []
        for i in self.planes:
            P = self.objs[i]
            den = d @ P["normal"]
            num = (P["point"] - o) @ P["normal"]
            with np.errstate(divide="ignore", invalid="ignore"):
                t = num / den
            t[~(t > 1e-9) | ~np.isfinite(t)] = np.inf
            out.append(t)
        return out

    def intersect(self, o, d):
        """Returns t (inf = miss), obj index (-1), p, outward normal n (float64)."""
        n_rays = len(o)
        t = np.full(n_rays, np.inf)
        obj = np.full(n_rays, -1, np.int64)
        part = np.zeros(n_rays, np.int64)
        if self.has_mi and n_rays:
            pi = self.scene.ray_intersect_preliminary(self._ray(o, d))
            tm = pi.t.numpy().astype(np.float64)
            sid = self.dr.reinterpret_array(self.mi.UInt32, pi.shape).numpy()
            hit = np.isfinite(tm) & (sid > 0)
            t[hit] = tm[hit]
            obj[hit] = self.lut_obj[sid[hit]]
            part[hit] = self.lut_part[sid[hit]]
        # planes: analytic; a plane wins ties (|dt| <= 1e-6 (1+t)) with any other surface
        for i, tp in zip(self.planes, self._planes_t(o, d)):
            win = np.isfinite(tp) & (tp <= t + 1e-6 * (1 + np.where(np.isfinite(t), t, 0)))
            t[win] = tp[win]
            obj[win] = i
            part[win] = 0
        p = o + t[:, None] * d
        n = np.zeros_like(o)
        for i, ob in enumerate(self.objs):
            m = obj == i
            if not m.any():
                continue
            typ = ob["type"]
            if typ == "plane":
                n[m] = ob["normal"]
            elif typ == "sphere":
                v = p[m] - ob["center"]
                nn = v / np.linalg.norm(v, axis=1, keepdims=True)
                n[m] = nn
                p[m] = ob["center"] + ob["radius"] * nn
            elif typ == "box":
                loc = (p[m] - ob["center"]) @ ob["R"]
                rel = np.abs(loc) / (ob["size"] / 2)
                ax = np.argmax(rel, axis=1)
                nl = np.zeros_like(loc)
                nl[np.arange(len(ax)), ax] = np.sign(loc[np.arange(len(ax)), ax])
                n[m] = nl @ ob["R"].T
            elif typ == "cylinder":
                a = ob["axis"]
                pt = part[m]
                v = p[m] - ob["base"]
                h = v @ a
                rad = v - h[:, None] * a
                nn = rad / np.linalg.norm(rad, axis=1, keepdims=True)
                nn[pt == 1] = -a
                nn[pt == 2] = a
                n[m] = nn
        return t, obj, p, n

    def occluded(self, o, d, maxt):
        occ = np.zeros(len(o), bool)
        if self.has_mi and len(o):
            occ = self.scene.ray_test(self._ray(o, d, maxt)).numpy().astype(bool)
        for tp in self._planes_t(o, d):
            occ |= tp < maxt
        return occ


# ----------------------------------------------------------------------------- optics
def reflect(d, n):
    return d - 2 * np.sum(d * n, axis=1, keepdims=True) * n


def fresnel_refract(d, n, ior):
    """Per-ray: F, refracted dir (undefined where tir), tir mask, eta_i, eta_t. n outward."""
    cosd = np.sum(d * n, axis=1)
    entering = cosd < 0
    eta_i = np.where(entering, 1.0, ior)
    eta_t = np.where(entering, ior, 1.0)
    nf = np.where(entering[:, None], n, -n)  # normal facing the incident side
    cos_i = np.abs(cosd)
    eta = eta_i / eta_t
    sin2_t = eta * eta * np.maximum(0.0, 1 - cos_i * cos_i)
    tir = sin2_t >= 1.0
    cos_t = np.sqrt(np.maximum(0.0, 1 - sin2_t))
    rs = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t)
    rp = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t)
    F = np.where(tir, 1.0, 0.5 * (rs * rs + rp * rp))
    t_dir = eta[:, None] * d + (eta * cos_i - cos_t)[:, None] * nf
    t_dir /= np.linalg.norm(t_dir, axis=1, keepdims=True)
    return F, t_dir, tir, eta_i, eta_t, entering


def absorb(w, objs, medium, t):
    """Beer-Lambert over the segments just traced: scales in place the weights `w` of the
    rays inside dielectric `medium` (an object index, -1 outside) by exp(-absorption t)."""
    for i, ob in enumerate(objs):
        m = (medium == i) & np.isfinite(t)
        if m.any() and ob["mat"]["type"] == "dielectric":
            w[m] *= np.exp(-ob["mat"]["absorption"][None] * t[m, None])


def offset(p, n, d):
    s = np.sign(np.sum(d * n, axis=1))
    s[s == 0] = 1
    return p + (EPS * s)[:, None] * n


# ----------------------------------------------------------------------------- camera
class Camera:
    def __init__(self, cam, W, H):
        self.W, self.H = W, H
        self.pos = cam["position"]
        self.fwd = _normalize(cam["look_at"] - cam["position"])
        self.right = _normalize(np.cross(self.fwd, cam["up"]))
        self.up = np.cross(self.right, self.fwd)
        self.half_h = math.tan(math.radians(cam["fov"]) / 2)
        self.half_w = self.half_h * W / H

    def rays_at(self, fx, fy):
        """Rays through image points (fx, fy) in pixel units (x right, y down)."""
        u = (2 * fx / self.W - 1) * self.half_w
        v = (1 - 2 * fy / self.H) * self.half_h
        d = self.fwd[None] + u[:, None] * self.right[None] + v[:, None] * self.up[None]
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        o = np.repeat(self.pos[None], len(d), axis=0)
        return o, d

    def pixel_area(self):
        return (2 * self.half_w / self.W) * (2 * self.half_h / self.H)


# ----------------------------------------------------------------------------- photons
def bounding_sphere(ob):
    t = ob["type"]
    if t == "sphere":
        return ob["center"], ob["radius"]
    if t == "box":
        return ob["center"], 0.5 * np.linalg.norm(ob["size"])
    if t == "cylinder":
        return ob["base"] + 0.5 * ob["height"] * ob["axis"], math.hypot(ob["radius"], 0.5 * ob["height"])
    return None, None


def unit_square(rng, n):
    """n points in [0,1)^2: an Owen-scrambled Sobol' set (scipy.stats.qmc) drawn from rng.
    Each point is marginally uniform (so every photon has exactly the pdf its weight
    assumes: unbiased), and the set is stratified, which lowers the variance of the photon
    count reaching a pixel where the light's directions map smoothly onto the caustic."""
    import warnings
    from scipy.stats import qmc
    if n == 0:
        return np.zeros((0, 2))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # balance warning for n not a power of 2
        return qmc.Sobol(d=2, scramble=True, seed=rng).random(n)


class Emitter:
    """Direction sampling restricted to the cones that contain the specular objects
    (photons that first hit a diffuse surface carry direct light, not caustics), as a
    mixture; weight = intensity / pdf, so the estimator equals uniform emission of 4*pi*I."""

    def __init__(self, light, objs):
        self.pos = light["position"]
        self.I = light["intensity"]
        self.cones = []
        self.full = False
        for ob in objs:
            if ob["mat"]["type"] == "diffuse":
                continue
            c, r = bounding_sphere(ob)
            if c is None:
                self.full = True
                continue
            r *= 1.01
            v = c - self.pos
            D = np.linalg.norm(v)
            if D <= r * 1.0001:
                self.full = True
                continue
            cos_max = math.sqrt(1 - (r / D) ** 2)
            self.cones.append((v / D, cos_max, 2 * math.pi * (1 - cos_max)))
        if self.full:
            self.cones = []
        self.omega = 4 * math.pi if self.full else sum(c[2] for c in self.cones)

    def sample(self, rng, n):
        if self.full:
            u = unit_square(rng, n)
            z = 2 * u[:, 0] - 1
            phi = 2 * math.pi * u[:, 1]
            s = np.sqrt(1 - z * z)
            d = np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=1)
            return d, np.full(n, 4 * math.pi)
        probs = np.array([c[2] for c in self.cones]) / self.omega
        k = rng.choice(len(self.cones), size=n, p=probs)
        d = np.zeros((n, 3))
        for j, (ax, cm, _) in enumerate(self.cones):
            m = k == j
            nm = int(m.sum())
            u = unit_square(rng, nm)
            cz = 1 - u[:, 0] * (1 - cm)
            phi = 2 * math.pi * u[:, 1]
            s = np.sqrt(np.maximum(0, 1 - cz * cz))
            F = frame_z_to(ax)
            d[m] = (np.stack([s * np.cos(phi), s * np.sin(phi), cz], axis=1)) @ F.T
        # pdf = (number of cones containing d) / omega_total
        cnt = np.zeros(n)
        for ax, cm, _ in self.cones:
            cnt += (d @ ax) >= cm
        return d, self.omega / cnt  # 1/pdf


def trace_photons(scene, geo, emitter, rng, n):
    """Traces n photons; returns deposits (p, obj, power RGB, n) on diffuse front sides
    after >= 1 specular interaction. Power normalised for n photons from this light."""
    d, inv_pdf = emitter.sample(rng, n)
    o = np.repeat(emitter.pos[None], n, axis=0)
    pw = (inv_pdf / n)[:, None] * emitter.I[None]
    nspec = np.zeros(n, np.int64)
    medium = np.full(n, -1, np.int64)
    objs = scene["objects"]
    max_depth = scene["max_depth"]
    out = []
    rays = 0
    while len(o):
        rays += len(o)
        t, obj, p, nrm = geo.intersect(o, d)
        absorb(pw, objs, medium, t)
        hit = obj >= 0
        no, nd, npw, nns, nmd = [], [], [], [], []
        for i, ob in enumerate(objs):
            m = hit & (obj == i)
            if not m.any():
                continue
            mat = ob["mat"]
            pp, nn, dd, ww, ns, md = p[m], nrm[m], d[m], pw[m], nspec[m], medium[m]
            if mat["type"] == "diffuse":
                dep = (ns >= 1) & (np.sum(dd * nn, axis=1) < 0)
                out.append((pp[dep], np.full(int(dep.sum()), i), ww[dep], nn[dep]))
                continue
            ok = ns < max_depth
            pp, nn, dd, ww, ns, md = pp[ok], nn[ok], dd[ok], ww[ok], ns[ok], md[ok]
            if mat["type"] == "mirror":
                rd = reflect(dd, nn)
                ww = ww * mat["reflectance"][None]
                nmd.append(md)
            else:
                F, td, tir, _, _, entering = fresnel_refract(dd, nn, mat["ior"])
                refl = tir | (rng.uniform(0, 1, len(F)) < F)
                rd = np.where(refl[:, None], reflect(dd, nn), td)
                nmd.append(np.where(refl, md, np.where(entering, i, -1)))
            no.append(offset(pp, nn, rd))
            nd.append(rd)
            npw.append(ww)
            nns.append(ns + 1)
        if not no:
            break
        o, d, pw = np.concatenate(no), np.concatenate(nd), np.concatenate(npw)
        nspec, medium = np.concatenate(nns), np.concatenate(nmd)
        keep = np.any(pw > 0, axis=1)
        o, d, pw, nspec, medium = o[keep], d[keep], pw[keep], nspec[keep], medium[keep]
    if out:
        dep = tuple(np.concatenate([x[k] for x in out]) for k in range(4))
    else:
        dep = (np.zeros((0, 3)), np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros((0, 3)))
    return dep, rays


# ----------------------------------------------------------------------------- estimators
class Splat:
    """Light-tracing estimate of caustics seen directly (L S+ D E): each deposited photon
    is connected to the pinhole; the estimate is the pixel-area average of radiance over
    the pixel's image-plane footprint."""

    def __init__(self, scene, geo, cam):
        self.scene, self.geo, self.cam = scene, geo, cam
        self.img = np.zeros((cam.W * cam.H, 3))

    def add(self, dep):
        p, obj, pw, n = dep
        cam = self.cam
        v = cam.pos[None] - p
        dist = np.linalg.norm(v, axis=1)
        toc = v / dist[:, None]
        cos_s = np.sum(n * toc, axis=1)
        w = -toc
        cos_c = w @ cam.fwd
        ok = (cos_s > 0) & (cos_c > 1e-6)
        u = (w @ cam.right) / np.where(ok, cos_c, 1)
        vv = (w @ cam.up) / np.where(ok, cos_c, 1)
        fx = (u / cam.half_w + 1) * cam.W / 2
        fy = (1 - vv / cam.half_h) * cam.H / 2
        ok &= (fx >= 0) & (fx < cam.W) & (fy >= 0) & (fy < cam.H)
        idx = np.nonzero(ok)[0]
        if not len(idx):
            return
        o2 = p[idx] + EPS * n[idx]
        d2 = cam.pos[None] - o2
        l2 = np.linalg.norm(d2, axis=1)
        vis = ~self.geo.occluded(o2, d2 / l2[:, None], l2 * (1 - 1e-6))
        idx = idx[vis]
        alb = np.array([o["mat"]["albedo"] if o["mat"]["type"] == "diffuse" else np.zeros(3)
                        for o in self.scene["objects"]])
        f = cos_s[idx] / (dist[idx] ** 2 * cos_c[idx] ** 3 * cam.pixel_area())
        contrib = alb[obj[idx]] / math.pi * pw[idx] * f[:, None]
        pix = fy[idx].astype(np.int64) * cam.W + fx[idx].astype(np.int64)
        np.add.at(self.img, pix, contrib)


# ----------------------------------------------------------------------------- io
def write_pfm(path, img, W, H):
    a = np.asarray(img, dtype="<f4").reshape(H, W, 3)[::-1]  # bottom row first
    with open(path, "wb") as f:
        f.write(f"PF\n{W} {H}\n-1.0\n".encode())
        f.write(np.ascontiguousarray(a).tobytes())


def read_pfm(path):
    with open(path, "rb") as f:
        data = f.read()
    parts = data.split(b"\n", 3)
    assert parts[0].strip() == b"PF"
    W, H = map(int, parts[1].split())
    scale = float(parts[2])
    a = np.frombuffer(parts[3], dtype="<f4" if scale < 0 else ">f4").reshape(H, W, 3)[::-1]
    return a.astype(np.float64).copy()


# ----------------------------------------------------------------------------- driver
def init_mitsuba():
    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")


def load_scene(path):
    with open(path) as f:
        js = json.load(f)
    return parse_scene(js)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if "--check" in argv:
        import check
        return check.main([a for a in argv if a != "--check"])
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scene", nargs="?")
    ap.add_argument("-o", "--output")
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=240)
    ap.add_argument("--photons", type=int, default=20_000_000, help="photons emitted per light (into the cones around the specular objects)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--radius", type=float, default=0.0015,
                    help="largest disk radius of the gather at diffuse points seen through glass or in a mirror (scene units)")
    ap.add_argument("--radius-frac", type=float, default=0.05,
                    help="gather radius = this fraction of the pixel footprint's side at the vertex (at most --radius)")
    ap.add_argument("--spp", type=int, default=64, help="pilot eye samples per pixel (uniform random points)")
    ap.add_argument("--spp-max", type=int, default=4096, help="adaptive cap of eye samples per pixel")
    ap.add_argument("--tol", type=float, default=0.01,
                    help="adaptive target: standard error of a pixel <= tol * max(pixel, 5%% of the mean)")
    ap.add_argument("--batch", type=int, default=1_000_000)
    ap.add_argument("--parts-prefix", help="also write PREFIX.<part>.pfm for each part and PREFIX.spp.pfm")
    ap.add_argument("--json", help="write the run's statistics (photons, spp, seed, time) to this file")
    ap.add_argument("--check", action="store_true", help="run the self-checks (check.py) instead")
    args = ap.parse_args(argv)
    if not args.scene or not args.output:
        ap.error("SCENE and -o OUT.pfm are required")
    try:
        scene = load_scene(args.scene)
    except SceneError as e:
        log(f"error: {args.scene}: {e}")
        return 2
    import pixel
    full, parts, stats, nsamp = pixel.render(scene, args.width, args.height, args.photons, args.seed, args.radius,
                                             radius_frac=args.radius_frac, spp=args.spp, spp_max=args.spp_max, tol=args.tol, batch=args.batch)
    W, H = args.width, args.height
    write_pfm(args.output, full, W, H)
    if args.parts_prefix:
        for k, v in parts.items():
            write_pfm(f"{args.parts_prefix}.{k}.pfm", v, W, H)
        write_pfm(f"{args.parts_prefix}.spp.pfm", np.repeat(nsamp[:, None].astype(np.float64), 3, axis=1), W, H)
    stats["scene"] = os.path.basename(args.scene)
    stats["size"] = [W, H]
    if args.json:
        with open(args.json, "w") as f:
            json.dump(stats, f, indent=1)
    log("stats: " + json.dumps(stats))
    return 0


if __name__ == "__main__":
    sys.exit(main())

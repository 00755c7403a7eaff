"""Pixel-area estimators of the reference (see README.md, "What is computed").

* Eye sub-samples: independent uniform random points in each pixel (box filter), each a
  path tree that follows both Fresnel branches for its first SPLIT specular interactions
  and then chooses one branch by Russian roulette on F (unbiased). At each diffuse vertex:
  point-light direct light (L D S* E); at diffuse vertices reached through >= 1 specular
  interaction, the caustic irradiance from the photon map with a disk of 5% of the pixel's
  footprint side at that vertex (finite differences along the same path), shrunk where it
  holds > 1000 photons (L S+ D S+ E, consistent); also with twice that radius (gather2, the
  bias estimate).
* Caustics seen directly (L S+ D E) are not gathered: reference.Splat (light tracing).
* Adaptive: a pilot of `spp` samples per pixel; pixels whose pilot standard error exceeds
  `tol` of max(pixel, 5% of the mean image luminance) are re-rendered with fresh samples
  (the pilot is discarded there, so the pixel estimate is not conditioned on its own
  spread), up to `spp_max`.
"""
import math
import time

import numpy as np

import reference as R

SPLIT = 2  # specular interactions at which both Fresnel branches are followed
PARTS = ("direct_seen", "direct_through", "gather", "background")
# gather2: the same vertices and photons gathered with twice the radius; not part of the
# image: gather2 - gather estimates the kernel bias (see README)


class PhotonMap:
    """All caustic deposits, one kd-tree per diffuse object; irradiance at a point is
    sum_{|x_i - x| < r, same object} Phi_i / (pi r^2)."""

    def __init__(self, deps, radius, frac=0.05, rmin=2e-4, kmax=1000):
        from scipy.spatial import cKDTree
        self.cKDTree = cKDTree
        self.r, self.frac, self.rmin, self.kmax = radius, frac, rmin, kmax
        self.rhist = {}  # gather vertices per radius class
        p = np.concatenate([d[0] for d in deps]) if deps else np.zeros((0, 3))
        obj = np.concatenate([d[1] for d in deps]) if deps else np.zeros(0, np.int64)
        pw = np.concatenate([d[2] for d in deps]) if deps else np.zeros((0, 3))
        self.trees = {}
        for i in np.unique(obj):
            m = obj == i
            self.trees[int(i)] = (cKDTree(p[m].astype(np.float64)), pw[m].astype(np.float64))
        self.pairs = 0

    def radius_for(self, fp):
        """Gather radius per vertex: frac x the footprint, in classes r_max 2^(-k/2), at least
        rmin; r_max where the footprint is unknown (an offset path leaves the object)."""
        want = np.where(np.isfinite(fp), self.frac * fp, self.r)
        kmax = np.floor(2 * np.log2(self.r / self.rmin))
        k = np.ceil(2 * np.log2(self.r / np.clip(want, self.rmin, self.r)) - 1e-9)
        return self.r * 2.0 ** (-np.clip(k, 0, kmax) / 2)

    def limit(self, p, obj, radius):
        """Shrinks the radius (by classes of 1/sqrt 2) where the disk holds more than kmax
        photons: bounds the cost in a bright focus; a smaller disk only lowers the bias."""
        radius = radius.copy()
        for _ in range(16):
            cnt = np.zeros(len(p), np.int64)
            for r in np.unique(radius):
                m = radius == r
                for i, (tree, _) in self.trees.items():
                    mi = np.nonzero(m & (obj == i))[0]
                    if len(mi):
                        cnt[mi] = tree.query_ball_point(p[mi], r, return_length=True)
            big = cnt > self.kmax
            if not big.any():
                break
            radius[big] /= math.sqrt(2)
        return radius

    def irradiance(self, p, obj, radius, count=True):
        E = np.zeros((len(p), 3))
        for r in np.unique(radius):
            m = radius == r
            if count:
                key = f"{r:.2e}"
                self.rhist[key] = self.rhist.get(key, 0) + int(m.sum())
            E[m] = self._irradiance(p[m], obj[m], r)
        return E

    def _irradiance(self, p, obj, r, max_pairs=20_000_000):
        E = np.zeros((len(p), 3))
        for i, (tree, pw) in self.trees.items():
            idx = np.nonzero(obj == i)[0]
            if not len(idx):
                continue
            cnt = tree.query_ball_point(p[idx], r, return_length=True)
            cum = np.cumsum(cnt)
            start = 0
            while start < len(idx):
                stop = int(np.searchsorted(cum, (cum[start - 1] if start else 0) + max_pairs, side="right"))
                stop = max(stop, start + 1)
                sub = idx[start:stop]
                vt = self.cKDTree(p[sub])
                pr = vt.sparse_distance_matrix(tree, r, output_type="ndarray")
                self.pairs += len(pr)
                for c in range(3):
                    E[sub, c] += np.bincount(pr["i"], weights=pw[pr["j"], c], minlength=len(sub))
                start = stop
        return E / (math.pi * r ** 2)


def trace_samples(scene, geo, cam, pix, rng, pmap, fresnel_rng=None):
    """Per-sample contributions (dict of (n, 3) arrays, keys PARTS) of one eye sample per
    entry of pix. rng=None: pixel-centre rays (analytic check)."""
    frng = fresnel_rng if fresnel_rng is not None else (rng if rng is not None else np.random.default_rng(0))
    ns_total = len(pix)
    out = {k: np.zeros((ns_total, 3)) for k in PARTS + ("gather2",)}
    fx = (pix % cam.W) + (0.5 if rng is None else rng.uniform(0, 1, ns_total))
    fy = (pix // cam.W) + (0.5 if rng is None else rng.uniform(0, 1, ns_total))
    o, d = cam.rays_at(fx, fy)
    bits = np.zeros(ns_total, np.int64)  # bit k set: the k-th specular interaction reflected
    sid = np.arange(ns_total)
    w = np.ones((ns_total, 3))
    nspec = np.zeros(ns_total, np.int64)
    medium = np.full(ns_total, -1, np.int64)
    objs, max_depth = scene["objects"], scene["max_depth"]
    gv = []  # diffuse vertices behind >= 1 specular interaction: (sid, w, p, obj, bits, nspec)
    rays = 0
    while len(o):
        rays += len(o)
        t, obj, p, n = geo.intersect(o, d)
        R.absorb(w, objs, medium, t)
        miss = obj < 0
        _acc(out["background"], sid[miss], w[miss] * scene["background"][None])
        new = []
        for i, ob in enumerate(objs):
            m = obj == i
            if not m.any():
                continue
            mat = ob["mat"]
            pp, nn, dd, ww, si, ns, md, bb = p[m], n[m], d[m], w[m], sid[m], nspec[m], medium[m], bits[m]
            if mat["type"] == "diffuse":
                front = np.sum(dd * nn, axis=1) < 0
                pp, nn, ww, si, ns, bb = pp[front], nn[front], ww[front], si[front], ns[front], bb[front]
                L = _direct_light(scene, geo, pp, nn) * (mat["albedo"] / math.pi)[None]
                seen = ns == 0
                _acc(out["direct_seen"], si[seen], ww[seen] * L[seen])
                _acc(out["direct_through"], si[~seen], ww[~seen] * L[~seen])
                gv.append((si[~seen], ww[~seen] * (mat["albedo"] / math.pi)[None], pp[~seen],
                           np.full(int((~seen).sum()), i), bb[~seen], ns[~seen]))
                continue
            ok = ns < max_depth  # a further specular interaction beyond max_depth: nothing
            pp, nn, dd, ww, si, ns, md, bb = pp[ok], nn[ok], dd[ok], ww[ok], si[ok], ns[ok], md[ok], bb[ok]
            if not len(pp):
                continue
            rd = R.reflect(dd, nn)
            br = bb | (np.int64(1) << ns)
            if mat["type"] == "mirror":
                new.append((R.offset(pp, nn, rd), rd, ww * mat["reflectance"][None], si, ns + 1, md, br))
                continue
            F, td, tir, eta_i, eta_t, entering = R.fresnel_refract(dd, nn, mat["ior"])
            split = ns < SPLIT
            # reflection: weight F when split, else chosen with probability F (weight 1)
            pick_r = tir | (frng.uniform(0, 1, len(F)) < F)
            keep_r = split | pick_r
            wr = np.where(split, F, 1.0)[:, None] * ww
            new.append((R.offset(pp[keep_r], nn[keep_r], rd[keep_r]), rd[keep_r], wr[keep_r], si[keep_r], ns[keep_r] + 1, md[keep_r], br[keep_r]))
            keep_t = ~tir & (split | ~pick_r)
            scale = np.where(split, 1 - F, 1.0) * (eta_i / eta_t) ** 2
            wt = ww * scale[:, None]
            md_t = np.where(entering, i, -1)
            new.append((R.offset(pp[keep_t], nn[keep_t], td[keep_t]), td[keep_t], wt[keep_t], si[keep_t], ns[keep_t] + 1, md_t[keep_t], bb[keep_t]))
        if not new:
            break
        o, d, w, sid, nspec, medium, bits = (np.concatenate([x[k] for x in new]) for k in range(7))
        keep = np.any(w > 0, axis=1)
        o, d, w, sid, nspec, medium, bits = o[keep], d[keep], w[keep], sid[keep], nspec[keep], medium[keep], bits[keep]
    if gv and pmap is not None:
        si, ww, pp, ob, bb, ns = (np.concatenate([x[k] for x in gv]) for k in range(6))
        if len(si):
            fp = footprint(scene, geo, cam, fx[si], fy[si], bb, ns, ob, pp)
            r = pmap.limit(pp, ob, pmap.radius_for(fp))
            _acc(out["gather"], si, ww * pmap.irradiance(pp, ob, r))
            _acc(out["gather2"], si, ww * pmap.irradiance(pp, ob, 2 * r, count=False))
    return out, rays


def footprint(scene, geo, cam, fx, fy, bits, nspec, obj, p, delta=0.01):
    """sqrt of the area of the pixel's footprint at each gather vertex: the same path (same
    reflect/refract choices) retraced from image points offset by delta pixels in x and in
    y; nan where an offset path does not reach the same object (an edge)."""
    px = _retrace(scene, geo, cam, fx + delta, fy, bits, nspec, obj)
    py = _retrace(scene, geo, cam, fx, fy + delta, bits, nspec, obj)
    area = np.linalg.norm(np.cross(px - p, py - p), axis=1) / delta ** 2
    return np.sqrt(area)


def _retrace(scene, geo, cam, fx, fy, bits, nspec, obj):
    objs = scene["objects"]
    o, d = cam.rays_at(fx, fy)
    out = np.full((len(fx), 3), np.nan)
    idx = np.arange(len(fx))
    k = 0
    while len(idx):
        t, ob, p, n = geo.intersect(o[idx], d[idx])
        final = nspec[idx] == k
        good = final & (ob == obj[idx])
        out[idx[good]] = p[good]
        cont = ~final & (ob >= 0)
        idx, ob, p, n, dd = idx[cont], ob[cont], p[cont], n[cont], d[idx][cont]
        refl = ((bits[idx] >> k) & 1) == 1
        nd = R.reflect(dd, n)
        alive = np.ones(len(idx), bool)
        for i, o_ in enumerate(objs):
            m = ob == i
            if not m.any():
                continue
            if o_["mat"]["type"] == "diffuse":
                alive[m] = False
            elif o_["mat"]["type"] == "dielectric":
                _, td, tir, *_ = R.fresnel_refract(dd[m], n[m], o_["mat"]["ior"])
                tr = ~refl[m]
                alive[np.nonzero(m)[0][tr & tir]] = False
                nd[np.nonzero(m)[0][tr]] = td[tr]
            else:
                alive[m & ~refl] = False
        idx, p, n, nd = idx[alive], p[alive], n[alive], nd[alive]
        o[idx] = R.offset(p, n, nd)
        d[idx] = nd
        k += 1
    return out


def _acc(dst, idx, val):
    for c in range(3):
        dst[:, c] += np.bincount(idx, weights=val[:, c], minlength=len(dst))


def _direct_light(scene, geo, p, n):
    """Irradiance from the point lights at diffuse points p (normal n), shadowed by every object."""
    E = np.zeros((len(p), 3))
    for L in scene["lights"]:
        lv = L["position"] - p
        dist = np.linalg.norm(lv, axis=1)
        ldir = lv / dist[:, None]
        cos = np.sum(n * ldir, axis=1)
        ok = cos > 0
        o2 = p[ok] + R.EPS * n[ok]
        vis = np.zeros(len(p), bool)
        vis[ok] = ~geo.occluded(o2, ldir[ok], np.linalg.norm(L["position"] - o2, axis=1) * (1 - 1e-6) - R.EPS)
        E += np.where(vis, cos / dist ** 2, 0.0)[:, None] * L["intensity"][None]
    return E


def eye_pass(scene, geo, cam, pix_list, nper, rng, pmap, chunk=250_000):
    """Means and the standard error of the luminance over nper fresh samples per pixel."""
    npx = len(pix_list)
    sums = {k: np.zeros((npx, 3)) for k in PARTS + ("gather2",)}
    sq = np.zeros(npx)
    rays = 0
    per = max(1, chunk // nper)
    for a in range(0, npx, per):
        px = pix_list[a:a + per]
        loc = np.repeat(np.arange(len(px)), nper)
        out, r = trace_samples(scene, geo, cam, px[loc], rng, pmap)
        rays += r
        tot = sum(out[k] for k in PARTS).mean(axis=1)
        sq[a:a + len(px)] = np.bincount(loc, weights=tot * tot, minlength=len(px))
        for k in PARTS + ("gather2",):
            for c in range(3):
                sums[k][a:a + len(px), c] = np.bincount(loc, weights=out[k][:, c], minlength=len(px))
    means = {k: v / nper for k, v in sums.items()}
    m = sum(means[k] for k in PARTS).mean(axis=1)
    var = np.maximum(sq / nper - m * m, 0) * nper / max(nper - 1, 1)
    return means, np.sqrt(var / nper), rays


def render(scene, W, H, photons, seed, radius, radius_frac=0.05, spp=64, spp_max=1024, tol=0.01, batch=1_000_000,
           quiet=False, centre=False):
    """Returns (full, parts, stats); parts hold (W*H, 3) images."""
    R.init_mitsuba()
    t0 = time.time()
    geo = R.Geometry(scene)
    cam = R.Camera(scene["camera"], W, H)
    rng = np.random.default_rng(seed)
    spl = R.Splat(scene, geo, cam)
    deps, ph_rays, ndep = [], 0, 0
    for L in scene["lights"]:
        em = R.Emitter(L, scene["objects"])
        if em.omega == 0:
            continue
        done = 0
        while done < photons:
            nb = min(batch, photons - done)
            dep, r = R.trace_photons(scene, geo, em, rng, nb)
            dep = (dep[0].astype(np.float32), dep[1].astype(np.int16), dep[2] * (nb / photons), dep[3])
            ph_rays += r
            ndep += len(dep[0])
            spl.add((dep[0].astype(np.float64), dep[1].astype(np.int64), dep[2], dep[3]))
            deps.append((dep[0], dep[1], dep[2].astype(np.float32)))
            done += nb
            if not quiet:
                log(f"  photons {done}/{photons} ({ndep} deposits, {time.time() - t0:.0f}s)")
    pmap = PhotonMap(deps, radius, frac=radius_frac)
    del deps
    t_ph = time.time() - t0
    allpix = np.arange(W * H)
    if centre:
        out, eye_rays = trace_samples(scene, geo, cam, allpix, None, pmap)
        parts, nsamp = out, np.ones(W * H, np.int64)
    else:
        parts, se, eye_rays = eye_pass(scene, geo, cam, allpix, spp, rng, pmap)
        nsamp = np.full(W * H, spp, np.int64)
        m = sum(parts[k] for k in PARTS).mean(axis=1)
        floor = 0.05 * m.mean()
        need = spp * (se / (tol * np.maximum(m, floor))) ** 2
        n_new = np.minimum(spp_max, 2 ** np.ceil(np.log2(np.maximum(need, 1)))).astype(np.int64)
        if not quiet:
            log(f"pilot: {spp} spp, {eye_rays} rays, {time.time() - t0 - t_ph:.0f}s; "
                f"pixels above tol {tol}: {int((n_new > spp).sum())}")
        for n in np.unique(n_new[n_new > spp]):
            sel = np.nonzero(n_new == n)[0]
            means, _, r = eye_pass(scene, geo, cam, sel, int(n), rng, pmap)
            eye_rays += r
            for k in PARTS + ("gather2",):
                parts[k][sel] = means[k]
            nsamp[sel] = n
            if not quiet:
                log(f"  adaptive: {len(sel)} px at {n} spp ({time.time() - t0:.0f}s)")
    parts["splat"] = spl.img
    parts["caustic"] = parts["splat"] + parts["gather"]
    full = sum(parts[k] for k in PARTS) + parts["splat"]
    stats = dict(photons_per_light=photons, lights=len(scene["lights"]), seed=seed, radius=radius,
                 spp_pilot=spp, spp_max=spp_max, tol=tol, eye_samples=int(nsamp.sum()),
                 adaptive_pixels=int((nsamp > spp).sum()), eye_rays=int(eye_rays),
                 photon_rays=int(ph_rays), deposits=int(ndep), gather_pairs=int(pmap.pairs), radius_frac=radius_frac,
                 gather_vertices_per_radius=dict(sorted(pmap.rhist.items())),
                 seconds_photons=round(t_ph, 1), seconds=round(time.time() - t0, 1))
    return full, parts, stats, nsamp


def log(*a):
    R.log(*a)

#!/usr/bin/python3
# evaluate_numpy.py: an independent NumPy implementation of the ground-truth metric that
# `burnish evaluate` computes (core/src/eval/evaluate.cpp), for the naive, toksvig, lean, clean and
# vmf methods with box footprints. Two uses: the speed baseline `burnish evaluate` is measured
# against (a plain vectorised NumPy version: texels vectorised, directions, mips and methods looped
# in Python, float64 throughout, one process), and an independent check of the C++ figures.
#
# The metric (evaluate.h): for mip k a texel's footprint is its aligned 2^k x 2^k block of finest
# normals n_i, GT = mean_i D_s(n_i.h) max(0, n_i.l) with D_s the normalised Blinn-Phong NDF
# (s+2)/(2pi) (n.h)^s; a method's value is its own NDF times max(0, nbar.l). Over every texel of
# the mip and every direction pair: relative L1 = sum|M - GT| / sum GT, energy = sum M / sum GT.
# Like the C++, the finest normals and the pyramid's stored moments are float32 (the pyramid is
# built level from level in double and rounded to float at each level), lobe normals are float32,
# and everything else is float64.
#
# Run (/usr/bin/python3 has numpy and PIL):
#   /usr/bin/python3 core/bench/evaluate_numpy.py MAP.png [--power 512 ...] [--first-mip 1]
#       [--last-mip 4] [--methods naive,toksvig,lean,clean,vmf] [--compare DIR/evaluate.json]
# --compare takes the evaluate.json of
#   build/bin/burnish evaluate MAP --power S --methods naive,toksvig,lean,clean,vmf --out DIR
# and prints the largest relative difference of each figure from the C++ one.
# Limits: 8-bit PNG/TGA/... as PIL reads them (L+A, RGB, RGBA), OpenGL green, wrap border, sizes
# divisible by 2^last-mip (the power-of-two footprints); no --gloss, kernels or the bake's lobe mixture.
#
# Two references no bake can store, for judging how far a lobe fit could go on a map:
#   --methods blurredF (F a number, e.g. blurred2,blurred16): every finest normal of the footprint
#       kept, each shaded with power s/F instead of s (the truth itself with lobes sqrt(F) times wider):
#       a fit that merges normals can only be blurrier than its footprint's normals are.
#   --rings: the share of the sampled truth at each half-vector angle, per power and mip (where the
#       energy figure comes from).
# --energy-split [--steep-deg 45]: where LEAN's energy goes (evaluate --energy-split, evaluate.h
#   LeanEnergySplit): its energy ratio as cosine x shape x steep, from the truth, the truth with LEAN's
#   one cosine, and the Gaussian of the normals tilted at most steep-deg weighted by their share; with
#   --compare the largest relative difference from the C++ figures.
# --brdf ggx: the GGX truth of evaluate --brdf ggx (evaluate.h EvaluateOptions::brdf): each finest texel
#   shaded by ggx_specular.h's term, D_GGX(n.h) V_SmithGGXCorrelated(n.l, n.v)/4 max(0, n.l) with
#   alpha^2 = 2/(s+2) clamped to [kMinRoughness, 1] and n.v clamped to [1e-6, 1], against each isotropic
#   method's one GGX lobe about its mean normal with the alpha of its power (naive, toksvig, vmf; lean and
#   clean have no GGX form). With --methods floor: the one-lobe floor by an independent dense search
#   (FLOOR_GRID alphas evenly in log alpha over [alpha_base, 1] per texel, no refinement: no lobe sharper
#   than the base, as the C++ fit and floor), which the C++
#   fitted lobe and its --floor row are compared with (their rows must lie at or below it, to the grid's
#   spacing).
# --truth-normals bilinear (the default under --brdf ggx, as evaluate's): each finest texel's truth is the
#   mean over its 2x2 sub-samples (at +-1/4 texel) of the bilinear interpolant of the texels, wrapping,
#   each renormalized (fitted_lobe.h TruthNormals::Bilinear: the surface an engine draws when it
#   magnifies the map); texels: its own normal (the default under Blinn-Phong).
# And the plain fit the lobe mixture is measured against, for any K:
#   --methods emK / hardemK (e.g. em3,hardem3): K slope-space Gaussians fitted to each footprint's
#       finest slopes by expectation-maximisation, each slope a Gaussian of covariance I/s (so every
#       lobe's covariance is its points' spread plus I/s), 30 iterations; soft responsibilities (em)
#       or each slope to its most likely lobe (hardem). Deterministic start: the slopes in K equal
#       groups by distance from the footprint's mean slope (core, skirt, steep tail; farthest-first
#       centres made the noisy maps' fits far worse, picking outliers). Shaded as the mixture's shader does:
#       sum_i w_i D_i(h) max(0, n_i.l), D_i the slope-space Gaussian, n_i = normalize(b_i, 1).

import argparse
import json
import math
import sys
import time

import numpy as np
from PIL import Image

VIEW_ANGLE_DEG = 30.0
HALF_ANGLES_DEG = [0.0, 2.5, 5.0, 10.0, 15.0, 20.0, 30.0]
AZIMUTHS = 8
HORIZON_DEG = 3.0
MAX_POWER = 1e9          # numeric.h kMaxPower
MIN_BASE_POWER = 1e-6    # methods.h kMinBasePower
MIN_SLOPE_Z = float(np.float32(0.01))  # normal_pyramid.h kMinSlopeZ (a float)
MIN_COSINE = 1e-6        # numeric.h kMinCosine
MIN_ROUGHNESS = math.sqrt(2.0 / (MAX_POWER + 2.0))  # numeric.h kMinRoughness
FLOOR_GRID = 241
BRDF = "blinn-phong"     # --brdf
TRUTH_NORMALS = "texels"  # --truth-normals (bilinear by default under --brdf ggx)
F32 = np.float32


def load_normals(path):
    """normal_map.cpp decodeTexels for an 8-bit image: unit float32 normals (H, W, 3)."""
    im = Image.open(path)
    if im.mode == "P":
        im = im.convert("RGBA" if "transparency" in im.info else "RGB")
    if im.mode not in ("LA", "RGB", "RGBA"):
        sys.exit(f"unsupported image mode {im.mode} (8-bit LA, RGB or RGBA only)")
    codes = np.asarray(im)
    # OpenImageIO's uint8 -> float conversion: code * (1/255) in float.
    vals = codes.astype(F32) * F32(1.0 / 255.0)
    v = 2.0 * vals.astype(np.float64) - 1.0   # unsigned encoding, in double
    rg = codes.shape[2] == 2
    if not rg:   # auto layout: a constant blue beside varying red/green is an RG map
        const = lambda c: bool(np.all(codes[..., c] == codes.flat[c]))
        rg = const(2) and not (const(0) and const(1))
    x, y = v[..., 0], v[..., 1]
    if rg:
        r2 = x * x + y * y
        scale = np.where(r2 > 1.0, 1.0 / np.sqrt(r2), 1.0)
        x, y = np.where(r2 > 1.0, x * scale, x), np.where(r2 > 1.0, y * scale, y)
        z = np.sqrt(np.maximum(0.0, 1.0 - x * x - y * y))
    else:
        z = v[..., 2]   # alpha (channel 3) is ignored
    length = np.sqrt(x * x + y * y + z * z)
    ok = length >= 1e-4  # shorter vectors become a flat normal
    inv = 1.0 / np.where(ok, length, 1.0)
    n = np.stack([np.where(ok, x * inv, 0.0), np.where(ok, y * inv, 0.0), np.where(ok, z * inv, 1.0)], -1)
    return n.astype(F32)


def view():
    tv = math.radians(VIEW_ANGLE_DEG)
    return (math.sin(tv), 0.0, math.cos(tv))


def ggx_alpha(power):
    """ndf.h ggxAlphaFromPower, clamped as ggx_specular.h ggxSpecularAlpha."""
    return np.clip(np.sqrt(2.0 / (np.clip(power, 0.0, MAX_POWER) + 2.0)), MIN_ROUGHNESS, 1.0)


def ggx_term(nx, ny, nz, alpha, l, h):
    """ggx_specular.h ggxSpecularTerm(n.h, n.l, n.v, alpha), alpha already clamped."""
    v = view()
    noh = nx * h[0] + ny * h[1] + nz * h[2]
    nol = nx * l[0] + ny * l[1] + nz * l[2]
    nov = nx * v[0] + ny * v[1] + nz * v[2]
    a2 = alpha * alpha
    c = np.where(noh > 0.0, np.minimum(noh, 1.0), 0.0)
    d = (1.0 - c) * (1.0 + c) + c * c * a2
    dd = a2 / (math.pi * d * d)
    lc = np.where(nol > MIN_COSINE, np.minimum(nol, 1.0), MIN_COSINE)
    vc = np.where(nov > MIN_COSINE, np.minimum(nov, 1.0), MIN_COSINE)
    gv = lc * np.sqrt(vc * vc * (1.0 - a2) + a2)
    gl = vc * np.sqrt(lc * lc * (1.0 - a2) + a2)
    return np.where((noh > 0.0) & (nol > 0.0), dd * (0.5 / (gv + gl)) * lc, 0.0)


def directions():
    """evaluate.cpp evaluationDirections: (l, h) pairs, in its order."""
    tv = math.radians(VIEW_ANGLE_DEG)
    v = (math.sin(tv), 0.0, math.cos(tv))
    min_lz = math.sin(math.radians(HORIZON_DEG))
    pairs = []
    for deg in HALF_ANGLES_DEG:
        th = math.radians(deg)
        count = 1 if deg == 0.0 else max(AZIMUTHS, 1)
        for j in range(count):
            phi = 2.0 * math.pi * j / count
            h = (math.sin(th) * math.cos(phi), math.sin(th) * math.sin(phi), math.cos(th))
            vh = v[0] * h[0] + v[1] * h[1] + v[2] * h[2]
            l = tuple(2.0 * vh * h[i] - v[i] for i in range(3))
            if l[2] < min_lz:
                continue
            inv = 1.0 / math.sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2])
            pairs.append((tuple(c * inv for c in l), h))
    return pairs


def bilinear_samples(n):
    """fitted_lobe.cpp TruthBand (TruthNormals::Bilinear): per texel the 2x2 sub-samples at +-1/4 texel of the
    bilinear interpolant (wrapping), each renormalized (the texel's own normal where the blend cancels),
    in the C++ order (row offset, then column offset); x, y, z float64 arrays per sample."""
    d = n.astype(np.float64)
    out = []
    for oy in (-1, 1):
        for ox in (-1, 1):
            row = np.roll(d, -oy, axis=0)
            m = 0.75 * (0.75 * d + 0.25 * np.roll(d, -ox, axis=1)) + 0.25 * (0.75 * row + 0.25 * np.roll(row, -ox, axis=1))
            length = np.sqrt(m[..., 0] * m[..., 0] + m[..., 1] * m[..., 1] + m[..., 2] * m[..., 2])
            ok = length > 1e-6
            u = np.where(ok[..., None], m / np.where(ok, length, 1.0)[..., None], d)
            out.append((u[..., 0], u[..., 1], u[..., 2]))
    return out


def truth_values(fx, fy, fz, samples, s, l, h):
    """The truth per finest texel under BRDF: its own normal (texels) or the mean over its bilinear sub-samples."""
    def one(x, y, z):
        if BRDF == "ggx":
            return ggx_term(x, y, z, ggx_alpha(s), l, h)
        return blinn_phong(x, y, z, s, h) * np.maximum(0.0, x * l[0] + y * l[1] + z * l[2])
    if samples is None:
        return one(fx, fy, fz)
    acc = np.zeros(fx.shape)
    for sx, sy, sz in samples:
        acc = acc + one(sx, sy, sz)
    return acc * (1.0 / len(samples))


def block_sum(a):
    """Sum of each aligned 2x2 block, in the C++ order (row by row, left to right)."""
    return ((a[0::2, 0::2] + a[0::2, 1::2]) + a[1::2, 0::2]) + a[1::2, 1::2]


def pyramid(n, last_mip):
    """normal_pyramid.cpp box moments per level: mean Na, slope B and slope covariance, float32.
    Level 1 sums the finest normals in double, level k > 1 its children's float moments weighted
    by their footprint counts (4^(k-1), which cancel: every child weighs the same)."""
    nx, ny, nz = (n[..., i].astype(np.float64) for i in range(3))
    zs = np.maximum(nz, MIN_SLOPE_Z)
    bx, by = nx / zs, ny / zs
    levels = [None]
    # Level 1: raw sums of x, b and b b^T.
    raw = [nx, ny, nz, bx, by, bx * bx, by * by, bx * by]
    for k in range(1, last_mip + 1):
        w = 4.0 ** (k - 1)
        if k > 1:  # children's float moments back to raw second moments (w * (C + b b^T))
            m = levels[k - 1]
            mx, my, mz, sx, sy = (m[c].astype(np.float64) for c in ("mx", "my", "mz", "bx", "by"))
            c0, c1, c2 = (m[c].astype(np.float64) for c in ("c0", "c1", "c2"))
            raw = [w * mx, w * my, w * mz, w * sx, w * sy, w * (c0 + sx * sx), w * (c1 + sy * sy),
                   w * (c2 + sx * sy)]
        inv = 1.0 / (4.0 * w)
        s = [block_sum(r) * inv for r in raw]
        mbx, mby = s[3], s[4]
        levels.append({"mx": s[0].astype(F32), "my": s[1].astype(F32), "mz": s[2].astype(F32),
                       "bx": mbx.astype(F32), "by": mby.astype(F32),
                       "c0": np.maximum(0.0, s[5] - mbx * mbx).astype(F32),
                       "c1": np.maximum(0.0, s[6] - mby * mby).astype(F32),
                       "c2": (s[7] - mbx * mby).astype(F32)})
    return levels


def level0_moments(n):
    """NormalMoments::ofNormal for mip 0: the normal, its float slope, no spread."""
    nx, ny, nz = n[..., 0], n[..., 1], n[..., 2]
    z = np.maximum(nz, F32(0.01))
    zero = np.zeros_like(nx)
    return {"mx": nx, "my": ny, "mz": nz, "bx": nx / z, "by": ny / z, "c0": zero, "c1": zero, "c2": zero}


def method_lobe(method, m, s):
    """methods.cpp methodLobe for box moments m (float32 arrays) and base power s."""
    s = max(min(s, MAX_POWER), MIN_BASE_POWER)   # max(clampPower(s), kMinBasePower)
    if method in ("lean", "clean"):
        bx, by = m["bx"].astype(np.float64), m["by"].astype(np.float64)
        inv = 1.0 / np.sqrt(bx * bx + by * by + 1.0)  # glm::normalize(b.x, b.y, 1), then float
        normal = [(bx * inv).astype(F32), (by * inv).astype(F32), inv.astype(F32)]
        c0, c1, c2 = (m[c].astype(np.float64) for c in ("c0", "c1", "c2"))
        if method == "lean":
            cov = (c0 + 1.0 / s, c1 + 1.0 / s, c2)
        else:
            sigma2 = 0.5 * (c0 + c1) + 1.0 / s
            cov = (sigma2, sigma2, np.zeros_like(sigma2))
        det = cov[0] * cov[1] - cov[2] * cov[2]
        good = det > 0.0
        return {"normal": [c.astype(np.float64) for c in normal], "bx": bx, "by": by, "cov": cov,
                "det": np.where(good, det, 1.0), "good": good,
                "norm": (2.0 * math.pi) * np.sqrt(np.where(good, det, 1.0))}
    # Isotropic lobes: the float mean direction Na/|Na| and a power.
    mx, my, mz = m["mx"], m["my"], m["mz"]
    length = np.sqrt(mx * mx + my * my + mz * mz)   # float32, glm::length
    ok = (length > 0) & np.isfinite(length)
    safe = np.where(ok, length, F32(1))
    normal = [np.where(ok, mx / safe, F32(0)), np.where(ok, my / safe, F32(0)), np.where(ok, mz / safe, F32(1))]
    r = np.minimum(length, F32(1)).astype(np.float64)   # lengthNa()
    r = np.where(r > 0.0, r, 0.0)
    if method == "naive":
        power = s
    elif method == "toksvig":   # gloss.cpp toksvigPower
        denom = r + s * (1.0 - r)
        ft = np.where(denom > 0.0, r / np.where(denom > 0.0, denom, 1.0), 1.0)
        power = np.clip(ft * s, 0.0, s)
    elif method == "vmf":       # methods.cpp vmfKappa, methodPower
        one_minus_r2 = (1.0 - r) * (1.0 + r)
        pos = one_minus_r2 > 0.0
        kappa = np.where(pos, np.clip(r * (3.0 - r * r) / np.where(pos, one_minus_r2, 1.0), 0.0, MAX_POWER),
                         MAX_POWER)
        kpos = kappa > 0.0
        p = 1.0 / (1.0 / s + 1.0 / np.where(kpos, kappa, 1.0))
        power = np.where(kpos, np.clip(p, 0.0, MAX_POWER), 0.0)
    else:
        sys.exit(f"unknown method {method}")
    return {"normal": [c.astype(np.float64) for c in normal], "power": power}


def blinn_phong(nx, ny, nz, power, h):
    """ndf.h blinnPhongNdf(n.h, power) with numeric.h powCos."""
    c = nx * h[0] + ny * h[1] + nz * h[2]
    p = np.clip(power, 0.0, MAX_POWER)
    pos = c > 0.0
    pc = np.exp(p * np.log(np.where(pos, np.minimum(c, 1.0), 1.0)))
    pc = np.where(pos, pc, 0.0)
    if np.ndim(p) or p == 0.0:
        pc = np.where(p == 0.0, 1.0, pc)
    return (p + 2.0) / (2.0 * math.pi) * pc


def method_value(lobe, l, h):
    """evaluate.cpp methodValue: the lobe's NDF times max(0, nbar.l) (under --brdf ggx: ggx_term)."""
    nx, ny, nz = lobe["normal"]
    if BRDF == "ggx":
        return ggx_term(nx, ny, nz, ggx_alpha(lobe["power"]), l, h)
    if "power" in lobe:
        d = blinn_phong(nx, ny, nz, lobe["power"], h)
    elif h[2] > 0.0:   # methods.cpp slopeGaussianNdf
        c0, c1, c2 = lobe["cov"]
        dx = h[0] / h[2] - lobe["bx"]
        dy = h[1] / h[2] - lobe["by"]
        e = (dx * dx * c1 + dy * dy * c0 - 2.0 * dx * dy * c2) / lobe["det"]
        hz2 = h[2] * h[2]
        d = np.where(lobe["good"], np.exp(-0.5 * e) / (lobe["norm"] * hz2 * hz2), 0.0)
    else:
        d = 0.0
    return d * np.maximum(0.0, nx * l[0] + ny * l[1] + nz * l[2])


EM_ITERATIONS = 30


def em_fit(slopes, k, v, hard):
    """K Gaussians fitted to each row of slopes (T, N, 2) by EM, each slope a Gaussian of covariance
    v I: weights (T, K), means (T, K, 2), covariances (T, K, 2, 2)."""
    t, n, _ = slopes.shape
    k = min(k, n)
    # Start: the slopes split into K equal groups by their distance from the footprint's mean slope
    # (a core, a skirt, the steep tail), stable order so ties go to the lower index.
    dist = ((slopes - slopes.mean(1, keepdims=True)) ** 2).sum(-1)
    rank = np.argsort(np.argsort(dist, 1, kind="stable"), 1, kind="stable")   # T, N
    resp = ((rank * k // n)[..., None] == np.arange(k)).astype(np.float64)   # T, N, K
    eye = np.eye(2)
    for it in range(EM_ITERATIONS + 1):
        w = resp.sum(1)   # T, K
        safe = np.where(w > 0.0, w, 1.0)
        mean = np.einsum("tnk,tnd->tkd", resp, slopes) / safe[..., None]
        d = slopes[:, :, None] - mean[:, None]   # T, N, K, 2
        cov = np.einsum("tnk,tnkd,tnke->tkde", resp, d, d) / safe[..., None, None] + v * eye
        if it == EM_ITERATIONS:
            break
        inv = np.linalg.inv(cov)
        logdet = np.log(np.linalg.det(cov))
        e = np.einsum("tnkd,tkde,tnke->tnk", d, inv, d) + v * np.trace(inv, axis1=-2, axis2=-1)[:, None]
        score = np.where(w[:, None] > 0.0, np.log(safe / n)[:, None] - 0.5 * logdet[:, None] - 0.5 * e, -np.inf)
        if hard:
            resp = (np.argmax(score, 2)[..., None] == np.arange(k)).astype(np.float64)
        else:
            score = score - score.max(2, keepdims=True)
            resp = np.exp(score)
            resp /= resp.sum(2, keepdims=True)
    return w / n, mean, cov


def footprint_rows(a, f):
    """The aligned f x f footprints of a (H, W) or (H, W, C) array as rows, footprints row-major:
    (H/f * W/f, f*f) or (H/f * W/f, f*f, C)."""
    h, w = a.shape[:2]
    rest = a.shape[2:]
    return a.reshape((h // f, f, w // f, f) + rest).swapaxes(1, 2).reshape((-1, f * f) + rest)


def em_lobes(method, n, k_mip, s):
    """The EM reference's lobes for mip k_mip (method emK or hardemK)."""
    hard = method.startswith("hard")
    k = int(method[len("hardem") if hard else len("em"):])
    height, width = n.shape[:2]
    f = 1 << k_mip
    z = np.maximum(n[..., 2], F32(0.01))
    b = np.stack([n[..., 0] / z, n[..., 1] / z], -1).astype(np.float64)
    slopes = footprint_rows(b, f)
    w, mean, cov = em_fit(slopes, k, 1.0 / s, hard)
    lobes = []
    for i in range(w.shape[1]):
        bx, by = mean[:, i, 0], mean[:, i, 1]
        c = (cov[:, i, 0, 0], cov[:, i, 1, 1], cov[:, i, 0, 1])
        det = c[0] * c[1] - c[2] * c[2]   # at least (1/s)^2: every covariance has I/s added
        inv = 1.0 / np.sqrt(bx * bx + by * by + 1.0)
        lobes.append({"normal": [bx * inv, by * inv, inv], "bx": bx, "by": by, "cov": c, "det": det,
                      "good": det > 0.0, "norm": (2.0 * math.pi) * np.sqrt(det)})
    return {"w": w, "lobes": lobes, "shape": (height // f, width // f)}


def em_value(lobes, l, h):
    """sum_i w_i D_i(h) max(0, n_i.l) of the EM reference's lobes (method_value's slope-space Gaussian
    for each), one value per texel."""
    w, value = lobes["w"], 0.0
    for lobe, weight in zip(lobes["lobes"], w.T):
        value = value + np.where(weight > 0.0, weight * method_value(lobe, l, h), 0.0)
    return np.reshape(value, lobes["shape"])


def energy_split(n, levels, s, k, pairs, steep_deg):
    """LeanEnergySplit for base power s at mip k (power-of-two box footprints): (energy, cosine, shape,
    steep, steep normals' share, their share of the truth)."""
    f = 1 << k
    fx, fy, fz = (n[..., i].astype(np.float64) for i in range(3))
    steep = fz < math.cos(math.radians(steep_deg))
    lean = method_lobe("lean", levels[k], s)   # levels[0]: evaluate's level0_moments
    # The slope moments of the normals that are not steep, per footprint (as the pyramid's slopes),
    # rounded to float as NormalMoments holds them, then LEAN's lobe of them weighted by their share.
    zs = np.maximum(fz, float(MIN_SLOPE_Z))
    keep = footprint_rows((~steep).astype(np.float64), f)
    bx, by = footprint_rows(fx / zs, f), footprint_rows(fy / zs, f)
    count = keep.sum(1)
    safe = np.where(count > 0, count, 1.0)
    mx, my = (keep * bx).sum(1) / safe, (keep * by).sum(1) / safe
    c0 = np.maximum(0.0, (keep * bx * bx).sum(1) / safe - mx * mx)
    c1 = np.maximum(0.0, (keep * by * by).sum(1) / safe - my * my)
    c2 = (keep * bx * by).sum(1) / safe - mx * my
    shape = lean["normal"][0].shape
    m = {"bx": mx.astype(F32).reshape(shape), "by": my.astype(F32).reshape(shape),
         "c0": c0.astype(F32).reshape(shape), "c1": c1.astype(F32).reshape(shape),
         "c2": c2.astype(F32).reshape(shape)}
    flat = method_lobe("lean", m, s)
    flat["normal"] = lean["normal"]
    share = (count / float(f * f)).reshape(shape)
    sums = dict(truth=0.0, cosine=0.0, steep_truth=0.0, flat=0.0, lean=0.0)
    nx, ny, nz = lean["normal"]
    for l, h in pairs:
        d = blinn_phong(fx, fy, fz, s, h)
        dc = d * np.maximum(0.0, fx * l[0] + fy * l[1] + fz * l[2])
        block = lambda a: footprint_rows(a, f).mean(1).reshape(shape)
        sums["truth"] += float(np.sum(block(dc)))
        sums["cosine"] += float(np.sum(block(d) * np.maximum(0.0, nx * l[0] + ny * l[1] + nz * l[2])))
        sums["steep_truth"] += float(np.sum(block(np.where(steep, dc, 0.0))))
        sums["flat"] += float(np.sum(np.where(share > 0.0, share * method_value(flat, l, h), 0.0)))
        sums["lean"] += float(np.sum(method_value(lean, l, h)))
    ratio = lambda a, b: a / b if b > 0.0 else 1.0
    # A step that sums to 0 is skipped (factor 1), as in the C++.
    cosine_base = sums["cosine"] if sums["cosine"] > 0.0 else sums["truth"]
    shape_base = sums["flat"] if sums["flat"] > 0.0 else cosine_base
    return (ratio(sums["lean"], sums["truth"]), ratio(cosine_base, sums["truth"]),
            ratio(shape_base, cosine_base), ratio(sums["lean"], shape_base), float(steep.mean()),
            sums["steep_truth"] / sums["truth"] if sums["truth"] > 0.0 else 0.0)


def evaluate(n, powers, first_mip, last_mip, methods):
    """Returns {(method, power, mip): (relative L1, energy)} and the direction count."""
    height, width = n.shape[:2]
    last_level = int(math.log2(max(width, height)))
    last_mip = min(last_mip, last_level)
    if first_mip < 0 or first_mip > last_mip or width % (1 << last_mip) or height % (1 << last_mip):
        sys.exit(f"mips {first_mip}..{last_mip}: need sizes divisible by 2^last (box footprints only)")
    pairs = directions()
    levels = pyramid(n, last_mip)
    levels[0] = level0_moments(n)
    fx, fy, fz = (n[..., i].astype(np.float64) for i in range(3))
    samples = bilinear_samples(n) if TRUTH_NORMALS == "bilinear" else None
    mips = range(first_mip, last_mip + 1)
    out = {}
    rings = {}
    blurred = {m: float(m[len("blurred"):]) for m in methods if m.startswith("blurred")}
    em = [m for m in methods if m.startswith("em") or m.startswith("hardem")]
    for s in powers:
        lobes = {(m, k): method_lobe(m, levels[k], s)
                 for m in methods if m not in blurred and m not in em and m != "floor" for k in mips}
        # The floor's candidates: per texel and candidate alpha, sum over pairs of |lobe - truth|.
        floor_alphas = np.exp(np.linspace(math.log(float(ggx_alpha(s))), 0.0, FLOOR_GRID))
        floor_err = {k: np.zeros((FLOOR_GRID,) + levels[k]["mx"].shape) for k in mips} if "floor" in methods else {}
        floor_truth = {k: [] for k in floor_err}
        em_fits = {(m, k): em_lobes(m, n, k, s) for m in em for k in mips}
        acc = {(m, k): [0.0, 0.0, 0.0] for m in methods for k in mips}   # sum |M - GT|, sum M, sum GT
        for l, h in pairs:
            # Ground truth per finest texel, then summed over 2x2 blocks level by level.
            sums = truth_values(fx, fy, fz, samples, s, l, h)
            truth = {}
            for k in range(0, last_mip + 1):
                if k > 0:
                    sums = block_sum(sums)
                if k >= first_mip:
                    truth[k] = sums / float(4 ** k)
            theta = round(math.degrees(math.acos(min(1.0, h[2]))), 3)
            for k in mips:
                rings.setdefault((s, k), {}).setdefault(theta, 0.0)
                rings[(s, k)][theta] += float(np.sum(truth[k]))
            values = {}
            for m, f in blurred.items():   # the truth's own sums with power s / f
                b = blinn_phong(fx, fy, fz, s / f, h) * np.maximum(0.0, fx * l[0] + fy * l[1] + fz * l[2])
                for k in range(0, last_mip + 1):
                    if k > 0:
                        b = block_sum(b)
                    if k >= first_mip:
                        values[(m, k)] = b / float(4 ** k)
            for (m, k), lobe in lobes.items():
                values[(m, k)] = method_value(lobe, l, h)
            for (m, k), fit in em_fits.items():
                values[(m, k)] = em_value(fit, l, h)
            for k, err in floor_err.items():   # every candidate alpha about the mean normal (naive's)
                lobe = method_lobe("naive", levels[k], s)
                nx, ny, nz = lobe["normal"]
                for i, a in enumerate(floor_alphas):
                    v = ggx_term(nx, ny, nz, a, l, h) if BRDF == "ggx" else \
                        blinn_phong(nx, ny, nz, 2.0 / (a * a) - 2.0, h) * np.maximum(0.0, nx * l[0] + ny * l[1] + nz * l[2])
                    err[i] += np.abs(v - truth[k])
                floor_truth[k].append(float(np.sum(truth[k])))
            for (m, k), value in values.items():
                a = acc[(m, k)]
                a[0] += float(np.sum(np.abs(value - truth[k])))
                a[1] += float(np.sum(value))
                a[2] += float(np.sum(truth[k]))
        for k, err in floor_err.items():   # the per-texel minimum over the grid
            tsum = sum(floor_truth[k])
            acc[("floor", k)] = [float(np.sum(np.min(err, axis=0))), float("nan"), tsum]
        for (m, k), (err, msum, tsum) in acc.items():
            out[(m, s, k)] = (err / tsum, msum / tsum) if tsum > 0.0 else (0.0, 1.0)
    return out, len(pairs), last_mip, rings, levels


def compare_split(splits, report, path):
    ref = {(float(e["base_power"]), int(e["mip"])): e for e in report.get("lean_energy_split", [])}
    keys = ("energy", "cosine", "shape", "steep", "steep_normals", "steep_truth")
    worst = {key: 0.0 for key in keys}
    for (s, k), values in splits.items():
        if (s, k) not in ref:
            print(f"  energy split, power {s:g} mip {k}: not in the C++ report (run it with --energy-split)")
            continue
        for key, v in zip(keys, values):
            c = ref[(s, k)][key]
            worst[key] = max(worst[key], abs(v - c) / abs(c) if c else abs(v))
    print("energy split, max rel diff: " + ", ".join(f"{key} {w:.3e}" for key, w in worst.items()))


def compare(results, path, splits=None):
    with open(path) as f:
        report = json.load(f)
    ref = {}
    for e in report["errors"]:
        if e.get("kernel", "box") == "box" and not e.get("between_texels") and not e.get("lobes"):
            ref[(e["method"], float(e["base_power"]), int(e["mip"]))] = (e["relative_l1"], e["energy_ratio"])
    if report.get("brdf", "blinn-phong") != BRDF:
        print(f"note: the C++ report is under --brdf {report.get('brdf', 'blinn-phong')}, this run under {BRDF}")
    # The NumPy floor (a dense grid) against the C++ fitted lobe and one-lobe floor: C++ <= NumPy + spacing.
    for (m, s, k), (rl1, _) in results.items():
        if m != "floor":
            continue
        for name in ("fitted", "one-lobe floor"):
            if (name, s, k) in ref:
                print(f"  power {s:g} mip {k}: NumPy grid floor {rl1:.6f}, C++ {name} {ref[(name, s, k)][0]:.6f} "
                      f"(ratio {ref[(name, s, k)][0] / rl1:.4f})")
    print(f"\nAgainst {path} (C++ evaluation_seconds {report.get('evaluation_seconds', float('nan')):.3f}, "
          f"{report.get('directions')} directions):")
    print(f"{'method':<10}{'max rel diff relL1':>20}{'max rel diff energy':>21}  figures")
    worst = {}
    for (m, s, k), (rl1, en) in results.items():
        if m == "floor":
            continue
        if (m, s, k) not in ref:
            print(f"  {m} power {s:g} mip {k}: not in the C++ report")
            continue
        cr, ce = ref[(m, s, k)]
        dr = abs(rl1 - cr) / abs(cr) if cr else abs(rl1)
        de = abs(en - ce) / abs(ce) if ce else abs(en)
        w = worst.setdefault(m, [0.0, 0.0, 0])
        w[0], w[1], w[2] = max(w[0], dr), max(w[1], de), w[2] + 1
    for m, (dr, de, count) in worst.items():
        print(f"{m:<10}{dr:>20.3e}{de:>21.3e}  {count}")
    if splits:
        compare_split(splits, report, path)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("map")
    ap.add_argument("--power", type=float, nargs="+", default=[512.0])
    ap.add_argument("--first-mip", type=int, default=1)
    ap.add_argument("--last-mip", type=int, default=4)
    ap.add_argument("--methods", default="naive,toksvig,lean,clean,vmf")
    ap.add_argument("--compare", metavar="EVALUATE_JSON")
    ap.add_argument("--rings", action="store_true", help="print the share of the sampled truth per half-vector angle")
    ap.add_argument("--energy-split", action="store_true", help="where LEAN's energy goes (evaluate --energy-split)")
    ap.add_argument("--steep-deg", type=float, default=45.0)
    ap.add_argument("--brdf", choices=["blinn-phong", "ggx"], default="blinn-phong",
                    help="the truth's and the lobes' BRDF (evaluate --brdf)")
    ap.add_argument("--truth-normals", choices=["texels", "bilinear"],
                    help="the finest normals as facets or as the bilinear interpolant (evaluate --truth-normals; "
                         "default bilinear under --brdf ggx, texels otherwise)")
    args = ap.parse_args()
    global BRDF, TRUTH_NORMALS
    BRDF = args.brdf
    TRUTH_NORMALS = args.truth_normals or ("bilinear" if BRDF == "ggx" else "texels")
    if args.energy_split and TRUTH_NORMALS != "texels":
        sys.exit("the energy split is measured on the finest texels (--truth-normals texels), as evaluate's")
    methods = [m for m in args.methods.split(",") if m]
    if BRDF == "ggx":
        for m in methods:
            if m not in ("naive", "toksvig", "vmf", "floor"):
                sys.exit(f"method {m} has no GGX form here (--brdf ggx: naive, toksvig, vmf, floor)")
    for m in methods:
        for prefix, kind in (("blurred", float), ("hardem", int), ("em", int)):
            if m.startswith(prefix):
                try:
                    ok = kind(m[len(prefix):]) > 0
                except ValueError:
                    ok = False
                if not ok:
                    sys.exit(f"method {m}: {prefix} takes a positive number, e.g. {prefix}{'2' if kind is float else '3'}")
                break
    for s in args.power:
        if not (0.0 < s <= MAX_POWER):
            sys.exit(f"base power {s} is outside (0, 1e9]")

    t0 = time.perf_counter()
    n = load_normals(args.map)
    t1 = time.perf_counter()
    results, ndirs, last_mip, rings, levels = evaluate(n, args.power, args.first_mip, args.last_mip, methods)
    t2 = time.perf_counter()

    print(f"{args.map}: {n.shape[1]}x{n.shape[0]}, {ndirs} direction pairs, mips {args.first_mip}..{last_mip}")
    mips = range(args.first_mip, last_mip + 1)
    for s in args.power:
        print(f"\nbase power {s:g}: relative L1 / energy per mip")
        print(f"{'method':<10}" + "".join(f"{'mip ' + str(k):>22}" for k in mips))
        for m in methods:
            cells = "".join(f"{results[(m, s, k)][0]:>11.6f}{results[(m, s, k)][1]:>11.6f}" for k in mips)
            print(f"{m:<10}{cells}")
    if args.rings:
        for s in args.power:
            print(f"\nbase power {s:g}: share of the sampled truth per half-vector angle (degrees)")
            thetas = sorted(rings[(s, args.first_mip)])
            print(f"{'mip':<10}" + "".join(f"{t:>9g}" for t in thetas))
            for k in mips:
                total = sum(rings[(s, k)].values())
                print(f"{k:<10}" + "".join(f"{rings[(s, k)][t] / total:>9.3f}" for t in thetas))
    splits = {}
    if args.energy_split:
        if not 0.0 < args.steep_deg < 90.0:
            sys.exit(f"--steep-deg {args.steep_deg} is outside (0, 90)")
        pairs = directions()
        for s in args.power:
            print(f"\nbase power {s:g}: where LEAN's energy goes (energy = cosine x shape x steep; "
                  f"steep: tilted more than {args.steep_deg:g} deg)")
            print(f"{'mip':<6}{'energy':>10}{'cosine':>10}{'shape':>10}{'steep':>10}{'steep n.':>10}{'steep GT':>11}")
            for k in mips:
                splits[(s, k)] = energy_split(n, levels, s, k, pairs, args.steep_deg)
                print(f"{k:<6}" + "".join(f"{v:>10.4f}" for v in splits[(s, k)][:5]) + f"{splits[(s, k)][5]:>11.3e}")
    print(f"\nload: {t1 - t0:.3f} s; evaluation (pyramid, lobes, truth, errors): {t2 - t1:.3f} s")
    if args.compare:
        compare(results, args.compare, splits)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Where a method's image of a suite sphere differs from the reference (docs/evaluation.md,
"Why skin1 spheres are dark"). Reads .raw files written by `dirpole_sphere exr2raw` (the method
image, the reference and the reference's coverage layer) and optionally a model image from
`dirpole_sphere image`. Prints the mean ratio per channel over the covered pixels, the share of
the GL surface term (normalised Blinn-Phong, specular albedo F0 = ((eta-1)/(eta+1))^2, shininess
64: lucent::methods::translucentSurface and shaders/common/lighting.glsl), which the reference
cannot have (a smooth dielectric reflects a point or directional light as a delta), and the
ratios binned by the cosine between the normal and the light direction.

  python3 ratios.py METHOD.raw REF.raw COVERAGE.raw ETA point|directional [MODEL.raw]
"""
import sys

import numpy as np

LIGHT_POS = np.array([30.0, 30.0, 30.0])  # the suite's key light, 1e4 W/sr
SUN_DIR = np.array([0.6, -0.4, -0.7]) / np.linalg.norm([0.6, -0.4, -0.7])  # travel, 3 W/mm^2


def load(path):
    b = open(path, "rb").read()
    w, h = np.frombuffer(b[:8], dtype=np.int32)
    return np.frombuffer(b[8:], dtype=np.float32).reshape(h, w, 3).astype(np.float64)


def sphere_geometry(w=64, h=64, radius=10.0, cam=np.array([0.0, 0.0, 60.0]), fov_deg=40.0):
    t = np.tan(np.radians(fov_deg / 2))
    xs = (2 * (np.arange(w) + 0.5) / w - 1) * t * w / h
    ys = (1 - 2 * (np.arange(h) + 0.5) / h) * t
    d = np.stack(np.broadcast_arrays(xs[None, :], ys[:, None], -np.ones((h, w))), 2)
    d /= np.linalg.norm(d, axis=2, keepdims=True)
    b = d @ cam
    disc = b * b - cam @ cam + radius * radius
    hit = disc > 0
    s = -b - np.sqrt(np.maximum(disc, 0))
    p = cam + s[..., None] * d
    return p / radius, p, hit, -d


def main():
    method, ref, cov = load(sys.argv[1]), load(sys.argv[2]), load(sys.argv[3])[..., 0] > 0.5
    eta, light = float(sys.argv[4]), sys.argv[5]
    model = load(sys.argv[6]) if len(sys.argv) > 6 else None
    n, p, hit, v = sphere_geometry()
    if light == "point":
        wl = LIGHT_POS - p
        d2 = (wl * wl).sum(2)
        wl /= np.sqrt(d2)[..., None]
        irradiance = 1e4 / d2
    else:
        wl = np.broadcast_to(-SUN_DIR, p.shape)
        irradiance = np.full(p.shape[:2], 3.0)
    half = wl + v
    half /= np.linalg.norm(half, axis=2, keepdims=True)
    cos_l = (n * wl).sum(2)
    f0 = ((eta - 1) / (eta + 1)) ** 2
    highlight = np.where(hit, f0 * 72 / (8 * np.pi) * np.maximum((n * half).sum(2), 0) ** 64
                         * np.maximum(cos_l, 0) * irradiance, 0)[..., None]

    def ratio(a, b, sel=cov):
        return a[sel].sum(0) / b[sel].sum(0)

    print("mean ratio R G B            method/ref        %.3f %.3f %.3f" % tuple(ratio(method, ref)))
    print("surface term share of the method image        %.3f %.3f %.3f"
          % tuple(highlight[cov].sum(0) / method[cov].sum(0)))
    print("(method - surface term)/ref                   %.3f %.3f %.3f"
          % tuple(ratio(method - highlight, ref)))
    if model is not None:
        print("(method - surface term)/model quadrature      %.3f %.3f %.3f"
              % tuple(ratio(method - highlight, model)))
        print("model quadrature/ref                          %.3f %.3f %.3f" % tuple(ratio(model, ref)))
    sub = model if model is not None else method - highlight
    total = ref[cov].sum(0)
    print("cos(normal, light)   pixels  share of ref (R G B)   subsurface/ref (R G B)")
    for lo, hi in [(-1, -0.3), (-0.3, 0), (0, 0.3), (0.3, 0.6), (0.6, 0.85), (0.85, 1.01)]:
        sel = cov & (cos_l >= lo) & (cos_l < hi)
        if sel.any():
            print("[%5.2f, %5.2f)   %5d   %5.1f %5.1f %5.1f %%   %.3f %.3f %.3f"
                  % (lo, hi, sel.sum(), *(100 * ref[sel].sum(0) / total), *ratio(sub, ref, sel)))


if __name__ == "__main__":
    main()

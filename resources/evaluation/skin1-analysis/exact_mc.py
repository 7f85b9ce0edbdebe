#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Independent radiative-transfer answers for docs/evaluation.md "Why skin1 spheres are dark".

Analog Monte Carlo (numpy only, shares no code with the engine) of an isotropically scattering
medium (g = 0, the suite's skin1 cases) behind a smooth dielectric boundary of relative index
eta (unpolarised Fresnel, total internal reflection included): the total exitance per unit flux
entering the medium,

  half-space at incidence mu0 (outside cosine), and
  a sphere of radius R entered at its pole along the normal (plus where it leaves: polar angle).

At eta = 1 the half-space value has a closed form, Chandrasekhar's A(mu0) = 1 - H(mu0) sqrt(1 - a)
(isotropic H-function, solved here by iteration); `check` compares the two (agree to ~1e-3).

  python3 exact_mc.py check                 # MC half-space vs the H-function closed form, eta 1
  python3 exact_mc.py table [ETA]           # skin1 / jade / marble: half-space vs 10 mm sphere
  python3 exact_mc.py oblique [ETA]         # skin1 half-space totals vs incidence mu0
  python3 exact_mc.py slab [ETA]            # skin1: a 5 mm slab vs the half-space, mu0 = 0.76
"""
import sys

import numpy as np

MATERIALS = {  # sigma_a, sigma_s' in mm^-1 (resources/presets)
    "skin1": ([0.032, 0.17, 0.48], [0.74, 0.88, 1.01]),
    "jade": ([0.06, 0.012, 0.04], [0.6, 0.9, 0.7]),
    "marble": ([0.0021, 0.0041, 0.0071], [2.19, 2.62, 3.00]),
}
ROULETTE_WEIGHT = 0.05  # unbiased weight-window roulette below this weight


def fresnel_leaving(cos_inside, eta):
    """Unpolarised Fresnel reflectance for light inside (index eta) meeting the boundary."""
    sin_t2 = eta * eta * (1 - cos_inside**2)
    f = np.ones_like(cos_inside)
    ok = sin_t2 < 1
    ci = cos_inside[ok]
    ct = np.sqrt(1 - sin_t2[ok])
    rs = (eta * ci - ct) / (eta * ci + ct)
    rp = (ci - eta * ct) / (ci + eta * ct)
    f[ok] = 0.5 * (rs * rs + rp * rp)
    return f


def roulette(rng, w, *arrays):
    low = w < ROULETTE_WEIGHT
    if low.any():
        survive = rng.random(low.sum()) < w[low] / ROULETTE_WEIGHT
        wl = w[low]
        wl[survive] = ROULETTE_WEIGHT
        wl[~survive] = 0
        w[low] = wl
    keep = w > 0
    return (w[keep],) + tuple(a[keep] for a in arrays)


def half_space(albedo, eta, mu0=1.0, n=200000, seed=1, thickness=np.inf):
    """Exitance through the lit face per unit entering flux; depth z > 0, sigma_t = 1 (lengths
    in mean free paths). A finite `thickness` makes it a laterally infinite slab whose back face
    is the same smooth dielectric (light leaving there is lost to the lit side)."""
    rng = np.random.default_rng(seed)
    sin_t = np.sqrt(1 - mu0 * mu0) / eta
    z = np.zeros(n)
    dz = np.full(n, np.sqrt(1 - sin_t * sin_t))
    w = np.ones(n)
    escaped = 0.0
    while len(w):
        z_new = z - np.log(rng.random(len(w))) * dz
        back = np.nonzero(z_new > thickness)[0]
        if len(back):  # the back face: leave (lost) or reflect back in, then step afresh
            stay = rng.random(len(back)) < fresnel_leaving(dz[back], eta)
            w[back[~stay]] = 0
            z_new[back] = thickness
            dz[back] *= -1
        out = z_new < 0
        idx = np.nonzero(out)[0]
        reflect = rng.random(len(idx)) < fresnel_leaving(-dz[idx], eta)
        escaped += w[idx[~reflect]].sum()
        keep = np.ones(len(w), bool)
        keep[idx[~reflect]] = False
        z_new[idx[reflect]] = 0.0  # mirrored at the boundary; a fresh step is exact (memoryless)
        dz[idx[reflect]] *= -1
        inside = np.nonzero(~out)[0]
        if len(back):
            inside = np.setdiff1d(inside, back)
        w[inside] *= albedo
        dz[inside] = 2 * rng.random(len(inside)) - 1
        w, z, dz = roulette(rng, w[keep], z_new[keep], dz[keep])
    return escaped / n


def sphere(sigma_t, albedo, eta, radius, n=200000, seed=2, bins=36):
    """Exitance per unit flux entering at the pole along -z; histogram over exit polar angle."""
    rng = np.random.default_rng(seed)
    p = np.tile([0.0, 0.0, radius * (1 - 1e-9)], (n, 1))
    d = np.tile([0.0, 0.0, -1.0], (n, 1))
    w = np.ones(n)
    hist = np.zeros(bins)
    edges = np.linspace(0, np.pi, bins + 1)
    while len(w):
        s = -np.log(rng.random(len(w))) / sigma_t
        pd = (p * d).sum(1)
        t_exit = -pd + np.sqrt(np.maximum(pd * pd - (p * p).sum(1) + radius * radius, 0))
        out = s >= t_exit
        ins = ~out
        p[ins] += s[ins, None] * d[ins]
        w[ins] *= albedo
        u = 2 * rng.random(ins.sum()) - 1
        phi = 2 * np.pi * rng.random(ins.sum())
        r = np.sqrt(1 - u * u)
        d[ins] = np.stack([r * np.cos(phi), r * np.sin(phi), u], 1)
        idx = np.nonzero(out)[0]
        keep = np.ones(len(w), bool)
        if len(idx):
            q = p[idx] + t_exit[idx, None] * d[idx]
            nrm = q / np.linalg.norm(q, axis=1, keepdims=True)
            cos_i = np.clip((d[idx] * nrm).sum(1), 0, 1)
            reflect = rng.random(len(idx)) < fresnel_leaving(cos_i, eta)
            leave = idx[~reflect]
            polar = np.arccos(np.clip(nrm[~reflect][:, 2], -1, 1))
            hist += np.histogram(polar, bins=edges, weights=w[leave])[0]
            back = idx[reflect]
            nb = nrm[reflect]
            p[back] = q[reflect] * (1 - 1e-9)
            d[back] -= 2 * (d[back] * nb).sum(1)[:, None] * nb
            keep[leave] = False
        w, p, d = roulette(rng, w[keep], p[keep], d[keep])
    return hist / n, edges


def h_function(albedo, mu, nodes=400):
    """Chandrasekhar's H(mu) for isotropic scattering, by fixed-point iteration."""
    x, wq = np.polynomial.legendre.leggauss(nodes)
    m = 0.5 * (x + 1)
    wq = 0.5 * wq
    h = np.ones(nodes)
    for _ in range(5000):
        h_new = 1 / (1 - 0.5 * albedo * m * np.sum(wq * h / (m[:, None] + m), axis=1))
        if np.max(abs(h_new - h)) < 1e-13:
            break
        h = h_new
    return 1 / (1 - 0.5 * albedo * mu * np.sum(wq * h / (mu + m)))


def main():
    cmd = sys.argv[1] if len(sys.argv) > 1 else "table"
    eta = float(sys.argv[2]) if len(sys.argv) > 2 else 1.3
    if cmd == "check":
        for a in [0.9585, 0.8381, 0.6779]:
            exact = 1 - h_function(a, 1.0) * np.sqrt(1 - a)
            print("albedo %.4f  H-function %.4f  Monte Carlo %.4f" % (a, exact, half_space(a, 1.0)))
    elif cmd == "slab":  # the suite's 5 mm skin1 slab, its light at mu0 = 0.76, vs half-space
        sa, ss = MATERIALS["skin1"]
        for c, (a, s) in enumerate(zip(sa, ss)):
            slab = half_space(s / (s + a), eta, 0.76, thickness=5.0 * (a + s))
            half = half_space(s / (s + a), eta, 0.76)
            print("%s  5 mm slab %.4f  half-space %.4f  (x%.3f)" % ("RGB"[c], slab, half, slab / half))
    elif cmd == "oblique":
        sa, ss = MATERIALS["skin1"]
        for mu0 in [1.0, 0.9, 0.75, 0.5, 0.3, 0.15, 0.05]:
            vals = [half_space(s / (s + a), eta, mu0) for a, s in zip(sa, ss)]
            print("mu0 %.2f  R %.4f  G %.4f  B %.4f" % (mu0, *vals), flush=True)
    else:
        for name, (sa, ss) in MATERIALS.items():
            for c, (a, s) in enumerate(zip(sa, ss)):
                st = a + s
                half = half_space(s / st, eta)
                sph = sphere(st, s / st, eta, 10.0)[0].sum()
                print("%-6s %s  albedo %.3f  mfp %.2f mm  half-space %.4f  sphere r 10 mm %.4f  (x%.3f)"
                      % (name, "RGB"[c], s / st, 1 / st, half, sph, sph / half), flush=True)


if __name__ == "__main__":
    main()

// SPDX-License-Identifier: MIT
// Dipole profiles and exact importance sampling in GLSL (float), mirroring
// engine/src/dipole/Profiles.cpp and Sampling.cpp; see docs/methods/dipole.md for the equations.
#pragma once

struct Profile {
    float alphaP, sigma, zr, zv, D, cPhi, cE, pReal;
};

// Seed 004 Table 1 (model 0) / d'Eon 2012 (model 1); boundary = (F_dr, C1, C2).
Profile makeProfile(int model, float sigma_a, float sigma_s, vec3 boundary) {
    Profile p = Profile(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0);
    float st = sigma_a + sigma_s;
    if (!(st > 0.0)) return p;
    p.alphaP = sigma_s / st;
    p.zr = 1.0 / st;
    float A;
    if (model == 0) {
        p.D = 1.0 / (3.0 * st);
        p.sigma = sqrt(3.0 * sigma_a * st);
        A = (1.0 + boundary.x) / (1.0 - boundary.x);
    } else {
        p.D = (2.0 * sigma_a + sigma_s) / (3.0 * st * st);
        p.sigma = sqrt(sigma_a / p.D);
        A = (1.0 + 3.0 * boundary.z) / (1.0 - 2.0 * boundary.y);
        p.cPhi = 0.25 * (1.0 - 2.0 * boundary.y);
        p.cE = 0.5 * (1.0 - 3.0 * boundary.z);
    }
    p.zv = p.zr + 4.0 * A * p.D;
    p.pReal = 1.0 / (1.0 + exp(-p.sigma * (p.zv - p.zr)));
    return p;
}

float decayTerm(float x, float e) { return e > 0.0 ? e + x * e : 0.0; }

// R_d(r), mm⁻² (Table 1 flux term + d'Eon fluence term).
float rd(Profile p, float r) {
    if (p.alphaP <= 0.0 || p.zr <= 0.0) return 0.0;
    float dr = sqrt(r * r + p.zr * p.zr), dv = sqrt(r * r + p.zv * p.zv);
    float er = exp(-p.sigma * dr), ev = exp(-p.sigma * dv);
    float flux = p.zr * decayTerm(p.sigma * dr, er) / (dr * dr * dr) +
                 p.zv * decayTerm(p.sigma * dv, ev) / (dv * dv * dv);
    float v = p.cE * p.alphaP / (4.0 * 3.14159265358979) * flux;
    if (p.cPhi != 0.0) v += p.cPhi * p.alphaP / (4.0 * 3.14159265358979 * p.D) * (er / dr - ev / dv);
    return v;
}

// Normalised area density of the two-source sampler at radius r.
float pdfArea(Profile p, float r) {
    if (p.zr <= 0.0) return 0.0;
    float dr = sqrt(r * r + p.zr * p.zr), dv = sqrt(r * r + p.zv * p.zv);
    float gr = p.zr * (1.0 + p.sigma * dr) * exp(-p.sigma * (dr - p.zr)) / (2.0 * 3.14159265358979 * dr * dr * dr);
    float gv = p.zv * (1.0 + p.sigma * dv) * exp(-p.sigma * (dv - p.zv)) / (2.0 * 3.14159265358979 * dv * dv * dv);
    return p.pReal * gr + (1.0 - p.pReal) * gv;
}

float expm1Safe(float x) { return abs(x) < 1e-3 ? x * (1.0 + x * (0.5 + x / 6.0)) : exp(x) - 1.0; }
float log1pSafe(float x) { return abs(x) < 1e-3 ? x * (1.0 - x * (0.5 - x / 3.0)) : log(1.0 + x); }

// σz(u − 1) + log u + log(1 − ξ) = 0 in v = log u: bracketed Newton (seed 004 §4).
float solveLogU(float c, float xi) {
    float L = -log1pSafe(-min(xi, 0.99999994));
    if (L <= 0.0) return 0.0;
    if (c == 0.0) return L;
    float lo = 0.0, hi = min(L, log1pSafe(L / c));
    float v = hi;
    for (int it = 0; it < 60; ++it) {
        float g = c * expm1Safe(v) + v - L;
        if (g == 0.0) return v;
        if (g > 0.0) hi = v; else lo = v;
        float next = v - g / (c * exp(v) + 1.0);
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        if (abs(next - v) <= 1e-7 * abs(v) || hi - lo <= 1e-7 * hi) return next;
        v = next;
    }
    return v;
}

float sampleSourceRadius(float sigma, float z, float xi) {
    return z * sqrt(expm1Safe(2.0 * solveLogU(sigma * z, xi)));
}

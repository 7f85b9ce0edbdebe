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

// σz(u − 1) + log u + log(1 − ξ) = 0 in v = log u: bracketed Newton (Mertens et al. 2005 §4).
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

// R′, the radius of the uniform disc samples (mm): the `quantile` quantile of the widest
// channel's virtual-source radius (as the CPU gather's PixelMaterial), capped at maxRadius > 0
// (the local-radius window); 0 when no channel scatters.
float discRadius(int model, vec3 sigT, vec3 sigS, vec3 boundary, float quantile, float maxRadius) {
    float R = 0.0;
    for (int c = 0; c < 3; ++c) {
        Profile prof = makeProfile(model, max(sigT[c] - sigS[c], 0.0), sigS[c], boundary);
        if (prof.zr > 0.0) R = max(R, sampleSourceRadius(prof.sigma, prof.zv, quantile));
    }
    return maxRadius > 0.0 ? min(R, maxRadius) : R;
}

// Frisvad, Hachisuka & Kjeldsen 2014 directional dipole S_d (ACM TOG 34(1):5), float mirror of
// lucent::dipole::DirectionalDipole (Profiles.cpp; equations and clamps documented there).
// moments = (C₁(η), C₂(η), C₁(1/η)) (Fresnel moments, η-only: computed once on the CPU).
struct Dirpole {
    float D, sigmaTr, sigmaTp, de, A, cPhi, cE, norm;
    bool zero;
};

Dirpole makeDirpole(float sigma_a, float sigma_s, vec3 moments) {
    Dirpole d = Dirpole(0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, true);
    float st = sigma_a + sigma_s;
    if (!(st > 0.0) || !(sigma_s > 0.0)) return d;  // zero profile (documented clamp)
    d.zero = false;
    d.sigmaTp = st;
    d.D = (2.0 * sigma_a + sigma_s) / (3.0 * st * st);  // paper Sec. 4
    d.sigmaTr = sqrt(sigma_a / d.D);
    d.cPhi = 0.25 * (1.0 - 2.0 * moments.x);  // C_φ(η)
    d.cE = 0.5 * (1.0 - 3.0 * moments.y);     // C_E(η)
    d.A = (1.0 - d.cE) / (2.0 * d.cPhi);
    d.de = 2.131 * d.D / sqrt(sigma_s / st);  // paper Eq. 21
    float cPhiInv = 0.25 * (1.0 - 2.0 * moments.z);  // C_φ(1/η)
    d.norm = 1.0 / (4.0 * cPhiInv) / (4.0 * 3.14159265358979 * 3.14159265358979);
    return d;
}

// S′_d(x, ω, r): the ray-source diffusion term of Frisvad et al. 2014.
float dirpoleSdPrime(Dirpole d, vec3 x, vec3 w, float r, vec3 no) {
    float s = d.sigmaTr * r;
    if (s > 80.0) return 0.0;  // e^{−s} underflows float
    float r2 = r * r;
    float xw = dot(x, w), wn = dot(w, no), xn = dot(x, no);
    float fluence = d.cPhi * (r2 / d.D + 3.0 * (1.0 + s) * xw);
    float flux = d.cE * (3.0 * d.D * (1.0 + s) * wn -
                         ((1.0 + s) + 3.0 * d.D * (3.0 * (1.0 + s) + s * s) / r2 * xw) * xn);
    return d.norm * exp(-s) / (r2 * r) * (fluence - flux);
}

// S_d(x_i, ω₁₂; x_o) in mm⁻² sr⁻¹ (ω₁₂ refracted direction of travel, n_i, n_o outward).
float dirpoleSd(Dirpole d, vec3 xi, vec3 ni, vec3 w12, vec3 xo, vec3 no) {
    if (d.zero) return 0.0;
    vec3 x = xo - xi;
    float r2 = dot(x, x);
    // Modified tangent plane normal n_i* = x × (n_i × x)/|·| (n_i when x ∥ n_i or x = 0).
    vec3 niStar = cross(x, cross(ni, x));
    float len = length(niStar);
    niStar = len > 1e-6 * max(r2, 1e-30) ? niStar / len : ni;
    vec3 xv = xi + 2.0 * d.A * d.de * niStar;  // virtual source in the extrapolated plane
    vec3 wv = w12 - 2.0 * dot(w12, niStar) * niStar;
    float dv = length(xo - xv);
    float mu0 = -dot(no, w12);
    float dr2;
    if (mu0 > 0.0) {
        float xw = dot(x, w12);
        float cosBeta = -sqrt(max(0.0, r2 - xw * xw) / (r2 + d.de * d.de));
        dr2 = r2 + d.D * mu0 * (d.D * mu0 - 2.0 * d.de * cosBeta);
    } else {
        float l = 1.0 / (3.0 * d.sigmaTp);
        dr2 = r2 + l * l;
    }
    float v = dirpoleSdPrime(d, x, w12, sqrt(dr2), no) - dirpoleSdPrime(d, xo - xv, wv, dv, no);
    return (v > 0.0 && !isinf(v)) ? v : 0.0;  // clamp as the paper's §6.1 (NaN fails v > 0)
}

// P(radius ≤ r) of one source, 1 − (z/d)e^{−σ(d − z)} (Mertens et al. 2005 Eq. 6–7; Sampling.cpp).
float sourceRadiusCdf(float sigma, float z, float r) {
    float d = sqrt(r * r + z * z);
    return 1.0 - (z / d) * exp(-sigma * (d - z));
}

// Local-radius window r ≤ R of the sampler (DipoleSampler::truncated; R ≤ 0: no window):
// (F_real(R), F_virtual(R), F(R)) — the per-source kept masses and the mixture's.
vec3 windowMasses(Profile p, float R) {
    if (!(R > 0.0) || p.zr <= 0.0) return vec3(1.0);
    float fr = sourceRadiusCdf(p.sigma, p.zr, R), fv = sourceRadiusCdf(p.sigma, p.zv, R);
    return vec3(fr, fv, p.pReal * fr + (1.0 - p.pReal) * fv);
}

// A radius of the sampler conditioned on r ≤ R (masses from windowMasses; R ≤ 0: no window):
// source s with P(s)F_s(R)/F(R), then F_s inverted on [0, F_s(R)).
float sampleWindowed(Profile p, vec3 masses, float R, float uSrc, float uR) {
    bool real = uSrc < p.pReal * masses.x / masses.z;
    float z = real ? p.zr : p.zv;
    float r = sampleSourceRadius(p.sigma, z, uR * (real ? masses.x : masses.y));
    return R > 0.0 ? min(r, R) : r;
}

// The renormalised area density of sampleWindowed at radius r (0 beyond the window).
float pdfWindowed(Profile p, vec3 masses, float R, float r) {
    if (R > 0.0 && r > R) return 0.0;
    return pdfArea(p, r) / masses.z;
}

// SPDX-License-Identifier: MIT
/// @file
/// @brief Analysis tool for docs/evaluation.md "Why skin1 spheres are dark": the energy-normalised
/// directional dipole (lucent/dipole/Profiles.h) integrated by brute-force quadrature on an
/// analytic sphere, independent of the GL pipeline's sampling, G-buffers and cube faces.
///
///   exr2raw IN.exr OUT.raw [LAYER]       an EXR as int32 width, height, then float RGB rows
///   image ETA LIGHT OUT.raw [N]          the suite's 64×64 sphere view (radius 10 mm, camera at
///                                        z = 60 mm, fov 40°) of skin1: T₂₁ ∫ S_d T₁₂ E dA over
///                                        the lit sphere (N × 2N cells); LIGHT = point (10⁴ W/sr
///                                        at (30, 30, 30)) or directional (3 W/mm² along
///                                        (0.6, −0.4, −0.7), the lights-directional case)
///   ratiomap OUT.png A.raw B.raw [A2.raw B2.raw ...] COVERAGE.raw
///                                        a / b per channel (R, G, B side by side, one row per
///                                        pair), 4× enlarged; blue 0.5 → white 1 → red 1.5
///   totals ETA RADIUS_MM SA SS           exitance per unit flux entering at the pole of a sphere
///                                        at normal incidence (S_d · π(1 − 2C₁(1/η)) over the
///                                        sphere); SA, SS = "r,g,b" σa and σs′ in mm⁻¹
///
/// Build (from the repository root, after the ci preset's build):
///   g++ -O2 -std=c++20 -Iengine/include -I/usr/include/OpenEXR -I/usr/include/Imath \
///     resources/evaluation/skin1-analysis/dirpole_sphere.cpp
///     build/ci/engine/src/dipole/liblucent_dipole.a \ build/ci/engine/src/core/liblucent_core.a
///     -lOpenEXR -lIex -lImath -lpng -lz -ltbb -o dirpole_sphere
#include <lucent/core/Image.h>
#include <lucent/dipole/Profiles.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

using glm::dvec3;
using namespace lucent::dipole;

namespace {

constexpr double PI = 3.14159265358979323846;
constexpr double SPHERE_RADIUS_MM = 10.0;
const double SKIN1_SIGMA_A[3] = {0.032, 0.17, 0.48};  // resources/presets/jensen2001.json
const double SKIN1_SIGMA_S[3] = {0.74, 0.88, 1.01};

void writeRaw(const std::string& path, int w, int h, const std::vector<float>& rgb) {
    FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) {
        std::perror(path.c_str());
        std::exit(1);
    }
    const int wh[2] = {w, h};
    std::fwrite(wh, sizeof(int), 2, f);
    std::fwrite(rgb.data(), sizeof(float), rgb.size(), f);
    std::fclose(f);
}

std::vector<DirectionalDipole> normalisedDipoles(const double* sa, const double* ss, double eta) {
    const DirpoleEnergyTable table(eta);
    std::vector<DirectionalDipole> dd;
    for (int c = 0; c < 3; ++c)
        dd.emplace_back(sa[c], ss[c], eta, table.scale(ss[c] / (sa[c] + ss[c])));
    return dd;
}

/// Direction of travel after refraction into the medium (incoming direction `in`, outward `n`).
dvec3 refractInto(const dvec3& in, const dvec3& n, double eta) {
    const double r = 1.0 / eta, c = -glm::dot(in, n);
    return glm::normalize(r * in + (r * c - std::sqrt(1.0 - r * r * (1.0 - c * c))) * n);
}

int image(double eta, bool directional, const std::string& out, int n) {
    const double R = SPHERE_RADIUS_MM;
    const dvec3 lightPos(30, 30, 30), sunDir = glm::normalize(dvec3(0.6, -0.4, -0.7));
    const double intensity = 1e4, irradiance = 3.0;
    const auto dd = normalisedDipoles(SKIN1_SIGMA_A, SKIN1_SIGMA_S, eta);
    struct Source {
        dvec3 x, n, w;
        double flux;  // W entering through the cell
    };
    std::vector<Source> sources;
    const double cellArea = 4 * PI * R * R / (double(n) * 2 * n);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < 2 * n; ++j) {
            const double ct = 1 - 2 * (i + 0.5) / n, st = std::sqrt(1 - ct * ct);
            const double ph = 2 * PI * (j + 0.5) / (2 * n);
            const dvec3 nrm(st * std::cos(ph), st * std::sin(ph), ct), x = R * nrm;
            dvec3 toLight = -sunDir;
            double e = irradiance;
            if (!directional) {
                const dvec3 d = lightPos - x;
                e = intensity / glm::dot(d, d);
                toLight = glm::normalize(d);
            }
            const double cosI = glm::dot(toLight, nrm);
            if (cosI <= 0)
                continue;
            const double t12 = 1 - fresnelReflectance(cosI, eta);
            sources.push_back({x, nrm, refractInto(-toLight, nrm, eta), e * cosI * t12 * cellArea});
        }
    const int W = 64, H = 64;
    const double tanHalf = std::tan(20.0 * PI / 180.0);
    const dvec3 cam(0, 0, 60);
    std::vector<float> rgb(size_t(W) * H * 3, 0.f);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const dvec3 d = glm::normalize(
                dvec3((2 * (x + 0.5) / W - 1) * tanHalf, (1 - 2 * (y + 0.5) / H) * tanHalf, -1));
            const double b = glm::dot(cam, d), disc = b * b - glm::dot(cam, cam) + R * R;
            if (disc <= 0)
                continue;
            const dvec3 xo = cam + (-b - std::sqrt(disc)) * d, no = xo / R;
            const double t21 = 1 - fresnelReflectance(glm::dot(-d, no), eta);
            for (int c = 0; c < 3; ++c) {
                double sum = 0;
                for (const Source& s : sources)
                    sum += s.flux * dd[c].Sd(s.x, s.n, s.w, xo, no);
                rgb[(size_t(y) * W + x) * 3 + c] = float(t21 * sum);
            }
        }
    writeRaw(out, W, H, rgb);
    return 0;
}

int totals(double eta, double radius, const double* sa, const double* ss) {
    const auto dd = normalisedDipoles(sa, ss, eta);
    const double cPhiExt = (1 - 2 * fresnelMoment(1, 1.0 / eta)) / 4;
    const dvec3 ni(0, 0, 1), xi(0, 0, radius), w12(0, 0, -1);
    for (int c = 0; c < 3; ++c) {
        double total = 0;
        const int NG = 4000, NP = 256;
        for (int i = 0; i < NG; ++i) {
            const double u = (i + 0.5) / NG, g = PI * u * u * u, dg = PI * 3 * u * u / NG;
            double ring = 0;
            for (int j = 0; j < NP; ++j) {
                const double ph = (j + 0.5) * 2 * PI / NP;
                const dvec3 no(std::sin(g) * std::cos(ph), std::sin(g) * std::sin(ph), std::cos(g));
                ring += dd[c].Sd(xi, ni, w12, radius * no, no) * (2 * PI / NP);
            }
            total += ring * radius * radius * std::sin(g) * dg * 4 * PI * cPhiExt;
        }
        std::printf("%c %.4f\n", "RGB"[c], total);
    }
    return 0;
}

std::vector<float> readRaw(const std::string& path, int& w, int& h) {
    FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) {
        std::perror(path.c_str());
        std::exit(1);
    }
    int wh[2] = {0, 0};
    std::vector<float> rgb;
    if (std::fread(wh, sizeof(int), 2, f) == 2) {
        rgb.resize(size_t(wh[0]) * wh[1] * 3);
        rgb.resize(std::fread(rgb.data(), sizeof(float), rgb.size(), f));
    }
    std::fclose(f);
    w = wh[0];
    h = wh[1];
    return rgb;
}

/// Diverging colour of a ratio: blue at 0.5, white at 1, red at 1.5 (clamped); grey off-object.
lucent::Rgb ratioColour(double r) {
    const float t = float(std::clamp((r - 1.0) / 0.5, -1.0, 1.0));
    return t < 0 ? lucent::Rgb(1 + t, 1 + t, 1) : lucent::Rgb(1, 1 - t, 1 - t);
}

int ratioMap(const std::string& out, int pairs, char** files, const std::string& coverage) {
    int w = 0, h = 0;
    const std::vector<float> cov = readRaw(coverage, w, h);
    // Crop to the covered pixels' bounding box plus one pixel.
    int x0 = w, y0 = h, x1 = -1, y1 = -1;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            if (cov[(size_t(y) * w + x) * 3] > 0.5f) {
                x0 = std::min(x0, x);
                y0 = std::min(y0, y);
                x1 = std::max(x1, x);
                y1 = std::max(y1, y);
            }
    x0 = std::max(0, x0 - 1);
    y0 = std::max(0, y0 - 1);
    x1 = std::min(w - 1, x1 + 1);
    y1 = std::min(h - 1, y1 + 1);
    const int cw = x1 - x0 + 1, ch = y1 - y0 + 1, scale = 4, gap = 2;
    lucent::ImageRgb img(3 * (cw * scale + gap), pairs * (ch * scale + gap), lucent::Rgb(0.2f));
    for (int k = 0; k < pairs; ++k) {
        int wa = 0, ha = 0, wb = 0, hb = 0;
        const std::vector<float> a = readRaw(files[2 * k], wa, ha),
                                 b = readRaw(files[2 * k + 1], wb, hb);
        if (wa != w || wb != w || ha != h || hb != h) {
            std::fprintf(stderr, "size mismatch\n");
            return 1;
        }
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x)
                for (int c = 0; c < 3; ++c) {
                    const size_t i = (size_t(y) * w + x) * 3;
                    const lucent::Rgb col = cov[i] > 0.5f && b[i + c] > 0
                                                ? ratioColour(a[i + c] / b[i + c])
                                                : lucent::Rgb(0.2f);
                    for (int sy = 0; sy < scale; ++sy)
                        for (int sx = 0; sx < scale; ++sx)
                            img.at(c * (cw * scale + gap) + (x - x0) * scale + sx,
                                   k * (ch * scale + gap) + (y - y0) * scale + sy) = col;
                }
    }
    lucent::writePng(img, out);
    return 0;
}

void parseRgb(const char* text, double* out) {
    if (std::sscanf(text, "%lf,%lf,%lf", &out[0], &out[1], &out[2]) != 3) {
        std::fprintf(stderr, "expected r,g,b, got %s\n", text);
        std::exit(2);
    }
}

}  // namespace

int main(int argc, char** argv) {
    const std::string cmd = argc > 1 ? argv[1] : "";
    if (cmd == "exr2raw" && argc >= 4) {
        const lucent::ImageRgb im = lucent::readExr(argv[2], argc > 4 ? argv[4] : "");
        std::vector<float> rgb;
        for (const lucent::Rgb& p : im.pixels())
            rgb.insert(rgb.end(), {p.x, p.y, p.z});
        writeRaw(argv[3], im.width(), im.height(), rgb);
        return 0;
    }
    if (cmd == "image" && argc >= 5)
        return image(std::atof(argv[2]), std::string(argv[3]) == "directional", argv[4],
                     argc > 5 ? std::atoi(argv[5]) : 500);
    if (cmd == "ratiomap" && argc >= 6 && (argc - 4) % 2 == 0)
        return ratioMap(argv[2], (argc - 4) / 2, argv + 3, argv[argc - 1]);
    if (cmd == "totals" && argc >= 6) {
        double sa[3], ss[3];
        parseRgb(argv[4], sa);
        parseRgb(argv[5], ss);
        return totals(std::atof(argv[2]), std::atof(argv[3]), sa, ss);
    }
    std::fprintf(stderr, "usage: see the @file comment of dirpole_sphere.cpp\n");
    return 2;
}

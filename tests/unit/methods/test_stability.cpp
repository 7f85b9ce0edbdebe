// SPDX-License-Identifier: MIT
/// @file
/// @brief One numerical stability matrix across every registered method (issue 16, item 4):
/// extreme coefficients, albedo 1, g = ±0.99, η 1 and 2.5, grazing light, cells from 10⁻³ to
/// 10³ mm, degenerate triangles and a one-voxel-thick shell. Every method renders every case
/// (48×48, its cheapest quality level, subsurface only); the image must be finite and its
/// energy ratio (below) at most 2. Prints the table of docs/benchmarks.md, "Stability matrix".
///
/// Energy ratio: a sphere of radius R under a directional light of irradiance E receives
/// Φ = E·πR² whatever the light's direction. An orthographic camera measures Σ L·A_pixel over
/// the image; if the light leaving the object were Lambertian, π·Σ L·A_pixel would be the flux
/// leaving the visible half, at most Φ. So ratio = π·Σ L·A_pixel / (E·πR²) is 1 for a white
/// Lambertian disc facing both. Fresnel-weighted exitance, brighter toward the normal, can pass
/// 1 by tens of per cent legitimately, hence the limit of 2: this is a blow-up guard (an
/// unstable method gives ×10⁶, NaN or Inf), not an accuracy check (docs/evaluation.md). The
/// light comes 30° off the view: aligned with it, a strongly backscattering medium is a
/// retroreflector and breaks the Lambertian assumption (see StabilityCase::incidenceDeg).
///
/// Optically thin cases get a tighter bound: only light that interacts inside the sphere can
/// come out as subsurface light, and along any chord (at most 2R) that is at most
/// 1 − exp(−2σt′R) of what enters; the limit is that fraction times the same factor 2. It catches
/// a method that counts light crossing the medium unscattered as subsurface light (SSLPV did:
/// 0.157 at σt′ = 10⁻⁴ mm⁻¹, where the bound is 0.004 and the reference reads 0.001).

#include <lucent/core/Error.h>
#include <lucent/core/Image.h>
#include <lucent/methods/Registry.h>
#include <lucent/methods/RenderImage.h>
#include <lucent/scene/SceneFile.h>

#include "GlTestContext.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

using namespace lucent;
using nlohmann::json;

namespace {

constexpr int IMAGE = 48;
constexpr double PI_D = 3.14159265358979323846;

struct StabilityCase {
    std::string name;
    double radius = 10.0;  ///< mm
    double sigmaT = 1.0, sigmaS = 0.9, g = 0.0, eta = 1.3;
    double incidenceDeg = 0.0;         ///< light travel direction against −z, in the xz-plane
    std::function<void(Scene&)> edit;  ///< after loading (mesh or volume changes)
};

Scene buildScene(const StabilityCase& c) {
    const double th = c.incidenceDeg * PI_D / 180.0;
    json j = {{"mesh", {{"procedural", "sphere"}, {"radius", c.radius}, {"subdivisions", 3}}},
              {"material",
               {{"sigma_t", {c.sigmaT, c.sigmaT, c.sigmaT}},
                {"sigma_s", {c.sigmaS, c.sigmaS, c.sigmaS}},
                {"g", {c.g, c.g, c.g}}}},
              {"eta", c.eta},
              {"resolution", 32},
              {"lights", json::array({{{"type", "directional"},
                                       {"direction", {std::sin(th), 0.0, -std::cos(th)}},
                                       {"irradiance", {1, 1, 1}}}})},
              {"camera",
               {{"position", {0, 0, 6 * c.radius}},
                {"target", {0, 0, 0}},
                {"up", {0, 1, 0}},
                {"ortho_height", 2.4 * c.radius},
                {"near", 0.01 * c.radius},
                {"far", 20 * c.radius},
                {"width", IMAGE},
                {"height", IMAGE}}}};
    Scene s = parseScene(j.dump());
    if (c.edit)
        c.edit(s);
    return s;
}

StabilityCase make(const std::string& name, double radius = 10.0, double sigmaT = 1.0,
                   double sigmaS = 0.9, double g = 0.0, double eta = 1.3,
                   double incidenceDeg = 30.0) {
    StabilityCase c;
    c.name = name;
    c.radius = radius;
    c.sigmaT = sigmaT;
    c.sigmaS = sigmaS;
    c.g = g;
    c.eta = eta;
    c.incidenceDeg = incidenceDeg;
    return c;
}

std::vector<StabilityCase> cases() {
    std::vector<StabilityCase> v;
    v.push_back(make("baseline (σt′ 1, α′ 0.9, η 1.3)"));
    v.push_back(make("σt′ → 0 (10⁻⁴ mm⁻¹)", 10.0, 1e-4, 0.9e-4));
    v.push_back(make("σt′ = 10⁴ mm⁻¹", 10.0, 1e4, 0.9e4));
    v.push_back(make("albedo 1 (σs′ = σt′)", 10.0, 1.0, 1.0));
    v.push_back(make("g = +0.99", 10.0, 1.0, 0.9, 0.99));
    v.push_back(make("g = −0.99", 10.0, 1.0, 0.9, -0.99));
    v.push_back(make("η = 1", 10.0, 1.0, 0.9, 0.0, 1.0));
    v.push_back(make("η = 2.5", 10.0, 1.0, 0.9, 0.0, 2.5));
    v.push_back(make("grazing light (89°)", 10.0, 1.0, 0.9, 0.0, 1.3, 89.0));
    v.push_back(make("cells 10⁻³ mm (r = 0.016 mm)", 0.016));
    v.push_back(make("cells 10³ mm (r = 16 m)", 16000.0));
    StabilityCase degenerate = make("degenerate triangles");
    degenerate.edit = [](Scene& s) {
        // Zero-area triangles (a repeated vertex, and three collinear vertices) among the
        // sphere's own, as broken exports contain.
        TriangleMesh& m = s.objects[0].mesh;
        const uint32_t n = uint32_t(m.positions.size());
        const Point3f a = m.positions[0], b = m.positions[1];
        m.positions.push_back(0.5f * (a + b));
        m.normals.push_back(m.normals[0]);
        for (uint32_t t = 0; t < 64; ++t) {
            m.triangles.push_back({t % n, t % n, (t + 1) % n});
            m.triangles.push_back({0, 1, n});
        }
    };
    v.push_back(degenerate);
    StabilityCase shell = make("one-voxel shell (hollow)");
    shell.edit = [](Scene& s) {
        // Only the outermost voxel layer keeps material; everything deeper is vacuum (σ = 0).
        MaterialVolume& vol = *s.objects[0].material;
        const GridSpec& spec = vol.spec();
        const auto& in = vol.insideMask();
        const auto inside = [&](int x, int y, int z) {
            const Coord c(x, y, z);
            return spec.contains(c) && in[spec.linearIndex(c)] != 0;
        };
        std::vector<Coord> deep;
        for (int z = 0; z < spec.resolution; ++z)
            for (int y = 0; y < spec.resolution; ++y)
                for (int x = 0; x < spec.resolution; ++x)
                    if (inside(x, y, z) && inside(x - 1, y, z) && inside(x + 1, y, z) &&
                        inside(x, y - 1, z) && inside(x, y + 1, z) && inside(x, y, z - 1) &&
                        inside(x, y, z + 1))
                        deep.push_back(Coord(x, y, z));
        for (const Coord& c : deep)
            vol.set(c, {Rgb(0.f), Rgb(0.f), Rgb(0.f)});
    };
    v.push_back(shell);
    return v;
}

}  // namespace

TEST(StabilityMatrix, EveryMethodStaysFiniteAndBoundedOnEveryCase) {
    std::string why;
    gpu::GlContext* ctx = lucent::test::sharedGlContext(&why);
    std::printf("| case | method | finite | energy ratio | time (ms) |\n|---|---|---|---:|---:|\n");
    for (const StabilityCase& c : cases()) {
        const Scene scene = buildScene(c);
        const double pixelArea = std::pow(2.4 * c.radius / IMAGE, 2.0);
        for (const methods::MethodInfo* info : methods::all()) {
            if (!info->caps.cpu && !ctx)
                continue;  // a GL-only method without GL: nothing to render here
            // The method as registered, then each of its variants (sslpv:diffusion, dirpole:raw,
            // ...), at its cheapest quality level.
            std::vector<const methods::ParamPreset*> variants = {nullptr};
            for (const methods::ParamPreset& v : info->variants)
                variants.push_back(&v);
            for (const methods::ParamPreset* variant : variants) {
                if (variant && variant->backend == methods::Backend::Gl && !ctx)
                    continue;  // a variant pinned to GL without GL: nothing to render here
                const std::string name = info->name + (variant ? ":" + variant->name : "");
                methods::ParamSet params =
                    info->quality.empty() ? methods::ParamSet{} : info->quality.front().values;
                if (variant)
                    params.merge(variant->values);
                if (info->name == "reference")
                    params.set("spp", 4);
                methods::RenderOptions options;
                options.subsurfaceOnly = true;
                options.context = ctx;
                if (variant)
                    options.backend = variant->backend;
                methods::RenderResult r;
                try {
                    r = methods::renderImage(scene, info->name, params, options);
                } catch (const ValueError& e) {
                    // A method may refuse a scene it cannot render, with a reason: that is an
                    // answer, not an instability.
                    std::printf("| %s | %s | refused: %s | – | – |\n", c.name.c_str(), name.c_str(),
                                e.what());
                    continue;
                }
                bool finite = true;
                double sum = 0.0;
                for (const Rgb& p : r.radiance.pixels()) {
                    finite = finite && isFinite(p) && p.r >= 0 && p.g >= 0 && p.b >= 0;
                    sum += double(luminance(p));
                }
                const double ratio = PI_D * sum * pixelArea / (PI_D * c.radius * c.radius);
                const double limit = 2.0 * -std::expm1(-2.0 * c.sigmaT * c.radius);
                std::printf("| %s | %s | %s | %.3f | %.0f |\n", c.name.c_str(), name.c_str(),
                            finite ? "yes" : "**no**", ratio, r.milliseconds);
                EXPECT_TRUE(finite) << name << " on " << c.name;
                EXPECT_LE(ratio, limit) << name << " on " << c.name;
            }
        }
    }
}

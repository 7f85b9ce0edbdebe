// SPDX-License-Identifier: MIT
/// @file
/// @brief Benchmark scenes and bandwidth floor of the SSLPV propagation (SslpvBench.h).

#include <lucent/sslpv/SslpvBench.h>

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/core/Random.h>
#include <lucent/core/Timer.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace lucent::sslpv {

SslpvBenchScene parseSslpvBenchScene(const std::string& name) {
    for (SslpvBenchScene s : {SslpvBenchScene::Cube, SslpvBenchScene::Sphere,
                              SslpvBenchScene::Shell, SslpvBenchScene::Spot})
        if (name == sslpvBenchSceneName(s))
            return s;
    LUCENT_THROW(ValueError, "--scene: '", name, "' is not cube, sphere, shell or spot");
}

const char* sslpvBenchSceneName(SslpvBenchScene scene) {
    switch (scene) {
        case SslpvBenchScene::Cube:
            return "cube";
        case SslpvBenchScene::Sphere:
            return "sphere";
        case SslpvBenchScene::Shell:
            return "shell";
        case SslpvBenchScene::Spot:
            return "spot";
    }
    return "?";
}

SslpvBenchSetup makeSslpvBenchSetup(SslpvBenchScene scene, int n, bool heterogeneous) {
    LUCENT_CHECK(n >= 4 && n <= 1022, "SSLPV bench: grid ", n, " outside [4, 1022]");
    SslpvBenchSetup b;
    CoarseMaterial& m = b.material;
    m.spec.resolution = n;
    m.spec.voxelSize = 1.f;
    m.spec.origin = Point3f(0.f);
    const size_t count = m.spec.voxelCount();
    const bool ball = scene == SslpvBenchScene::Sphere || scene == SslpvBenchScene::Shell;
    const float c = 0.5f * float(n), outer = 0.45f * float(n);
    const float inner = scene == SslpvBenchScene::Shell ? 0.38f * float(n) : -1.f;
    m.insideFraction.assign(count, ball ? 0.f : 1.f);
    if (ball)
        for (int z = 0; z < n; ++z)
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    const float r = glm::length(m.spec.cellCenter({x, y, z}) - Point3f(c));
                    if (r <= outer && r >= inner)
                        m.insideFraction[m.spec.linearIndex({x, y, z})] = 1.f;
                }
    Pcg32 rng(1234);
    for (int ch = 0; ch < 3; ++ch) {
        m.sigma_t[ch].assign(count, 1.f);
        m.sigma_s[ch].assign(count, 0.8f);
        m.g[ch].assign(count, 0.2f);
        if (heterogeneous)
            for (size_t k = 0; k < count; ++k) {
                m.sigma_t[ch][k] = 0.5f + 1.5f * rng.uniform();
                m.sigma_s[ch][k] = m.sigma_t[ch][k] * rng.uniform();
                m.g[ch][k] = 1.6f * rng.uniform() - 0.8f;
            }
    }
    m.homogeneous = !heterogeneous;
    b.sinks = ball;

    // One unit-flux texel per lit column (x, y) of cells.
    switch (scene) {
        case SslpvBenchScene::Cube:
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x)
                    b.texels.push_back({Point3f(x + 0.5f, y + 0.5f, float(n)), Normal3f(0, 0, 1),
                                        glm::normalize(Vector3f(0.3f, 0.1f, -1.f)), Rgb(1.f)});
            break;
        case SslpvBenchScene::Spot:
            for (int y = n / 2 - 2; y < n / 2 + 2; ++y)
                for (int x = n / 2 - 2; x < n / 2 + 2; ++x)
                    b.texels.push_back({Point3f(x + 0.5f, y + 0.5f, float(n)), Normal3f(0, 0, 1),
                                        Vector3f(0, 0, -1), Rgb(1.f)});
            break;
        case SslpvBenchScene::Sphere:
        case SslpvBenchScene::Shell:
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    const float dx = x + 0.5f - c, dy = y + 0.5f - c;
                    const float r2 = dx * dx + dy * dy;
                    if (r2 >= outer * outer)
                        continue;
                    const Vector3f d(dx, dy, std::sqrt(outer * outer - r2));
                    b.texels.push_back(
                        {Point3f(c) + d, Normal3f(d / outer), Vector3f(0, 0, -1), Rgb(1.f)});
                }
            break;
    }
    return b;
}

double sslpvBandwidthFloorMs(int n, int order, bool heterogeneous, int steps, int repeats) {
    LUCENT_CHECK(n >= 1 && n <= 1022 && (order == 1 || order == 2) && steps >= 1 && repeats >= 1,
                 "SSLPV bandwidth floor: grid ", n, ", order ", order, ", steps ", steps,
                 ", repeats ", repeats, " out of range");
    const size_t plane = size_t(n + 2) * (n + 2) * (n + 2);
    const size_t planes = size_t(3) * shCount(order);
    const size_t factorPlanes = heterogeneous ? size_t(3) * (order + 1) : 0;
    std::vector<float> src(plane * planes, 1.f), dst(plane * planes), acc(plane * planes),
        fac(std::max<size_t>(plane * factorPlanes, 1), 0.5f);
    std::vector<double> ms;
    volatile float sink = 0.f;
    for (int i = 0; i < repeats + 3; ++i) {
        const Timer t;
        for (int s = 0; s < steps; ++s) {
            parallelFor(
                0, int64_t(planes),
                [&](int64_t b, int64_t e) {
                    for (int64_t p = b; p < e; ++p) {
                        const float* __restrict a = &src[size_t(p) * plane];
                        float* __restrict d = &dst[size_t(p) * plane];
                        float* __restrict c = &acc[size_t(p) * plane];
                        std::memcpy(d, a, plane * sizeof(float));
                        for (size_t k = 0; k < plane; ++k)
                            c[k] += a[k];
                    }
                },
                /*grain=*/1);
            if (heterogeneous) {
                float f = 0.f;
                for (size_t k = 0; k < fac.size(); k += 16)
                    f += fac[k];  // one read per 64-byte line
                sink = sink + f;
            }
            std::swap(src, dst);
        }
        if (i >= 3)
            ms.push_back(t.elapsedMs());
    }
    (void)sink;
    std::sort(ms.begin(), ms.end());
    return ms[ms.size() / 2];
}

}  // namespace lucent::sslpv

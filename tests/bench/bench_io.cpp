// SPDX-License-Identifier: MIT
// OpenVDB export/import of a painted 128³ object: time and file size, against a baseline
// measured in the same run (writing the raw dense float32 σt, σs′, g arrays with std::ofstream).
//
//   build/ci/tests/bench/bench_io --benchmark_min_time=1
#include <lucent/core/Random.h>
#include <lucent/core/Timer.h>
#include <lucent/io/VdbIO.h>
#include <lucent/material/MaterialVolume.h>

#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <fstream>

using namespace lucent;
using namespace lucent::io;

namespace {

constexpr int RES = 128;

std::string benchPath(const char* name) {
    return (std::filesystem::temp_directory_path() / name).string();
}

/// A ball-shaped object filling 128³ (radius 0.45·res) in 0.2 mm voxels. `kind` 0: the preset
/// only (homogeneous); 1: painted with smooth strokes (sinusoidal layers as a brush would lay,
/// the realistic case); 2: every voxel independent random (worst case for compression).
MaterialVolume makeObject(int kind) {
    GridSpec spec;
    spec.origin = Point3f(-12.8f);
    spec.voxelSize = 0.2f;
    spec.resolution = RES;
    const MaterialSample marble{Rgb(2.19f + 0.0021f, 2.62f + 0.0041f, 3.00f + 0.0071f),
                                Rgb(2.19f, 2.62f, 3.00f), Rgb(0.f)};
    MaterialVolume vol(spec, marble);
    std::vector<uint8_t> mask(spec.voxelCount(), 0);
    const float c = 0.5f * RES, r = 0.45f * RES;
    for (int z = 0; z < RES; ++z)
        for (int y = 0; y < RES; ++y)
            for (int x = 0; x < RES; ++x)
                mask[spec.linearIndex({x, y, z})] =
                    glm::length(glm::vec3(x, y, z) + 0.5f - glm::vec3(c)) < r;
    vol.setInsideMask(mask);
    if (kind == 0)
        return vol;
    Pcg32 rng(17);
    for (int z = 0; z < RES; ++z)
        for (int y = 0; y < RES; ++y)
            for (int x = 0; x < RES; ++x) {
                MaterialSample s = marble;
                if (kind == 1) {
                    // Veins: σt scaled by a smooth layered pattern quantised to 16 levels (a
                    // brush paints a few distinct values with soft edges).
                    const float v = 0.5f + 0.5f * std::sin(0.15f * float(x) +
                                                           2.f * std::sin(0.07f * float(y + z)));
                    const float q = std::round(v * 15.f) / 15.f;
                    s.sigma_t *= 1.f + 3.f * q;
                    s.sigma_s *= 1.f + 3.f * q;
                    s.g = Rgb(0.4f * q);
                } else {
                    for (int k = 0; k < 3; ++k) {
                        s.sigma_t[k] = 10.f * rng.uniform();
                        s.sigma_s[k] = s.sigma_t[k] * rng.uniform();
                        s.g[k] = 1.8f * rng.uniform() - 0.9f;
                    }
                }
                vol.set({x, y, z}, s);
            }
    return vol;
}

const MaterialVolume& object(int kind) {
    static const MaterialVolume objects[3] = {makeObject(0), makeObject(1), makeObject(2)};
    return objects[kind];
}

double g_rawSeconds = 0;  // baseline time per iteration, set by BM_RawDenseWrite

/// Baseline: the dense σt, σs′, g components (9 × 128³ float32, 75.5 MB) written raw.
void BM_RawDenseWrite(benchmark::State& state) {
    const MaterialVolume& vol = object(1);
    std::vector<std::vector<float>> comps;
    for (int k = 0; k < MaterialVolume::COMPONENTS; ++k)
        comps.push_back(vol.denseComponent(k));
    const std::string path = benchPath("lucent_bench_raw.bin");
    double total = 0;
    for (auto _ : state) {
        Timer t;
        std::ofstream os(path, std::ios::binary | std::ios::trunc);
        for (const auto& c : comps)
            os.write(reinterpret_cast<const char*>(c.data()), std::streamsize(c.size() * 4));
        os.close();
        total += t.elapsedMs() * 1e-3;
    }
    g_rawSeconds = total / double(state.iterations());
    state.counters["file_MB"] = double(std::filesystem::file_size(path)) / 1e6;
    std::filesystem::remove(path);
}

void BM_ExportVdb(benchmark::State& state) {
    const int kind = int(state.range(0));
    const MaterialVolume& vol = object(kind);
    const std::string path = benchPath("lucent_bench_export.vdb");
    double total = 0;
    for (auto _ : state) {
        Timer t;
        exportVdb(vol, path);
        total += t.elapsedMs() * 1e-3;
    }
    const double bytes = double(std::filesystem::file_size(path));
    const double dense = 9.0 * RES * RES * RES * 4.0;
    state.counters["file_MB"] = bytes / 1e6;
    state.counters["size_vs_dense"] = bytes / dense;
    if (g_rawSeconds > 0)
        state.counters["time_vs_raw"] = total / double(state.iterations()) / g_rawSeconds;
    state.SetLabel(kind == 0 ? "homogeneous" : kind == 1 ? "painted strokes" : "random noise");
    std::filesystem::remove(path);
}

void BM_ImportVdb(benchmark::State& state) {
    const int kind = int(state.range(0));
    const std::string path = benchPath("lucent_bench_import.vdb");
    exportVdb(object(kind), path);
    for (auto _ : state)
        benchmark::DoNotOptimize(importVdb(path));
    state.SetLabel(kind == 0 ? "homogeneous" : kind == 1 ? "painted strokes" : "random noise");
    std::filesystem::remove(path);
}

}  // namespace

BENCHMARK(BM_RawDenseWrite)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ExportVdb)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ImportVdb)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_MAIN();

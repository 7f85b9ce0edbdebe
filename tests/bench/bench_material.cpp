// SPDX-License-Identifier: MIT
/// @file
/// @brief Material painting benchmarks: brush stamp throughput on a 128³ volume against a
/// memcpy of the same bytes, bytes of undo history per stroke, undo/redo and resampling time.
/// Prints ratios to the baseline measured in the same run. Results: docs/benchmarks.md.
#include <lucent/core/Random.h>
#include <lucent/material/Brush.h>
#include <lucent/material/History.h>
#include <lucent/material/Presets.h>
#include <lucent/material/Procedural.h>
#include <lucent/material/Resample.h>

#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <vector>

using namespace lucent;

namespace {

constexpr int N = 128;
constexpr float RADIUS = 8.f;  // mm (h = 1 mm): ≈ 2145 voxels per stamp
constexpr int COMPONENT_BYTES = MaterialVolume::COMPONENTS * int(sizeof(float));

GridSpec grid() {
    GridSpec s;
    s.resolution = N;
    s.voxelSize = 1.f;
    return s;
}

std::vector<Point3f> randomCentres(size_t n) {
    Pcg32 rng(1234);
    std::vector<Point3f> out(n);
    for (auto& p : out)
        p = Point3f(RADIUS + (N - 2 * RADIUS) * rng.uniform(),
                    RADIUS + (N - 2 * RADIUS) * rng.uniform(),
                    RADIUS + (N - 2 * RADIUS) * rng.uniform());
    return out;
}

void stampBench(benchmark::State& state, BrushMode mode, bool sameCentre = false) {
    MaterialVolume vol(grid(), findPreset("marble").sample());
    BrushSettings b;
    b.radius = RADIUS;
    b.mode = mode;
    b.value = findPreset("skin1").sample();
    if (mode == BrushMode::Multiply)
        b.value = {Rgb(1.01f), Rgb(0.99f), Rgb(1.f)};
    b.strength = 0.5f;
    const auto centres = randomCentres(1024);
    size_t i = 0, voxels = 0;
    for (auto _ : state) {
        voxels += stamp(vol, b, sameCentre ? Point3f(64.f) : centres[i++ % centres.size()]);
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(int64_t(voxels));
    state.SetBytesProcessed(int64_t(voxels) * 2 * COMPONENT_BYTES);  // read + write 9 floats
}

void BM_StampSet(benchmark::State& s) {
    stampBench(s, BrushMode::Set);
}
void BM_StampAdd(benchmark::State& s) {
    stampBench(s, BrushMode::Add);
}
void BM_StampMultiply(benchmark::State& s) {
    stampBench(s, BrushMode::Multiply);
}
void BM_StampSmooth(benchmark::State& s) {
    stampBench(s, BrushMode::Smooth);
}
/// Same centre every time: the touched bricks stay in cache (compute-bound upper limit).
void BM_StampSetCacheWarm(benchmark::State& s) {
    stampBench(s, BrushMode::Set, /*sameCentre=*/true);
}

/// Baseline: copy the bytes one stamp touches (voxels × 9 floats) between two buffers that are
/// as large as the volume (so the working set is the same), at the same scattered offsets.
void BM_MemcpyBaseline(benchmark::State& state) {
    MaterialVolume vol(grid(), findPreset("marble").sample());
    BrushSettings b;
    b.radius = RADIUS;
    const size_t perStamp = stamp(vol, b, Point3f(64.f)) * COMPONENT_BYTES;
    std::vector<char> src(size_t(N) * N * N * COMPONENT_BYTES, 1), dst(src.size());
    const auto centres = randomCentres(1024);
    size_t i = 0, voxels = 0;
    for (auto _ : state) {
        const Point3f& p = centres[i++ % centres.size()];
        const size_t off = (size_t(p.x) * 7919 + size_t(p.y) * 104729 + size_t(p.z) * 1299709) *
                           64 % (src.size() - perStamp);
        std::memcpy(dst.data() + off, src.data() + off, perStamp);
        benchmark::ClobberMemory();
        voxels += perStamp / COMPONENT_BYTES;
    }
    state.SetItemsProcessed(int64_t(voxels));
    state.SetBytesProcessed(int64_t(voxels) * 2 * COMPONENT_BYTES);
}

/// A 40 mm stroke (spacing ¼ radius: 21 stamps) recorded in a History: reports the undo bytes
/// per stroke and the bricks it touched.
void BM_StrokeWithHistory(benchmark::State& state) {
    MaterialVolume vol(grid(), findPreset("marble").sample());
    History history(size_t(4) << 30);
    PaintSession session(vol, history);
    BrushSettings b;
    b.radius = RADIUS;
    b.mode = BrushMode::Add;
    b.value = {Rgb(0.01f), Rgb(0.005f), Rgb(0.f)};
    const auto centres = randomCentres(1024);
    size_t i = 0, strokes = 0;
    for (auto _ : state) {
        const Point3f p = centres[i++ % centres.size()];
        session.stroke(b, {p, p + Vector3f(40.f, 0.f, 0.f) * (p.x < 64.f ? 1.f : -1.f)});
        ++strokes;
        if (history.bytesUsed() > (size_t(1) << 30)) {
            state.PauseTiming();
            history.clear();
            state.ResumeTiming();
        }
    }
    const double brickBytes = 2.0 * MaterialVolume::BRICK_VOXELS * COMPONENT_BYTES;
    const double bytesPerStroke =
        double(history.bytesUsed()) / double(std::max<size_t>(1, history.undoCount()));
    state.counters["undo_bytes_per_stroke"] = bytesPerStroke;
    state.counters["bricks_per_stroke"] = bytesPerStroke / brickBytes;
    state.counters["dense_volume_bytes"] = double(size_t(N) * N * N * COMPONENT_BYTES);
    state.SetItemsProcessed(int64_t(strokes));
}

void BM_UndoRedoStroke(benchmark::State& state) {
    MaterialVolume vol(grid(), findPreset("marble").sample());
    History history;
    PaintSession session(vol, history);
    BrushSettings b;
    b.radius = RADIUS;
    session.stroke(b, {Point3f(40.f), Point3f(80.f, 40.f, 40.f)});
    for (auto _ : state) {
        session.undo();
        session.redo();
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * 2);
}

void BM_FillProceduralMarble(benchmark::State& state) {
    MaterialVolume vol(grid(), findPreset("marble").sample());
    ProceduralFill f;
    f.pattern = ProceduralPattern::Marble;
    f.materialA = findPreset("marble").sample();
    f.materialB = findPreset("skin1").sample();
    f.scale = 30.f;
    for (auto _ : state)
        fillProcedural(vol, f);
    state.SetItemsProcessed(int64_t(state.iterations()) * N * N * N);
}

void BM_Resample128To32(benchmark::State& state) {
    MaterialVolume vol(grid(), findPreset("marble").sample());
    for (auto _ : state)
        benchmark::DoNotOptimize(resampleForPropagation(vol, 32));
    state.SetItemsProcessed(int64_t(state.iterations()) * N * N * N);
}

/// A ball (radius 0.42 of the grid) inside the 128³ grid: the mask has a surface, so the
/// resample also reads the boundary skin around it (BoundarySkin.h) — the case an object is in.
MaterialVolume ballVolume() {
    MaterialVolume vol(grid(), findPreset("marble").sample());
    std::vector<uint8_t> mask(size_t(N) * N * N, 0);
    const float c = 0.5f * N, r = 0.42f * N;
    for (int z = 0; z < N; ++z)
        for (int y = 0; y < N; ++y)
            for (int x = 0; x < N; ++x) {
                const float dx = x + 0.5f - c, dy = y + 0.5f - c, dz = z + 0.5f - c;
                mask[(size_t(z) * N + size_t(y)) * N + size_t(x)] =
                    dx * dx + dy * dy + dz * dz < r * r ? 1 : 0;
            }
    vol.setInsideMask(mask);
    return vol;
}

void BM_Resample128BallTo(benchmark::State& state) {
    const MaterialVolume vol = ballVolume();
    for (auto _ : state)
        benchmark::DoNotOptimize(resampleForPropagation(vol, int(state.range(0))));
    state.SetItemsProcessed(int64_t(state.iterations()) * N * N * N);
}

/// One 8³ brick on the ball's surface dirty, as after a stamp there: the cells it and its
/// neighbours' skin overlap are recomputed.
void BM_ResampleUpdateSurfaceBrick(benchmark::State& state) {
    MaterialVolume vol = ballVolume();
    const int res = int(state.range(0));
    CoarseMaterial coarse = resampleForPropagation(vol, res);
    const int b = vol.brickIndexOf(Coord(N / 2, N / 2, int(0.5f * N + 0.42f * N) - 1));
    for (auto _ : state)
        benchmark::DoNotOptimize(updateCoarseMaterial(coarse, vol, {b}));
}

BENCHMARK(BM_MemcpyBaseline);
BENCHMARK(BM_StampSet);
BENCHMARK(BM_StampAdd);
BENCHMARK(BM_StampMultiply);
BENCHMARK(BM_StampSmooth);
BENCHMARK(BM_StampSetCacheWarm);
BENCHMARK(BM_StrokeWithHistory);
BENCHMARK(BM_UndoRedoStroke);
BENCHMARK(BM_FillProceduralMarble)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Resample128To32)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Resample128BallTo)->Arg(32)->Arg(64)->Arg(128)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ResampleUpdateSurfaceBrick)->Arg(32)->Arg(64)->Unit(benchmark::kMicrosecond);

/// Console output plus a record of items/s per benchmark for the ratio table.
class RatioReporter : public benchmark::ConsoleReporter {
public:
    void ReportRuns(const std::vector<Run>& runs) override {
        ConsoleReporter::ReportRuns(runs);
        for (const Run& r : runs) {
            const auto it = r.counters.find("items_per_second");
            if (it != r.counters.end())
                itemsPerSecond[r.benchmark_name()] = it->second.value;
        }
    }
    std::map<std::string, double> itemsPerSecond;
};

}  // namespace

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv))
        return 1;
    RatioReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    const auto& ips = reporter.itemsPerSecond;
    const auto base = ips.find("BM_MemcpyBaseline");
    if (base != ips.end() && base->second > 0.0) {
        std::printf("\nStamp throughput vs memcpy of the same bytes (%.1f Mvoxel/s):\n",
                    base->second * 1e-6);
        for (const char* name : {"BM_StampSet", "BM_StampAdd", "BM_StampMultiply", "BM_StampSmooth",
                                 "BM_StampSetCacheWarm"}) {
            const auto it = ips.find(name);
            if (it != ips.end())
                std::printf("  %-18s %8.1f Mvoxel/s  = %.3f x baseline\n", name, it->second * 1e-6,
                            it->second / base->second);
        }
    }
    benchmark::Shutdown();
    return 0;
}

// SPDX-License-Identifier: MIT
/// @file
/// @brief Solid voxelisation at 128³: the closed bunny (/work/shared/meshes) and a procedural
/// sphere, against a baseline measured in the same run: per-voxel parity, one Embree ray
/// cast from every voxel centre (no column coherence, single direction).
///
/// Also the legacy VTK walk (engine/src/mesh/MeshValidate.cpp) against VTK 9.1's own read of
/// the same file, a 180 000-triangle torus written by vtkPolyDataWriter (saveMesh: version 5.1,
/// with point normals), ASCII and binary: the walk runs before every legacy .vtk import.
///
///     bench_mesh                       # prints ratios after the Google Benchmark table
///     bench_mesh --benchmark_filter=LegacyVtk   # the walk only

#include "MeshValidate.h"

#include <lucent/core/Parallel.h>
#include <lucent/mesh/MeshIO.h>
#include <lucent/mesh/Procedural.h>
#include <lucent/mesh/Voxelize.h>

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkPolyDataReader.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <string>

namespace {

using namespace lucent;

std::map<std::string, double> g_seconds;  // name → best seconds per iteration

GridSpec gridAround(const Bounds3f& b, int n) {
    const Vector3f e = b.extent();
    GridSpec s;
    s.resolution = n;
    s.voxelSize = std::max({e.x, e.y, e.z}) / (float(n) - 3.f);
    s.origin = b.center() - Vector3f(0.5f * s.voxelSize * float(n));
    return s;
}

const TriangleMesh& bunny() {
    static const TriangleMesh m = [] {
        const std::string path = std::string(LUCENT_SHARED_DIR) + "/meshes/bunny_closed_75k.ply";
        return std::filesystem::exists(path) ? loadMesh(path, 100.f) : TriangleMesh{};
    }();
    return m;
}
const TriangleMesh& sphere() {
    static const TriangleMesh m = makeSphere(10.f, 5);
    return m;
}

/// Baseline: one +x ray per voxel centre, parity of all crossings beyond it.
std::vector<uint8_t> naivePerVoxel(const TriangleMesh& mesh, const GridSpec& spec) {
    RTCDevice dev = rtcNewDevice(nullptr);
    RTCScene scene = rtcNewScene(dev);
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, mesh.positions.size()));
    auto* ix = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, mesh.triangles.size()));
    std::memcpy(v, mesh.positions.data(), mesh.positions.size() * 12);
    std::memcpy(ix, mesh.triangles.data(), mesh.triangles.size() * 12);
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene);
    std::vector<uint8_t> inside(spec.voxelCount());
    const int n = spec.resolution;
    const float eps = 1e-6f * spec.voxelSize * float(n);
    parallelFor(
        0, int64_t(spec.voxelCount()),
        [&](int64_t b, int64_t e) {
            RTCIntersectContext ctx;
            rtcInitIntersectContext(&ctx);
            for (int64_t i = b; i < e; ++i) {
                const Coord c(int(i % n), int((i / n) % n), int(i / (int64_t(n) * n)));
                const Point3f o = spec.cellCenter(c);
                int hits = 0;
                float tnear = 0.f;
                for (;;) {
                    RTCRayHit rh{};
                    rh.ray.org_x = o.x, rh.ray.org_y = o.y, rh.ray.org_z = o.z;
                    rh.ray.dir_x = 1.f;
                    rh.ray.tnear = tnear;
                    rh.ray.tfar = INF;
                    rh.ray.mask = 0xFFFFFFFFu;
                    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                    rtcIntersect1(scene, &ctx, &rh);
                    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
                        break;
                    ++hits;
                    tnear = rh.ray.tfar + eps;
                }
                inside[size_t(i)] = uint8_t(hits & 1);
            }
        },
        4096);
    rtcReleaseScene(scene);
    rtcReleaseDevice(dev);
    return inside;
}

template <typename Fn>
void timed(benchmark::State& state, const std::string& name, Fn fn) {
    double best = 1e30;
    for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        benchmark::DoNotOptimize(fn());
        best = std::min(
            best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    g_seconds[name] = best;
}

void BM_Voxelize128(benchmark::State& state, const TriangleMesh* (*mesh)(), const char* name) {
    const TriangleMesh* m = mesh();
    if (m->isEmpty()) {
        state.SkipWithError("bunny_closed_75k.ply not present");
        return;
    }
    const GridSpec spec = gridAround(m->bounds(), 128);
    timed(state, std::string("voxelizeSolid/") + name, [&] { return voxelizeSolid(*m, spec); });
}
void BM_Naive128(benchmark::State& state, const TriangleMesh* (*mesh)(), const char* name) {
    const TriangleMesh* m = mesh();
    if (m->isEmpty()) {
        state.SkipWithError("bunny_closed_75k.ply not present");
        return;
    }
    const GridSpec spec = gridAround(m->bounds(), 128);
    timed(state, std::string("naive/") + name, [&] { return naivePerVoxel(*m, spec); });
}

/// The torus written once per encoding into the temporary folder (2 · 300 · 300 triangles).
const std::string& torusFile(bool binary) {
    static std::string paths[2];
    std::string& path = paths[binary ? 1 : 0];
    if (path.empty()) {
        path = (std::filesystem::temp_directory_path() /
                (std::string("lucent_bench_torus_") + (binary ? "binary" : "ascii") + ".vtk"))
                   .string();
        saveMesh(makeTorus(10.f, 4.f, /*majorSegments=*/300, /*minorSegments=*/300), path, binary);
    }
    return path;
}

void BM_LegacyVtkWalk(benchmark::State& state, bool binary) {
    const std::string& path = torusFile(binary);
    const uint64_t size = std::filesystem::file_size(path);
    timed(state, std::string("walk/") + (binary ? "binary" : "ascii"),
          [&] { return lucent::detail::validateMeshFile(path, ".vtk", size).polygons; });
}

void BM_LegacyVtkRead(benchmark::State& state, bool binary) {
    const std::string& path = torusFile(binary);
    timed(state, std::string("vtk/") + (binary ? "binary" : "ascii"), [&] {
        vtkNew<vtkPolyDataReader> reader;
        reader->SetFileName(path.c_str());
        reader->Update();
        return reader->GetOutput()->GetNumberOfPolys();
    });
}

const TriangleMesh* bunnyPtr() {
    return &bunny();
}
const TriangleMesh* spherePtr() {
    return &sphere();
}

}  // namespace

BENCHMARK_CAPTURE(BM_Voxelize128, bunny, bunnyPtr, "bunny")
    ->Unit(benchmark::kMillisecond)
    ->Iterations(5);
BENCHMARK_CAPTURE(BM_Naive128, bunny, bunnyPtr, "bunny")
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_Voxelize128, sphere, spherePtr, "sphere")
    ->Unit(benchmark::kMillisecond)
    ->Iterations(5);
BENCHMARK_CAPTURE(BM_Naive128, sphere, spherePtr, "sphere")
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

BENCHMARK_CAPTURE(BM_LegacyVtkWalk, ascii, false)->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK_CAPTURE(BM_LegacyVtkRead, ascii, false)->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK_CAPTURE(BM_LegacyVtkWalk, binary, true)->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK_CAPTURE(BM_LegacyVtkRead, binary, true)->Unit(benchmark::kMillisecond)->Iterations(5);

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv))
        return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    std::printf(
        "\n128^3 solid voxelisation, best of runs (3-axis column voting vs per-voxel rays):\n");
    for (const char* m : {"bunny", "sphere"}) {
        const auto a = g_seconds.find(std::string("voxelizeSolid/") + m);
        const auto b = g_seconds.find(std::string("naive/") + m);
        if (a == g_seconds.end() || b == g_seconds.end())
            continue;
        std::printf("  %-7s voxelizeSolid %8.1f ms   naive per-voxel %8.1f ms   speed-up x%.1f\n",
                    m, 1e3 * a->second, 1e3 * b->second, b->second / a->second);
    }
    std::printf(
        "\nlegacy VTK, 180 000 triangles, best of 5 (walk before the import vs VTK's read):\n");
    for (const bool binary : {false, true}) {
        const char* encoding = binary ? "binary" : "ascii";
        const auto walk = g_seconds.find(std::string("walk/") + encoding);
        const auto vtk = g_seconds.find(std::string("vtk/") + encoding);
        if (walk != g_seconds.end() && vtk != g_seconds.end())
            std::printf("  %-6s %5.1f MB  walk %7.1f ms   VTK %7.1f ms   walk/VTK %.2f\n", encoding,
                        double(std::filesystem::file_size(torusFile(binary))) / 1e6,
                        1e3 * walk->second, 1e3 * vtk->second, walk->second / vtk->second);
        std::filesystem::remove(torusFile(binary));
    }
    return 0;
}

// SPDX-License-Identifier: MIT
/// @file
/// @brief The cost of the legacy VTK walk (engine/src/mesh/MeshValidate.cpp) against VTK 9.1's
/// own reading of the same file, measured in the same run: a 180 000-triangle torus written by
/// vtkPolyDataWriter (saveMesh: version 5.1, with point normals), ASCII and binary. The walk
/// runs before every legacy .vtk import; VTK reads the file once more in a child process.
///
///     bench_vtk_walk                   # prints walk / VTK ratios after the benchmark table

#include "MeshValidate.h"

#include <lucent/mesh/MeshIO.h>
#include <lucent/mesh/Procedural.h>

#include <benchmark/benchmark.h>
#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkPolyDataReader.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>

using namespace lucent;

namespace {

std::map<std::string, double> g_seconds;  // name → best seconds per iteration

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

template <class Fn>
void timed(benchmark::State& state, const std::string& name, Fn&& fn) {
    double best = 1e30;
    for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        benchmark::DoNotOptimize(fn());
        best = std::min(
            best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    g_seconds[name] = best;
}

void BM_Walk(benchmark::State& state, bool binary) {
    const std::string& path = torusFile(binary);
    const uint64_t size = std::filesystem::file_size(path);
    timed(state, std::string("walk/") + (binary ? "binary" : "ascii"),
          [&] { return lucent::detail::validateMeshFile(path, ".vtk", size).polygons; });
}

void BM_VtkRead(benchmark::State& state, bool binary) {
    const std::string& path = torusFile(binary);
    timed(state, std::string("vtk/") + (binary ? "binary" : "ascii"), [&] {
        vtkNew<vtkPolyDataReader> reader;
        reader->SetFileName(path.c_str());
        reader->Update();
        return reader->GetOutput()->GetNumberOfPolys();
    });
}

}  // namespace

BENCHMARK_CAPTURE(BM_Walk, ascii, false)->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK_CAPTURE(BM_VtkRead, ascii, false)->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK_CAPTURE(BM_Walk, binary, true)->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK_CAPTURE(BM_VtkRead, binary, true)->Unit(benchmark::kMillisecond)->Iterations(5);

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv))
        return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    std::printf(
        "\nlegacy VTK, 180 000 triangles, best of 5 (walk before the import vs VTK's read):\n");
    for (const char* encoding : {"ascii", "binary"}) {
        const auto walk = g_seconds.find(std::string("walk/") + encoding);
        const auto vtk = g_seconds.find(std::string("vtk/") + encoding);
        if (walk == g_seconds.end() || vtk == g_seconds.end())
            continue;
        std::printf("  %-6s %6.1f MB  walk %7.1f ms   VTK %7.1f ms   walk/VTK %.2f\n", encoding,
                    double(std::filesystem::file_size(torusFile(encoding[0] == 'b'))) / 1e6,
                    1e3 * walk->second, 1e3 * vtk->second, walk->second / vtk->second);
    }
    for (bool binary : {false, true})
        std::filesystem::remove(torusFile(binary));
    return 0;
}

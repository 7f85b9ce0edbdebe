// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli export`: fills a mesh's volume with a material preset and writes it as
/// OpenVDB (docs/file-formats.md, "Material volumes (OpenVDB)").

#include "CliArgs.h"

#include <lucent/core/Error.h>
#include <lucent/core/Timer.h>
#include <lucent/io/VdbIO.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/material/Presets.h>
#include <lucent/mesh/MeshIO.h>
#include <lucent/mesh/Procedural.h>
#include <lucent/mesh/Voxelize.h>

#include <cstdio>
#include <filesystem>

namespace lucent::cli {

namespace {

/// Procedural shapes of `--procedural`, sized for a ~20 mm object (the default scene's scale).
TriangleMesh proceduralMesh(const std::string& name) {
    if (name == "sphere")
        return makeSphere(/*radius=*/10.f);
    if (name == "box")
        return makeBox(Vector3f(20.f));
    if (name == "torus")
        return makeTorus(/*majorRadius=*/10.f, /*minorRadius=*/4.f);
    if (name == "thin-thick")
        return makeThinThick(/*size=*/20.f);
    LUCENT_THROW(ValueError, "--procedural: unknown shape '", name,
                 "' (valid: sphere, box, torus, thin-thick)");
}

int runExport(const std::vector<std::string>& argv) {
    const Args args(argv, {"preset", "mesh", "procedural", "res", "scale", "o", "output"},
                    {"no-renderer-grids"});
    if (!args.positional().empty())
        LUCENT_THROW(ValueError, "unexpected argument '", args.positional().front(),
                     "' (see --help)");
    const auto presetName = args.value("preset");
    if (!presetName)
        LUCENT_THROW(ValueError, "--preset NAME is required (see --help)");
    const MaterialPreset& preset = findPreset(*presetName);
    const auto out = args.value("o") ? args.value("o") : args.value("output");
    if (!out || out->empty())
        LUCENT_THROW(ValueError, "-o FILE.vdb is required (see --help)");
    if (args.has("mesh") && args.has("procedural"))
        LUCENT_THROW(ValueError, "give either --mesh or --procedural, not both");
    const int res = args.intOr("res", GridSpec::DEFAULT_RESOLUTION, GridSpec::MIN_RESOLUTION,
                               GridSpec::MAX_RESOLUTION);
    const float scale = args.floatOr("scale", 1.f, 1e-6f, 1e6f);
    if (args.has("scale") && !args.has("mesh"))
        LUCENT_THROW(ValueError, "--scale applies to --mesh only");

    Timer timer;
    TriangleMesh mesh;
    std::string source;
    if (const auto file = args.value("mesh")) {
        mesh = loadMesh(*file, scale);
        source = *file;
    } else {
        source = args.valueOr("procedural", "sphere");
        mesh = proceduralMesh(source);
    }
    const GridSpec spec = GridSpec::around(mesh.bounds(), res);
    MaterialVolume volume(spec, preset.sample());
    volume.setEta(preset.eta);
    const std::vector<uint8_t> inside = voxelizeSolid(mesh, spec);
    size_t insideCount = 0;
    for (uint8_t v : inside)
        insideCount += v != 0;
    if (insideCount == 0)
        LUCENT_THROW(ValueError, "mesh '", source, "' covers no voxel centre at resolution ", res,
                     " (is it closed, and not too thin?)");
    volume.setInsideMask(inside);

    VdbExportOptions options;
    options.materialName = preset.name;
    options.rendererGrids = !args.has("no-renderer-grids");
    exportVdb(volume, *out, options);

    std::error_code ec;
    const auto bytes = std::filesystem::file_size(*out, ec);
    std::printf(
        "wrote %s: preset %s on %s, %d^3 voxels of %.4g mm, %zu inside, %llu bytes, %.0f ms\n",
        out->c_str(), preset.name.c_str(), source.c_str(), res, double(spec.voxelSize), insideCount,
        static_cast<unsigned long long>(ec ? 0 : bytes), timer.elapsedMs());
    return 0;
}

}  // namespace

extern const Command exportCommand;
const Command exportCommand{
    "export", "write a material preset filling a mesh as OpenVDB",
    "usage: lucent-cli export --preset NAME [--mesh FILE [--scale S] | --procedural SHAPE]\n"
    "                         [--res N] [--no-renderer-grids] -o OUT.vdb\n"
    "\n"
    "Fills the volume of a mesh with a material preset and writes an OpenVDB file with the\n"
    "grids sigma_t, sigma_s (REDUCED scattering), g (vec3s, 1/mm) and, unless\n"
    "--no-renderer-grids, density (float), albedo and color (vec3s) for Blender/Mitsuba.\n"
    "Lengths are millimetres (docs/file-formats.md).\n"
    "\n"
    "  --preset NAME         material preset (e.g. marble, skin1, jade; case-insensitive)\n"
    "  --mesh FILE           mesh file (.obj .ply .off .stl .vtp .vtk), must be closed\n"
    "  --scale S             mesh file units to mm (default 1; 1000 for metres)\n"
    "  --procedural SHAPE    sphere (radius 10 mm, the default), box (20 mm), torus (10/4 mm),\n"
    "                        thin-thick (20 mm)\n"
    "  --res N               voxels per axis, 16..256 (default 128)\n"
    "  --no-renderer-grids   write only sigma_t, sigma_s and g\n"
    "  -o, --output FILE     output .vdb (written atomically)\n",
    &runExport};

}  // namespace lucent::cli

// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli export`: fills a mesh's volume with a material preset and writes it as
/// OpenVDB and/or Mitsuba 3 `.vol` grids + medium XML (docs/file-formats.md, "Material volumes
/// (OpenVDB)" and its "Mitsuba 3 (.vol)" subsection).

#include "CliArgs.h"

#include <lucent/core/Error.h>
#include <lucent/core/Timer.h>
#include <lucent/io/MitsubaIO.h>
#include <lucent/io/VdbIO.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/material/Presets.h>
#include <lucent/mesh/MeshIO.h>
#include <lucent/mesh/Procedural.h>
#include <lucent/scene/Scene.h>

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

/// True when `output` names the existing file `input` (same file, whatever the path spelling).
bool isSameFile(const std::string& input, const std::string& output) {
    std::error_code ec;
    return std::filesystem::exists(output, ec) && std::filesystem::equivalent(input, output, ec);
}

int runExport(const std::vector<std::string>& argv) {
    const Args args(
        argv, {"preset", "mesh", "procedural", "res", "scale", "o", "output", "mitsuba"},
        {"no-renderer-grids", "mitsuba-grey-sigma-t", "mitsuba-isotropic", "allow-open"});
    if (!args.positional().empty())
        LUCENT_THROW(ValueError, "unexpected argument '", args.positional().front(),
                     "' (see --help)");
    const auto presetName = args.value("preset");
    if (!presetName)
        LUCENT_THROW(ValueError, "--preset NAME is required (see --help)");
    const MaterialPreset& preset = findPreset(*presetName);
    const auto out = args.value("o") ? args.value("o") : args.value("output");
    const auto mitsuba = args.value("mitsuba");
    if ((!out || out->empty()) && !mitsuba)
        LUCENT_THROW(ValueError, "-o FILE.vdb or --mitsuba PREFIX is required (see --help)");
    if (mitsuba && mitsuba->empty())
        LUCENT_THROW(ValueError, "--mitsuba needs a non-empty PREFIX");
    if (!mitsuba && (args.has("mitsuba-grey-sigma-t") || args.has("mitsuba-isotropic")))
        LUCENT_THROW(ValueError,
                     "--mitsuba-grey-sigma-t and --mitsuba-isotropic apply to --mitsuba only");
    if (!out && args.has("no-renderer-grids"))
        LUCENT_THROW(ValueError, "--no-renderer-grids applies to the .vdb output (-o) only");
    if (args.has("mesh") && args.has("procedural"))
        LUCENT_THROW(ValueError, "give either --mesh or --procedural, not both");
    const int res = args.intOr("res", GridSpec::DEFAULT_RESOLUTION, GridSpec::MIN_RESOLUTION,
                               GridSpec::MAX_RESOLUTION);
    const float scale = args.floatOr("scale", 1.f, 1e-6f, 1e6f);
    if (args.has("scale") && !args.has("mesh"))
        LUCENT_THROW(ValueError, "--scale applies to --mesh only");
    if (args.has("allow-open") && !args.has("mesh"))
        LUCENT_THROW(ValueError, "--allow-open applies to --mesh only");
    if (const auto file = args.value("mesh")) {
        // An output path naming the input mesh would replace it with the export.
        std::vector<std::string> outputs;
        if (out)
            outputs.push_back(*out);
        if (mitsuba)
            for (const char* suffix : {"_sigma_t.vol", "_albedo.vol", "_medium.xml"})
                outputs.push_back(*mitsuba + suffix);
        for (const std::string& o : outputs)
            if (isSameFile(*file, o))
                LUCENT_THROW(ValueError, "output '", o, "' is the input mesh '", *file,
                             "': it would be overwritten (choose another output name)");
    }

    Timer timer;
    TriangleMesh mesh;
    std::string source;
    if (const auto file = args.value("mesh")) {
        MeshReport report;
        mesh = loadMesh(*file, scale, &report);
        source = *file;
        // An open mesh has no inside to fill: most often a truncated or incomplete file, whose
        // few enclosed voxels would otherwise be exported without complaint.
        if (report.boundaryEdges > 0 && !args.has("allow-open"))
            LUCENT_THROW(IoError, "mesh '", *file, "' is open (", report.boundaryEdges,
                         " boundary edges): truncated or incomplete? Export fills the inside of "
                         "a closed mesh; --allow-open voxelises it anyway");
        for (const std::string& w : report.warnings)
            std::fprintf(stderr, "lucent-cli export: warning: %s\n", w.c_str());
    } else {
        source = args.valueOr("procedural", "sphere");
        mesh = proceduralMesh(source);
    }
    const SceneObject object = makeObject(std::move(mesh), res, preset.sample());
    MaterialVolume& volume = *object.material;
    volume.setEta(preset.eta);
    const GridSpec& spec = volume.spec();
    size_t insideCount = 0;
    for (uint8_t v : volume.insideMask())
        insideCount += v != 0;
    if (insideCount == 0)
        LUCENT_THROW(ValueError, "mesh '", source, "' covers no voxel centre at resolution ", res,
                     " (is it closed, and not too thin?)");

    if (out) {
        io::VdbExportOptions options;
        options.materialName = preset.name;
        options.rendererGrids = !args.has("no-renderer-grids");
        io::exportVdb(volume, *out, options);

        std::error_code ec;
        const auto bytes = std::filesystem::file_size(*out, ec);
        std::printf(
            "wrote %s: preset %s on %s, %d^3 voxels of %.4g mm, %zu inside, %llu bytes, %.0f ms\n",
            out->c_str(), preset.name.c_str(), source.c_str(), res, double(spec.voxelSize),
            insideCount, static_cast<unsigned long long>(ec ? 0 : bytes), timer.elapsedMs());
    }
    if (mitsuba) {
        Timer mitsubaTimer;
        io::MitsubaExportOptions options;
        options.materialName = preset.name;
        options.rgbSigmaT = !args.has("mitsuba-grey-sigma-t");
        options.hgMeanG = !args.has("mitsuba-isotropic");
        const io::MitsubaExportResult r = io::exportMitsubaVol(volume, *mitsuba, options);
        std::printf(
            "wrote %s, %s, %s: Mitsuba 3 medium '%s', preset %s on %s, %d^3 voxels of "
            "%.4g mm, %s sigma_t, phase %s g = %.4g, %.0f ms\n",
            r.sigmaTPath.c_str(), r.albedoPath.c_str(), r.xmlPath.c_str(), options.mediumId.c_str(),
            preset.name.c_str(), source.c_str(), res, double(spec.voxelSize),
            options.rgbSigmaT ? "RGB" : "grey", options.hgMeanG ? "hg" : "isotropic",
            double(r.meanG), mitsubaTimer.elapsedMs());
    }
    return 0;
}

}  // namespace

const Command exportCommand{
    "export", "write a material preset filling a mesh as OpenVDB and/or Mitsuba 3 .vol",
    "usage: lucent-cli export --preset NAME [--mesh FILE [--scale S] [--allow-open] |\n"
    "                                       --procedural SHAPE]\n"
    "                         [--res N] [--no-renderer-grids] [-o OUT.vdb]\n"
    "                         [--mitsuba PREFIX [--mitsuba-grey-sigma-t] [--mitsuba-isotropic]]\n"
    "\n"
    "Fills the volume of a mesh with a material preset and writes an OpenVDB file with the\n"
    "grids sigma_t, sigma_s (REDUCED scattering), g (vec3s, 1/mm) and, unless\n"
    "--no-renderer-grids, density (float), albedo and color (vec3s) for Blender/Mitsuba.\n"
    "Lengths are millimetres (docs/file-formats.md).\n"
    "\n"
    "  --preset NAME         material preset (e.g. marble, skin1, jade; case-insensitive)\n"
    "  --mesh FILE           mesh file (.obj .ply .off .stl .vtp .vtk), must be closed\n"
    "                        (repairs and problems are printed as warnings on stderr)\n"
    "  --allow-open          voxelise an open mesh (boundary edges) anyway, by ray voting\n"
    "  --scale S             mesh file units to mm (default 1; 1000 for metres)\n"
    "  --procedural SHAPE    sphere (radius 10 mm, the default), box (20 mm), torus (10/4 mm),\n"
    "                        thin-thick (20 mm)\n"
    "  --res N               voxels per axis, 16..256 (default 128)\n"
    "  --no-renderer-grids   write only sigma_t, sigma_s and g\n"
    "  -o, --output FILE     output .vdb (written atomically)\n"
    "  --mitsuba PREFIX      also (or instead) write Mitsuba 3 files PREFIX_sigma_t.vol,\n"
    "                        PREFIX_albedo.vol (dense, 1/mm and 1) and PREFIX_medium.xml (a\n"
    "                        heterogeneous medium with gridvolume textures, to_world in mm,\n"
    "                        scale 1: the scene must be in mm). sigma_t/albedo are the medium\n"
    "                        unreduced with the mean g, used as the HG phase parameter\n"
    "  --mitsuba-grey-sigma-t  1-channel sigma_t (Rec.709 luminance) instead of RGB\n"
    "  --mitsuba-isotropic   write the reduced medium with an isotropic phase instead\n"
    "At least one of -o and --mitsuba is required.\n",
    &runExport};

}  // namespace lucent::cli

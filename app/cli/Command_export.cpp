// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli export`: fills a mesh's volume with a material preset and writes it as
/// OpenVDB and/or Mitsuba 3 `.vol` grids + medium XML (docs/file-formats.md, "Material volumes
/// (OpenVDB)" and its "Mitsuba 3 (.vol)" subsection).

#include "CliCommon.h"

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
#include <memory>
#include <optional>
#include <string>
#include <vector>

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

struct ExportOptions {
    std::string preset, mesh, procedural = "sphere", output, mitsuba;
    int res = GridSpec::DEFAULT_RESOLUTION;
    float scale = 1.f;
    bool noRendererGrids = false, mitsubaGreySigmaT = false, mitsubaIsotropic = false,
         allowOpen = false;
    const CLI::App* app = nullptr;
    bool has(const std::string& option) const { return app->count(option) > 0; }
};

void runExport(const ExportOptions& args) {
    const MaterialPreset& preset = findPreset(args.preset);
    const std::optional<std::string> out =
        args.has("--output") ? std::optional(args.output) : std::nullopt;
    const std::optional<std::string> mitsuba =
        args.has("--mitsuba") ? std::optional(args.mitsuba) : std::nullopt;
    if ((!out || out->empty()) && !mitsuba)
        LUCENT_THROW(ValueError, "-o FILE.vdb or --mitsuba PREFIX is required (see --help)");
    if (mitsuba && mitsuba->empty())
        LUCENT_THROW(ValueError, "--mitsuba needs a non-empty PREFIX");
    if (!mitsuba && (args.mitsubaGreySigmaT || args.mitsubaIsotropic))
        LUCENT_THROW(ValueError,
                     "--mitsuba-grey-sigma-t and --mitsuba-isotropic apply to --mitsuba only");
    if (!out && args.noRendererGrids)
        LUCENT_THROW(ValueError, "--no-renderer-grids applies to the .vdb output (-o) only");
    const int res = args.res;
    const float scale = args.scale;
    if (const std::string& file = args.mesh; !file.empty()) {
        // An output path naming the input mesh would replace it with the export.
        std::vector<std::string> outputs;
        if (out)
            outputs.push_back(*out);
        if (mitsuba)
            for (const char* suffix : {"_sigma_t.vol", "_albedo.vol", "_medium.xml"})
                outputs.push_back(*mitsuba + suffix);
        for (const std::string& o : outputs)
            if (isSameFile(file, o))
                LUCENT_THROW(ValueError, "output '", o, "' is the input mesh '", file,
                             "': it would be overwritten (choose another output name)");
    }

    Timer timer;
    TriangleMesh mesh;
    std::string source;
    if (args.has("--mesh")) {
        const std::string& file = args.mesh;
        MeshReport report;
        mesh = loadMesh(file, scale, &report);
        source = file;
        // An open mesh has no inside to fill: most often a truncated or incomplete file, whose
        // few enclosed voxels would otherwise be exported without complaint.
        if (report.boundaryEdges > 0 && !args.allowOpen)
            LUCENT_THROW(IoError, "mesh '", file, "' is open (", report.boundaryEdges,
                         " boundary edges): truncated or incomplete? Export fills the inside of "
                         "a closed mesh; --allow-open voxelises it anyway");
        for (const std::string& w : report.warnings)
            std::fprintf(stderr, "lucent-cli export: warning: %s\n", w.c_str());
    } else {
        source = args.procedural;
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
        options.rendererGrids = !args.noRendererGrids;
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
        options.rgbSigmaT = !args.mitsubaGreySigmaT;
        options.hgMeanG = !args.mitsubaIsotropic;
        const io::MitsubaExportResult r = io::exportMitsubaVol(volume, *mitsuba, options);
        std::printf(
            "wrote %s, %s, %s: Mitsuba 3 medium '%s', preset %s on %s, %d^3 voxels of "
            "%.4g mm, %s sigma_t, phase %s g = %.4g, %.0f ms\n",
            r.sigmaTPath.c_str(), r.albedoPath.c_str(), r.xmlPath.c_str(), options.mediumId.c_str(),
            preset.name.c_str(), source.c_str(), res, double(spec.voxelSize),
            options.rgbSigmaT ? "RGB" : "grey", options.hgMeanG ? "hg" : "isotropic",
            double(r.meanG), mitsubaTimer.elapsedMs());
    }
}

}  // namespace

void addExportCommand(CLI::App& cli, const CommandContext&) {
    CLI::App* sub = addCommand(
        cli, "export", "write a material preset filling a mesh as OpenVDB and/or Mitsuba 3 .vol",
        "usage: lucent-cli export --preset NAME [--mesh FILE [--scale S] [--allow-open] |\n"
        "                                       --procedural SHAPE]\n"
        "                         [--res N] [--no-renderer-grids] [-o OUT.vdb]\n"
        "                         [--mitsuba PREFIX [--mitsuba-grey-sigma-t]\n"
        "                                          [--mitsuba-isotropic]]\n",
        "Fills the volume of a mesh with a material preset and writes an OpenVDB file with the\n"
        "grids sigma_t, sigma_s (REDUCED scattering), g (vec3s, 1/mm) and, unless\n"
        "--no-renderer-grids, density (float), albedo and color (vec3s) for Blender/Mitsuba.\n"
        "Lengths are millimetres (docs/file-formats.md). -o, --mitsuba or both.\n");
    auto args = std::make_shared<ExportOptions>();
    args->app = sub;
    sub->add_option("--preset", args->preset,
                    "material preset (e.g. marble, skin1, jade; case-insensitive)")
        ->type_name("NAME")
        ->required();
    CLI::Option* mesh =
        sub->add_option("--mesh", args->mesh,
                        "mesh file (.obj .ply .off .stl .vtp .vtk), must be closed (repairs and "
                        "problems are printed as warnings on stderr)")
            ->type_name("FILE")
            ->check(existingFile());
    sub->add_flag("--allow-open", args->allowOpen,
                  "voxelise an open mesh (boundary edges) anyway, by ray voting")
        ->needs(mesh);
    sub->add_option("--scale", args->scale, "mesh file units to mm (default 1; 1000 for metres)")
        ->type_name("S")
        ->check(finiteRange(1e-6, 1e6))
        ->needs(mesh);
    sub->add_option("--procedural", args->procedural,
                    "sphere (radius 10 mm, the default), box (20 mm), torus (10/4 mm), "
                    "thin-thick (20 mm)")
        ->type_name("SHAPE")
        ->check(CLI::IsMember({"sphere", "box", "torus", "thin-thick"}))
        ->excludes(mesh);
    sub->add_option("--res", args->res, "voxels per axis (default 128)")
        ->type_name("N")
        ->check(CLI::Range(GridSpec::MIN_RESOLUTION, GridSpec::MAX_RESOLUTION));
    sub->add_flag("--no-renderer-grids", args->noRendererGrids,
                  "write only sigma_t, sigma_s and g");
    sub->add_option("-o,--output", args->output, "output .vdb (written atomically)")
        ->type_name("FILE");
    sub->add_option("--mitsuba", args->mitsuba,
                    "also (or instead) write Mitsuba 3 files PREFIX_sigma_t.vol, "
                    "PREFIX_albedo.vol (dense, 1/mm and 1) and PREFIX_medium.xml (a "
                    "heterogeneous medium with gridvolume textures, to_world in mm, scale 1: the "
                    "scene must be in mm). sigma_t/albedo are the medium unreduced with the mean "
                    "g, used as the HG phase parameter")
        ->type_name("PREFIX");
    sub->add_flag("--mitsuba-grey-sigma-t", args->mitsubaGreySigmaT,
                  "1-channel sigma_t (Rec.709 luminance) instead of RGB");
    sub->add_flag("--mitsuba-isotropic", args->mitsubaIsotropic,
                  "write the reduced medium with an isotropic phase instead");
    sub->callback([args] { runExport(*args); });
}

}  // namespace lucent::cli

// SPDX-License-Identifier: MIT
/// @file
/// @brief Mitsuba 3 export: dense `.vol` grids (Mitsuba's own binary format, the only one its
/// `gridvolume` plugin reads) and a `heterogeneous` medium as scene XML. Format facts from
/// mitsuba-renderer/mitsuba3: src/render/volumegrid.cpp (reader), src/volumes/grid.cpp
/// (layout, voxel centres, to_world / use_grid_bbox), src/media/heterogeneous.cpp (sigma_t,
/// albedo, scale, phase); docs/file-formats.md, "Mitsuba 3 (.vol)".

#include <lucent/io/MitsubaIO.h>

#include <lucent/core/Error.h>
#include <lucent/core/FileIO.h>
#include <lucent/material/BoundarySkin.h>
#include <lucent/material/Medium.h>

#include <algorithm>
#include <bit>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <sstream>
#include <vector>

#ifndef LUCENT_VERSION
#define LUCENT_VERSION "unknown"
#endif

namespace lucent::io {

namespace {

/// Mitsuba medium values of one voxel.
struct VoxelValues {
    Rgb sigmaT{0.f};  ///< extinction, mm⁻¹
    Rgb albedo{0.f};  ///< single-scattering albedo σs/σt (0 where σt = 0)
};

/// The mapping documented in MitsubaIO.h. With ḡ = 0 the reduced values are passed through
/// untouched (bit-identical to the OpenVDB `sigma_t` / `albedo` grids).
/// Similarity relation σs′ = σs(1 − g) (Wyman et al. 1989), applied with the single phase
/// parameter ḡ; the diffusion dipole (Jensen et al. 2001, restated in Mertens et al. 2005,
/// Table 1, seeds/004) depends on σs′ and σa only, so it is unchanged by the unreduction.
VoxelValues mitsubaValues(const MaterialSample& s, float meanG) {
    VoxelValues v;
    if (meanG == 0.f) {
        v.sigmaT = s.sigma_t;
        v.albedo = reducedAlbedo(s);
        return v;
    }
    for (int c = 0; c < 3; ++c) {
        const float sigmaA = s.sigma_t[c] - s.sigma_s[c];
        const float sigmaS = s.sigma_s[c] / (1.f - meanG);
        const float sigmaT = sigmaA + sigmaS;
        v.sigmaT[c] = sigmaT;
        v.albedo[c] = sigmaT > 0.f ? sigmaS / sigmaT : 0.f;
    }
    return v;
}

void putU32(std::vector<char>& out, uint32_t v) {
    // Little endian, whatever the host order (the .vol format is little endian).
    for (int i = 0; i < 4; ++i)
        out.push_back(char((v >> (8 * i)) & 0xffu));
}
void putF32(std::vector<char>& out, float f) {
    putU32(out, std::bit_cast<uint32_t>(f));
}

/// Writes one dense `.vol` file atomically. `fill(z, slice)` writes the res² × channels floats
/// of slice z (x fastest, channels interleaved).
void writeVol(const std::string& path, const GridSpec& spec, int channels,
              const std::function<void(int, float*)>& fill) {
    const int res = spec.resolution;
    const Bounds3f box = spec.bounds();
    std::vector<char> header;
    header.reserve(MITSUBA_VOL_HEADER_BYTES);
    header.insert(header.end(), {'V', 'O', 'L', char(MITSUBA_VOL_VERSION)});
    putU32(header, uint32_t(MITSUBA_VOL_ENCODING_FLOAT32));
    for (int a = 0; a < 3; ++a)
        putU32(header, uint32_t(res));
    putU32(header, uint32_t(channels));
    for (int a = 0; a < 3; ++a)
        putF32(header, box.lo[a]);
    for (int a = 0; a < 3; ++a)
        putF32(header, box.hi[a]);
    LUCENT_ASSERT(header.size() == MITSUBA_VOL_HEADER_BYTES);

    writeStreamAtomically(path, [&](FileSink& out) {
        out.write(header.data(), header.size());
        const size_t sliceFloats = size_t(res) * res * channels;
        std::vector<float> slice(sliceFloats);
        std::vector<char> bytes;
        bytes.reserve(sliceFloats * 4);
        for (int z = 0; z < res; ++z) {
            fill(z, slice.data());
            bytes.clear();
            for (float f : slice)
                putF32(bytes, f);
            out.write(bytes.data(), bytes.size());
        }
    });
}

std::string xmlEscape(const std::string& s) {
    std::string out;
    for (char c : s) {
        switch (c) {
            case '&':
                out += "&amp;";
                break;
            case '<':
                out += "&lt;";
                break;
            case '>':
                out += "&gt;";
                break;
            case '"':
                out += "&quot;";
                break;
            case '\'':
                out += "&apos;";
                break;
            default:
                out += c;
        }
    }
    return out;
}

/// Free text made safe inside an XML comment (no "--", no markup characters).
std::string commentSafe(const std::string& s) {
    std::string out;
    for (char c : s) {
        const bool ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') ||
                        (c >= '0' && c <= '9') || c == ' ' || c == '_' || c == '.' || c == '(' ||
                        c == ')';
        out += ok ? c : '_';
    }
    return out;
}

/// Shortest decimal text that reads back as the same float.
std::string floatText(float f) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", double(f));
    return buf;
}

std::string volumeXml(const char* name, const std::string& file, const std::string& matrix,
                      bool nearest) {
    std::ostringstream x;
    x << "        <volume type=\"gridvolume\" name=\"" << name << "\">\n"
      << "            <string name=\"filename\" value=\"" << xmlEscape(file) << "\"/>\n";
    if (nearest)
        x << "            <string name=\"filter_type\" value=\"nearest\"/>\n";
    x << "            <transform name=\"to_world\">\n"
      << "                <matrix value=\"" << matrix << "\"/>\n"
      << "            </transform>\n"
      << "        </volume>\n";
    return x.str();
}

}  // namespace

MitsubaExportResult exportMitsubaVol(const MaterialVolume& volume, const std::string& prefix,
                                     const MitsubaExportOptions& options) {
    namespace fs = std::filesystem;
    const GridSpec& spec = volume.spec();
    LUCENT_CHECK(spec.resolution > 0 && volume.insideMask().size() == spec.voxelCount(),
                 "cannot export an empty material volume to Mitsuba prefix '", prefix, "'");
    LUCENT_CHECK(!prefix.empty(), "Mitsuba export needs a file prefix");
    LUCENT_CHECK(!options.mediumId.empty() &&
                     options.mediumId.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                                        "abcdefghijklmnopqrstuvwxyz0123456789_-") ==
                         std::string::npos,
                 "Mitsuba medium id '", options.mediumId, "' must be non-empty [A-Za-z0-9_-]");
    const fs::path parent = fs::path(prefix).parent_path();
    if (!parent.empty() && !fs::is_directory(parent))
        LUCENT_THROW(IoError, "cannot write Mitsuba files '", prefix, "_*': directory '",
                     parent.string(), "' does not exist");

    MitsubaExportResult result;
    result.sigmaTPath = prefix + "_sigma_t.vol";
    result.albedoPath = prefix + "_albedo.vol";
    result.xmlPath = prefix + "_medium.xml";

    // ḡ: mean of g over the inside voxels and the three channels, accumulated in double in
    // storage order (z, y, x, channel).
    const int res = spec.resolution;
    double gSum = 0.0;
    for (int z = 0; z < res; ++z)
        for (int y = 0; y < res; ++y)
            for (int x = 0; x < res; ++x)
                if (volume.isInside({x, y, z})) {
                    const MaterialSample s = volume.at({x, y, z});
                    gSum += double(s.g.r) + double(s.g.g) + double(s.g.b);
                    ++result.insideVoxels;
                }
    LUCENT_CHECK(result.insideVoxels > 0, "material volume has no inside voxel: nothing to ",
                 "export to '", prefix, "_*'");
    result.meanG = options.hgMeanG ? float(gSum / (3.0 * double(result.insideVoxels))) : 0.f;
    const float meanG = result.meanG;

    // Mitsuba bounds the medium by the mesh, whose interior reaches past the inside mask into
    // the voxels its faces cut: those carry the material too, as the reference path tracer
    // reads it (BoundarySkin.h), not the zero of the voxels further out.
    const std::vector<SkinVoxel> skin = boundarySkin(volume);
    std::vector<MaterialSample> slice(size_t(res) * res);
    const auto sliceOf = [&](int z) -> const std::vector<MaterialSample>& {
        for (int y = 0; y < res; ++y)
            for (int x = 0; x < res; ++x)
                slice[size_t(y) * res + x] = volume.at({x, y, z});
        const size_t first = size_t(z) * res * res;
        auto it = std::lower_bound(skin.begin(), skin.end(), first,
                                   [](const SkinVoxel& v, size_t i) { return v.index < i; });
        for (; it != skin.end() && it->index < first + slice.size(); ++it)
            slice[it->index - first] = it->value;
        return slice;
    };

    const int sigmaChannels = options.rgbSigmaT ? 3 : 1;
    writeVol(result.sigmaTPath, spec, sigmaChannels, [&](int z, float* out) {
        const std::vector<MaterialSample>& values = sliceOf(z);
        for (int y = 0; y < res; ++y)
            for (int x = 0; x < res; ++x) {
                const Rgb st = mitsubaValues(values[size_t(y) * res + x], meanG).sigmaT;
                if (options.rgbSigmaT) {
                    *out++ = st.r;
                    *out++ = st.g;
                    *out++ = st.b;
                } else {
                    *out++ = luminance(st);  // as the OpenVDB `density` grid
                }
            }
    });
    writeVol(result.albedoPath, spec, 3, [&](int z, float* out) {
        const std::vector<MaterialSample>& values = sliceOf(z);
        for (int y = 0; y < res; ++y)
            for (int x = 0; x < res; ++x) {
                const Rgb a = mitsubaValues(values[size_t(y) * res + x], meanG).albedo;
                *out++ = a.r;
                *out++ = a.g;
                *out++ = a.b;
            }
    });

    // to_world: the unit cube [0,1]³ of gridvolume's local space onto the grid box
    // [origin, origin + res·h] (mm). Mitsuba samples voxel i at local (i + ½)/res, i.e. at
    // origin + (i + ½)·h: Lucent's cell centre. Row-major 4×4, as Mitsuba's <matrix> reads it.
    const Bounds3f box = spec.bounds();
    std::string matrix;
    for (int row = 0; row < 3; ++row) {
        for (int col = 0; col < 3; ++col)
            matrix += (col == row ? floatText(box.hi[row] - box.lo[row]) : "0") + " ";
        matrix += floatText(box.lo[row]) + " ";
    }
    matrix += "0 0 0 1";

    const std::string sigmaFile = fs::path(result.sigmaTPath).filename().string();
    const std::string albedoFile = fs::path(result.albedoPath).filename().string();
    std::ostringstream x;
    x << "<scene version=\"3.0.0\">\n"
      << "    <!-- Lucent material volume"
      << (options.materialName.empty() ? "" : " '" + commentSafe(options.materialName) + "'")
      << ", written by Lucent " << commentSafe(LUCENT_VERSION) << " for Mitsuba 3.\n"
      << "         UNITS: lengths in mm, sigma_t in 1/mm (mm^-1). The scene must be in\n"
      << "         millimetres (scale = 1). For a scene in metres set scale to 1000 and append\n"
      << "         <scale value=\"0.001\"/> after the matrix of both to_world transforms.\n"
      << "         Grid: " << res << "^3 voxels of " << floatText(spec.voxelSize)
      << " mm, box min (" << floatText(box.lo.x) << ", " << floatText(box.lo.y) << ", "
      << floatText(box.lo.z) << ") max (" << floatText(box.hi.x) << ", " << floatText(box.hi.y)
      << ", " << floatText(box.hi.z) << ") mm.\n"
      << "         sigma_t = sigma_a + sigma_s, sigma_s = sigma_s'/(1 - g), albedo = "
         "sigma_s/sigma_t,\n"
      << "         with g = " << floatText(meanG)
      << (options.hgMeanG ? " (mean over the inside voxels)" : " (isotropic phase)")
      << ": the reduced medium sigma_s (1 - g) equals Lucent's painted sigma_s'.\n"
      << "         "
      << (options.rgbSigmaT ? "sigma_t has 3 channels (RGB): use an *_rgb variant for exact "
                              "values."
                            : "sigma_t has 1 channel: Rec.709 luminance of the RGB extinction.")
      << "\n"
      << "         The .vol files are resolved relative to the scene file: keep them next to it.\n"
      << "         Use: <include filename=\""
      << xmlEscape(fs::path(result.xmlPath).filename().string())
      << "\"/> in the scene, then give the closed mesh\n"
      << "         the volume was painted in (same mm coordinates) <ref name=\"interior\" id=\""
      << options.mediumId << "\"/>\n"
      << "         and a dielectric BSDF with int_ior/ext_ior ratio " << floatText(volume.eta())
      << ". -->\n"
      << "    <medium type=\"heterogeneous\" id=\"" << options.mediumId << "\">\n"
      << volumeXml("sigma_t", sigmaFile, matrix, options.nearestFilter)
      << volumeXml("albedo", albedoFile, matrix, options.nearestFilter)
      << "        <float name=\"scale\" value=\"1\"/>\n";
    if (options.hgMeanG)
        x << "        <phase type=\"hg\">\n"
          << "            <float name=\"g\" value=\"" << floatText(meanG) << "\"/>\n"
          << "        </phase>\n";
    else
        x << "        <phase type=\"isotropic\"/>\n";
    x << "    </medium>\n"
      << "</scene>\n";
    const std::string xml = x.str();

    writeFileAtomically(result.xmlPath, xml);
    return result;
}

}  // namespace lucent::io

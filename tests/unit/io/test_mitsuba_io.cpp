// SPDX-License-Identifier: MIT
// Mitsuba 3 export: the .vol files are read back with an independent reader written here from
// the format description (mitsuba3 src/volumes/grid.cpp, src/render/volumegrid.cpp), and the
// medium XML is checked structurally.
#include "IoTestUtil.h"

#include <lucent/io/MitsubaIO.h>
#include <lucent/material/BoundarySkin.h>
#include <lucent/material/Medium.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

using namespace lucent;
using namespace lucent::io;
using namespace lucent::test;

namespace {

std::vector<unsigned char> readBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string readText(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// A .vol file as Mitsuba 3 reads it: little-endian header, then float32 data with
/// data[((z*yres + y)*xres + x)*channels + c].
struct VolFile {
    std::string magic;
    int version = 0;
    int32_t encoding = 0;
    int32_t xres = 0, yres = 0, zres = 0, channels = 0;
    float bbox[6] = {};
    std::vector<float> data;

    [[nodiscard]] float at(int x, int y, int z, int c) const {
        return data[((size_t(z) * yres + y) * xres + x) * channels + c];
    }
};

uint32_t le32(const std::vector<unsigned char>& b, size_t at) {
    return uint32_t(b[at]) | uint32_t(b[at + 1]) << 8 | uint32_t(b[at + 2]) << 16 |
           uint32_t(b[at + 3]) << 24;
}

VolFile readVol(const std::string& path) {
    const std::vector<unsigned char> b = readBytes(path);
    VolFile v;
    if (b.size() < 48) {
        ADD_FAILURE() << path << ": " << b.size() << " bytes, shorter than the 48-byte header";
        return v;
    }
    v.magic = std::string(b.begin(), b.begin() + 3);
    v.version = b[3];
    v.encoding = int32_t(le32(b, 4));
    v.xres = int32_t(le32(b, 8));
    v.yres = int32_t(le32(b, 12));
    v.zres = int32_t(le32(b, 16));
    v.channels = int32_t(le32(b, 20));
    for (int i = 0; i < 6; ++i)
        v.bbox[i] = std::bit_cast<float>(le32(b, 24 + 4 * size_t(i)));
    const size_t n = size_t(v.xres) * v.yres * v.zres * v.channels;
    EXPECT_EQ(b.size(), 48 + 4 * n) << path << ": data size disagrees with the header";
    if (b.size() != 48 + 4 * n)
        return v;
    v.data.resize(n);
    for (size_t i = 0; i < n; ++i)
        v.data[i] = std::bit_cast<float>(le32(b, 48 + 4 * i));
    return v;
}

bool sameBits(float a, float b) {
    return std::bit_cast<uint32_t>(a) == std::bit_cast<uint32_t>(b);
}

void expectHeader(const VolFile& v, const GridSpec& spec, int channels) {
    EXPECT_EQ(v.magic, "VOL");
    EXPECT_EQ(v.version, 3);
    EXPECT_EQ(v.encoding, 1);  // float32
    EXPECT_EQ(v.xres, spec.resolution);
    EXPECT_EQ(v.yres, spec.resolution);
    EXPECT_EQ(v.zres, spec.resolution);
    EXPECT_EQ(v.channels, channels);
    // bbox: xmin ymin zmin xmax ymax zmax = the grid's voxel-face box in mm.
    const Bounds3f box = spec.bounds();
    for (int a = 0; a < 3; ++a) {
        EXPECT_TRUE(sameBits(v.bbox[a], box.lo[a])) << "bbox min axis " << a;
        EXPECT_TRUE(sameBits(v.bbox[3 + a], box.hi[a])) << "bbox max axis " << a;
    }
}

/// Minimal XML well-formedness check: balanced, properly nested tags, comments without "--",
/// quoted attributes. Returns the element names in document order.
std::vector<std::string> checkXmlStructure(const std::string& xml) {
    std::vector<std::string> stack, names;
    size_t i = 0;
    while ((i = xml.find('<', i)) != std::string::npos) {
        if (xml.compare(i, 4, "<!--") == 0) {
            const size_t end = xml.find("-->", i + 4);
            EXPECT_NE(end, std::string::npos) << "unterminated comment";
            if (end == std::string::npos)
                break;
            EXPECT_EQ(xml.substr(i + 4, end - i - 4).find("--"), std::string::npos)
                << "'--' inside a comment is not XML";
            i = end + 3;
            continue;
        }
        const size_t end = xml.find('>', i);
        EXPECT_NE(end, std::string::npos) << "unterminated tag";
        if (end == std::string::npos)
            break;
        std::string tag = xml.substr(i + 1, end - i - 1);
        i = end + 1;
        size_t quotes = 0;
        for (char c : tag)
            quotes += c == '"';
        EXPECT_EQ(quotes % 2, 0u) << "unbalanced quotes in <" << tag << ">";
        if (!tag.empty() && tag[0] == '/') {
            const std::string name = tag.substr(1);
            EXPECT_FALSE(stack.empty()) << "closing </" << name << "> without an open element";
            if (stack.empty())
                break;
            EXPECT_EQ(stack.back(), name) << "mis-nested </" << name << ">";
            stack.pop_back();
            continue;
        }
        const bool selfClosing = !tag.empty() && tag.back() == '/';
        const std::string name = tag.substr(0, tag.find_first_of(" \t\n/"));
        names.push_back(name);
        if (!selfClosing)
            stack.push_back(name);
    }
    EXPECT_TRUE(stack.empty()) << "unclosed element <" << (stack.empty() ? "" : stack.back())
                               << ">";
    return names;
}

size_t countOf(const std::string& text, const std::string& needle) {
    size_t n = 0;
    for (size_t p = text.find(needle); p != std::string::npos; p = text.find(needle, p + 1))
        ++n;
    return n;
}

/// The 16 numbers of every <matrix value="..."/>.
std::vector<std::vector<float>> matrices(const std::string& xml) {
    std::vector<std::vector<float>> out;
    const std::string key = "<matrix value=\"";
    for (size_t p = xml.find(key); p != std::string::npos; p = xml.find(key, p + 1)) {
        const size_t start = p + key.size();
        std::istringstream in(xml.substr(start, xml.find('"', start) - start));
        std::vector<float> m;
        std::string tok;
        while (in >> tok)
            m.push_back(std::strtof(tok.c_str(), nullptr));
        out.push_back(m);
    }
    return out;
}

std::string attributeAfter(const std::string& xml, const std::string& key) {
    const size_t p = xml.find(key);
    if (p == std::string::npos)
        return {};
    const size_t start = p + key.size();
    return xml.substr(start, xml.find('"', start) - start);
}

/// What the exports hold at voxel c: the painted value inside, the boundary skin's value in the
/// masked-out voxels next to the inside (BoundarySkin.h), zero further out.
MaterialSample exportedAt(const MaterialVolume& vol, const std::vector<SkinVoxel>& skin,
                          const Coord& c) {
    const size_t i = vol.spec().linearIndex(c);
    const auto it = std::lower_bound(skin.begin(), skin.end(), i,
                                     [](const SkinVoxel& v, size_t k) { return v.index < k; });
    if (!vol.isInside(c) && it != skin.end() && it->index == i)
        return it->value;
    return vol.at(c);
}

double meanInsideG(const MaterialVolume& vol) {
    const int res = vol.resolution();
    double sum = 0.0;
    size_t n = 0;
    for (int z = 0; z < res; ++z)
        for (int y = 0; y < res; ++y)
            for (int x = 0; x < res; ++x)
                if (vol.isInside({x, y, z})) {
                    const Rgb g = vol.at({x, y, z}).g;
                    sum += double(g.r) + double(g.g) + double(g.b);
                    ++n;
                }
    return sum / (3.0 * double(n));
}

}  // namespace

TEST(MitsubaIo, IsotropicGridsEqualReducedMediumBitExact) {
    const MaterialVolume vol = randomPaintedVolume(16, 11);
    const std::string prefix = outputPath("mitsuba_iso");
    MitsubaExportOptions opt;
    opt.hgMeanG = false;
    const MitsubaExportResult r = exportMitsubaVol(vol, prefix, opt);
    EXPECT_EQ(r.sigmaTPath, prefix + "_sigma_t.vol");
    EXPECT_EQ(r.albedoPath, prefix + "_albedo.vol");
    EXPECT_EQ(r.xmlPath, prefix + "_medium.xml");
    EXPECT_EQ(r.meanG, 0.f);

    const VolFile st = readVol(r.sigmaTPath);
    const VolFile al = readVol(r.albedoPath);
    expectHeader(st, vol.spec(), 3);
    expectHeader(al, vol.spec(), 3);
    ASSERT_FALSE(st.data.empty());
    ASSERT_FALSE(al.data.empty());
    const int res = vol.resolution();
    const std::vector<SkinVoxel> skin = boundarySkin(vol);
    size_t inside = 0, mismatches = 0, empty = 0;
    for (int z = 0; z < res; ++z)
        for (int y = 0; y < res; ++y)
            for (int x = 0; x < res; ++x) {
                // Random, channel-distinct values: a swapped axis or channel cannot pass.
                const MaterialSample s = exportedAt(vol, skin, {x, y, z});
                inside += vol.isInside({x, y, z});
                empty += s == MaterialSample{};
                const Rgb a = reducedAlbedo(s);  // what the OpenVDB `albedo` grid holds
                for (int c = 0; c < 3; ++c) {
                    mismatches += !sameBits(st.at(x, y, z, c), s.sigma_t[c]);
                    mismatches += !sameBits(al.at(x, y, z, c), a[c]);
                }
            }
    EXPECT_EQ(mismatches, 0u);
    EXPECT_EQ(r.insideVoxels, inside);
    // Inside voxels, the skin and empty voxels beyond it were all checked.
    EXPECT_GT(inside, 0u);
    EXPECT_GT(skin.size(), 0u);
    EXPECT_GT(empty, 0u);
    EXPECT_EQ(inside + skin.size() + empty, vol.spec().voxelCount());

    const std::string xml = readText(r.xmlPath);
    checkXmlStructure(xml);
    EXPECT_EQ(countOf(xml, "<phase type=\"isotropic\"/>"), 1u);
    EXPECT_EQ(countOf(xml, "type=\"hg\""), 0u);
}

TEST(MitsubaIo, MeanGUnreductionKeepsTheReducedMedium) {
    // Forward-scattering g ∈ [0.14, 0.86] (ḡ ≈ 0.5), so that the unreduction is substantial.
    MaterialVolume vol = randomPaintedVolume(16, 12);
    for (int z = 0; z < vol.resolution(); ++z)
        for (int y = 0; y < vol.resolution(); ++y)
            for (int x = 0; x < vol.resolution(); ++x) {
                MaterialSample s = vol.at({x, y, z});
                s.g = Rgb(0.5f) + 0.4f * s.g;
                vol.set({x, y, z}, s);
            }
    const MitsubaExportResult r = exportMitsubaVol(vol, outputPath("mitsuba_hg"));
    const float gBar = float(meanInsideG(vol));
    EXPECT_TRUE(sameBits(r.meanG, gBar));
    EXPECT_GT(gBar, 0.4f);
    EXPECT_LT(gBar, 0.6f);
    const VolFile st = readVol(r.sigmaTPath);
    const VolFile al = readVol(r.albedoPath);
    expectHeader(st, vol.spec(), 3);
    ASSERT_FALSE(st.data.empty());
    ASSERT_FALSE(al.data.empty());
    const int res = vol.resolution();
    const std::vector<SkinVoxel> skin = boundarySkin(vol);
    size_t mismatches = 0;
    double worstReduced = 0.0, worstAbsorption = 0.0;
    for (int z = 0; z < res; ++z)
        for (int y = 0; y < res; ++y)
            for (int x = 0; x < res; ++x) {
                const MaterialSample s = exportedAt(vol, skin, {x, y, z});
                for (int c = 0; c < 3; ++c) {
                    // The documented float formula, evaluated independently.
                    const float sigmaA = s.sigma_t[c] - s.sigma_s[c];
                    const float sigmaS = s.sigma_s[c] / (1.f - gBar);
                    const float sigmaT = sigmaA + sigmaS;
                    const float albedo = sigmaT > 0.f ? sigmaS / sigmaT : 0.f;
                    mismatches += !sameBits(st.at(x, y, z, c), sigmaT);
                    mismatches += !sameBits(al.at(x, y, z, c), albedo);
                    // Physics: what Mitsuba computes, σs = albedo·σt and σa = σt − σs, must
                    // give back Lucent's reduced medium, σs(1 − ḡ) = σs′ and σa = σt′ − σs′.
                    const double ms = double(al.at(x, y, z, c)) * st.at(x, y, z, c);
                    const double ma = double(st.at(x, y, z, c)) - ms;
                    const double scaleRef = std::max(1.0, double(s.sigma_t[c]) / (1.0 - gBar));
                    worstReduced = std::max(worstReduced,
                                            std::abs(ms * (1.0 - gBar) - s.sigma_s[c]) / scaleRef);
                    worstAbsorption =
                        std::max(worstAbsorption,
                                 std::abs(ma - (double(s.sigma_t[c]) - s.sigma_s[c])) / scaleRef);
                }
            }
    EXPECT_EQ(mismatches, 0u);
    // Four float roundings (subtract, divide, add, divide) of relative size 2^-24 ≈ 6e-8,
    // each amplified at most by σt/σs-type ratios bounded by scaleRef: 1e-6 covers them.
    EXPECT_LT(worstReduced, 1e-6);
    EXPECT_LT(worstAbsorption, 1e-6);

    const std::string xml = readText(r.xmlPath);
    checkXmlStructure(xml);
    const std::string g = attributeAfter(xml, "<float name=\"g\" value=\"");
    ASSERT_FALSE(g.empty());
    EXPECT_TRUE(sameBits(std::strtof(g.c_str(), nullptr), gBar)) << g;
}

TEST(MitsubaIo, ScalarSigmaTIsLuminance) {
    const MaterialVolume vol = randomPaintedVolume(16, 13);
    MitsubaExportOptions opt;
    opt.rgbSigmaT = false;
    opt.hgMeanG = false;
    const MitsubaExportResult r = exportMitsubaVol(vol, outputPath("mitsuba_grey"), opt);
    const VolFile st = readVol(r.sigmaTPath);
    expectHeader(st, vol.spec(), 1);
    expectHeader(readVol(r.albedoPath), vol.spec(), 3);
    ASSERT_FALSE(st.data.empty());
    const int res = vol.resolution();
    const std::vector<SkinVoxel> skin = boundarySkin(vol);
    size_t mismatches = 0;
    for (int z = 0; z < res; ++z)
        for (int y = 0; y < res; ++y)
            for (int x = 0; x < res; ++x) {
                const Rgb t = exportedAt(vol, skin, {x, y, z}).sigma_t;
                // The OpenVDB `density` definition: 0.2126 R + 0.7152 G + 0.0722 B.
                const float lum = 0.2126f * t.r + 0.7152f * t.g + 0.0722f * t.b;
                mismatches += !sameBits(st.at(x, y, z, 0), lum);
            }
    EXPECT_EQ(mismatches, 0u);
}

TEST(MitsubaIo, XmlMediumHasGridVolumesAndToWorldOntoTheBox) {
    const MaterialVolume vol = randomPaintedVolume(16, 14);
    const std::string prefix = outputPath("mitsuba_xml");
    MitsubaExportOptions opt;
    opt.materialName = "marble <test> -- x";
    const MitsubaExportResult r = exportMitsubaVol(vol, prefix, opt);
    const std::string xml = readText(r.xmlPath);
    const std::vector<std::string> names = checkXmlStructure(xml);
    ASSERT_FALSE(names.empty());
    EXPECT_EQ(names.front(), "scene");
    EXPECT_EQ(countOf(xml, "<medium type=\"heterogeneous\" id=\"lucent_medium\">"), 1u);
    EXPECT_EQ(countOf(xml, "<volume type=\"gridvolume\" name=\"sigma_t\">"), 1u);
    EXPECT_EQ(countOf(xml, "<volume type=\"gridvolume\" name=\"albedo\">"), 1u);
    EXPECT_EQ(countOf(xml, "<string name=\"filename\" value=\"mitsuba_xml_sigma_t.vol\"/>"), 1u);
    EXPECT_EQ(countOf(xml, "<string name=\"filename\" value=\"mitsuba_xml_albedo.vol\"/>"), 1u);
    EXPECT_EQ(countOf(xml, "<string name=\"filter_type\" value=\"nearest\"/>"), 2u);
    EXPECT_EQ(countOf(xml, "<transform name=\"to_world\">"), 2u);
    EXPECT_EQ(countOf(xml, "<float name=\"scale\" value=\"1\"/>"), 1u);
    EXPECT_EQ(countOf(xml, "<phase type=\"hg\">"), 1u);
    EXPECT_NE(xml.find("1/mm"), std::string::npos) << "the unit must be stated";

    // to_world (row-major, as Mitsuba's <matrix> reads it) maps the unit cube onto the box
    // [origin, origin + res·h]; Mitsuba samples voxel i at local (i + ½)/res (grid.cpp:
    // p·res − ½), which must land on Lucent's cell centre origin + (i + ½)·h.
    const GridSpec& spec = vol.spec();
    const Bounds3f box = spec.bounds();
    const auto ms = matrices(xml);
    ASSERT_EQ(ms.size(), 2u);
    for (const auto& m : ms) {
        ASSERT_EQ(m.size(), 16u);
        for (int row = 0; row < 4; ++row)
            for (int col = 0; col < 3; ++col)
                if (row != col) {
                    EXPECT_EQ(m[size_t(row * 4 + col)], 0.f) << row << "," << col;
                }
        EXPECT_EQ(m[15], 1.f);
        for (int a = 0; a < 3; ++a) {
            EXPECT_TRUE(sameBits(m[size_t(a * 4 + a)], box.hi[a] - box.lo[a])) << a;
            EXPECT_TRUE(sameBits(m[size_t(a * 4 + 3)], spec.origin[a])) << a;
        }
        const int res = spec.resolution;
        for (int i : {0, 5, res - 1}) {
            for (int a = 0; a < 3; ++a) {
                const double local = (i + 0.5) / res;
                const double world = m[size_t(a * 4 + a)] * local + m[size_t(a * 4 + 3)];
                const Coord c(i);
                // Float rounding of origin + (i+½)h and of res·h: a few ulp of |world| ~ 1e-5.
                EXPECT_NEAR(world, spec.cellCenter(c)[a], 1e-5 * (1.0 + std::abs(world)));
            }
        }
    }
    // The material name is sanitised inside the comment (no markup, no "--").
    EXPECT_EQ(xml.find("<test>"), std::string::npos);
}

TEST(MitsubaIo, BadInputIsRejectedAndLeavesNoFiles) {
    const MaterialVolume vol = randomPaintedVolume(16, 15);
    const std::string missingDir = outputPath("no-such-dir") + "/sub/out";
    expectIoError([&] { exportMitsubaVol(vol, missingDir); }, missingDir, "does not exist");
    EXPECT_FALSE(std::filesystem::exists(missingDir + "_sigma_t.vol"));

    EXPECT_THROW(exportMitsubaVol(MaterialVolume(), outputPath("mitsuba_empty")), ValueError);
    EXPECT_THROW(exportMitsubaVol(vol, ""), ValueError);
    MitsubaExportOptions badId;
    badId.mediumId = "a\"b";
    EXPECT_THROW(exportMitsubaVol(vol, outputPath("mitsuba_badid"), badId), ValueError);
    EXPECT_FALSE(std::filesystem::exists(outputPath("mitsuba_badid") + "_sigma_t.vol"));

    MaterialVolume hollow = randomPaintedVolume(16, 16);
    hollow.setInsideMask(std::vector<uint8_t>(hollow.spec().voxelCount(), 0));
    EXPECT_THROW(exportMitsubaVol(hollow, outputPath("mitsuba_hollow")), ValueError);
    EXPECT_FALSE(std::filesystem::exists(outputPath("mitsuba_hollow") + "_medium.xml"));
}

TEST(MitsubaIo, ReExportReplacesFilesAtomically) {
    const std::string prefix = outputPath("mitsuba_again");
    exportMitsubaVol(randomPaintedVolume(16, 17), prefix);
    const MaterialVolume second = randomPaintedVolume(32, 18);
    exportMitsubaVol(second, prefix);
    const VolFile st = readVol(prefix + "_sigma_t.vol");
    expectHeader(st, second.spec(), 3);
    // No temporary file is left next to the outputs.
    for (const auto& e : std::filesystem::directory_iterator(outputPath("")))
        EXPECT_EQ(e.path().filename().string().find("mitsuba_again_sigma_t.vol.tmp"),
                  std::string::npos)
            << e.path();
}

// SPDX-License-Identifier: MIT
// Round trip, metadata, sparsity, renderer grids and atomic export of the VDB material files.
#include "IoTestUtil.h"

#include <lucent/io/VdbIO.h>

#include <gtest/gtest.h>

#include <csignal>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sys/resource.h>

using namespace lucent;
using namespace lucent::io;
using namespace lucent::test;

namespace {

std::vector<char> readBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

const VdbGridSummary* findGrid(const VdbFileSummary& s, const std::string& name) {
    for (const auto& g : s.grids)
        if (g.name == name)
            return &g;
    return nullptr;
}

std::string metaValue(const std::vector<std::pair<std::string, std::string>>& meta,
                      const std::string& name) {
    for (const auto& [k, v] : meta)
        if (k == name)
            return v;
    return "<missing>";
}

bool bitEqual(const Rgb& a, const Rgb& b) {
    return std::memcmp(&a, &b, sizeof(Rgb)) == 0;
}

}  // namespace

TEST(VdbIo, RoundTripIsBitExact) {
    const MaterialVolume vol = randomPaintedVolume(32, /*seed=*/7);
    const std::string path = outputPath("roundtrip.vdb");
    exportVdb(vol, path, {.rendererGrids = true, .materialName = "random"});
    const ImportedMaterial back = importVdb(path);
    ASSERT_EQ(back.volume.spec(), vol.spec());
    EXPECT_EQ(back.volume.eta(), vol.eta());
    EXPECT_EQ(back.volume.base(), vol.base());
    size_t inside = 0, mismatches = 0;
    for (int z = 0; z < 32; ++z)
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 32; ++x) {
                const Coord c(x, y, z);
                ASSERT_EQ(back.volume.isInside(c), vol.isInside(c)) << x << ' ' << y << ' ' << z;
                inside += vol.isInside(c);
                const MaterialSample a = vol.at(c), b = back.volume.at(c);
                if (!bitEqual(a.sigma_t, b.sigma_t) || !bitEqual(a.sigma_s, b.sigma_s) ||
                    !bitEqual(a.g, b.g))
                    ++mismatches;
            }
    EXPECT_EQ(mismatches, 0u);
    // The mask is a ball of radius 0.42·32 voxels: about (4/3)π·13.44³ ≈ 10 170 voxels.
    EXPECT_GT(inside, 9000u);
    EXPECT_LT(inside, 11500u);
}

TEST(VdbIo, MetadataRoundTripsAndIsListed) {
    const MaterialVolume vol = randomPaintedVolume(16, /*seed=*/3);
    const std::string path = outputPath("metadata.vdb");
    exportVdb(vol, path, {.rendererGrids = true, .materialName = "marble, painted"});
    const ImportedMaterial back = importVdb(path);
    EXPECT_EQ(back.metadata.spec, vol.spec());
    EXPECT_EQ(back.metadata.eta, 1.45f);
    EXPECT_EQ(back.metadata.base, vol.base());
    EXPECT_EQ(back.metadata.materialName, "marble, painted");
    EXPECT_EQ(back.metadata.generator, "Lucent");
    EXPECT_FALSE(back.metadata.generatorVersion.empty());
    EXPECT_EQ(back.metadata.formatVersion, VDB_FORMAT_VERSION);

    const VdbFileSummary s = summarizeVdb(path);
    EXPECT_EQ(metaValue(s.metadata, "length_unit"), "mm");
    EXPECT_EQ(metaValue(s.metadata, "sigma_unit"), "1/mm");
    EXPECT_EQ(metaValue(s.metadata, "sigma_s_is_reduced"), "true");
    EXPECT_EQ(metaValue(s.metadata, "lucent_resolution"), "16");
    ASSERT_EQ(s.grids.size(), 6u);
    for (const char* name : {"sigma_t", "sigma_s", "g", "albedo", "color"}) {
        const VdbGridSummary* g = findGrid(s, name);
        ASSERT_NE(g, nullptr) << name;
        EXPECT_EQ(g->valueType, "vec3s") << name;
        EXPECT_EQ(g->components, 3) << name;
    }
    const VdbGridSummary* density = findGrid(s, "density");
    ASSERT_NE(density, nullptr);
    EXPECT_EQ(density->valueType, "float");
    EXPECT_EQ(density->gridClass, "fog volume");
    EXPECT_EQ(metaValue(findGrid(s, "sigma_s")->metadata, "sigma_s_is_reduced"), "true");
    EXPECT_EQ(metaValue(findGrid(s, "sigma_t")->metadata, "units"), "1/mm");

    // Without renderer grids only the three material grids are written, and import still works.
    exportVdb(vol, path, {.rendererGrids = false, .materialName = ""});
    EXPECT_EQ(summarizeVdb(path).grids.size(), 3u);
    EXPECT_EQ(importVdb(path).metadata.materialName, "");
}

TEST(VdbIo, SparseActiveInsideRendererGridsOnTheSkinHalfVoxelTransform) {
    GridSpec spec;
    spec.origin = Point3f(-8.f, 2.f, 100.f);
    spec.voxelSize = 0.5f;
    spec.resolution = 24;
    const MaterialSample base{Rgb(2.f, 3.f, 4.f), Rgb(1.f, 2.f, 3.f), Rgb(0.f, 0.5f, -0.5f)};
    MaterialVolume vol(spec, base);
    // Inside: the box [5, 14] × [3, 20] × [0, 23] of voxels.
    std::vector<uint8_t> mask(spec.voxelCount(), 0);
    for (int z = 0; z < 24; ++z)
        for (int y = 3; y <= 20; ++y)
            for (int x = 5; x <= 14; ++x)
                mask[spec.linearIndex({x, y, z})] = 1;
    vol.setInsideMask(mask);
    const std::string path = outputPath("sparse.vdb");
    exportVdb(vol, path);
    const VdbFileSummary s = summarizeVdb(path);
    for (const auto& g : s.grids) {
        // The Lucent grids are active exactly inside; the renderer grids also on the boundary
        // skin (BoundarySkin.h), one voxel around the box in x and y (it spans the grid in z):
        // (12·20 − 10·18)·24 more voxels.
        const bool renderer = g.name == "density" || g.name == "albedo" || g.name == "color";
        const int skin = renderer ? 1 : 0;
        EXPECT_EQ(g.activeVoxelCount, uint64_t(renderer ? 12 * 20 * 24 : 10 * 18 * 24)) << g.name;
        EXPECT_EQ(g.activeBox.lo, Coord(5 - skin, 3 - skin, 0)) << g.name;
        EXPECT_EQ(g.activeBox.hi, Coord(14 + skin, 20 + skin, 23)) << g.name;
        // World bounds are the voxel faces: origin + lo·h .. origin + (hi+1)·h. Exact in float
        // here (all values are multiples of 0.5), so a tolerance of 1e-5 mm is only rounding.
        const Point3f lo =
            spec.origin + Vector3f(5.f - float(skin), 3.f - float(skin), 0.f) * spec.voxelSize;
        const Point3f hi =
            spec.origin + Vector3f(15.f + float(skin), 21.f + float(skin), 24.f) * spec.voxelSize;
        for (int k = 0; k < 3; ++k) {
            EXPECT_NEAR(g.worldMin[k], lo[k], 1e-5f) << g.name;
            EXPECT_NEAR(g.worldMax[k], hi[k], 1e-5f) << g.name;
        }
        EXPECT_DOUBLE_EQ(g.voxelSize.x, 0.5);
    }
    // Homogeneous volume: the renderer grids hold the documented constants exactly.
    const VdbGridSummary* density = findGrid(s, "density");
    ASSERT_NE(density, nullptr);
    ASSERT_EQ(density->minValue.size(), 1u);
    EXPECT_FLOAT_EQ(float(density->minValue[0]), luminance(base.sigma_t));
    EXPECT_FLOAT_EQ(float(density->maxValue[0]), luminance(base.sigma_t));
    const VdbGridSummary* albedo = findGrid(s, "albedo");
    ASSERT_NE(albedo, nullptr);
    for (int c = 0; c < 3; ++c) {
        EXPECT_FLOAT_EQ(float(albedo->minValue[c]), base.sigma_s[c] / base.sigma_t[c]);
        EXPECT_FLOAT_EQ(float(albedo->maxValue[c]), base.sigma_s[c] / base.sigma_t[c]);
    }
    const ImportedMaterial back = importVdb(path);
    for (int z = 0; z < 24; ++z)
        for (int y = 0; y < 24; ++y)
            for (int x = 0; x < 24; ++x) {
                const Coord c(x, y, z);
                EXPECT_EQ(back.volume.isInside(c), vol.isInside(c));
                EXPECT_EQ(back.volume.at(c), vol.at(c));
            }
}

TEST(VdbIo, FailedExportLeavesExistingFileUntouched) {
    const std::string path = outputPath("atomic.vdb");
    exportVdb(randomPaintedVolume(16, /*seed=*/1), path);
    const std::vector<char> before = readBytes(path);
    ASSERT_FALSE(before.empty());

    // Inject a real write failure: cap the file size of this process below what the 32³
    // export needs (EFBIG instead of SIGXFSZ once the signal is ignored).
    const MaterialVolume big = randomPaintedVolume(32, /*seed=*/2);
    struct rlimit old {};
    ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
    auto oldHandler = std::signal(SIGXFSZ, SIG_IGN);
    struct rlimit capped = old;
    capped.rlim_cur = 4096;
    ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &capped), 0);
    bool threw = false;
    try {
        exportVdb(big, path);
    } catch (const IoError& e) {
        threw = true;
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
    setrlimit(RLIMIT_FSIZE, &old);
    std::signal(SIGXFSZ, oldHandler);
    EXPECT_TRUE(threw);
    EXPECT_EQ(readBytes(path), before);
    // No temporary left behind.
    for (const auto& entry :
         std::filesystem::directory_iterator(std::filesystem::path(path).parent_path()))
        EXPECT_EQ(entry.path().filename().string().find("atomic.vdb.tmp"), std::string::npos)
            << entry.path();
    EXPECT_NO_THROW(importVdb(path));

    // Unwritable destination: a directory that does not exist.
    const std::string bad = outputPath("no-such-dir/x.vdb");
    expectIoError([&] { exportVdb(big, bad); }, bad, "cannot");
}

TEST(VdbIo, EmptyVolumeIsRejected) {
    EXPECT_THROW(exportVdb(MaterialVolume(), outputPath("empty.vdb")), ValueError);
}

TEST(VdbIo, MissingFileNamesThePath) {
    const std::string path = outputPath("does-not-exist.vdb");
    expectIoError([&] { importVdb(path); }, path, "does not exist");
    expectIoError([&] { summarizeVdb(path); }, path, "does not exist");
}

TEST(VdbIo, SummaryTextListsGrids) {
    const std::string path = outputPath("summary.vdb");
    exportVdb(randomPaintedVolume(16, /*seed=*/5), path);
    const std::string text = formatVdbSummary(summarizeVdb(path));
    for (const char* s :
         {"grid 'sigma_t'", "grid 'sigma_s'", "grid 'g'", "grid 'density'", "grid 'albedo'",
          "grid 'color'", "vec3s", "float", "generator = Lucent", "active voxels"})
        EXPECT_NE(text.find(s), std::string::npos) << s << "\n" << text;
}

TEST(VdbIo, RoundTripWhenChannelsPruneDifferently) {
    // σt varies voxel to voxel while g (and σs′) stay uniform: OpenVDB's per-grid prune turns
    // uniform blocks of g into tiles while σt keeps leaves, so the trees' topologies differ
    // although their active voxels are the same. Import must compare active voxels, not trees
    // (this was a real bug: untouched default scenes could not be reopened).
    MaterialVolume vol = randomPaintedVolume(32, /*seed=*/11);
    const MaterialSample base = vol.base();
    for (int z = 0; z < 32; ++z)
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 32; ++x) {
                MaterialSample s = base;
                s.sigma_t = base.sigma_t + Rgb(0.01f * float(x + y + z));
                vol.set({x, y, z}, s);
            }
    const std::string path = outputPath("prune_differently.vdb");
    exportVdb(vol, path, {.rendererGrids = true, .materialName = "prune"});
    const ImportedMaterial back = importVdb(path);
    for (int z = 0; z < 32; ++z)
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 32; ++x) {
                const Coord c(x, y, z);
                ASSERT_EQ(back.volume.isInside(c), vol.isInside(c));
                const MaterialSample a = back.volume.at(c), b = vol.at(c);
                ASSERT_TRUE(bitEqual(a.sigma_t, b.sigma_t) && bitEqual(a.sigma_s, b.sigma_s) &&
                            bitEqual(a.g, b.g))
                    << x << ' ' << y << ' ' << z;
            }
}

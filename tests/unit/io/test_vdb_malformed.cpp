// SPDX-License-Identifier: MIT
// Malformed and foreign VDB files: every one must give an IoError naming the file, never a
// crash. This TU includes OpenVDB to craft the bad files (wrong types, NaN, missing grids...).
#include "IoTestUtil.h"

#include <lucent/io/VdbIO.h>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <limits>

using namespace lucent;
using namespace lucent::test;

namespace {

namespace vdb = openvdb;

std::vector<char> readBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const std::string& path, const char* data, size_t n) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(data, std::streamsize(n));
}

/// A valid Lucent file, read back with plain OpenVDB so that a test can break one thing.
struct RawFile {
    vdb::GridPtrVec grids;
    vdb::MetaMap meta;

    RawFile() {
        vdb::initialize();
        const std::string path = outputPath("raw-source.vdb");
        exportVdb(randomPaintedVolume(16, /*seed=*/11), path);
        vdb::io::File file(path);
        file.open(false);
        grids = *file.getGrids();
        meta = *file.getMetadata();
        file.close();
    }
    vdb::GridBase::Ptr grid(const std::string& name) {
        for (auto& g : grids)
            if (g->getName() == name)
                return g;
        return nullptr;
    }
    void remove(const std::string& name) {
        std::erase_if(grids, [&](const vdb::GridBase::Ptr& g) { return g->getName() == name; });
    }
    void replace(const std::string& name, vdb::GridBase::Ptr g) {
        remove(name);
        g->setName(name);
        grids.push_back(g);
    }
    std::string write(const std::string& name) const {
        const std::string path = outputPath(name);
        vdb::io::File(path).write(grids, meta);
        return path;
    }
};

/// The first active voxel of grid `name`, set to `v`.
void poison(RawFile& raw, const std::string& name, float v) {
    auto grid = vdb::gridPtrCast<vdb::Vec3SGrid>(raw.grid(name));
    ASSERT_TRUE(grid);
    auto it = grid->beginValueOn();
    ASSERT_TRUE(bool(it));
    vdb::CoordBBox box;
    it.getBoundingBox(box);
    grid->tree().setValueOn(box.min(), vdb::Vec3s(0.5f, v, 0.25f));
}

}  // namespace

TEST(VdbMalformed, TruncatedFilesAreRejected) {
    const std::string src = outputPath("truncate-source.vdb");
    exportVdb(randomPaintedVolume(16, /*seed=*/4), src);
    const std::vector<char> bytes = readBytes(src);
    ASSERT_GT(bytes.size(), 1000u);
    // Cuts in the header, the metadata, the grid descriptors and inside the compressed data.
    const size_t n = bytes.size();
    for (size_t cut : {size_t(0), size_t(4), size_t(8), size_t(40), size_t(200), size_t(600), n / 4,
                       n / 2, 3 * n / 4, n - 100, n - 1}) {
        const std::string path = outputPath("truncated-" + std::to_string(cut) + ".vdb");
        writeBytes(path, bytes.data(), cut);
        // Cuts inside the 8-byte magic number leave no VDB signature; every later cut is
        // caught by the layout parser (byte ranges) as a truncation.
        expectIoError([&] { importVdb(path); }, path,
                      cut < 8 ? "not an OpenVDB file" : "truncated");
    }
}

TEST(VdbMalformed, GarbageBytesAreRejected) {
    Pcg32 rng(99);
    std::vector<char> junk(5000);
    for (char& c : junk)
        c = char(rng.uniformBelow(256));
    const std::string path = outputPath("garbage.vdb");
    writeBytes(path, junk.data(), junk.size());
    expectIoError([&] { importVdb(path); }, path, "VDB file");
    expectIoError([&] { summarizeVdb(path); }, path, "VDB file");
    // A real VDB header followed by garbage.
    const std::string src = outputPath("garbage-source.vdb");
    exportVdb(randomPaintedVolume(16, /*seed=*/8), src);
    std::vector<char> bytes = readBytes(src);
    for (size_t i = bytes.size() / 3; i < bytes.size(); ++i)
        bytes[i] = char(rng.uniformBelow(256));
    const std::string half = outputPath("garbage-tail.vdb");
    writeBytes(half, bytes.data(), bytes.size());
    expectIoError([&] { importVdb(half); }, half, "VDB file");
}

TEST(VdbMalformed, ForeignFileIsSummarisedButNotImported) {
    vdb::initialize();
    auto fog = vdb::FloatGrid::create(0.f);
    fog->setName("density");
    fog->setGridClass(vdb::GRID_FOG_VOLUME);
    fog->tree().setValueOn(vdb::Coord(-3, 4, 1000), 2.5f);
    fog->tree().setValueOn(vdb::Coord(7, -2, 999), 0.5f);
    const std::string path = outputPath("foreign.vdb");
    vdb::io::File(path).write({fog});
    expectIoError([&] { importVdb(path); }, path, "not a Lucent material file");
    const VdbFileSummary s = summarizeVdb(path);
    ASSERT_EQ(s.grids.size(), 1u);
    EXPECT_EQ(s.grids[0].name, "density");
    EXPECT_EQ(s.grids[0].activeVoxelCount, 2u);
    EXPECT_EQ(s.grids[0].activeBox.lo, Coord(-3, -2, 999));
    EXPECT_EQ(s.grids[0].activeBox.hi, Coord(7, 4, 1000));
    ASSERT_EQ(s.grids[0].minValue.size(), 1u);
    EXPECT_EQ(s.grids[0].minValue[0], 0.5);
    EXPECT_EQ(s.grids[0].maxValue[0], 2.5);
}

TEST(VdbMalformed, CorruptedBytesFailTheChecksum) {
    const std::string src = outputPath("flip-source.vdb");
    exportVdb(randomPaintedVolume(16, /*seed=*/6), src);
    std::vector<char> bytes = readBytes(src);
    // One flipped bit anywhere after the file metadata (here: in the middle of the grid data)
    // changes FNV-1a 64; OpenVDB alone would often decode the damaged block silently.
    bytes[bytes.size() / 2] ^= 0x10;
    const std::string path = outputPath("flipped.vdb");
    writeBytes(path, bytes.data(), bytes.size());
    expectIoError([&] { importVdb(path); }, path, "checksum mismatch");
    expectIoError([&] { summarizeVdb(path); }, path, "checksum mismatch");
}

TEST(VdbMalformed, FileRewrittenByAnotherToolStillImports) {
    // Rewriting with plain OpenVDB changes the header UUID, so the stale checksum is not
    // applied; the content checks still run and pass.
    RawFile raw;
    const std::string path = raw.write("rewritten.vdb");
    const ImportedMaterial m = importVdb(path);
    const MaterialVolume ref = randomPaintedVolume(16, /*seed=*/11);
    for (int z = 0; z < 16; ++z)
        for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 16; ++x)
                ASSERT_EQ(m.volume.at({x, y, z}), ref.at({x, y, z}));
}

TEST(VdbMalformed, WrongGridTypeIsRejected) {
    RawFile raw;
    raw.replace("g", vdb::FloatGrid::create(0.f));
    const std::string path = raw.write("wrong-type.vdb");
    expectIoError([&] { importVdb(path); }, path, "grid 'g' has type 'float', expected 'vec3s'");
}

TEST(VdbMalformed, MissingGridIsRejected) {
    for (const char* name : {"sigma_t", "sigma_s", "g"}) {
        RawFile raw;
        raw.remove(name);
        const std::string path = raw.write(std::string("missing-") + name + ".vdb");
        expectIoError([&] { importVdb(path); }, path, std::string("missing grid '") + name + "'");
    }
}

TEST(VdbMalformed, NonFiniteValuesAreRejected) {
    const float bad[] = {std::numeric_limits<float>::quiet_NaN(),
                         std::numeric_limits<float>::infinity()};
    for (const char* name : {"sigma_t", "sigma_s", "g"})
        for (float v : bad) {
            RawFile raw;
            poison(raw, name, v);
            const std::string path = raw.write(std::string("nonfinite-") + name +
                                               (std::isnan(v) ? "-nan" : "-inf") + ".vdb");
            expectIoError([&] { importVdb(path); }, path,
                          std::string("grid '") + name + "' holds a non-finite");
            // The summary still works and counts the bad value.
            const VdbFileSummary s = summarizeVdb(path);
            uint64_t nonFinite = 0;
            for (const auto& g : s.grids)
                nonFinite += g.nonFiniteCount;
            EXPECT_EQ(nonFinite, 1u);
        }
}

TEST(VdbMalformed, OutOfDomainValueIsRejected) {
    RawFile raw;
    poison(raw, "g", 1.5f);  // |g| > 0.99
    const std::string path = raw.write("out-of-domain.vdb");
    expectIoError([&] { importVdb(path); }, path, "outside the valid domain");
}

TEST(VdbMalformed, AbsurdMetadataIsRejected) {
    {
        RawFile raw;
        raw.meta.insertMeta("lucent_resolution", vdb::Int32Metadata(1 << 20));
        const std::string path = raw.write("absurd-resolution.vdb");
        expectIoError([&] { importVdb(path); }, path, "resolution 1048576 is outside");
    }
    {
        RawFile raw;
        raw.meta.insertMeta("lucent_voxel_size_mm",
                            vdb::FloatMetadata(std::numeric_limits<float>::quiet_NaN()));
        const std::string path = raw.write("nan-voxel-size.vdb");
        expectIoError([&] { importVdb(path); }, path, "voxel size");
    }
    {
        RawFile raw;
        raw.meta.removeMeta("lucent_resolution");
        raw.meta.insertMeta("lucent_resolution", vdb::StringMetadata("sixteen"));
        const std::string path = raw.write("string-resolution.vdb");
        expectIoError([&] { importVdb(path); }, path,
                      "metadata 'lucent_resolution' has type 'string'");
    }
    {
        RawFile raw;
        raw.meta.removeMeta("lucent_origin_mm");
        const std::string path = raw.write("no-origin.vdb");
        expectIoError([&] { importVdb(path); }, path, "missing metadata 'lucent_origin_mm'");
    }
}

TEST(VdbMalformed, ActiveVoxelsOutsideTheGridAreRejected) {
    RawFile raw;
    for (const char* name : {"sigma_t", "sigma_s", "g"})
        vdb::gridPtrCast<vdb::Vec3SGrid>(raw.grid(name))
            ->tree()
            .setValueOn(vdb::Coord(16, 0, 0), vdb::Vec3s(0.f));
    const std::string path = raw.write("outside.vdb");
    expectIoError([&] { importVdb(path); }, path, "outside the 16^3 grid");
}

TEST(VdbMalformed, MismatchedTopologyIsRejected) {
    RawFile raw;
    auto g = vdb::gridPtrCast<vdb::Vec3SGrid>(raw.grid("g"));
    vdb::CoordBBox box;
    g->beginValueOn().getBoundingBox(box);
    g->tree().setValueOff(box.min());
    const std::string path = raw.write("topology.vdb");
    expectIoError([&] { importVdb(path); }, path, "not active on the same voxels");
}

TEST(VdbMalformed, MismatchedTransformIsRejected) {
    RawFile raw;
    raw.grid("sigma_s")->setTransform(vdb::math::Transform::createLinearTransform(2.0));
    const std::string path = raw.write("transform.vdb");
    expectIoError([&] { importVdb(path); }, path, "transform of grid 'sigma_s'");
}

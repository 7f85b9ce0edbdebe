// SPDX-License-Identifier: MIT
// Malformed and foreign VDB files: every one must give an IoError naming the file, never a
// crash. The bad files (wrong types, NaN, missing grids...) are crafted with OpenVDB in
// VdbFixtures.cpp, a library of its own (not instrumented in the sanitizer build).
#include "IoTestUtil.h"
#include "VdbFixtures.h"

#include <lucent/core/FileIO.h>
#include <lucent/io/VdbIO.h>

#include <gtest/gtest.h>

#include <malloc.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>

using namespace lucent;
using namespace lucent::io;
using namespace lucent::test;

namespace {

std::vector<char> readBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const std::string& path, const char* data, size_t n) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(data, std::streamsize(n));
}

/// A valid Lucent file (16³, seed 11), read back with plain OpenVDB so that a test can break
/// one thing.
struct RawFile : RawVdbFile {
    RawFile() : RawVdbFile(exportSource()) {}
    std::string write(const std::string& name) const { return RawVdbFile::write(outputPath(name)); }

private:
    static std::string exportSource() {
        const std::string path = outputPath("raw-source.vdb");
        exportVdb(randomPaintedVolume(16, /*seed=*/11), path);
        return path;
    }
};

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
    const std::string path = outputPath("foreign.vdb");
    writeForeignFogVdb(path);
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
    const std::vector<char> source = readBytes(src);
    // One flipped bit anywhere after the file metadata changes FNV-1a 64; OpenVDB alone would
    // often decode the damaged block silently. The integrity walk sees some flips first (a
    // compressed block's header, a node mask): every flip must be reported as corruption, and
    // the ones the walk cannot see by the checksum. Sixteen places over the grid data, so the
    // test does not hang on where one byte of the layout happens to fall.
    const std::string path = outputPath("flipped.vdb");
    int byChecksum = 0;
    for (int k = 0; k < 16; ++k) {
        std::vector<char> bytes = source;
        bytes[bytes.size() / 4 + size_t(k) * (bytes.size() / 2) / 16] ^= 0x10;
        writeBytes(path, bytes.data(), bytes.size());
        for (const bool summary : {false, true}) {
            try {
                if (summary)
                    summarizeVdb(path);
                else
                    importVdb(path);
                ADD_FAILURE() << "flip " << k << " was not detected";
            } catch (const IoError& e) {
                const std::string msg = e.what();
                EXPECT_NE(msg.find(path), std::string::npos) << msg;
                EXPECT_NE(msg.find("corrupt"), std::string::npos) << msg;
                byChecksum += !summary && msg.find("checksum mismatch") != std::string::npos;
            }
        }
    }
    EXPECT_GE(byChecksum, 4) << "the checksum caught too few of the 16 flips";
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
    raw.replaceWithFloatGrid("g");
    const std::string path = raw.write("wrong-type.vdb");
    expectIoError([&] { importVdb(path); }, path, "grid 'g' has type 'float', expected 'vec3s'");
}

TEST(VdbMalformed, MissingGridIsRejected) {
    for (const char* name : {"sigma_t", "sigma_s", "g"}) {
        RawFile raw;
        raw.removeGrid(name);
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
            ASSERT_TRUE(raw.setFirstActiveValue(name, v));
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
    ASSERT_TRUE(raw.setFirstActiveValue("g", 1.5f));  // |g| > 0.99
    const std::string path = raw.write("out-of-domain.vdb");
    expectIoError([&] { importVdb(path); }, path, "outside the valid domain");
}

TEST(VdbMalformed, AbsurdMetadataIsRejected) {
    {
        RawFile raw;
        raw.setFileMetaInt("lucent_resolution", 1 << 20);
        const std::string path = raw.write("absurd-resolution.vdb");
        expectIoError([&] { importVdb(path); }, path, "resolution 1048576 is outside");
    }
    {
        RawFile raw;
        raw.setFileMetaFloat("lucent_voxel_size_mm", std::numeric_limits<float>::quiet_NaN());
        const std::string path = raw.write("nan-voxel-size.vdb");
        expectIoError([&] { importVdb(path); }, path, "voxel size");
    }
    {
        RawFile raw;
        raw.setFileMetaString("lucent_resolution", "sixteen");
        const std::string path = raw.write("string-resolution.vdb");
        expectIoError([&] { importVdb(path); }, path,
                      "metadata 'lucent_resolution' has type 'string'");
    }
    {
        RawFile raw;
        raw.removeFileMeta("lucent_origin_mm");
        const std::string path = raw.write("no-origin.vdb");
        expectIoError([&] { importVdb(path); }, path, "missing metadata 'lucent_origin_mm'");
    }
}

TEST(VdbMalformed, ActiveVoxelsOutsideTheGridAreRejected) {
    RawFile raw;
    for (const char* name : {"sigma_t", "sigma_s", "g"})
        ASSERT_TRUE(raw.activateVoxel(name, 16, 0, 0));
    const std::string path = raw.write("outside.vdb");
    expectIoError([&] { importVdb(path); }, path, "outside the 16^3 grid");
}

TEST(VdbMalformed, MismatchedTopologyIsRejected) {
    RawFile raw;
    ASSERT_TRUE(raw.deactivateFirstActiveVoxel("g"));
    const std::string path = raw.write("topology.vdb");
    expectIoError([&] { importVdb(path); }, path, "not active on the same voxels");
}

TEST(VdbMalformed, MismatchedTransformIsRejected) {
    RawFile raw;
    raw.setUniformTransform("sigma_s", 2.0);
    const std::string path = raw.write("transform.vdb");
    expectIoError([&] { importVdb(path); }, path, "transform of grid 'sigma_s'");
}

// ------------------------------------------------------------------------------------------
// Issue 18 §1: files whose checksum no longer applies (rewritten by another tool) are walked
// completely before OpenVDB reads them; every size OpenVDB 10 would trust is checked.

namespace {

/// `name` in the output folder: writeRandomLeavesVdb's grid of `leaves` incompressible leaves,
/// so each leaf's block is int64 6160 followed by Blosc's header and the 6144 bytes of values.
std::string writeRandomLeaves(const std::string& name, int leaves) {
    const std::string path = outputPath(name);
    writeRandomLeavesVdb(path, leaves);
    return path;
}

/// Offset of the first occurrence of the 8 bytes of `v`.
size_t findInt64(const std::vector<char>& bytes, int64_t v) {
    char pattern[8];
    std::memcpy(pattern, &v, 8);
    const auto it = std::search(bytes.begin(), bytes.end(), pattern, pattern + 8);
    return it == bytes.end() ? std::string::npos : size_t(it - bytes.begin());
}

/// Every load of `path` either succeeds or throws lucent::Error.
void expectLoadOrError(const std::string& path) {
    try {
        summarizeVdb(path);
    } catch (const Error&) {
    }
    try {
        importVdb(path);
    } catch (const Error&) {
    }
}

}  // namespace

TEST(VdbMalformed, OversizedStoredBlockIsRejectedBeforeOpenVdbReadsIt) {
    // Regression: OpenVDB 10.0 reads a stored (negative-size) block into the leaf's buffer
    // before comparing its size: one changed size byte overflowed the heap (ASan:
    // heap-buffer-overflow WRITE in bloscFromStream <- readCompressedValues<Vec3s>).
    const std::string src = writeRandomLeaves("stored-blocks.vdb", 64);
    std::vector<char> bytes = readBytes(src);
    const size_t at = findInt64(bytes, 6144 + 16);  // 512 voxels × 12 bytes + Blosc header
    ASSERT_NE(at, std::string::npos);
    // One changed size field: now a stored (negative) block far larger than the 6144-byte
    // buffer, within the file.
    const int64_t huge = -200000;
    std::memcpy(bytes.data() + at, &huge, 8);
    const std::string path = outputPath("stored-block-overflow.vdb");
    writeBytes(path, bytes.data(), bytes.size());
    expectIoError([&] { summarizeVdb(path); }, path, "stored block of 200000 bytes");
    expectIoError([&] { importVdb(path); }, path, "stored block of 200000 bytes");
}

TEST(VdbMalformed, CheckedInRegressionInputsAreRejected) {
    // tests/data/robust/README.md: a rewritten file with one stored-block size changed
    // (OpenVDB 10 aborted: "free(): invalid pointer"), and a grid metadata name length of
    // 2^31 - 16 (OpenVDB allocated and filled 2 GiB, then misread the rest).
    const std::string dir = std::string(LUCENT_TEST_DATA_DIR) + "/robust/";
    const std::string stored = dir + "vdb_stored_block_overflow.vdb";
    expectIoError([&] { summarizeVdb(stored); }, stored, "stored block of 20000 bytes");
    const std::string meta = dir + "vdb_grid_meta_length.vdb";
    expectIoError([&] { summarizeVdb(meta); }, meta, "metadata name of 2147483632 bytes");
}

namespace {

/// Bytes of the C heap in use over all arenas: chunks in use plus mmapped chunks (glibc
/// mallinfo2; a 520 KiB node is above the mmap threshold, or in an arena once the threshold
/// has grown, and is counted either way).
int64_t heapBytesInUse() {
    const struct mallinfo2 m = mallinfo2();
    return int64_t(m.uordblks + m.hblkhd);
}

// ASan and TSan replace malloc: glibc's mallinfo2 no longer sees the program's heap. Under ASan,
// LeakSanitizer reports a leak at exit instead (the asan-ubsan presets; the tests build with GCC,
// which defines these macros, as in tests/unit/core/test_fileio.cpp).
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr bool GLIBC_HEAP = false;
#else
constexpr bool GLIBC_HEAP = true;
#endif

}  // namespace

TEST(VdbMalformed, FuzzFindingIsRefusedBeforeOpenVdbCanLeak) {
    // tests/data/fuzz/README.md: found by fuzz_vdb's 10^6-execution run of 2026-12-04, reduced
    // to three changed bytes of tests/data/robust/material_sphere16.vdb: the header UUID (so the
    // checksum no longer applies), grid sigma_s's compression flag (blosc -> zip) and one bit of
    // its 32^3 node's value mask (an active tile). That tile's value block, 16 bytes, does not
    // unzip to the 12 bytes of one vec3s. OpenVDB 10.0's RootNode::readTopology allocated the
    // 32^3 node (520 KiB) and lost it when the node's readTopology threw "Expected to
    // decompress 12 bytes, got 16 bytes", once per refused file. The walk now decodes every
    // compressed block of the topology, so the file is refused before OpenVDB reads it: the
    // message is the walk's ("is corrupt (...)"), not OpenVDB's, which only OpenVDB's reader
    // can produce.
    const std::string path =
        std::string(LUCENT_TEST_DATA_DIR) + "/fuzz/vdb_topology_zip_block_wrong_size.vdb";
    const std::string walkText =
        "internal node values: zip block of 16 bytes does not decode to 12";
    expectIoError([&] { summarizeVdb(path); }, path, walkText);
    expectIoError([&] { importVdb(path); }, path, walkText);
    // Without LeakSanitizer (the ci and release builds): the heap must not grow over repeated
    // refusals. The calls above made OpenVDB's one-time state (initialize, registries); the old
    // code lost one 520 KiB node per call, 2 MiB over four, far above this bound.
    if (GLIBC_HEAP) {
        const int64_t before = heapBytesInUse();
        for (int i = 0; i < 4; ++i)
            EXPECT_THROW(importVdb(path), IoError);
        EXPECT_LT(heapBytesInUse() - before, int64_t(256) << 10)
            << "the heap grew over four refused imports: a leak on OpenVDB's error path?";
    }
}

TEST(VdbMalformed, CompressedBlockSizesAreCheckedAgainstTheFileAndTheBloscHeader) {
    RawFile raw;  // rewritten: a fresh UUID, so the Lucent checksum does not apply
    const std::string src = raw.write("rewritten-blosc.vdb");
    const std::vector<char> bytes = readBytes(src);
    // Lucent's σt leaves compress: find a positive block size followed by a Blosc header
    // (version byte 2) and corrupt the size in both directions.
    size_t at = std::string::npos;
    int64_t size = 0;
    for (size_t i = 0; i + 24 < bytes.size(); ++i) {
        std::memcpy(&size, bytes.data() + i, 8);
        uint32_t headerBytes = 0;
        std::memcpy(&headerBytes, bytes.data() + i + 8 + 12, 4);
        if (size > 16 && size < 100000 && bytes[i + 8] == 2 && int64_t(headerBytes) == size) {
            at = i;
            break;
        }
    }
    ASSERT_NE(at, std::string::npos) << "no Blosc block found";
    for (const int64_t bad : {size + 1, size - 1, int64_t(bytes.size()), int64_t(1) << 40}) {
        std::vector<char> mutated = bytes;
        std::memcpy(mutated.data() + at, &bad, 8);
        const std::string path = outputPath("blosc-size.vdb");
        writeBytes(path, mutated.data(), mutated.size());
        expectIoError([&] { summarizeVdb(path); }, path, "VDB file");
    }
}

TEST(VdbMalformed, GridMetadataSizesAreChecked) {
    // Regression: grid-level metadata was not checked; a corrupt string length made OpenVDB
    // allocate (and fill) gigabytes in MetaMap::readMeta.
    RawFile raw;
    raw.setGridMetaString("g", "zz_probe", "abcdefgh");
    const std::string src = raw.write("grid-meta-source.vdb");
    std::vector<char> bytes = readBytes(src);
    const std::string name = "zz_probe";
    const auto it = std::search(bytes.begin(), bytes.end(), name.begin(), name.end());
    ASSERT_NE(it, bytes.end());
    const size_t nameLength = size_t(it - bytes.begin()) - 4;
    const uint32_t huge = 0x7ffffff0u;
    std::memcpy(bytes.data() + nameLength, &huge, 4);
    const std::string path = outputPath("grid-meta-length.vdb");
    writeBytes(path, bytes.data(), bytes.size());
    expectIoError([&] { importVdb(path); }, path, "metadata name of 2147483632 bytes");
    // A fixed-size value whose size field disagrees with its type desynchronises OpenVDB (it
    // reads sizeof(T) whatever the size field says).
    raw.setGridMetaVec3s("g", "zz_vec", 1.f, 1.f, 1.f);
    std::vector<char> typed = readBytes(raw.write("grid-meta-typed.vdb"));
    const std::string key = "zz_vec", type = "vec3s";
    const auto kt = std::search(typed.begin(), typed.end(), key.begin(), key.end());
    ASSERT_NE(kt, typed.end());
    // name characters, then the type name's length and characters, then the value size
    const size_t sizeField = size_t(kt - typed.begin()) + key.size() + 4 + type.size();
    uint32_t twelve = 0;
    std::memcpy(&twelve, typed.data() + sizeField, 4);
    ASSERT_EQ(twelve, 12u);
    const uint32_t wrong = 11;
    std::memcpy(typed.data() + sizeField, &wrong, 4);
    const std::string path2 = outputPath("grid-meta-size.vdb");
    writeBytes(path2, typed.data(), typed.size());
    expectIoError([&] { importVdb(path2); }, path2, "has 11 bytes, not 12");
}

TEST(VdbMalformed, DecodedSizeOverTheImportLimitIsRejected) {
    const std::string path = outputPath("decoded-limit.vdb");
    exportVdb(randomPaintedVolume(32, /*seed=*/3), path);
    ImportLimits small = importLimits();
    small.maxDecodedBytes = 1 << 20;  // a 32³ file decodes to several MiB of tree nodes
    {
        ScopedImportLimits scoped(small);
        expectIoError([&] { importVdb(path); }, path, "import limit");
    }
    EXPECT_NO_THROW(importVdb(path));
}

TEST(VdbMalformed, ByteMutationsOfARewrittenFileNeverCrash) {
    // The fault campaign's class of inputs: a file whose checksum no longer applies, with one
    // or a few bytes changed. Every load must succeed or throw lucent::Error.
    RawFile raw;
    const std::string src = raw.write("mutate-source.vdb");
    const std::vector<char> bytes = readBytes(src);
    Pcg32 rng(2024);
    const std::string path = outputPath("mutated.vdb");
    for (int it = 0; it < 300; ++it) {
        std::vector<char> data = bytes;
        const int changes = 1 + int(rng.uniformBelow(3));
        for (int k = 0; k < changes; ++k)
            data[rng.uniformBelow(uint32_t(data.size()))] = char(rng.uniformBelow(256));
        writeBytes(path, data.data(), data.size());
        expectLoadOrError(path);
    }
}

TEST(VdbMalformed, ValidFilesOfEveryCheckedKindAreRead) {
    // The preflight walk must accept whatever OpenVDB writes: every value type, half floats,
    // zip / no compression, active-mask compression off, tiles at every level, instances and
    // stream-written files.
    auto checkAll = [&](const std::string& path, size_t expected) {
        const VdbFileSummary s = summarizeVdb(path);
        ASSERT_EQ(s.grids.size(), expected) << path;
        std::vector<double> dupValues;
        for (const VdbGridSummary& g : s.grids) {
            EXPECT_TRUE(g.note.empty()) << path << " " << g.name << ": " << g.note;
            EXPECT_GE(g.activeVoxelCount, 1u) << path << " " << g.name;
            if (g.name == "dup" && g.maxValue.size() == 1)
                dupValues.push_back(g.maxValue[0]);
        }
        std::sort(dupValues.begin(), dupValues.end());
        EXPECT_EQ(dupValues, (std::vector<double>{1.0, 2.0})) << path;
    };
    for (const VdbCompression mode :
         {VdbCompression::BloscActiveMask, VdbCompression::ZipActiveMask, VdbCompression::None,
          VdbCompression::ActiveMaskOnly, VdbCompression::BloscOnly, VdbCompression::ZipOnly}) {
        const std::string path = outputPath("every-kind-" + std::to_string(int(mode)) + ".vdb");
        checkAll(path, writeEveryKindVdb(path, mode));
    }
    // Stream-written (no grid offsets): OpenVDB reads every grid when it opens the file.
    const std::string streamed = outputPath("every-kind-stream.vdb");
    checkAll(streamed, writeEveryKindVdbStream(streamed));
}

TEST(VdbMalformed, SummaryOfHugeBoxesDoesNotOverflow) {
    // Regression: the index box extent hi - lo + 1 overflowed int at ±2^30 (UBSan:
    // signed-integer-overflow in formatVdbSummary) and printed a negative size.
    VdbFileSummary s;
    VdbGridSummary g;
    g.name = "huge";
    g.activeBox = {Coord(-(1 << 30), 0, -2147483647 - 1), Coord(1 << 30, 0, 2147483647)};
    g.components = 1;
    s.grids.push_back(g);
    const std::string text = formatVdbSummary(s);
    EXPECT_NE(text.find("(2147483649x1x4294967296)"), std::string::npos) << text;
}

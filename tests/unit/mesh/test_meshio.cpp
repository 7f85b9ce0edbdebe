// SPDX-License-Identifier: MIT
/// @file
/// @brief Mesh import/export: every format round-trips a generated fixture; malformed files
/// fail cleanly with the file named; repairs are reported.

#include "MeshTestUtil.h"

#include <lucent/core/Error.h>
#include <lucent/core/FileIO.h>
#include <lucent/mesh/MeshIO.h>
#include <lucent/mesh/Procedural.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>

namespace lucent {
namespace {

std::string outPath(const std::string& name) {
    std::filesystem::create_directories(LUCENT_TEST_OUTPUT_DIR);
    return std::string(LUCENT_TEST_OUTPUT_DIR) + "/mesh_" + name;
}

void writeText(const std::string& path, const std::string& text) {
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    f << text;
}

/// Expects `fn` to throw IoError whose message names `path`.
template <typename Fn>
void expectIoErrorNaming(Fn fn, const std::string& path) {
    try {
        fn();
        ADD_FAILURE() << "no exception for " << path;
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
}

struct Format {
    const char* ext;
    bool binary;
};

class RoundTrip : public ::testing::TestWithParam<Format> {};

TEST_P(RoundTrip, GeneratedFixtureReadsBackIdentically) {
    const Format f = GetParam();
    const TriangleMesh src = makeSphere(7.5f, 3);
    const std::string path =
        outPath(std::string("roundtrip_") + (f.binary ? "bin" : "ascii") + f.ext);
    std::filesystem::remove(path);
    saveMesh(src, path, f.binary);
    ASSERT_TRUE(std::filesystem::exists(path));
    MeshReport report;
    const TriangleMesh back = loadMesh(path, 1.f, &report);
    EXPECT_EQ(back.triangleCount(), src.triangleCount());
    EXPECT_EQ(back.vertexCount(), src.vertexCount());  // STL re-merges by position
    EXPECT_TRUE(report.isClosedManifold());
    EXPECT_EQ(report.degenerateDropped, 0u);
    EXPECT_TRUE(test::isClosedOriented(back));
    // Same geometry: text formats print ≥ 6 significant digits (≤ 1e-5 relative error of 7.5).
    EXPECT_NEAR(test::signedVolume(back), test::signedVolume(src), 1e-4 * test::signedVolume(src));
    const Bounds3f a = src.bounds(), b = back.bounds();
    EXPECT_NEAR(glm::length(a.lo - b.lo), 0.f, 1e-4f);
    EXPECT_NEAR(glm::length(a.hi - b.hi), 0.f, 1e-4f);
    ASSERT_EQ(back.normals.size(), back.positions.size());
    for (size_t i = 0; i < back.positions.size(); ++i)  // sphere normals are radial
        EXPECT_GT(glm::dot(back.normals[i], glm::normalize(back.positions[i])), 0.99f);
}

INSTANTIATE_TEST_SUITE_P(Formats, RoundTrip,
                         ::testing::Values(Format{".obj", false}, Format{".ply", false},
                                           Format{".ply", true}, Format{".off", false},
                                           Format{".stl", false}, Format{".stl", true},
                                           Format{".vtp", false}, Format{".vtp", true},
                                           Format{".vtk", false}, Format{".vtk", true}),
                         [](const auto& info) {
                             return std::string(info.param.ext + 1) +
                                    (info.param.binary ? "Binary" : "Ascii");
                         });

TEST(MeshIO, ScaleConvertsToMillimetres) {
    const std::string path = outPath("scale.ply");
    saveMesh(makeBox({1.f, 2.f, 3.f}), path);
    const TriangleMesh m = loadMesh(path, /*scale=*/10.f);
    EXPECT_NEAR(m.bounds().extent().z, 30.f, 1e-4f);
    EXPECT_THROW(loadMesh(path, 0.f), ValueError);
    EXPECT_THROW(loadMesh(path, NAN), ValueError);
}

TEST(MeshIO, MalformedFilesFailCleanly) {
    const std::string missing = outPath("does_not_exist.obj");
    expectIoErrorNaming([&] { loadMesh(missing); }, missing);

    const std::string empty = outPath("empty.obj");
    writeText(empty, "");
    expectIoErrorNaming([&] { loadMesh(empty); }, empty);

    const std::string nan = outPath("nan.obj");
    writeText(nan, "v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n");
    expectIoErrorNaming([&] { loadMesh(nan); }, nan);

    const std::string inf = outPath("inf.off");
    writeText(inf,
              "OFF\n4 4 0\n0 0 0\n1 0 0\n0 inf 0\n0 0 1\n3 0 1 2\n3 0 2 3\n3 0 3 1\n3 1 3 2\n");
    expectIoErrorNaming([&] { loadMesh(inf); }, inf);

    const std::string garbage = outPath("garbage.ply");
    writeText(garbage, "this is not a mesh \x01\x02\x03 at all\n");
    expectIoErrorNaming([&] { loadMesh(garbage); }, garbage);

    const std::string garbageObj = outPath("garbage.obj");
    writeText(garbageObj, "hello world\nnothing here\n");
    expectIoErrorNaming([&] { loadMesh(garbageObj); }, garbageObj);

    const std::string garbageVtp = outPath("garbage.vtp");
    writeText(garbageVtp, "<VTKFile broken");
    expectIoErrorNaming([&] { loadMesh(garbageVtp); }, garbageVtp);

    const std::string truncated = outPath("truncated.ply");
    saveMesh(makeSphere(1.f, 2), truncated, /*binary=*/true);
    std::filesystem::resize_file(truncated, std::filesystem::file_size(truncated) / 2);
    expectIoErrorNaming([&] { loadMesh(truncated); }, truncated);

    const std::string unknown = outPath("mesh.xyz");
    writeText(unknown, "1 2 3\n");
    expectIoErrorNaming([&] { loadMesh(unknown); }, unknown);
}

TEST(MeshIO, DegenerateDuplicateAndOpenFacesAreReported) {
    // A tetrahedron plus a zero-area face (collinear vertices 1, 2, 5) and a duplicate face.
    const std::string path = outPath("repair.obj");
    writeText(path,
              "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 2 0 0\n"
              "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
              "f 1 2 5\n"
              "f 2 3 4\n");
    MeshReport r;
    const TriangleMesh m = loadMesh(path, 1.f, &r);
    EXPECT_EQ(m.triangleCount(), 4u);
    EXPECT_EQ(r.degenerateDropped, 1u);
    EXPECT_EQ(r.duplicateDropped, 1u);
    EXPECT_EQ(r.unreferencedDropped, 1u);  // vertex 5 only served the degenerate face
    EXPECT_TRUE(r.isClosedManifold());
    EXPECT_GE(r.warnings.size(), 3u);

    // An open mesh (tetrahedron without one face): reported, not rejected.
    const std::string open = outPath("open.obj");
    writeText(open, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\n");
    MeshReport ro;
    loadMesh(open, 1.f, &ro);
    EXPECT_EQ(ro.boundaryEdges, 3u);
    EXPECT_FALSE(ro.isClosedManifold());
    ASSERT_FALSE(ro.warnings.empty());
    EXPECT_NE(ro.warnings.back().find("open"), std::string::npos);
}

TEST(MeshIO, NonManifoldEdgeIsReported) {
    // Three triangles sharing the edge (1, 2): OpenMesh detaches one; we weld it back and
    // report the non-manifold edge.
    const std::string path = outPath("nonmanifold.obj");
    writeText(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n");
    MeshReport r;
    const TriangleMesh m = loadMesh(path, 1.f, &r);
    EXPECT_EQ(m.triangleCount(), 3u);
    EXPECT_EQ(r.nonManifoldEdges, 1u);
    EXPECT_FALSE(r.isClosedManifold());
}

TEST(MeshIO, ValidateRejectsNonFiniteAndBadIndices) {
    TriangleMesh m = makeSphere(1.f, 1);
    m.positions[0].y = INFINITY;
    EXPECT_THROW(validateMesh(m), ValueError);
    TriangleMesh n = makeSphere(1.f, 1);
    n.triangles[0][1] = 99999;
    EXPECT_THROW(validateMesh(n), ValueError);
    TriangleMesh empty;
    EXPECT_THROW(validateMesh(empty), ValueError);
}

TEST(MeshIO, SharedMeshesLoadIfPresent) {
    const std::string dir = std::string(LUCENT_SHARED_DIR) + "/meshes/";
    if (!std::filesystem::exists(dir + "suzanne.obj"))
        GTEST_SKIP() << "shared meshes absent";
    MeshReport r;
    const TriangleMesh suz = loadMesh(dir + "suzanne.obj", 10.f, &r);
    // 968 faces in the file; one repeats the vertex set of another (removed, reported).
    EXPECT_EQ(suz.triangleCount() + r.duplicateDropped + r.degenerateDropped, 968u);
    EXPECT_EQ(r.duplicateDropped, 1u);
    EXPECT_GT(r.boundaryEdges, 0u);  // SOURCES.md: 42 boundary edges
    MeshReport rb;
    const TriangleMesh bunny = loadMesh(dir + "bunny_closed_75k.ply", 100.f, &rb);
    EXPECT_EQ(bunny.triangleCount(), 75408u);
    EXPECT_TRUE(rb.isClosedManifold());
    EXPECT_GT(test::signedVolume(bunny), 0.0);
}

/// A checked-in regression input (tests/data/robust/README.md).
std::string robustInput(const std::string& name) {
    return std::string(LUCENT_TEST_DATA_DIR) + "/robust/" + name;
}

/// Expects loadMesh(path) to throw IoError naming the file and containing `fragment`.
/// @return the message ("" when there was none).
std::string expectLoadError(const std::string& path, const std::string& fragment) {
    try {
        loadMesh(path);
        ADD_FAILURE() << "no error for " << path;
    } catch (const IoError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(path), std::string::npos) << msg;
        EXPECT_NE(msg.find(fragment), std::string::npos) << "lacks '" << fragment << "': " << msg;
        return msg;
    }
    return {};
}

TEST(MeshIO, HalfTruncatedFilesAreErrorsNotSmallerMeshes) {
    // Regression (issue 18 §4): files cut in half (at a line end) loaded as a few faces and
    // exported a few voxels with exit 0; the legacy VTK reader crashed the process.
    expectLoadError(robustInput("off_half_truncated.off"), "claims 224 faces");
    // Before the legacy walk, the VTK reader's child process contained the crash ("VTK reader:
    // crashed"); now the walk refuses the file before VTK reads it.
    expectLoadError(robustInput("vtk_half_truncated.vtk"),
                    "legacy VTK, POLYGONS: claims 896 cell list entries, more than the 512 bytes");
    expectLoadError(robustInput("stl_truncated.stl"), "binary STL");
    // OBJ has no counts: a file cut at a line end is a valid, open mesh. It is reported as
    // open (and `lucent-cli export` refuses open meshes unless --allow-open).
    MeshReport r;
    loadMesh(robustInput("obj_half_truncated.obj"), 1.f, &r);
    EXPECT_GT(r.boundaryEdges, 0u);
    EXPECT_FALSE(r.warnings.empty());
}

TEST(MeshIO, CorruptCountsAreRejectedBeforeTheReaders) {
    // Regression (issue 18 §3): a face valence of -3 (4294967293 once read as unsigned) made
    // OpenMesh's OFF reader run for minutes at up to 13 GB; a mutated block count in a VTP
    // compression header did the same in vtkXMLDataParser::ReadCompressionHeader.
    expectLoadError(robustInput("off_face_valence.off"), "invalid vertex count '-3'");
    expectLoadError(robustInput("vtp_compression_header.vtp"), "claims 1073741824 blocks");
}

/// A checked-in input found by the fuzz targets (tests/data/fuzz/README.md).
std::string fuzzFinding(const std::string& name) {
    return std::string(LUCENT_TEST_DATA_DIR) + "/fuzz/" + name;
}

std::string readBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(MeshIO, FuzzFindingsAreClearErrors) {
    // A PLY format line without its version number ("format ascii"): OpenMesh's header loop
    // printed "Unsupported keyword : format" forever (a frozen app). Now the header check
    // refuses it before OpenMesh sees the file.
    expectLoadError(fuzzFinding("ply_format_without_version.ply"),
                    "expected 'format <encoding> <version number>'");
    // The same loop when the version does not fit a float ("format ascii 1e39"; the fuzzer's
    // input had a version of 76 digits).
    expectLoadError(fuzzFinding("ply_version_overflows_float.ply"),
                    "expected 'format <encoding> <version number>'");
    // "obj_info property float z" before any element: OpenMesh reads the words after obj_info
    // as header keywords, so it declared a property with no element and crashed (a write
    // through an empty list; the CI fuzz smoke run's first finding).
    expectLoadError(fuzzFinding("ply_obj_info_with_property.ply"),
                    "obj_info text holds a header keyword");
    // A VTP whose cell offsets (raw appended data, uncompressed) end in 0x7272727272727272:
    // VTK 9.1 sizes the connectivity array by that value before reading it. The fuzz build
    // reads VTK in-process and found it under ASan; the child process (lucent/core/Isolate.h)
    // contained it ("out of memory"). The offsets are now checked before VTK reads them.
    expectLoadError(fuzzFinding("vtp_cell_offsets_huge.vtp"),
                    "Polys: cell 5 ends at offset 5642533481364848658, past the 24 point ids");
    // Offsets that decrease (ASCII): refused before VTK, which would read cells of negative
    // length.
    expectLoadError(fuzzFinding("vtp_cell_offsets_decreasing.vtp"),
                    "cell 2 ends at offset 2, before the previous cell's end 6: cell offsets must "
                    "not decrease");
    // The same tetrahedron with increasing offsets loads: the check refuses only bad ones.
    std::ifstream in(fuzzFinding("vtp_cell_offsets_decreasing.vtp"));
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    text.replace(text.find("3 6 2 12"), 8, "3 6 9 12");
    const std::string fixed = outPath("tetra_ascii_offsets.vtp");
    std::ofstream(fixed) << text;
    EXPECT_EQ(loadMesh(fixed).triangleCount(), 4u);
    // The same with a last offset of 3 GiB: 25 s and 3 GiB in the in-process fuzz build, a
    // clear error from the child process. What made VTK allocate was not the offsets but a quote
    // before the '_' marker, which VTK reads as the start of the data (as in the next input):
    // the first array's size then reads 0x485F2027 bytes. Refused before VTK now.
    expectLoadError(fuzzFinding("vtp_cell_offsets_3gib.vtp"),
                    "the size of the appended array at offset 0 is larger than the file");
    // Zlib-compressed raw appended data with four bytes before the '_' marker: VTK takes the
    // first of them for the marker and reads its compression headers from there, the check
    // took them from after the first '_'. The fuzz build's VTK allocated 16 GiB for a block
    // count of 0xFFFFFFF2; the check now reads the header where VTK does.
    expectLoadError(fuzzFinding("vtp_appended_bytes_before_marker.vtp"),
                    "the compression header of the appended array at offset 0 claims 4294967282 "
                    "blocks, more than the file holds");
    // A compression header whose partial last block (64 bytes) is larger than its full blocks
    // (36): VTK then counts one block more than the header has and reads that block's
    // compressed size past the end of its array (the fuzz build's VTK allocated 0x60200024C070
    // bytes, a heap address). Refused before VTK.
    expectLoadError(fuzzFinding("vtp_last_block_larger_than_blocks.vtp"),
                    "claims a last block of 64 bytes, larger than its blocks of 36 (corrupt)");
    // The 10⁶-execution run of 2026-12-04 (evening): an array's offset moved into another
    // array's base64 data, where its compression header reads 0 blocks of 0 bytes; VTK divides
    // by the block size regardless (SIGFPE in vtkXMLDataParser::ReadCompressedData; in the app
    // the child process died with "crashed (Floating point exception)"). Refused before VTK.
    expectLoadError(fuzzFinding("vtp_compression_block_size_zero.vtp"),
                    "claims blocks of 0 bytes (corrupt)");
    // The CI fuzz smoke run of 2026-12-05: the `offsets` array's format mutated to "appen9ded",
    // its offset kept. VTK reads an array of an unknown format with an offset from the appended
    // data, where its compression header read 1.9·10⁹ blocks (the fuzz build's VTK allocated
    // 7.5 GB in vtkXMLDataParser::ReadCompressionHeader); the check took only format
    // "appended" for appended. Refused before VTK.
    expectLoadError(fuzzFinding("vtp_unknown_format_with_offset.vtp"),
                    "the compression header of the appended array at offset 101 claims 1868759041 "
                    "blocks, more than the file holds");
    // The CI fuzz smoke run of 2026-12-06: the points' compression header (base64 appended
    // data) reads 0 blocks of 32768 bytes with a partial last block of 48. VTK computes the
    // array's size as 0 · 32768 − 32768 + 48, which wraps around, and reads block 0 of a header
    // without blocks (SIGSEGV in vtkXMLDataParser::ReadBlock; in the app the child process
    // contained it). Refused before VTK.
    expectLoadError(fuzzFinding("vtp_no_blocks_partial_last_block.vtp"),
                    "the compression header of the appended array at offset 0 claims no blocks "
                    "but a last block of 48 bytes (corrupt)");
    // The same header fault in an inline base64 array, whose headers were not checked at all.
    expectLoadError(robustInput("vtp_last_block_larger_inline_binary_zlib.vtp"),
                    "the compression header of the inline array 'Points' claims a last block of "
                    "32780 bytes, larger than its blocks of 32768");
    // The CI fuzz smoke run of 2026-12-06 (night): a unit ran past libFuzzer's 20 s at 708 MB.
    // Rebuilt by hand: one triangle strip of 999 999 Int8 point ids in a file of 1.9 KB (zlib)
    // or 1.0 KB (LZMA), which VTK expands to 999 997 triangles (4.6–5 s and about 400 MB each in
    // the fuzz build). The point ids of the cells now count against maxElements, read from the
    // compression header, whatever the compressor; one id over the limit is refused.
    ImportLimits limits = importLimits();
    limits.maxElements = 999998;
    ScopedImportLimits scoped(limits);
    for (const char* compressor : {"zlib", "lzma"})
        expectLoadError(fuzzFinding(std::string("vtp_strip_million_ids_") + compressor + ".vtp"),
                        "the cells claim 999999 point ids, more than the import limit of 999998");
    // Found by fuzzing from the LZMA input above (2026-12-07): the compression headers of LZ4
    // and LZMA arrays reached VTK unchecked. A last block larger than its blocks overflowed a
    // heap buffer in vtkXMLDataParser::ReadCompressedData; a header read from mutated base64
    // claimed 2.4·10⁹ blocks and hung ReadCompressionHeader. Every compressor's headers are
    // checked now, and a compressor VTK does not know is refused.
    expectLoadError(fuzzFinding("vtp_lzma_last_block_larger_than_blocks.vtp"),
                    "the compression header of an unnamed inline Float32 array claims a last "
                    "block of 16384 bytes, larger than its blocks of 36 (corrupt)");
    expectLoadError(fuzzFinding("vtp_lzma_header_in_text.vtp"),
                    "claims 2399141889 blocks, more than the file holds (corrupt)");
    const std::string bogus = outPath("unknown_compressor.vtp");
    std::string lzma = readBytes(fuzzFinding("vtp_strip_million_ids_lzma.vtp"));
    lzma.replace(lzma.find("vtkLZMADataCompressor"), 21, "vtkXYZDataCompressor");
    std::ofstream(bogus) << lzma;
    expectLoadError(bogus, "unknown compressor 'vtkXYZDataCompressor'");
}

// Issue 16: the cell offsets of a VTK XML file are checked before VTK reads them in every
// encoding VTK writes, not only ASCII and raw appended data. The tetrahedra were written by
// vtkXMLPolyDataWriter (inline base64, appended base64, appended raw; each uncompressed and
// zlib); the corrupt twins end their last cell at offset 1000 of 12 point ids. Before, VTK in
// the child process sized its arrays by that offset and reported "VTK found no points".
TEST(MeshIO, CellOffsetsAreCheckedInEveryVtkXmlEncoding) {
    for (const char* encoding : {"inline_binary", "inline_binary_zlib", "appended_base64",
                                 "appended_base64_zlib", "appended_raw", "appended_raw_zlib"}) {
        SCOPED_TRACE(encoding);
        EXPECT_EQ(
            loadMesh(robustInput(std::string("vtp_tetra_") + encoding + ".vtp")).triangleCount(),
            4u);
        expectLoadError(robustInput(std::string("vtp_offsets_past_") + encoding + ".vtp"),
                        "Polys: cell 3 ends at offset 1000, past the 12 point ids");
    }
}

// VTK 9.1 reads cell arrays of every integer type, so the offsets check decodes all of them:
// the tetrahedron with its offsets as inline base64 Int16 and UInt8 ([UInt32 byte count][values]).
TEST(MeshIO, CellOffsetsOfEveryIntegerTypeAreChecked) {
    const std::string text = readBytes(fuzzFinding("vtp_cell_offsets_decreasing.vtp"));
    const size_t from = text.find("<DataArray type=\"Int64\" Name=\"offsets\"");
    const size_t to = text.find("</DataArray>", from) + std::string("</DataArray>").size();
    ASSERT_NE(from, std::string::npos);
    const auto withOffsets = [&](const std::string& name, const char* type, const char* base64) {
        const std::string path = outPath(name);
        std::ofstream(path) << text.substr(0, from) << "<DataArray type=\"" << type
                            << "\" Name=\"offsets\" format=\"binary\">" << base64 << "</DataArray>"
                            << text.substr(to);
        return path;
    };
    // 3 6 9 12 loads; 3 6 −1 12 (0xFFFF sign-extended) is refused.
    EXPECT_EQ(
        loadMesh(withOffsets("offsets_int16.vtp", "Int16", "CAAAAAMABgAJAAwA")).triangleCount(),
        4u);
    EXPECT_EQ(loadMesh(withOffsets("offsets_uint8.vtp", "UInt8", "BAAAAAMGCQw=")).triangleCount(),
              4u);
    expectLoadError(withOffsets("offsets_int16_negative.vtp", "Int16", "CAAAAAMABgD//wwA"),
                    "Polys: cell 2 ends at offset -1, before the previous cell's end 6");
}

/// Expects loadMesh(path) to be refused by the legacy VTK walk (MeshValidate.cpp), before VTK
/// reads the file: its messages start "legacy VTK, <section>:"; the reader's child process
/// would say "VTK reader".
void expectWalkError(const std::string& path, const std::string& fragment) {
    const std::string msg = expectLoadError(path, fragment);
    EXPECT_NE(msg.find("mesh file '" + path + "': legacy VTK, "), std::string::npos) << msg;
    EXPECT_EQ(msg.find("VTK reader"), std::string::npos) << msg;
}

// Issue 16: legacy .vtk files are walked completely before VTK 9.1's reader, which crashes
// in-process on nearly every malformed file. The tetrahedra were written by vtkPolyDataWriter
// (tests/data/robust/make_vtk_tetra.cpp) in versions 4.2 (cells as counts and ids) and 5.1
// (OFFSETS/CONNECTIVITY), ASCII and BINARY, with normals, a cell scalar and a METADATA block;
// each has four corrupt twins that the walk must refuse naming the problem.
TEST(MeshIO, LegacyVtkIsWalkedInEveryVersionAndEncoding) {
    for (const char* version : {"v42", "v51"}) {
        for (const char* encoding : {"ascii", "binary"}) {
            const std::string stem = std::string("vtk_tetra_") + version + "_" + encoding;
            SCOPED_TRACE(stem);
            const bool v5 = std::string(version) == "v51";
            const bool binary = std::string(encoding) == "binary";
            MeshReport report;
            const TriangleMesh tetra = loadMesh(robustInput(stem + ".vtk"), 1.f, &report);
            EXPECT_EQ(tetra.triangleCount(), 4u);
            EXPECT_EQ(tetra.vertexCount(), 4u);
            EXPECT_TRUE(report.isClosedManifold());
            EXPECT_FALSE(report.normalsComputed);  // the file's NORMALS were read
            EXPECT_GT(test::signedVolume(tetra), 0.0);
            expectWalkError(robustInput(stem + "_id_past_points.vtk"),
                            std::string(v5 ? "connectivity entry 11" : "cell 3") +
                                " refers to point 1000, not one of the 4 points");
            expectWalkError(robustInput(stem + "_count_past_end.vtk"),
                            "POINTS: claims 400000 points, more than the");
            // Cut 20 bytes into the cell data: a binary file is shorter than the claimed
            // cells, an ASCII one ends in the middle of them.
            expectWalkError(robustInput(stem + "_truncated.vtk"),
                            binary ? (v5 ? "claims 12 vtktypeint64 values, more than the 21 bytes"
                                         : "claims 16 cell list entries, more than the 21 bytes")
                                   : (v5 ? "truncated: the file ends at value 10 of 12"
                                         : "truncated: the file ends at entry 9 of 16"));
            if (v5)
                expectWalkError(robustInput(stem + "_offsets_decreasing.vtk"),
                                "POLYGONS: cell 2 ends at offset 6, before its start 9");
            else
                expectWalkError(robustInput(stem + "_cell_size_past_list.vtk"),
                                "POLYGONS: cell 0 claims 16 points, more than the 15 entries left");
        }
    }
}

// Inputs on which VTK 9.1's legacy reader hangs, recurses or misreads without failing, found
// by reading vtkDataReader: each one is the valid ASCII 5.1 tetrahedron with one change.
TEST(MeshIO, LegacyVtkReaderTrapsAreRefused) {
    const std::string valid = readBytes(robustInput("vtk_tetra_v51_ascii.vtk"));
    const auto variant = [&](const std::string& name, const std::string& from,
                             const std::string& to) {
        std::string text = valid;
        const size_t at = text.find(from);
        EXPECT_NE(at, std::string::npos) << from;
        text.replace(at, from.size(), to);
        const std::string path = outPath("legacy_" + name + ".vtk");
        writeText(path, text);
        return path;
    };
    // After each array VTK pops blank lines by peeking 256 bytes: 256 spaces make it loop
    // forever (checked with the system VTK 9.1).
    expectWalkError(variant("spaces", "0 0 1 \n", "0 0 1" + std::string(300, ' ') + "\n"),
                    "256 spaces after the data");
    // 255 spaces are popped like a blank line: the file loads.
    EXPECT_EQ(loadMesh(variant("spaces_255", "0 0 1 \n", "0 0 1" + std::string(255, ' ') + "\n"))
                  .triangleCount(),
              4u);
    // Each switch between POINT_DATA and CELL_DATA nests one more reader call in VTK.
    expectWalkError(variant("nested", "POINT_DATA 4\n", "POINT_DATA 4\nCELL_DATA 4\n"),
                    "CELL_DATA: a second CELL_DATA section");
    // An information key VTK would read by another type (a failed stream read, then an
    // endless loop over empty lines).
    expectWalkError(variant("info_key", "L2_NORM_RANGE", "GUI_HIDE"),
                    "information key 'vtkDataArray::GUI_HIDE' is not one the import reads");
    // A word longer than VTK's 256-character buffers is cut in two by its reader.
    expectWalkError(variant("long_name", "NORMALS Normals", "NORMALS " + std::string(300, 'n')),
                    "a word of more than 255 characters");
    // Attribute arrays must have one value per point / cell (VTK checks only the first
    // section's count).
    expectWalkError(variant("cell_count", "CELL_DATA 4", "CELL_DATA 5"),
                    "CELL_DATA: claims 5 values for the 4 cells");
    // An ASCII number VTK's stream cannot extract ("nan", a float beyond its range).
    expectWalkError(variant("nan", "0 0 1 \n", "0 0 nan \n"), "value 11 'nan' is not a float");
    expectWalkError(variant("overflow", "0 0 1 \n", "0 0 1e39 \n"), "'1e39' is not a float");
    // Binary: a NaN coordinate, refused like the ASCII one.
    std::string binary = readBytes(robustInput("vtk_tetra_v51_binary.vtk"));
    const size_t points = binary.find("POINTS 4 float\n") + 15;
    binary.replace(points, 4, std::string("\x7f\xc0\0\0", 4));
    const std::string nanPath = outPath("legacy_binary_nan.vtk");
    writeText(nanPath, binary);
    expectWalkError(nanPath, "POINTS: value 0 is not finite");
    // Unknown keywords and dataset types.
    expectWalkError(variant("grid", "POLYDATA", "UNSTRUCTURED_GRID"),
                    "only POLYDATA datasets are read");
    expectWalkError(variant("version", "Version 5.1", "Version 6.0"), "is not one VTK 9.1 reads");
}

TEST(MeshIO, ImportLimitsApplyBeforeAllocation) {
    const std::string sphere = robustInput("sphere_closed.off");
    EXPECT_EQ(loadMesh(sphere).triangleCount(), 224u);
    ImportLimits small = importLimits();
    small.maxElements = 100;  // the file claims 114 vertices
    {
        ScopedImportLimits scoped(small);
        expectLoadError(sphere, "import limit");
    }
    small = importLimits();
    small.maxFileBytes = 1000;
    {
        ScopedImportLimits scoped(small);
        expectLoadError(sphere, "import limit");
    }
    // Not a regular file: a device would be read without end.
    const std::string zero = outPath("zero.off");
    std::filesystem::remove(zero);
    std::filesystem::create_symlink("/dev/zero", zero);
    expectLoadError(zero, "not a regular file");
}

TEST(MeshIO, CorruptedFilesFailCleanly) {
    // Deterministic byte mutations and truncations of valid files of every format: each load
    // must either succeed or throw lucent::Error (never crash). This found crashes inside
    // OpenMesh (OBJ normals, PLY headers, a dangling error-log stream after a reader threw)
    // and VTK (cell ids) that loadMesh now guards against; the legacy .vtk walk (issue 16)
    // keeps VTK 9.1's legacy reader away from every corrupt file.
    const TriangleMesh src = makeSphere(5.f, 2);
    std::vector<std::pair<std::string, std::string>> originals;  // extension, bytes
    for (const Format f :
         {Format{".obj", false}, Format{".ply", false}, Format{".ply", true}, Format{".off", false},
          Format{".stl", false}, Format{".stl", true}, Format{".vtp", false}, Format{".vtp", true},
          Format{".vtk", false}, Format{".vtk", true}}) {
        const std::string path = outPath(std::string("fuzz_src") + (f.binary ? "b" : "a") + f.ext);
        saveMesh(src, path, f.binary);
        std::ifstream in(path, std::ios::binary);
        originals.emplace_back(f.ext, std::string(std::istreambuf_iterator<char>(in), {}));
    }
    std::mt19937 rng(12345);
    size_t loaded = 0, rejected = 0;
    for (int it = 0; it < 200; ++it) {
        const auto& [ext, bytes] = originals[size_t(it) % originals.size()];
        std::string data = bytes;
        const int flips = 1 + int(rng() % 20);
        for (int k = 0; k < flips; ++k)
            data[rng() % data.size()] = char(rng());
        if (rng() % 4 == 0)
            data.resize(rng() % data.size() + 1);
        const std::string path = outPath("fuzz" + ext);
        writeText(path, data);
        try {
            loadMesh(path);
            ++loaded;
        } catch (const Error&) {
            ++rejected;
        }
    }
    EXPECT_EQ(loaded + rejected, 200u);
    EXPECT_GT(rejected, 0u);
}

}  // namespace
}  // namespace lucent

// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Writers of malformed and foreign VDB files for the io tests, behind a plain
/// interface: no OpenVDB header here.
///
/// The implementation (VdbFixtures.cpp) is the only test code that instantiates OpenVDB's grid
/// and stream templates, the most expensive compile of the suite. It is a library of its own so
/// that the sanitizer build compiles it without instrumentation (tests/unit/io/CMakeLists.txt):
/// it only writes inputs, while the code under test (engine/src/io/VdbIO.cpp) stays
/// instrumented.

#include <cstdint>
#include <memory>
#include <string>

#if defined(__GNUC__)
#define LUCENT_VDB_FIXTURES_API __attribute__((visibility("default")))
#else
#define LUCENT_VDB_FIXTURES_API
#endif

namespace lucent::test {

/// A VDB file read back with plain OpenVDB so that a test can break one thing and write it
/// again. Writing with plain OpenVDB gives the file a fresh UUID: a Lucent checksum in it no
/// longer applies (a file "rewritten by another tool").
class LUCENT_VDB_FIXTURES_API RawVdbFile {
public:
    explicit RawVdbFile(const std::string& path);
    ~RawVdbFile();
    RawVdbFile(const RawVdbFile&) = delete;
    RawVdbFile& operator=(const RawVdbFile&) = delete;

    /// Writes every grid and the file metadata to `path`; returns `path`.
    std::string write(const std::string& path) const;

    void removeGrid(const std::string& name);
    /// Replaces grid `name` by an empty float grid of the same name.
    void replaceWithFloatGrid(const std::string& name);
    /// Sets the first active voxel of the vec3s grid `name` to (0.5, y, 0.25); false when the
    /// grid is missing, not vec3s or empty.
    bool setFirstActiveValue(const std::string& name, float y);
    /// Turns the first active voxel of the vec3s grid `name` off; false as above.
    bool deactivateFirstActiveVoxel(const std::string& name);
    /// Sets voxel (x, y, z) of the vec3s grid `name` active with value 0; false as above.
    bool activateVoxel(const std::string& name, int x, int y, int z);
    /// Gives grid `name` a uniform linear transform of `voxelSize`.
    void setUniformTransform(const std::string& name, double voxelSize);

    void setFileMetaInt(const std::string& key, int32_t value);
    void setFileMetaFloat(const std::string& key, float value);
    void setFileMetaString(const std::string& key, const std::string& value);
    void removeFileMeta(const std::string& key);
    void setGridMetaString(const std::string& grid, const std::string& key,
                           const std::string& value);
    void setGridMetaVec3s(const std::string& grid, const std::string& key, float x, float y,
                          float z);

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

/// A foreign fog volume: one float grid "density" with 2.5 at (-3, 4, 1000) and 0.5 at
/// (7, -2, 999).
LUCENT_VDB_FIXTURES_API void writeForeignFogVdb(const std::string& path);

/// One vec3s grid "velocity" of `leaves` full 8³ leaves of random finite bit patterns: Blosc
/// cannot shrink them and stores each leaf's 6144 bytes behind its 16-byte header.
LUCENT_VDB_FIXTURES_API void writeRandomLeavesVdb(const std::string& path, int leaves);

/// How writeEveryKindVdb compresses (OpenVDB's io::COMPRESS_* flags).
/// ZipOnly writes every value of an internal node (no active mask), so that its topology holds
/// zip blocks that compress (stored blocks otherwise: zip keeps a block only when it shrinks).
enum class VdbCompression {
    BloscActiveMask,
    ZipActiveMask,
    None,
    ActiveMaskOnly,
    BloscOnly,
    ZipOnly
};

/// Every grid kind OpenVDB writes, each with two voxels and tiles at every tree level: float,
/// double, int32, int64, bool, mask, vec3s, vec3d, vec3i, float and vec3s saved as half, an
/// instance (a grid sharing another's tree) and two grids named "dup" with maximum 1 and 2.
/// Returns the number of grids written.
LUCENT_VDB_FIXTURES_API size_t writeEveryKindVdb(const std::string& path,
                                                 VdbCompression compression);
/// The same grids through io::Stream (no grid offsets; OpenVDB reads them all on open).
LUCENT_VDB_FIXTURES_API size_t writeEveryKindVdbStream(const std::string& path);

}  // namespace lucent::test

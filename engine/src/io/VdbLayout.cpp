// SPDX-License-Identifier: MIT
/// @file
/// @brief Bounds-checked outer-structure parser for VDB files (see VdbLayout.h).

#include "VdbLayout.h"

#include <lucent/core/Error.h>

#include <cstdio>

namespace lucent::io_detail {

namespace {

constexpr int64_t VDB_MAGIC = 0x56444220;     // OPENVDB_MAGIC (openvdb/version.h)
constexpr uint32_t VERSION_BOOST_UUID = 218;  // UUID stored as 36 ASCII characters
constexpr uint32_t VERSION_SELECTIVE_COMPRESSION = 220;
constexpr uint32_t VERSION_NODE_MASK_COMPRESSION = 222;
constexpr uint32_t VERSION_GRID_INSTANCING = 216;
constexpr uint32_t MAX_KNOWN_VERSION = 224;  // OPENVDB_FILE_VERSION of OpenVDB 10
constexpr uint32_t MAX_NAME = 1u << 16;      // longest grid/metadata/type name accepted

class Cursor {
public:
    Cursor(const ByteReader& read, uint64_t size, const std::string& name)
        : m_read(read), m_size(size), m_name(name) {}

    void need(uint64_t n, const char* what) const {
        if (n > m_size || m_pos > m_size - n)
            LUCENT_THROW(IoError, "VDB file '", m_name, "' is truncated (", what, " at byte ",
                         m_pos, " needs ", n, " bytes, file has ", m_size, ")");
    }
    template <typename T>
    T read(const char* what) {
        need(sizeof(T), what);
        T v{};
        m_read(m_pos, &v, sizeof(T));
        m_pos += sizeof(T);
        return v;
    }
    std::string readString(const char* what, uint32_t maxLen) {
        const auto len = read<uint32_t>(what);
        if (len > maxLen)
            LUCENT_THROW(IoError, "VDB file '", m_name, "' is corrupt (", what, " of ", len,
                         " bytes at byte ", m_pos - 4, ")");
        need(len, what);
        std::string s(len, '\0');
        if (len)
            m_read(m_pos, s.data(), len);
        m_pos += len;
        return s;
    }
    void skip(uint64_t n, const char* what) {
        need(n, what);
        m_pos += n;
    }
    void seek(uint64_t pos) { m_pos = pos; }
    [[nodiscard]] uint64_t pos() const { return m_pos; }
    [[nodiscard]] uint64_t remaining() const { return m_size - m_pos; }

private:
    const ByteReader& m_read;
    uint64_t m_size;
    const std::string& m_name;
    uint64_t m_pos = 0;
};

}  // namespace

VdbLayout parseVdbLayout(const ByteReader& read, uint64_t size, const std::string& name) {
    VdbLayout layout;
    Cursor in(read, size, name);
    if (size < 8 || in.read<int64_t>("magic number") != VDB_MAGIC)
        LUCENT_THROW(IoError, "VDB file '", name, "' is not an OpenVDB file (bad magic number)");
    layout.fileVersion = in.read<uint32_t>("file version");
    if (layout.fileVersion < VERSION_BOOST_UUID)
        return layout;  // legacy: left to OpenVDB
    if (layout.fileVersion > MAX_KNOWN_VERSION)
        LUCENT_THROW(IoError, "VDB file '", name, "' has file format version ", layout.fileVersion,
                     ", newer than this OpenVDB (", MAX_KNOWN_VERSION, ")");
    in.read<uint32_t>("library major version");
    in.read<uint32_t>("library minor version");
    const auto hasGridOffsets = in.read<char>("grid offsets flag");
    if (layout.fileVersion >= VERSION_SELECTIVE_COMPRESSION &&
        layout.fileVersion < VERSION_NODE_MASK_COMPRESSION)
        in.read<char>("compression flag");
    in.need(36, "UUID");
    layout.uuid.resize(36);
    read(in.pos(), layout.uuid.data(), 36);
    in.skip(36, "UUID");

    // File metadata: count, then (name, type name, uint32 size, value bytes) per entry.
    const auto count = in.read<uint32_t>("metadata count");
    if (count > in.remaining() / 12)  // every entry takes at least 3 × 4 bytes
        LUCENT_THROW(IoError, "VDB file '", name, "' is truncated or corrupt (", count,
                     " metadata entries cannot fit in the remaining ", in.remaining(), " bytes)");
    for (uint32_t i = 0; i < count; ++i) {
        VdbMetaEntry e;
        e.name = in.readString("metadata name", MAX_NAME);
        e.typeName = in.readString("metadata type", MAX_NAME);
        e.valueSize = in.read<uint32_t>("metadata size");
        e.valueOffset = in.pos();
        in.skip(e.valueSize, "metadata value");
        layout.meta.push_back(std::move(e));
    }
    layout.metaEnd = in.pos();
    if (!hasGridOffsets) {  // stream-written file: grids follow without descriptors
        layout.parsed = true;
        return layout;
    }

    // Grid descriptors, each followed by its grid; endPos points at the next descriptor.
    const auto gridCount = in.read<int32_t>("grid count");
    if (gridCount < 0 || uint64_t(gridCount) > in.remaining() / 36)  // ≥ 3 strings + 3 offsets
        LUCENT_THROW(IoError, "VDB file '", name, "' is truncated or corrupt (grid count ",
                     gridCount, " with ", in.remaining(), " bytes left)");
    for (int32_t i = 0; i < gridCount; ++i) {
        VdbGridEntry g;
        g.uniqueName = in.readString("grid name", MAX_NAME);
        g.typeName = in.readString("grid type", MAX_NAME);
        if (layout.fileVersion >= VERSION_GRID_INSTANCING)
            in.readString("grid instance parent", MAX_NAME);
        const auto gridPos = in.read<int64_t>("grid offset");
        const auto blockPos = in.read<int64_t>("grid data offset");
        const auto endPos = in.read<int64_t>("grid end offset");
        if (gridPos < int64_t(in.pos()) || blockPos < gridPos || endPos < blockPos)
            LUCENT_THROW(IoError, "VDB file '", name, "' is corrupt (grid '", g.uniqueName,
                         "' has inconsistent offsets ", gridPos, ", ", blockPos, ", ", endPos, ")");
        if (uint64_t(endPos) > size)
            LUCENT_THROW(IoError, "VDB file '", name, "' is truncated (grid '", g.uniqueName,
                         "' ends at byte ", endPos, ", file has ", size, ")");
        g.gridPos = uint64_t(gridPos);
        g.blockPos = uint64_t(blockPos);
        g.endPos = uint64_t(endPos);
        in.seek(g.endPos);
        layout.grids.push_back(std::move(g));
    }
    layout.parsed = true;
    return layout;
}

uint64_t fnv1a64(const void* data, size_t n, uint64_t hash) {
    // FNV-1a, 64-bit: offset basis 0xcbf29ce484222325, prime 0x100000001b3.
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < n; ++i) {
        hash ^= p[i];
        hash *= 0x100000001b3ULL;
    }
    return hash;
}

std::string hex64(uint64_t v) {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
    return buf;
}

}  // namespace lucent::io_detail

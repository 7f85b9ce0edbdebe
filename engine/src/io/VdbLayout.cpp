// SPDX-License-Identifier: MIT
/// @file
/// @brief Bounds-checked walk of a whole VDB file (see VdbLayout.h).

#include "VdbLayout.h"

#include <lucent/core/Error.h>
#include <lucent/core/FileIO.h>

#include <blosc.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>

namespace lucent::io::detail {

namespace {

constexpr int64_t VDB_MAGIC = 0x56444220;  // OPENVDB_MAGIC (openvdb/version.h)
constexpr uint32_t VERSION_SELECTIVE_COMPRESSION = 220;
constexpr uint32_t VERSION_FLOAT_FRUSTUM_BBOX = 221;
constexpr uint32_t VERSION_NODE_MASK_COMPRESSION = 222;  // oldest format walked (OpenVDB 2.0)
constexpr uint32_t MAX_KNOWN_VERSION = 224;              // OPENVDB_FILE_VERSION of OpenVDB 10
constexpr uint32_t MAX_NAME = 1u << 16;                  // longest grid/metadata/type name accepted
constexpr uint32_t MAX_TYPE_NAME = 256;                  // longest transform map type name accepted

// io/Compression.h
constexpr uint32_t COMPRESS_ZIP = 0x1;
constexpr uint32_t COMPRESS_ACTIVE_MASK = 0x2;
constexpr uint32_t COMPRESS_BLOSC = 0x4;
// Per-node metadata byte of readCompressedValues (io/Compression.h).
constexpr int8_t NO_MASK_AND_ONE_INACTIVE_VAL = 2;
constexpr int8_t MASK_AND_NO_INACTIVE_VALS = 3;
constexpr int8_t MASK_AND_ONE_INACTIVE_VAL = 4;
constexpr int8_t MASK_AND_TWO_INACTIVE_VALS = 5;
constexpr int8_t NO_MASK_AND_ALL_VALS = 6;

constexpr size_t WINDOW_BYTES = size_t(1) << 20;

/// A read position in the file with a 1 MiB read-ahead window; every read is checked against
/// the file size first.
class Cursor {
public:
    Cursor(const ByteReader& read, uint64_t size, const std::string& name)
        : m_read(read), m_size(size), m_name(name) {}

    [[noreturn]] void corrupt(const std::string& what) const {
        LUCENT_THROW(IoError, "VDB file '", m_name, "' is corrupt (", what, " at byte ", m_pos,
                     ")");
    }
    void need(uint64_t n, const char* what) const {
        if (n > m_size || m_pos > m_size - n)
            LUCENT_THROW(IoError, "VDB file '", m_name, "' is truncated (", what, " at byte ",
                         m_pos, " needs ", n, " bytes, file has ", m_size, ")");
    }
    void bytes(void* dst, size_t n, const char* what) {
        need(n, what);
        if (n == 0)
            return;  // an empty block: `dst` may be null, and memcpy(null, ..., 0) is undefined
        fetch(m_pos, dst, n);
        m_pos += n;
    }
    template <typename T>
    T read(const char* what) {
        T v{};
        bytes(&v, sizeof(T), what);
        return v;
    }
    std::string readString(const char* what, uint32_t maxLen) {
        const auto len = read<uint32_t>(what);
        if (len > maxLen)
            LUCENT_THROW(IoError, "VDB file '", m_name, "' is corrupt (", what, " of ", len,
                         " bytes at byte ", m_pos - 4, ")");
        std::string s(len, '\0');
        bytes(s.data(), len, what);
        return s;
    }
    void skip(uint64_t n, const char* what) {
        need(n, what);
        m_pos += n;
    }
    void seek(uint64_t pos) { m_pos = pos; }
    [[nodiscard]] uint64_t pos() const { return m_pos; }
    [[nodiscard]] uint64_t remaining() const { return m_size - m_pos; }
    [[nodiscard]] const std::string& name() const { return m_name; }
    /// A second cursor on the same file with its own read-ahead window (for walking two
    /// regions in step without reloading one window for each).
    [[nodiscard]] Cursor clone() const {
        Cursor c(m_read, m_size, m_name);
        c.m_pos = m_pos;
        return c;
    }

private:
    void fetch(uint64_t pos, void* dst, size_t n) {
        if (n > WINDOW_BYTES / 2) {
            m_read(pos, dst, n);
            return;
        }
        if (pos < m_winStart || pos + n > m_winStart + m_win.size()) {
            m_winStart = pos;
            m_win.resize(size_t(std::min<uint64_t>(WINDOW_BYTES, m_size - pos)));
            m_read(pos, m_win.data(), m_win.size());
        }
        std::memcpy(dst, m_win.data() + (pos - m_winStart), n);
    }

    const ByteReader& m_read;
    uint64_t m_size;
    const std::string& m_name;
    uint64_t m_pos = 0;
    std::vector<char> m_win;
    uint64_t m_winStart = 0;
};

void requireBoolBytes(Cursor& in, const char* data, size_t n, const char* what) {
    for (size_t i = 0; i < n; ++i)
        if (data[i] != 0 && data[i] != 1)
            in.corrupt(std::string(what) + " holds a bool that is neither 0 nor 1");
}

// ------------------------------------------------------------------------------- metadata

/// Byte size TypedMetadata<T>::readValue reads for the fixed-size metadata types registered
/// by openvdb::initialize() (it reads sizeof(T), whatever size the file gives); 0 for the
/// variable-size types (string, __delayedload) and unknown ones (read as raw bytes).
uint32_t fixedMetaSize(const std::string& type) {
    static const std::pair<const char*, uint32_t> SIZES[] = {
        {"bool", 1},    {"double", 8},     {"float", 4},  {"int32", 4},  {"int64", 8},
        {"vec2i", 8},   {"vec2s", 8},      {"vec2d", 16}, {"vec3i", 12}, {"vec3s", 12},
        {"vec3d", 24},  {"vec4i", 16},     {"vec4s", 16}, {"vec4d", 32}, {"mat4s", 64},
        {"mat4d", 128}, {"ptdataidx32", 4}};
    for (const auto& [name, size] : SIZES)
        if (type == name)
            return size;
    return 0;
}

/// A blosc block of `cbytes` bytes at the cursor: the header must describe exactly this block
/// and `expected` uncompressed bytes (blosc trusts the sizes in its header). `padded`: the
/// block may also hold `expected` bytes padded with zeros to 128 (points/StreamCompression.cc,
/// BLOSC_PAD_BYTES: used by the delayed-load metadata, whose reader sizes its buffer from the
/// header).
void checkBloscHeader(Cursor& in, uint64_t cbytes, uint64_t expected, const char* what,
                      bool padded = false) {
    if (cbytes < BLOSC_MIN_HEADER_LENGTH)
        in.corrupt(std::string(what) + ": blosc block of " + std::to_string(cbytes) + " bytes");
    unsigned char header[BLOSC_MIN_HEADER_LENGTH];
    const uint64_t start = in.pos();
    in.bytes(header, sizeof header, what);
    in.seek(start);
    size_t nbytes = 0;
    constexpr uint64_t BLOSC_PAD_BYTES = 128;
    const bool valid = blosc_cbuffer_validate(header, size_t(cbytes), &nbytes) == 0;
    const bool sizeOk =
        nbytes == expected || (padded && expected < BLOSC_PAD_BYTES && nbytes == BLOSC_PAD_BYTES);
    if (!valid || !sizeOk)
        in.corrupt(std::string(what) + ": blosc block header does not match its " +
                   std::to_string(cbytes) + " bytes and " + std::to_string(expected) +
                   " uncompressed bytes");
}

/// io::DelayedLoadMetadata::readValue: count, mask (blosc or raw), compressed sizes (blosc,
/// raw or none); it allocates for `count` before reading.
void checkDelayedLoadMeta(Cursor& in, uint32_t numBytes) {
    if (numBytes == 0)
        return;
    const uint64_t start = in.pos();
    const auto count = in.read<uint32_t>("delayed-load count");
    checkElementCount(count, "VDB file", in.name(), "delayed-load entries");
    auto block = [&](uint64_t rawBytes, const char* what) {
        const auto bytes = in.read<uint32_t>(what);
        if (bytes > 0) {
            in.need(bytes, what);
            checkBloscHeader(in, bytes, rawBytes, what, /*padded=*/true);
            in.skip(bytes, what);
        } else {
            in.skip(rawBytes, what);
        }
        return bytes;
    };
    block(count, "delayed-load mask");
    const uint64_t sizesAt = in.pos();
    if (in.read<uint32_t>("delayed-load sizes") != std::numeric_limits<uint32_t>::max()) {
        in.seek(sizesAt);
        block(uint64_t(count) * 8, "delayed-load sizes");
    }
    if (in.pos() - start > numBytes)
        in.corrupt("delayed-load metadata larger than its " + std::to_string(numBytes) + " bytes");
    in.seek(start + numBytes);
}

/// MetaMap::readMeta: count, then (name, type name, uint32 size, value) per entry. Each value
/// must be exactly what OpenVDB's reader for that type consumes.
std::vector<VdbMetaEntry> readMetaMap(Cursor& in, const char* what) {
    const auto count = in.read<uint32_t>(what);
    if (count > in.remaining() / 12)  // every entry takes at least 3 × 4 bytes
        LUCENT_THROW(IoError, "VDB file '", in.name(), "' is truncated or corrupt (", count, " ",
                     what, " entries cannot fit in the remaining ", in.remaining(), " bytes)");
    std::vector<VdbMetaEntry> entries;
    entries.reserve(count);
    for (uint32_t i = 0; i < count; ++i) {
        VdbMetaEntry e;
        e.name = in.readString("metadata name", MAX_NAME);
        e.typeName = in.readString("metadata type", MAX_NAME);
        e.valueSize = in.read<uint32_t>("metadata size");
        e.valueOffset = in.pos();
        in.need(e.valueSize, "metadata value");
        const uint32_t fixed = fixedMetaSize(e.typeName);
        if (fixed != 0 && e.valueSize != fixed)
            in.corrupt("metadata '" + e.name + "' of type " + e.typeName + " has " +
                       std::to_string(e.valueSize) + " bytes, not " + std::to_string(fixed));
        if (e.typeName == "bool") {
            char b = 0;
            in.bytes(&b, 1, "metadata value");
            requireBoolBytes(in, &b, 1, "metadata");
            in.seek(e.valueOffset);
        }
        if (e.typeName == "__delayedload")
            checkDelayedLoadMeta(in, e.valueSize);
        in.seek(e.valueOffset + e.valueSize);
        entries.push_back(std::move(e));
    }
    return entries;
}

// ------------------------------------------------------------------------------ transform

/// Bytes a linear map's read() consumes (math/Maps.h), 0 if `type` is not a linear map.
uint64_t linearMapSize(const std::string& type) {
    if (type == "AffineMap" || type == "UnitaryMap")
        return 128;  // Mat4d
    if (type == "ScaleMap" || type == "UniformScaleMap")
        return 5 * 24;  // scale, voxel size, inverse scale, 1/scale², 1/(2 scale): Vec3d each
    if (type == "TranslationMap")
        return 24;
    if (type == "ScaleTranslateMap" || type == "UniformScaleTranslateMap")
        return 6 * 24;  // translation + the five ScaleMap vectors
    return 0;
}

void walkTransform(Cursor& in, uint32_t fileVersion) {
    const std::string type = in.readString("transform type", MAX_TYPE_NAME);
    if (const uint64_t n = linearMapSize(type)) {
        in.skip(n, "transform");
        return;
    }
    if (type != "NonlinearFrustumMap")
        in.corrupt("unknown transform type '" + type + "'");
    in.skip(fileVersion < VERSION_FLOAT_FRUSTUM_BBOX ? 24 : 48, "frustum bounds");
    in.skip(16, "frustum taper and depth");
    const std::string second = in.readString("frustum map type", MAX_TYPE_NAME);
    const uint64_t n = linearMapSize(second);
    if (n == 0)
        in.corrupt("frustum map of type '" + second + "'");
    in.skip(n, "frustum map");
}

// ----------------------------------------------------------------------------------- tree

/// What one value of a grid's tree is (the supported Tree_<type>_5_4_3 grids).
struct ValueType {
    const char* name;
    uint32_t size;      ///< bytes of one value in the file
    uint32_t halfSize;  ///< bytes when saved as half float (RealToHalf), 0 if not real
    bool isBool;        ///< C++ bool values (each byte must be 0 or 1)
    bool isMask;        ///< ValueMask leaves
};

constexpr ValueType VALUE_TYPES[] = {
    {"float", 4, 2, false, false},  {"double", 8, 2, false, false}, {"int32", 4, 0, false, false},
    {"int64", 8, 0, false, false},  {"bool", 1, 0, true, false},    {"mask", 1, 0, true, true},
    {"vec3s", 12, 6, false, false}, {"vec3d", 24, 6, false, false}, {"vec3i", 12, 0, false, false}};

const ValueType* findValueType(const std::string& name) {
    for (const ValueType& t : VALUE_TYPES)
        if (name == t.name)
            return &t;
    return nullptr;
}

/// The 5-4-3 tree: root children are 32³ internal nodes (4096³ voxels), their children 16³
/// internal nodes (128³ voxels), then 8³ leaves.
struct Level {
    int log2Dim;     ///< of this node
    int childTotal;  ///< log2 of a child's extent in voxels
};
constexpr Level LEVEL5{5, 7};
constexpr Level LEVEL4{4, 3};
constexpr uint32_t LEAF_VALUES = 512;
constexpr uint32_t LEAF_MASK_BYTES = LEAF_VALUES / 8;
constexpr int ROOT_CHILD_TOTAL = 12;

using Coord3 = std::array<int32_t, 3>;

uint64_t popcount(const std::vector<uint64_t>& words) {
    uint64_t n = 0;
    for (uint64_t w : words)
        n += uint64_t(std::popcount(w));
    return n;
}

/// Walks one grid's tree: topology (pass 1), then the value buffers in the same depth-first
/// order (pass 2, re-reading the topology's masks with a second cursor).
class TreeWalk {
public:
    TreeWalk(Cursor& in, const ValueType& vt, bool half, uint32_t compression)
        : m_in(in), m_vt(vt), m_half(half && vt.halfSize != 0), m_compression(compression) {}

    /// Pass 1 from the cursor; returns the estimated decoded bytes.
    uint64_t topology() {
        m_topologyStart = m_in.pos();
        m_in.read<int32_t>("buffer count");
        readValue("background");
        const auto numTiles = m_in.read<uint32_t>("root tile count");
        const auto numChildren = m_in.read<uint32_t>("root child count");
        checkElementCount(uint64_t(numTiles) + numChildren, "VDB file", m_in.name(), "root nodes");
        m_in.need(uint64_t(numTiles) * (12 + m_vt.size + 1), "root tiles");
        m_in.need(uint64_t(numChildren) * (12 + 2 * 4096), "root children");
        std::vector<Coord3> tiles;
        tiles.reserve(numTiles);
        for (uint32_t n = 0; n < numTiles; ++n) {
            const Coord3 c = readRootCoord("root tile", tiles);
            readValue("root tile value");
            char active = 0;
            m_in.bytes(&active, 1, "root tile state");
            requireBoolBytes(m_in, &active, 1, "root tile state");
            tiles.push_back(c);
        }
        std::vector<Coord3> children;
        for (uint32_t n = 0; n < numChildren; ++n) {
            const Coord3 c = readRootCoord("root child", children);
            if (std::binary_search(tiles.begin(), tiles.end(), c))
                m_in.corrupt("root child and tile at the same origin");
            children.push_back(c);
            internalTopology(LEVEL5, c);
        }
        m_numChildren = numChildren;
        const uint64_t unionBytes = (std::max<uint64_t>(m_vt.size, 8) + 7) / 8 * 8;
        return m_internal5 * ((uint64_t(1) << 15) * unionBytes + 8192 + 64) +
               m_internal4 * ((uint64_t(1) << 12) * unionBytes + 1024 + 64) +
               m_leaves * (96 + (m_vt.isBool ? 64 : uint64_t(LEAF_VALUES) * m_vt.size)) +
               uint64_t(numTiles) * 64;
    }

    /// Pass 2: the buffers start at the cursor; the topology is re-read in step with them by
    /// a second cursor.
    void buffers() {
        Cursor topo = m_in.clone();
        topo.seek(m_topologyStart + 4 + m_vt.size);  // after the buffer count and background
        const auto numTiles = topo.read<uint32_t>("root tile count");
        topo.read<uint32_t>("root child count");
        topo.skip(uint64_t(numTiles) * (12 + m_vt.size + 1), "root tiles");
        for (uint32_t n = 0; n < m_numChildren; ++n) {
            Coord3 c{};
            topo.bytes(c.data(), sizeof c, "root child");
            internalBuffers(LEVEL5, c, topo);
        }
    }

private:
    void readValue(const char* what) {
        char v[32];
        m_in.bytes(v, m_vt.size, what);
        if (m_vt.isBool)
            requireBoolBytes(m_in, v, m_vt.size, what);
    }

    Coord3 readRootCoord(const char* what, const std::vector<Coord3>& previous) {
        Coord3 c{};
        m_in.bytes(c.data(), sizeof c, what);
        for (int32_t v : c)
            if (v % (1 << ROOT_CHILD_TOTAL) != 0)
                m_in.corrupt(std::string(what) + " origin not aligned to 4096");
        // OpenVDB writes root entries in std::map (lexicographic) order; a duplicate would
        // replace an entry (leaking a node) and unsorted children would desynchronise the
        // buffers, which are read in map order.
        if (!previous.empty() && !(previous.back() < c))
            m_in.corrupt(std::string(what) + " origins not strictly increasing");
        return c;
    }

    std::vector<uint64_t> readMask(Cursor& in, uint32_t values, const char* what) {
        std::vector<uint64_t> words(values / 64);
        in.bytes(words.data(), values / 8, what);
        return words;
    }

    void internalTopology(const Level& level, const Coord3& origin) {
        const uint32_t values = 1u << (3 * level.log2Dim);
        const auto childMask = readMask(m_in, values, "child mask");
        const auto valueMask = readMask(m_in, values, "value mask");
        for (size_t w = 0; w < childMask.size(); ++w)
            if (childMask[w] & valueMask[w])
                m_in.corrupt("a node slot is both a child and an active tile");
        // Decoded, not only sized and its blosc header checked, because of a leak in OpenVDB
        // 10.0 (Debian 12's libopenvdb 10.0), tree/RootNode.h, RootNode::readTopology: it
        // allocates each root child, a 32³ InternalNode (520 KiB for vec3s), with `new`, calls
        // the child's readTopology and only then stores the pointer in its table. When that
        // readTopology throws, the node and everything read below it are lost. What can throw
        // there is this block: io::readCompressedValues -> readData -> io::unzipFromStream or
        // io::bloscFromStream, "Expected to decompress N bytes" when it decodes to another size
        // (fuzz_vdb, tests/data/fuzz/vdb_topology_zip_block_wrong_size.vdb). The rest of a
        // child's topology is masks, which read whatever their bits, and the other sizes
        // checked here. The value buffers (readBuffers) are read into a tree the grid already
        // owns, so a throw there frees everything: their blocks are only sized (decoding them
        // all would double the import's decompression work).
        compressedValues(m_in, values, popcount(valueMask), "internal node values",
                         /*decode=*/true);
        (level.log2Dim == 5 ? m_internal5 : m_internal4) += 1;
        const uint64_t children = popcount(childMask);
        checkElementCount(m_internal5 + m_internal4 + m_leaves + children, "VDB file", m_in.name(),
                          "tree nodes");
        for (uint32_t i = 0; i < values; ++i) {
            if (!(childMask[i / 64] >> (i % 64) & 1))
                continue;
            if (level.log2Dim == 5)
                internalTopology(LEVEL4, childOrigin(level, origin, i));
            else {
                m_in.skip(LEAF_MASK_BYTES, "leaf value mask");
                ++m_leaves;
            }
        }
    }

    /// Walks the buffers (at m_in) of the node whose topology is at `topo`.
    void internalBuffers(const Level& level, const Coord3& origin, Cursor& topo) {
        const uint32_t values = 1u << (3 * level.log2Dim);
        const auto childMask = readMask(topo, values, "child mask");
        const auto valueMask = readMask(topo, values, "value mask");
        compressedValues(topo, values, popcount(valueMask), "internal node values");
        for (uint32_t i = 0; i < values; ++i) {
            if (!(childMask[i / 64] >> (i % 64) & 1))
                continue;
            const Coord3 child = childOrigin(level, origin, i);
            if (level.log2Dim == 5)
                internalBuffers(LEVEL4, child, topo);
            else
                leafBuffer(child, popcount(readMask(topo, LEAF_VALUES, "leaf value mask")));
        }
    }

    static Coord3 childOrigin(const Level& level, const Coord3& origin, uint32_t i) {
        // InternalNode::offsetToLocalCoord: x is the slowest index.
        const uint32_t mask = (1u << level.log2Dim) - 1;
        const uint32_t x = i >> (2 * level.log2Dim), y = (i >> level.log2Dim) & mask, z = i & mask;
        return {int32_t(uint32_t(origin[0]) + (x << level.childTotal)),
                int32_t(uint32_t(origin[1]) + (y << level.childTotal)),
                int32_t(uint32_t(origin[2]) + (z << level.childTotal))};
    }

    void leafBuffer(const Coord3& origin, uint64_t activeCount) {
        if (m_vt.isBool || m_vt.isMask) {
            // LeafNode<bool>::readBuffers: value mask, origin, data mask;
            // LeafNode<ValueMask>::readBuffers: data mask, origin. The stored origin replaces
            // the leaf's place in the tree, so it must agree with it.
            m_in.skip(LEAF_MASK_BYTES, "leaf mask");
            Coord3 stored{};
            m_in.bytes(stored.data(), sizeof stored, "leaf origin");
            if (stored != origin)
                m_in.corrupt("leaf origin differs from its place in the tree");
            if (!m_vt.isMask)
                m_in.skip(LEAF_MASK_BYTES, "bool leaf data");
            return;
        }
        // LeafNode::readBuffers on a seekable stream: the value mask is skipped (the
        // topology's copy is used), then the values.
        m_in.skip(LEAF_MASK_BYTES, "leaf value mask");
        compressedValues(m_in, LEAF_VALUES, activeCount, "leaf values");
    }

    /// io::readCompressedValues for `destCount` values of which `activeCount` are active.
    /// `decode`: decompress a zip or blosc block and require exactly the bytes OpenVDB expects
    /// (otherwise only its size and blosc header are checked).
    void compressedValues(Cursor& in, uint32_t destCount, uint64_t activeCount, const char* what,
                          bool decode = false) {
        const auto meta = in.read<int8_t>("node compression flag");
        if (meta < 0 || meta > NO_MASK_AND_ALL_VALS)
            in.corrupt(std::string(what) + ": unknown compression flag " + std::to_string(meta));
        if (meta == NO_MASK_AND_ONE_INACTIVE_VAL || meta == MASK_AND_ONE_INACTIVE_VAL ||
            meta == MASK_AND_TWO_INACTIVE_VALS) {
            readValueAt(in, "inactive value");  // full size, even for half-float grids
            if (meta == MASK_AND_TWO_INACTIVE_VALS)
                readValueAt(in, "inactive value");
        }
        if (meta == MASK_AND_NO_INACTIVE_VALS || meta == MASK_AND_ONE_INACTIVE_VAL ||
            meta == MASK_AND_TWO_INACTIVE_VALS)
            in.skip(destCount / 8, "selection mask");
        uint64_t count = destCount;
        if ((m_compression & COMPRESS_ACTIVE_MASK) && meta != NO_MASK_AND_ALL_VALS)
            count = activeCount;
        if (m_half && count < 1)
            return;  // HalfReader reads nothing for an empty buffer
        const uint64_t bytes = count * (m_half ? m_vt.halfSize : m_vt.size);
        dataBlock(in, bytes, what, decode);
    }

    void readValueAt(Cursor& in, const char* what) {
        char v[32];
        in.bytes(v, m_vt.size, what);
        if (m_vt.isBool)
            requireBoolBytes(in, v, m_vt.size, what);
    }

    /// io::readData: a blosc or zip block (int64 size, negative for stored bytes), or raw bytes.
    /// `decode` as in compressedValues; bool blocks are always decoded (each byte must be 0 or 1).
    void dataBlock(Cursor& in, uint64_t bytes, const char* what, bool decode) {
        if (!(m_compression & (COMPRESS_BLOSC | COMPRESS_ZIP))) {
            rawBytes(in, bytes, what);
            return;
        }
        const auto n = in.read<int64_t>("compressed block size");
        if (n <= 0) {
            // OpenVDB 10.0 reads -n bytes into a buffer of `bytes` before comparing them.
            if (n != -int64_t(bytes))
                in.corrupt(std::string(what) + ": stored block of " +
                           (n == std::numeric_limits<int64_t>::min() ? std::string("2^63")
                                                                     : std::to_string(-n)) +
                           " bytes where " + std::to_string(bytes) + " are expected");
            rawBytes(in, bytes, what);
            return;
        }
        in.need(uint64_t(n), what);
        if (m_compression & COMPRESS_BLOSC)
            checkBloscHeader(in, uint64_t(n), bytes, what);
        if (decode || m_vt.isBool) {
            const std::vector<char> values = decompress(in, uint64_t(n), bytes, what);
            if (m_vt.isBool)
                requireBoolBytes(in, values.data(), values.size(), what);
        }
        in.skip(uint64_t(n), what);
    }

    void rawBytes(Cursor& in, uint64_t bytes, const char* what) {
        in.need(bytes, what);
        if (!m_vt.isBool) {
            in.skip(bytes, what);
            return;
        }
        std::vector<char> v(bytes);
        in.bytes(v.data(), v.size(), what);
        requireBoolBytes(in, v.data(), v.size(), what);
    }

    /// The `bytes` bytes the zip or blosc block of `n` bytes at the cursor decodes to, as
    /// io::unzipFromStream / io::bloscFromStream decode it (the cursor stays). OpenVDB throws
    /// when the decoded size differs; zlib's stricter Z_OK also refuses a stream that is corrupt
    /// after filling the buffer, which OpenVDB's writer never produces. (The blosc header was
    /// checked against `n` and `bytes` before: blosc trusts it.)
    std::vector<char> decompress(Cursor& in, uint64_t n, uint64_t bytes, const char* what) {
        const uint64_t start = in.pos();
        std::vector<char> src(n), dst(bytes);
        in.bytes(src.data(), src.size(), what);
        in.seek(start);
        const bool blosc = m_compression & COMPRESS_BLOSC;
        bool ok = false;
        if (blosc) {
            ok = blosc_decompress_ctx(src.data(), dst.data(), dst.size(), 1) == int64_t(bytes);
        } else {
            uLongf len = uLongf(bytes);
            ok = uncompress(reinterpret_cast<Bytef*>(dst.data()), &len,
                            reinterpret_cast<const Bytef*>(src.data()), uLong(n)) == Z_OK &&
                 len == bytes;
        }
        if (!ok)
            in.corrupt(std::string(what) + ": " + (blosc ? "blosc" : "zip") + " block of " +
                       std::to_string(n) + " bytes does not decode to " + std::to_string(bytes) +
                       " bytes");
        return dst;
    }

    Cursor& m_in;
    const ValueType& m_vt;
    bool m_half;
    uint32_t m_compression;
    uint64_t m_topologyStart = 0;
    uint32_t m_numChildren = 0;
    uint64_t m_internal5 = 0, m_internal4 = 0, m_leaves = 0;
};

/// Parses "Tree_<value>_5_4_3" into the value type name; empty if the grid type has another
/// form (point grids are Tree_ptdataidx32_5_4_3 and are listed but not walked).
std::string valueTypeOf(const std::string& gridType) {
    const std::string prefix = "Tree_", suffix = "_5_4_3";
    if (gridType.size() <= prefix.size() + suffix.size() || gridType.rfind(prefix, 0) != 0 ||
        gridType.compare(gridType.size() - suffix.size(), suffix.size(), suffix) != 0)
        return {};
    return gridType.substr(prefix.size(), gridType.size() - prefix.size() - suffix.size());
}

/// Reads a grid descriptor (io/GridDescriptor.cc).
VdbGridEntry readDescriptor(Cursor& in) {
    VdbGridEntry g;
    g.uniqueName = in.readString("grid name", MAX_NAME);
    g.typeName = in.readString("grid type", MAX_NAME);
    const std::string half = "_HalfFloat";
    if (const size_t at = g.typeName.rfind(half);
        at != std::string::npos && at + half.size() == g.typeName.size()) {
        g.halfFloat = true;
        g.typeName.erase(at);
    }
    g.valueType = valueTypeOf(g.typeName);
    g.instanceParent = in.readString("grid instance parent", MAX_NAME);
    return g;
}

/// Walks one grid from its start (the compression flags); leaves the cursor at its end.
void walkGrid(Cursor& in, VdbGridEntry& g, uint32_t fileVersion, bool hasOffsets) {
    const ValueType* vt = findValueType(g.valueType);
    if (!vt)
        return;  // not walked: must not be read (g.checked stays false)
    const auto compression = in.read<uint32_t>("grid compression");
    readMetaMap(in, "grid metadata");
    walkTransform(in, fileVersion);
    if (g.instanceParent.empty()) {
        TreeWalk tree(in, *vt, g.halfFloat, compression);
        g.decodedBytes = tree.topology();
        if (hasOffsets && in.pos() != g.blockPos)
            in.corrupt("grid '" + g.uniqueName + "' topology ends at byte " +
                       std::to_string(in.pos()) + ", its data is said to start at byte " +
                       std::to_string(g.blockPos));
        tree.buffers();
    }
    if (hasOffsets && in.pos() != g.endPos)
        in.corrupt("grid '" + g.uniqueName + "' ends at byte " + std::to_string(in.pos()) +
                   ", its descriptor says " + std::to_string(g.endPos));
    g.checked = true;
}

}  // namespace

const VdbGridEntry* VdbLayout::findGrid(const std::string& name) const {
    for (const VdbGridEntry& g : grids)
        if (g.uniqueName.substr(0, g.uniqueName.find('\x1e')) == name)
            return &g;
    return nullptr;
}

VdbLayout parseVdbLayout(const ByteReader& read, uint64_t size, const std::string& name) {
    VdbLayout layout;
    Cursor in(read, size, name);
    if (size < 8 || in.read<int64_t>("magic number") != VDB_MAGIC)
        LUCENT_THROW(IoError, "VDB file '", name, "' is not an OpenVDB file (bad magic number)");
    layout.fileVersion = in.read<uint32_t>("file version");
    if (layout.fileVersion < VERSION_NODE_MASK_COMPRESSION)
        LUCENT_THROW(IoError, "VDB file '", name, "' has file format version ", layout.fileVersion,
                     ", written by OpenVDB older than 2.0: not supported (save it again with a "
                     "current OpenVDB)");
    if (layout.fileVersion > MAX_KNOWN_VERSION)
        LUCENT_THROW(IoError, "VDB file '", name, "' has file format version ", layout.fileVersion,
                     ", newer than this OpenVDB (", MAX_KNOWN_VERSION, ")");
    in.read<uint32_t>("library major version");
    in.read<uint32_t>("library minor version");
    layout.hasGridOffsets = in.read<char>("grid offsets flag") != 0;
    if (layout.fileVersion >= VERSION_SELECTIVE_COMPRESSION &&
        layout.fileVersion < VERSION_NODE_MASK_COMPRESSION)
        in.read<char>("compression flag");
    layout.uuid.resize(36);
    in.bytes(layout.uuid.data(), 36, "UUID");

    layout.meta = readMetaMap(in, "file metadata");
    layout.metaEnd = in.pos();

    const auto gridCount = in.read<int32_t>("grid count");
    if (gridCount < 0 || uint64_t(gridCount) > in.remaining() / 36)  // ≥ 3 strings + 3 offsets
        LUCENT_THROW(IoError, "VDB file '", name, "' is truncated or corrupt (grid count ",
                     gridCount, " with ", in.remaining(), " bytes left)");
    uint64_t decoded = 0;
    for (int32_t i = 0; i < gridCount; ++i) {
        VdbGridEntry g = readDescriptor(in);
        const auto gridPos = in.read<int64_t>("grid offset");
        const auto blockPos = in.read<int64_t>("grid data offset");
        const auto endPos = in.read<int64_t>("grid end offset");
        if (layout.hasGridOffsets) {
            // An instance has no tree, hence no data offset (0).
            const bool instance = !g.instanceParent.empty();
            if (gridPos < int64_t(in.pos()) || endPos < gridPos ||
                (instance ? blockPos != 0 && (blockPos < gridPos || blockPos > endPos)
                          : blockPos < gridPos || endPos < blockPos))
                LUCENT_THROW(IoError, "VDB file '", name, "' is corrupt (grid '", g.uniqueName,
                             "' has inconsistent offsets ", gridPos, ", ", blockPos, ", ", endPos,
                             ")");
            if (uint64_t(endPos) > size)
                LUCENT_THROW(IoError, "VDB file '", name, "' is truncated (grid '", g.uniqueName,
                             "' ends at byte ", endPos, ", file has ", size, ")");
            g.gridPos = uint64_t(gridPos);
            g.blockPos = uint64_t(blockPos);
            g.endPos = uint64_t(endPos);
            in.seek(g.gridPos);
            walkGrid(in, g, layout.fileVersion, /*hasOffsets=*/true);
            in.seek(g.endPos);
        } else {
            // Stream-written: OpenVDB reads every grid as soon as the file is opened, so every
            // one must be walkable.
            g.gridPos = in.pos();
            walkGrid(in, g, layout.fileVersion, /*hasOffsets=*/false);
            if (!g.checked)
                LUCENT_THROW(IoError, "VDB file '", name, "': grid '", g.uniqueName, "' has type ",
                             g.typeName, ", which Lucent cannot check in a stream-written file");
            g.endPos = in.pos();
        }
        decoded += g.decodedBytes;
        const uint64_t limit = importLimits().maxDecodedBytes;
        if (decoded > limit)
            LUCENT_THROW(IoError, "VDB file '", name, "' decodes to more than ", limit,
                         " bytes (the import limit; ", decoded, " bytes after grid '", g.uniqueName,
                         "')");
        layout.grids.push_back(std::move(g));
    }
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

}  // namespace lucent::io::detail

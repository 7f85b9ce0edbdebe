// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Bounds-checked walk of a whole OpenVDB file without OpenVDB: header, file metadata,
/// grid descriptors and, per grid, its metadata, transform, tree topology and every value
/// block (compressed or not), each checked against the file size, the sizes OpenVDB will
/// read and the import limits (lucent/core/FileIO.h). Run before OpenVDB sees a file: the
/// system OpenVDB 10 trusts the sizes stored in a file (a block that claims more bytes than
/// its buffer holds overflows the heap in io::bloscFromStream), so every size it will trust
/// is verified here first. The compressed blocks of the topology (internal node values) are
/// also decoded: OpenVDB 10's RootNode::readTopology leaks a root child whose readTopology
/// throws on a block that decodes to another size (VdbLayout.cpp, internalTopology). Also the
/// integrity checksum of Lucent files.
///
/// Layout sources (OpenVDB 10.0, file format 222-224): io/Archive.cc (readHeader,
/// readGridCompression, doReadGrid), MetaMap::readMeta and TypedMetadata::readValue,
/// io/DelayedLoadMetadata.cc, io/GridDescriptor.cc, io/File.cc (open, readGridDescriptors),
/// math/Transform.cc and math/Maps.h (read), tree/RootNode.h, InternalNode.h, LeafNode.h,
/// LeafNodeBool.h, LeafNodeMask.h (readTopology, readBuffers), io/Compression.h/.cc
/// (readCompressedValues, readData, bloscFromStream, unzipFromStream).

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace lucent::io::detail {

/// Reads `n` bytes at absolute offset `pos` into `dst` (the caller has checked the range).
using ByteReader = std::function<void(uint64_t pos, void* dst, size_t n)>;

struct VdbMetaEntry {
    std::string name;
    std::string typeName;
    uint64_t valueOffset = 0;  ///< absolute offset of the value bytes
    uint32_t valueSize = 0;
};

struct VdbGridEntry {
    std::string uniqueName;
    std::string typeName;        ///< OpenVDB grid type without "_HalfFloat", e.g. Tree_vec3s_5_4_3
    std::string valueType;       ///< "vec3s", "float", ... (the middle of typeName)
    std::string instanceParent;  ///< non-empty for an instance (shares the parent's tree)
    bool halfFloat = false;
    uint64_t gridPos = 0, blockPos = 0, endPos = 0;
    /// True when the whole grid was walked and OpenVDB may read it. False for grid types the
    /// walk does not know (point data, point index): such grids are listed, never read.
    bool checked = false;
    uint64_t decodedBytes = 0;  ///< estimated memory of the tree once read
};

struct VdbLayout {
    uint32_t fileVersion = 0;
    bool hasGridOffsets = true;
    std::string uuid;      ///< 36-character header UUID
    uint64_t metaEnd = 0;  ///< offset just after the file-level metadata
    std::vector<VdbMetaEntry> meta;
    std::vector<VdbGridEntry> grids;

    /// The first grid whose name (unique name without its "[N]" suffix) is `name`.
    [[nodiscard]] const VdbGridEntry* findGrid(const std::string& name) const;
};

/// Walks a VDB file of `size` bytes completely (see the file comment).
/// @param name file name for messages.
/// @throw IoError naming the file and the byte offset at fault: not a VDB file (magic), a
/// format older than 222 or newer than 224, truncated, an inconsistent size or offset, a
/// value OpenVDB would misread, or more decoded memory or elements than the import limits.
VdbLayout parseVdbLayout(const ByteReader& read, uint64_t size, const std::string& name);

/// Integrity value written by exportVdb as file metadata `lucent_checksum`:
/// "<header uuid>:<16 hex digits of FNV-1a 64 of bytes [metaEnd, size)>".
inline constexpr const char* CHECKSUM_META = "lucent_checksum";
inline constexpr size_t CHECKSUM_TEXT_SIZE = 36 + 1 + 16;

/// FNV-1a 64 (Fowler–Noll–Vo) over bytes [begin, end), continuing from `hash`.
uint64_t fnv1a64(const void* data, size_t n, uint64_t hash = 0xcbf29ce484222325ULL);

/// Hex text of a 64-bit value, 16 digits.
std::string hex64(uint64_t v);

}  // namespace lucent::io::detail

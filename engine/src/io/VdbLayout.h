// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Bounds-checked parse of the outer structure of an OpenVDB file (header, file
/// metadata, grid descriptors and their byte ranges) without OpenVDB, and the integrity
/// checksum of Lucent files. Run before OpenVDB sees a file, so that truncated or garbage
/// files are rejected quickly with a precise reason instead of driving OpenVDB into huge
/// allocations. Layout: OpenVDB io/Archive.cc (readHeader), MetaMap::readMeta,
/// io/GridDescriptor.cc (read), io/File.cc (readGridDescriptors), file format 218–224.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace lucent::io_detail {

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
    std::string typeName;
    uint64_t gridPos = 0, blockPos = 0, endPos = 0;
};

struct VdbLayout {
    uint32_t fileVersion = 0;
    bool parsed = false;   ///< false for legacy files (< 218) that are left to OpenVDB
    std::string uuid;      ///< 36-character header UUID
    uint64_t metaEnd = 0;  ///< offset just after the file-level metadata
    std::vector<VdbMetaEntry> meta;
    std::vector<VdbGridEntry> grids;
};

/// Parses the outer structure of a VDB file of `size` bytes.
/// @param name file name for messages.
/// @throw IoError naming the file: not a VDB file (magic), truncated, or inconsistent sizes.
VdbLayout parseVdbLayout(const ByteReader& read, uint64_t size, const std::string& name);

/// Integrity value written by exportVdb as file metadata `lucent_checksum`:
/// "<header uuid>:<16 hex digits of FNV-1a 64 of bytes [metaEnd, size)>".
inline constexpr const char* CHECKSUM_META = "lucent_checksum";
inline constexpr size_t CHECKSUM_TEXT_SIZE = 36 + 1 + 16;

/// FNV-1a 64 (Fowler–Noll–Vo) over bytes [begin, end), continuing from `hash`.
uint64_t fnv1a64(const void* data, size_t n, uint64_t hash = 0xcbf29ce484222325ULL);

/// Hex text of a 64-bit value, 16 digits.
std::string hex64(uint64_t v);

}  // namespace lucent::io_detail

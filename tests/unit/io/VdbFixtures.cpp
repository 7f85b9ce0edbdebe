// SPDX-License-Identifier: MIT
// Writers of malformed and foreign VDB files (VdbFixtures.h): the io tests' only use of
// OpenVDB's templates, compiled without sanitizer instrumentation (see the header).
#include "VdbFixtures.h"

#include <lucent/core/Random.h>

#include <openvdb/io/File.h>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <bit>
#include <fstream>
#include <stdexcept>

namespace lucent::test {

namespace vdb = openvdb;

struct RawVdbFile::Impl {
    vdb::GridPtrVec grids;
    vdb::MetaMap meta;

    vdb::GridBase::Ptr grid(const std::string& name) const {
        for (const auto& g : grids)
            if (g->getName() == name)
                return g;
        throw std::invalid_argument("RawVdbFile: no grid '" + name + "'");
    }
    /// The first active voxel of the vec3s grid `name`, or null when it is not vec3s or empty.
    vdb::Vec3SGrid::Ptr vec3s(const std::string& name, vdb::Coord* firstActive) const {
        auto g = vdb::gridPtrCast<vdb::Vec3SGrid>(grid(name));
        if (!g || !firstActive)
            return g;
        auto it = g->beginValueOn();
        if (!it)
            return nullptr;
        vdb::CoordBBox box;
        it.getBoundingBox(box);
        *firstActive = box.min();
        return g;
    }
};

RawVdbFile::RawVdbFile(const std::string& path) : m_impl(std::make_unique<Impl>()) {
    vdb::initialize();
    vdb::io::File file(path);
    file.open(false);
    m_impl->grids = *file.getGrids();
    m_impl->meta = *file.getMetadata();
    file.close();
}

RawVdbFile::~RawVdbFile() = default;

std::string RawVdbFile::write(const std::string& path) const {
    vdb::io::File(path).write(m_impl->grids, m_impl->meta);
    return path;
}

void RawVdbFile::removeGrid(const std::string& name) {
    std::erase_if(m_impl->grids, [&](const vdb::GridBase::Ptr& g) { return g->getName() == name; });
}

void RawVdbFile::replaceWithFloatGrid(const std::string& name) {
    removeGrid(name);
    auto g = vdb::FloatGrid::create(0.f);
    g->setName(name);
    m_impl->grids.push_back(g);
}

bool RawVdbFile::setFirstActiveValue(const std::string& name, float y) {
    vdb::Coord at;
    auto g = m_impl->vec3s(name, &at);
    if (!g)
        return false;
    g->tree().setValueOn(at, vdb::Vec3s(0.5f, y, 0.25f));
    return true;
}

bool RawVdbFile::deactivateFirstActiveVoxel(const std::string& name) {
    vdb::Coord at;
    auto g = m_impl->vec3s(name, &at);
    if (!g)
        return false;
    g->tree().setValueOff(at);
    return true;
}

bool RawVdbFile::activateVoxel(const std::string& name, int x, int y, int z) {
    auto g = m_impl->vec3s(name, nullptr);
    if (!g)
        return false;
    g->tree().setValueOn(vdb::Coord(x, y, z), vdb::Vec3s(0.f));
    return true;
}

void RawVdbFile::setUniformTransform(const std::string& name, double voxelSize) {
    m_impl->grid(name)->setTransform(vdb::math::Transform::createLinearTransform(voxelSize));
}

void RawVdbFile::setFileMetaInt(const std::string& key, int32_t value) {
    m_impl->meta.removeMeta(key);
    m_impl->meta.insertMeta(key, vdb::Int32Metadata(value));
}

void RawVdbFile::setFileMetaFloat(const std::string& key, float value) {
    m_impl->meta.removeMeta(key);
    m_impl->meta.insertMeta(key, vdb::FloatMetadata(value));
}

void RawVdbFile::setFileMetaString(const std::string& key, const std::string& value) {
    m_impl->meta.removeMeta(key);
    m_impl->meta.insertMeta(key, vdb::StringMetadata(value));
}

void RawVdbFile::removeFileMeta(const std::string& key) {
    m_impl->meta.removeMeta(key);
}

void RawVdbFile::setGridMetaString(const std::string& grid, const std::string& key,
                                   const std::string& value) {
    m_impl->grid(grid)->insertMeta(key, vdb::StringMetadata(value));
}

void RawVdbFile::setGridMetaVec3s(const std::string& grid, const std::string& key, float x, float y,
                                  float z) {
    m_impl->grid(grid)->insertMeta(key, vdb::Vec3SMetadata(vdb::Vec3s(x, y, z)));
}

void writeForeignFogVdb(const std::string& path) {
    vdb::initialize();
    auto fog = vdb::FloatGrid::create(0.f);
    fog->setName("density");
    fog->setGridClass(vdb::GRID_FOG_VOLUME);
    fog->tree().setValueOn(vdb::Coord(-3, 4, 1000), 2.5f);
    fog->tree().setValueOn(vdb::Coord(7, -2, 999), 0.5f);
    vdb::io::File(path).write({fog});
}

void writeRandomLeavesVdb(const std::string& path, int leaves) {
    vdb::initialize();
    auto grid = vdb::Vec3SGrid::create(vdb::Vec3s(0.f));
    grid->setName("velocity");
    Pcg32 rng(5);
    // Random bit patterns (finite: exponent below 255) compress by nothing.
    auto randomFloat = [&] { return std::bit_cast<float>(rng.nextUint() & 0xbf7fffffu); };
    for (int l = 0; l < leaves; ++l)
        for (int i = 0; i < 512; ++i)
            grid->tree().setValueOn(vdb::Coord(8 * l + i % 8, (i / 8) % 8, i / 64),
                                    vdb::Vec3s(randomFloat(), randomFloat(), randomFloat()));
    vdb::io::File(path).write({grid});
}

namespace {

vdb::GridPtrVec everyKindOfGrid() {
    vdb::initialize();
    auto fill = [](auto grid, auto value) {
        grid->tree().setValueOn(vdb::Coord(1, 2, 3), value);
        grid->tree().setValueOn(vdb::Coord(-100, 50, 7), value);
        grid->tree().addTile(1, vdb::Coord(4096, 0, 0), value, true);     // 8³ tile
        grid->tree().addTile(2, vdb::Coord(8192, 4096, 0), value, true);  // 128³ tile
        grid->tree().addTile(3, vdb::Coord(0, 0, 40960), value, true);    // 4096³ root tile
        return grid;
    };
    vdb::GridPtrVec grids{
        fill(vdb::FloatGrid::create(0.5f), 2.f),
        fill(vdb::DoubleGrid::create(0.0), 3.0),
        fill(vdb::Int32Grid::create(0), 4),
        fill(vdb::Int64Grid::create(0), int64_t(5)),
        fill(vdb::BoolGrid::create(false), true),
        fill(vdb::MaskGrid::create(false), true),
        fill(vdb::Vec3SGrid::create(vdb::Vec3s(0.f)), vdb::Vec3s(1.f, 2.f, 3.f)),
        fill(vdb::Vec3DGrid::create(vdb::Vec3d(0.0)), vdb::Vec3d(1.0, 2.0, 3.0)),
        fill(vdb::Vec3IGrid::create(vdb::Vec3i(0)), vdb::Vec3i(1, 2, 3)),
    };
    for (size_t i = 0; i < grids.size(); ++i)
        grids[i]->setName("grid" + std::to_string(i));
    auto half = vdb::FloatGrid::create(0.f);
    half->setName("half");
    half->setSaveFloatAsHalf(true);
    half->tree().setValueOn(vdb::Coord(5, 5, 5), 0.25f);
    grids.push_back(half);
    auto halfVec = vdb::Vec3SGrid::create(vdb::Vec3s(0.f));
    halfVec->setName("halfvec");
    halfVec->setSaveFloatAsHalf(true);
    halfVec->tree().setValueOn(vdb::Coord(5, 5, 5), vdb::Vec3s(0.5f));
    grids.push_back(halfVec);
    auto shared = grids[0]->copyGrid();  // shares the tree: written as an instance
    shared->setName("instance");
    grids.push_back(shared);
    for (float v : {1.f, 2.f}) {  // two grids of the same name: both listed, each its own
        auto dup = vdb::FloatGrid::create(0.f);
        dup->setName("dup");
        dup->tree().setValueOn(vdb::Coord(int(v), 0, 0), v);
        grids.push_back(dup);
    }
    return grids;
}

uint32_t openVdbFlags(VdbCompression c) {
    switch (c) {
        case VdbCompression::BloscActiveMask:
            return vdb::io::COMPRESS_BLOSC | vdb::io::COMPRESS_ACTIVE_MASK;
        case VdbCompression::ZipActiveMask:
            return vdb::io::COMPRESS_ZIP | vdb::io::COMPRESS_ACTIVE_MASK;
        case VdbCompression::None:
            return vdb::io::COMPRESS_NONE;
        case VdbCompression::ActiveMaskOnly:
            return vdb::io::COMPRESS_ACTIVE_MASK;
        case VdbCompression::BloscOnly:
            return vdb::io::COMPRESS_BLOSC;
        case VdbCompression::ZipOnly:
            return vdb::io::COMPRESS_ZIP;
    }
    throw std::invalid_argument("unknown VdbCompression");
}

}  // namespace

size_t writeEveryKindVdb(const std::string& path, VdbCompression compression) {
    const vdb::GridPtrVec grids = everyKindOfGrid();
    vdb::io::File file(path);
    file.setCompression(openVdbFlags(compression));
    file.write(grids);
    return grids.size();
}

size_t writeEveryKindVdbStream(const std::string& path) {
    const vdb::GridPtrVec grids = everyKindOfGrid();
    std::ofstream os(path, std::ios::binary);
    vdb::io::Stream(os).write(grids);
    return grids.size();
}

}  // namespace lucent::test

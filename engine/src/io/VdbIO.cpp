// SPDX-License-Identifier: MIT
/// @file
/// @brief The only translation unit that includes OpenVDB: export/import of material volumes
/// and the summary of arbitrary VDB files (layout documented in docs/file-formats.md).

#include <lucent/io/VdbIO.h>

#include "VdbLayout.h"

#include <lucent/core/Error.h>
#include <lucent/core/FileIO.h>
#include <lucent/core/Parallel.h>
#include <lucent/material/BoundarySkin.h>

#include <openvdb/io/File.h>
#include <openvdb/io/GridDescriptor.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Prune.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <mutex>
#include <sstream>
#include <type_traits>

#ifndef LUCENT_VERSION
#define LUCENT_VERSION "unknown"
#endif

namespace lucent::io {

namespace {

namespace vdb = openvdb;

// Metadata names (docs/file-formats.md).
constexpr const char* META_FORMAT_VERSION = "lucent_format_version";
constexpr const char* META_GENERATOR = "generator";
constexpr const char* META_GENERATOR_VERSION = "generator_version";
constexpr const char* META_RESOLUTION = "lucent_resolution";
constexpr const char* META_ORIGIN = "lucent_origin_mm";
constexpr const char* META_VOXEL_SIZE = "lucent_voxel_size_mm";
constexpr const char* META_ETA = "lucent_eta";
constexpr const char* META_BASE_SIGMA_T = "lucent_base_sigma_t";
constexpr const char* META_BASE_SIGMA_S = "lucent_base_sigma_s";
constexpr const char* META_BASE_G = "lucent_base_g";
constexpr const char* META_NAME = "lucent_material_name";
constexpr const char* META_LENGTH_UNIT = "length_unit";
constexpr const char* META_SIGMA_UNIT = "sigma_unit";
constexpr const char* META_REDUCED = "sigma_s_is_reduced";
constexpr const char* META_NOTE = "lucent_note";
constexpr const char* META_DENSITY_DEF = "lucent_density_definition";

constexpr const char* GRID_SIGMA_T = "sigma_t";
constexpr const char* GRID_SIGMA_S = "sigma_s";
constexpr const char* GRID_G = "g";
constexpr const char* GRID_DENSITY = "density";
constexpr const char* GRID_ALBEDO = "albedo";
constexpr const char* GRID_COLOR = "color";

constexpr int BLOCK = 8;  // OpenVDB leaf edge (LeafNode log2dim 3), equal to MaterialVolume::BRICK
static_assert(vdb::FloatTree::LeafNodeType::DIM == BLOCK);
static_assert(vdb::Vec3STree::LeafNodeType::DIM == BLOCK);

void initializeOnce() {
    static std::once_flag flag;
    std::call_once(flag, [] { vdb::initialize(); });
}

vdb::Vec3s toVdb(const Rgb& v) {
    return {v.r, v.g, v.b};
}
Rgb fromVdb(const vdb::Vec3s& v) {
    return {v.x(), v.y(), v.z()};
}

/// Index → world transform: voxel size h, and a translation of origin + ½h so that the
/// OpenVDB voxel centre at integer index (i,j,k) lands on Lucent's cell centre
/// origin + (i+½, j+½, k+½)·h (MaterialVolume.h; OpenVDB doc/math.txt: voxel centres at
/// integer index coordinates).
vdb::math::Transform::Ptr makeTransform(const GridSpec& spec) {
    auto xf = vdb::math::Transform::createLinearTransform(double(spec.voxelSize));
    const double h = spec.voxelSize;
    xf->postTranslate(vdb::Vec3d(double(spec.origin.x) + 0.5 * h, double(spec.origin.y) + 0.5 * h,
                                 double(spec.origin.z) + 0.5 * h));
    return xf;
}

/// Builds a sparse grid from the volume leaf by leaf: one 8³ OpenVDB leaf per 8³ block that
/// holds an inside voxel, active exactly on inside voxels, and also on the `skin` voxels when
/// given (the renderer grids: BoundarySkin.h); then merges constant leaves into tiles
/// (lossless: tools::prune with tolerance 0 only merges identical values and states).
template <typename GridT, typename ValueFn>
typename GridT::Ptr buildGrid(const MaterialVolume& volume, const char* name, ValueFn value,
                              const std::vector<SkinVoxel>* skin = nullptr) {
    using TreeT = typename GridT::TreeType;
    using LeafT = typename TreeT::LeafNodeType;
    const GridSpec& spec = volume.spec();
    const int res = spec.resolution;
    const int blocks = (res + BLOCK - 1) / BLOCK;
    std::vector<std::unique_ptr<LeafT>> leaves(size_t(blocks) * blocks * blocks);
    parallelFor(0, int64_t(leaves.size()), [&](int64_t begin, int64_t end) {
        for (int64_t b = begin; b < end; ++b) {
            const Coord o(int(b % blocks) * BLOCK, int((b / blocks) % blocks) * BLOCK,
                          int(b / (int64_t(blocks) * blocks)) * BLOCK);
            auto leaf = std::make_unique<LeafT>(vdb::Coord(o.x, o.y, o.z),
                                                typename GridT::ValueType(0), false);
            bool any = false;
            for (int z = o.z; z < std::min(o.z + BLOCK, res); ++z)
                for (int y = o.y; y < std::min(o.y + BLOCK, res); ++y)
                    for (int x = o.x; x < std::min(o.x + BLOCK, res); ++x) {
                        const Coord c(x, y, z);
                        if (!volume.isInside(c))
                            continue;
                        leaf->setValueOn(LeafT::coordToOffset(vdb::Coord(x, y, z)),
                                         value(volume.at(c)));
                        any = true;
                    }
            if (any)
                leaves[size_t(b)] = std::move(leaf);
        }
    });
    const size_t n = size_t(res);
    if (skin != nullptr)
        for (const SkinVoxel& v : *skin) {
            const int x = int(v.index % n), y = int((v.index / n) % n), z = int(v.index / (n * n));
            auto& leaf = leaves[(size_t(z / BLOCK) * blocks + size_t(y / BLOCK)) * blocks +
                                size_t(x / BLOCK)];
            if (!leaf)
                leaf = std::make_unique<LeafT>(
                    vdb::Coord(x / BLOCK * BLOCK, y / BLOCK * BLOCK, z / BLOCK * BLOCK),
                    typename GridT::ValueType(0), false);
            leaf->setValueOn(LeafT::coordToOffset(vdb::Coord(x, y, z)), value(v.value));
        }
    auto grid = GridT::create(typename GridT::ValueType(0));
    for (auto& leaf : leaves)
        if (leaf)
            grid->tree().addLeaf(leaf.release());
    vdb::tools::prune(grid->tree(), /*tolerance=*/typename GridT::ValueType(0));
    grid->setName(name);
    grid->setTransform(makeTransform(spec));
    return grid;
}

/// Exposes Archive::write on a caller-owned (in-memory) stream: the bytes are then written
/// through the checked atomic writer (io::File::write ignores the stream state, so disk-full
/// errors would go unnoticed).
class CheckedArchive : public vdb::io::Archive {
public:
    void writeTo(std::ostream& os, const vdb::GridCPtrVec& grids, const vdb::MetaMap& meta) const {
        Archive::write(os, grids, /*seekable=*/true, meta);
    }
};

/// Grey extinction for renderers with a scalar density: Rec. 709 luminance-weighted reduced
/// extinction σt′ (docs/file-formats.md explains the choice).
float densityOf(const MaterialSample& s) {
    return luminance(s.sigma_t);
}

/// A library message as one line (the CLI prints errors as one line).
std::string vdbErrorText(const std::exception& e) {
    std::string t = e.what();
    for (char& c : t)
        if (c == '\n' || c == '\r')
            c = ' ';
    return t.empty() ? "unknown OpenVDB error" : t;
}

// ----------------------------------------------------------------------------------- import

template <typename MetaT>
auto requireMeta(const vdb::MetaMap& meta, const std::string& path, const char* name) {
    auto m = meta.getMetadata<MetaT>(name);
    if (!m) {
        if (meta[name])
            LUCENT_THROW(IoError, "VDB file '", path, "': metadata '", name, "' has type '",
                         meta[name]->typeName(), "', expected '", MetaT::staticTypeName(), "'");
        LUCENT_THROW(IoError, "VDB file '", path, "': missing metadata '", name, "'");
    }
    return m->value();
}

Rgb requireFiniteRgb(const vdb::MetaMap& meta, const std::string& path, const char* name) {
    const Rgb v = fromVdb(requireMeta<vdb::Vec3SMetadata>(meta, path, name));
    if (!isFinite(v))
        LUCENT_THROW(IoError, "VDB file '", path, "': metadata '", name, "' is not finite");
    return v;
}

vdb::Vec3SGrid::Ptr requireVec3Grid(vdb::io::File& file, const detail::VdbLayout& layout,
                                    const std::string& path, const char* name) {
    const detail::VdbGridEntry* entry = layout.findGrid(name);
    if (!file.hasGrid(name) || !entry)
        LUCENT_THROW(IoError, "VDB file '", path, "': missing grid '", name, "'");
    if (!entry->checked)  // a type the preflight walk does not know: never read
        LUCENT_THROW(IoError, "VDB file '", path, "': grid '", name, "' has type '",
                     entry->typeName, "', expected 'vec3s'");
    vdb::GridBase::Ptr base = file.readGrid(name);
    auto grid = vdb::gridPtrCast<vdb::Vec3SGrid>(base);
    if (!grid)
        LUCENT_THROW(IoError, "VDB file '", path, "': grid '", name, "' has type '",
                     base->valueType(), "', expected 'vec3s'");
    return grid;
}

ImportedMaterial importOpen(vdb::io::File& file, const detail::VdbLayout& layout,
                            const std::string& path) {
    const vdb::MetaMap::Ptr metaPtr = file.getMetadata();
    const vdb::MetaMap& meta = *metaPtr;
    if (!meta[META_FORMAT_VERSION])
        LUCENT_THROW(IoError, "VDB file '", path, "' is not a Lucent material file (no '",
                     META_FORMAT_VERSION, "' metadata)");
    VdbMaterialMetadata md;
    md.formatVersion = requireMeta<vdb::Int32Metadata>(meta, path, META_FORMAT_VERSION);
    if (md.formatVersion < 1 || md.formatVersion > VDB_FORMAT_VERSION)
        LUCENT_THROW(IoError, "VDB file '", path, "': Lucent format version ", md.formatVersion,
                     " is not supported (this build reads 1..", VDB_FORMAT_VERSION, ")");
    const int res = requireMeta<vdb::Int32Metadata>(meta, path, META_RESOLUTION);
    if (res < GridSpec::MIN_RESOLUTION || res > GridSpec::MAX_RESOLUTION)
        LUCENT_THROW(IoError, "VDB file '", path, "': resolution ", res, " is outside [",
                     GridSpec::MIN_RESOLUTION, ", ", GridSpec::MAX_RESOLUTION, "]");
    md.spec.resolution = res;
    md.spec.origin = requireFiniteRgb(meta, path, META_ORIGIN);
    md.spec.voxelSize = requireMeta<vdb::FloatMetadata>(meta, path, META_VOXEL_SIZE);
    if (!(md.spec.voxelSize >= VDB_MIN_VOXEL_SIZE_MM && md.spec.voxelSize <= VDB_MAX_VOXEL_SIZE_MM))
        LUCENT_THROW(IoError, "VDB file '", path, "': voxel size ", md.spec.voxelSize,
                     " mm is outside [", VDB_MIN_VOXEL_SIZE_MM, ", ", VDB_MAX_VOXEL_SIZE_MM, "]");
    md.eta = requireMeta<vdb::FloatMetadata>(meta, path, META_ETA);
    if (!(md.eta >= 1.f && md.eta <= 3.f))
        LUCENT_THROW(IoError, "VDB file '", path, "': eta ", md.eta, " is outside [1, 3]");
    md.base.sigma_t = requireFiniteRgb(meta, path, META_BASE_SIGMA_T);
    md.base.sigma_s = requireFiniteRgb(meta, path, META_BASE_SIGMA_S);
    md.base.g = requireFiniteRgb(meta, path, META_BASE_G);
    if (!(sanitize(md.base) == md.base))
        LUCENT_THROW(IoError, "VDB file '", path, "': base material is outside the valid domain");
    if (meta[META_NAME])
        md.materialName = requireMeta<vdb::StringMetadata>(meta, path, META_NAME);
    if (meta[META_GENERATOR])
        md.generator = requireMeta<vdb::StringMetadata>(meta, path, META_GENERATOR);
    if (meta[META_GENERATOR_VERSION])
        md.generatorVersion = requireMeta<vdb::StringMetadata>(meta, path, META_GENERATOR_VERSION);

    vdb::Vec3SGrid::Ptr grids[3] = {requireVec3Grid(file, layout, path, GRID_SIGMA_T),
                                    requireVec3Grid(file, layout, path, GRID_SIGMA_S),
                                    requireVec3Grid(file, layout, path, GRID_G)};
    const GridSpec& spec = md.spec;
    const vdb::CoordBBox domain(vdb::Coord(0), vdb::Coord(res - 1));
    for (const auto& grid : grids) {
        // The transform must agree with the metadata: same voxel size and centre of voxel 0
        // (relative tolerance 1e-5 covers the float → double rounding of h and the origin).
        const vdb::math::Transform& xf = grid->transform();
        const vdb::Vec3d vs = xf.voxelSize();
        const vdb::Vec3d c0 = xf.indexToWorld(vdb::Coord(0));
        const Point3f expect = spec.cellCenter(Coord(0));
        const double tol = 1e-5 * (double(spec.voxelSize) + glm::length(glm::dvec3(expect)));
        if (!xf.isLinear() || std::abs(vs.x() - spec.voxelSize) > tol ||
            std::abs(vs.y() - spec.voxelSize) > tol || std::abs(vs.z() - spec.voxelSize) > tol ||
            std::abs(c0.x() - expect.x) > tol || std::abs(c0.y() - expect.y) > tol ||
            std::abs(c0.z() - expect.z) > tol)
            LUCENT_THROW(IoError, "VDB file '", path, "': transform of grid '", grid->getName(),
                         "' does not match the voxel size/origin metadata");
        const vdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
        if (!box.empty() && !domain.isInside(box))
            LUCENT_THROW(IoError, "VDB file '", path, "': grid '", grid->getName(),
                         "' has active voxels ", box, " outside the ", res, "^3 grid");
    }
    // Same active voxels in every grid. Tree topology may legitimately differ: each grid is
    // pruned on its own, so a block uniform in g but varying in σt is a tile in one and a leaf
    // in the other. Equal counts plus "every active voxel of grid k is active in sigma_t"
    // means equal sets.
    for (int k = 1; k < 3; ++k) {
        bool same = grids[k]->activeVoxelCount() == grids[0]->activeVoxelCount();
        const auto acc0 = grids[0]->getConstAccessor();
        for (auto it = grids[k]->cbeginValueOn(); same && it; ++it) {
            vdb::CoordBBox box;
            it.getBoundingBox(box);
            for (auto ijk = box.begin(); same && ijk; ++ijk)
                same = acc0.isValueOn(*ijk);
        }
        if (!same)
            LUCENT_THROW(IoError, "VDB file '", path, "': grid '", grids[k]->getName(),
                         "' is not active on the same voxels as 'sigma_t'");
    }

    // Inside mask = active voxels of sigma_t (tiles expanded); then the values, validated as
    // they are stored: finite and already in the sanitised domain (so set() keeps them as is).
    auto forEachActive = [&](auto fn) {
        for (auto it = grids[0]->cbeginValueOn(); it; ++it) {
            vdb::CoordBBox box;
            it.getBoundingBox(box);
            for (auto ijk = box.begin(); ijk; ++ijk)
                fn(*ijk, *it);
        }
    };
    std::vector<uint8_t> mask(spec.voxelCount(), 0);
    forEachActive([&](const vdb::Coord& q, const vdb::Vec3s&) {
        mask[spec.linearIndex(Coord(q.x(), q.y(), q.z()))] = 1;
    });
    ImportedMaterial out{MaterialVolume(spec, md.base), md};
    out.volume.setEta(md.eta);
    out.volume.setInsideMask(mask);
    auto accS = grids[1]->getConstAccessor();
    auto accG = grids[2]->getConstAccessor();
    const char* names[3] = {GRID_SIGMA_T, GRID_SIGMA_S, GRID_G};
    forEachActive([&](const vdb::Coord& q, const vdb::Vec3s& sigmaT) {
        const MaterialSample s{fromVdb(sigmaT), fromVdb(accS.getValue(q)),
                               fromVdb(accG.getValue(q))};
        const Rgb* parts[3] = {&s.sigma_t, &s.sigma_s, &s.g};
        for (int k = 0; k < 3; ++k)
            if (!isFinite(*parts[k]))
                LUCENT_THROW(IoError, "VDB file '", path, "': grid '", names[k],
                             "' holds a non-finite value (NaN/Inf) at voxel ", q);
        if (!(sanitize(s) == s))
            LUCENT_THROW(IoError, "VDB file '", path, "': voxel ", q,
                         " is outside the valid domain (need 0 <= sigma_s <= sigma_t <= ",
                         SIGMA_MAX, ", |g| <= ", G_MAX, ")");
        out.volume.set(Coord(q.x(), q.y(), q.z()), s);
    });
    return out;
}

/// Writes "<uuid>:<FNV-1a 64 of the bytes after the file metadata>" into the placeholder of
/// metadata `lucent_checksum` of an in-memory file.
void stampChecksum(std::string& bytes, const std::string& path) {
    const detail::ByteReader reader = [&](uint64_t pos, void* dst, size_t n) {
        std::memcpy(dst, bytes.data() + pos, n);
    };
    const detail::VdbLayout layout = detail::parseVdbLayout(reader, bytes.size(), path);
    for (const auto& e : layout.meta)
        if (e.name == detail::CHECKSUM_META && e.valueSize == detail::CHECKSUM_TEXT_SIZE) {
            const uint64_t hash =
                detail::fnv1a64(bytes.data() + layout.metaEnd, bytes.size() - layout.metaEnd);
            const std::string text = layout.uuid + ":" + detail::hex64(hash);
            std::memcpy(bytes.data() + e.valueOffset, text.data(), text.size());
            return;
        }
    LUCENT_THROW(IoError, "cannot write VDB file '", path, "': checksum placeholder not found");
}

/// Checks the file (a regular file within the import limits), walks its whole structure
/// (VdbLayout.h: every size OpenVDB will trust is checked against the file) and, for a file
/// written by exportVdb and not rewritten since (same header UUID), verifies the checksum:
/// truncated, corrupt and garbage files are rejected here, before OpenVDB reads them.
detail::VdbLayout preflight(const std::string& path) {
    const uint64_t size = checkInputFile(path, "VDB file");
    std::ifstream in(path, std::ios::binary);
    if (!in)
        LUCENT_THROW(IoError, "cannot open VDB file '", path, "' for reading");
    const detail::ByteReader reader = [&](uint64_t pos, void* dst, size_t n) {
        in.seekg(std::streamoff(pos));
        in.read(static_cast<char*>(dst), std::streamsize(n));
        if (!in || size_t(in.gcount()) != n)
            LUCENT_THROW(IoError, "cannot read VDB file '", path, "' at byte ", pos,
                         " (changed while reading?)");
    };
    detail::VdbLayout layout = detail::parseVdbLayout(reader, size, path);
    for (const auto& e : layout.meta) {
        if (e.name != detail::CHECKSUM_META || e.valueSize != detail::CHECKSUM_TEXT_SIZE)
            continue;
        std::string text(detail::CHECKSUM_TEXT_SIZE, '\0');
        reader(e.valueOffset, text.data(), text.size());
        if (text.compare(0, 36, layout.uuid) != 0)
            break;  // rewritten by another tool: no check
        uint64_t hash = 0xcbf29ce484222325ULL;
        std::vector<char> chunk(1 << 20);
        for (uint64_t pos = layout.metaEnd; pos < size;) {
            const size_t n = size_t(std::min<uint64_t>(chunk.size(), size - pos));
            reader(pos, chunk.data(), n);
            hash = detail::fnv1a64(chunk.data(), n, hash);
            pos += n;
        }
        if (text.substr(37) != detail::hex64(hash))
            LUCENT_THROW(IoError, "VDB file '", path,
                         "' is corrupt or truncated (checksum mismatch)");
        break;
    }
    return layout;
}

/// Opens `path` fully loaded (no delayed loading: the file may change or vanish afterwards)
/// after preflight. Any OpenVDB/std failure becomes an IoError naming the file.
template <typename Fn>
auto withOpenFile(const std::string& path, const char* what, Fn fn) {
    const detail::VdbLayout layout = preflight(path);
    initializeOnce();
    try {
        vdb::io::File file(path);
        file.open(/*delayLoad=*/false);
        auto result = fn(file, layout);
        file.close();
        return result;
    } catch (const Error&) {
        throw;
    } catch (const std::bad_alloc&) {
        LUCENT_THROW(IoError, "cannot ", what, " VDB file '", path,
                     "': out of memory (corrupt sizes?)");
    } catch (const std::exception& e) {
        LUCENT_THROW(IoError, "cannot ", what, " VDB file '", path, "': ", vdbErrorText(e));
    }
}

// ---------------------------------------------------------------------------------- summary

template <typename T>
constexpr int componentsOf() {
    if constexpr (vdb::VecTraits<T>::IsVec)
        return vdb::VecTraits<T>::Size;
    else
        return 1;
}

template <typename GridT>
bool summarizeValues(const vdb::GridBase& base, VdbGridSummary& s) {
    const auto* grid = dynamic_cast<const GridT*>(&base);
    if (!grid)
        return false;
    using ValueT = typename GridT::ValueType;
    constexpr int N = componentsOf<ValueT>();
    s.components = N;
    s.minValue.assign(N, std::numeric_limits<double>::infinity());
    s.maxValue.assign(N, -std::numeric_limits<double>::infinity());
    bool any = false;
    for (auto it = grid->cbeginValueOn(); it; ++it) {
        const ValueT v = *it;
        bool finite = true;
        for (int k = 0; k < N; ++k) {
            double x;
            if constexpr (N == 1)
                x = double(v);
            else
                x = double(v[k]);
            if (!std::isfinite(x)) {
                finite = false;
                continue;
            }
            s.minValue[k] = std::min(s.minValue[k], x);
            s.maxValue[k] = std::max(s.maxValue[k], x);
            any = true;
        }
        if (!finite)
            ++s.nonFiniteCount;
    }
    if (!any) {
        s.minValue.clear();
        s.maxValue.clear();
    }
    return true;
}

std::vector<std::pair<std::string, std::string>> metaText(const vdb::MetaMap& meta) {
    std::vector<std::pair<std::string, std::string>> out;
    for (auto it = meta.beginMeta(); it != meta.endMeta(); ++it)
        out.emplace_back(it->first, it->second ? it->second->str() : std::string());
    return out;
}

VdbGridSummary summarizeGrid(const vdb::GridBase& grid) {
    VdbGridSummary s;
    s.name = grid.getName();
    s.valueType = grid.valueType();
    s.gridClass = vdb::GridBase::gridClassToString(grid.getGridClass());
    s.activeVoxelCount = grid.activeVoxelCount();
    s.leafCount = grid.baseTree().leafCount();
    const vdb::CoordBBox box = grid.evalActiveVoxelBoundingBox();
    if (!box.empty()) {
        s.activeBox = {Coord(box.min().x(), box.min().y(), box.min().z()),
                       Coord(box.max().x(), box.max().y(), box.max().z())};
        // Voxel faces: index box grown by ½ voxel (voxel centres at integer index coordinates).
        const vdb::BBoxd ib(box.min().asVec3d() - 0.5, box.max().asVec3d() + 0.5);
        const vdb::BBoxd wb = grid.transform().indexToWorld(ib);
        s.worldMin = Point3f(float(wb.min().x()), float(wb.min().y()), float(wb.min().z()));
        s.worldMax = Point3f(float(wb.max().x()), float(wb.max().y()), float(wb.max().z()));
    }
    const vdb::Vec3d vs = grid.voxelSize();
    s.voxelSize = glm::dvec3(vs.x(), vs.y(), vs.z());
    summarizeValues<vdb::FloatGrid>(grid, s) || summarizeValues<vdb::DoubleGrid>(grid, s) ||
        summarizeValues<vdb::Int32Grid>(grid, s) || summarizeValues<vdb::Int64Grid>(grid, s) ||
        summarizeValues<vdb::BoolGrid>(grid, s) || summarizeValues<vdb::Vec3SGrid>(grid, s) ||
        summarizeValues<vdb::Vec3DGrid>(grid, s) || summarizeValues<vdb::Vec3IGrid>(grid, s);
    s.metadata = metaText(grid);
    return s;
}

}  // namespace

// ------------------------------------------------------------------------------- public API

std::string encodeVdb(const MaterialVolume& volume, const VdbExportOptions& options) {
    const GridSpec& spec = volume.spec();
    LUCENT_CHECK(spec.resolution > 0 && volume.insideMask().size() == spec.voxelCount(),
                 "cannot encode an empty material volume as VDB");
    // Checked before OpenVDB sees the transform (it rejects tiny voxels with its own text) and
    // so that every file written can be imported again.
    LUCENT_CHECK(spec.voxelSize >= VDB_MIN_VOXEL_SIZE_MM &&
                     spec.voxelSize <= VDB_MAX_VOXEL_SIZE_MM && isFinite(spec.origin),
                 "cannot export a VDB material with voxels of ", spec.voxelSize,
                 " mm: VDB import accepts ", VDB_MIN_VOXEL_SIZE_MM, " to ", VDB_MAX_VOXEL_SIZE_MM,
                 " mm (", spec.resolution, " voxels across ",
                 spec.voxelSize * float(spec.resolution), " mm; is the mesh scale right?)");
    initializeOnce();

    auto sigmaT = buildGrid<vdb::Vec3SGrid>(
        volume, GRID_SIGMA_T, [](const MaterialSample& s) { return toVdb(s.sigma_t); });
    auto sigmaS = buildGrid<vdb::Vec3SGrid>(
        volume, GRID_SIGMA_S, [](const MaterialSample& s) { return toVdb(s.sigma_s); });
    auto g = buildGrid<vdb::Vec3SGrid>(volume, GRID_G,
                                       [](const MaterialSample& s) { return toVdb(s.g); });
    for (auto* grid : {sigmaT.get(), sigmaS.get()}) {
        grid->insertMeta("units", vdb::StringMetadata("1/mm"));
        grid->setVectorType(vdb::VEC_INVARIANT);
    }
    sigmaT->insertMeta(
        "description",
        vdb::StringMetadata("reduced extinction sigma_t' = sigma_a + sigma_s' per RGB channel"));
    sigmaS->insertMeta(
        "description",
        vdb::StringMetadata("REDUCED scattering sigma_s' = sigma_s (1 - g) per RGB channel"));
    sigmaS->insertMeta(META_REDUCED, vdb::BoolMetadata(true));
    g->insertMeta("units", vdb::StringMetadata("1"));
    g->insertMeta("description",
                  vdb::StringMetadata("Henyey-Greenstein asymmetry per RGB channel"));
    vdb::GridCPtrVec grids{sigmaT, sigmaS, g};

    if (options.rendererGrids) {
        // A renderer bounds the medium by the mesh, whose interior reaches past the inside
        // mask into the voxels its faces cut: the renderer grids carry the material there too,
        // as the reference path tracer reads it (BoundarySkin.h); without it they would render
        // a vacuum layer under the surface. The Lucent grids stay active exactly inside.
        const std::vector<SkinVoxel> skin = boundarySkin(volume);
        auto density = buildGrid<vdb::FloatGrid>(volume, GRID_DENSITY, densityOf, &skin);
        density->setGridClass(vdb::GRID_FOG_VOLUME);
        density->insertMeta("units", vdb::StringMetadata("1/mm"));
        density->insertMeta(
            "description",
            vdb::StringMetadata("grey extinction of the reduced (isotropic-phase) medium: "
                                "Rec.709 luminance of sigma_t'"));
        auto albedo = buildGrid<vdb::Vec3SGrid>(
            volume, GRID_ALBEDO, [](const MaterialSample& s) { return toVdb(reducedAlbedo(s)); },
            &skin);
        albedo->insertMeta("units", vdb::StringMetadata("1"));
        albedo->insertMeta(
            "description",
            vdb::StringMetadata("reduced single-scattering albedo sigma_s'/sigma_t' per channel"));
        auto color = albedo->deepCopy();
        color->setName(GRID_COLOR);
        color->insertMeta("description",
                          vdb::StringMetadata("copy of 'albedo' for Blender (Color attribute)"));
        grids.push_back(density);
        grids.push_back(albedo);
        grids.push_back(color);
    }

    vdb::MetaMap meta;
    meta.insertMeta(META_GENERATOR, vdb::StringMetadata("Lucent"));
    meta.insertMeta(META_GENERATOR_VERSION, vdb::StringMetadata(LUCENT_VERSION));
    meta.insertMeta(META_FORMAT_VERSION, vdb::Int32Metadata(VDB_FORMAT_VERSION));
    meta.insertMeta(META_RESOLUTION, vdb::Int32Metadata(spec.resolution));
    meta.insertMeta(META_ORIGIN, vdb::Vec3SMetadata(toVdb(spec.origin)));
    meta.insertMeta(META_VOXEL_SIZE, vdb::FloatMetadata(spec.voxelSize));
    meta.insertMeta(META_ETA, vdb::FloatMetadata(volume.eta()));
    meta.insertMeta(META_BASE_SIGMA_T, vdb::Vec3SMetadata(toVdb(volume.base().sigma_t)));
    meta.insertMeta(META_BASE_SIGMA_S, vdb::Vec3SMetadata(toVdb(volume.base().sigma_s)));
    meta.insertMeta(META_BASE_G, vdb::Vec3SMetadata(toVdb(volume.base().g)));
    meta.insertMeta(META_NAME, vdb::StringMetadata(options.materialName));
    meta.insertMeta(META_LENGTH_UNIT, vdb::StringMetadata("mm"));
    meta.insertMeta(META_SIGMA_UNIT, vdb::StringMetadata("1/mm"));
    meta.insertMeta(META_REDUCED, vdb::BoolMetadata(true));
    meta.insertMeta(META_NOTE,
                    vdb::StringMetadata(
                        "sigma_s is the REDUCED scattering coefficient sigma_s' = sigma_s (1 - g); "
                        "unreduced: sigma_s = sigma_s' / (1 - g), sigma_a = sigma_t - sigma_s'"));
    if (options.rendererGrids)
        meta.insertMeta(
            META_DENSITY_DEF,
            vdb::StringMetadata("density = 0.2126 R + 0.7152 G + 0.0722 B of sigma_t' (1/mm); "
                                "albedo = color = sigma_s'/sigma_t'; use with an isotropic phase"));

    // Serialise in memory, then stamp the integrity checksum into its fixed-size placeholder
    // (same length, so no offset moves) and write the bytes atomically.
    meta.insertMeta(detail::CHECKSUM_META,
                    vdb::StringMetadata(std::string(detail::CHECKSUM_TEXT_SIZE, '0')));
    std::string bytes;
    try {
        std::ostringstream buffer(std::ios::binary);
        CheckedArchive().writeTo(buffer, grids, meta);
        bytes = std::move(buffer).str();
    } catch (const std::exception& e) {
        LUCENT_THROW(IoError, "cannot encode the VDB file: ", vdbErrorText(e));
    }
    stampChecksum(bytes, "<encoded VDB>");
    return bytes;
}

void exportVdb(const MaterialVolume& volume, const std::string& path,
               const VdbExportOptions& options) {
    LUCENT_CHECK(!path.empty(), "VDB export needs a file name");
    const GridSpec& spec = volume.spec();
    LUCENT_CHECK(spec.resolution > 0 && volume.insideMask().size() == spec.voxelCount(),
                 "cannot export an empty material volume to '", path, "'");
    writeFileAtomically(path, encodeVdb(volume, options));
}

ImportedMaterial importVdb(const std::string& path) {
    return withOpenFile(path, "import", [&](vdb::io::File& file, const detail::VdbLayout& layout) {
        return importOpen(file, layout, path);
    });
}

VdbFileSummary summarizeVdb(const std::string& path) {
    return withOpenFile(path, "read", [&](vdb::io::File& file, const detail::VdbLayout& layout) {
        VdbFileSummary s;
        s.path = path;
        std::error_code ec;
        s.fileBytes = std::filesystem::file_size(path, ec);
        s.formatVersion = file.version();
        s.metadata = metaText(*file.getMetadata());
        // Grid by grid in file order; a grid the preflight walk could not check (point data,
        // point index) is listed by name and type and never handed to OpenVDB.
        for (const detail::VdbGridEntry& entry : layout.grids) {
            if (!entry.checked) {
                VdbGridSummary g;
                g.name = entry.uniqueName.substr(0, entry.uniqueName.find('\x1e'));
                g.valueType = entry.typeName;
                g.gridClass = "unknown";
                g.note = "not read: Lucent does not check grids of type " + entry.typeName;
                s.grids.push_back(std::move(g));
                continue;
            }
            // "name[N]" selects the N-th of several grids of the same name.
            const std::string name = vdb::io::GridDescriptor::nameAsString(entry.uniqueName);
            if (vdb::GridBase::Ptr grid = file.readGrid(name))
                s.grids.push_back(summarizeGrid(*grid));
        }
        return s;
    });
}

}  // namespace lucent::io

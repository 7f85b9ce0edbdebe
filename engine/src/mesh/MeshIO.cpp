// SPDX-License-Identifier: MIT
/// @file
/// @brief Mesh loading/saving by extension, and validation with repair reports.

#include "Backends.h"

#include <lucent/core/Error.h>
#include <lucent/core/FileIO.h>
#include <lucent/mesh/MeshIO.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <unordered_map>

namespace lucent {
namespace {

namespace fs = std::filesystem;

std::string lowerExtension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

bool isOpenMeshFormat(const std::string& ext) {
    return ext == ".obj" || ext == ".ply" || ext == ".off" || ext == ".stl";
}
bool isVtkFormat(const std::string& ext) {
    return ext == ".vtp" || ext == ".vtk";
}

uint64_t edgeKey(uint32_t a, uint32_t b) {
    if (a > b)
        std::swap(a, b);
    return (uint64_t(a) << 32) | b;
}

/// Merges vertices with bit-identical positions (readers split vertices at seams and at
/// non-manifold faces) and removes the merged copies; returns how many were merged.
size_t weldIdentical(TriangleMesh& m) {
    struct Hash {
        size_t operator()(const Point3f& p) const {
            uint32_t b[3];
            std::memcpy(b, &p, sizeof b);
            return (size_t(b[0]) * 73856093u) ^ (size_t(b[1]) * 19349663u) ^
                   (size_t(b[2]) * 83492791u);
        }
    };
    std::unordered_map<Point3f, uint32_t, Hash> first;
    std::vector<uint32_t> remap(m.positions.size());
    size_t merged = 0;
    for (size_t i = 0; i < m.positions.size(); ++i) {
        auto [it, inserted] = first.emplace(m.positions[i], uint32_t(i));
        remap[i] = it->second;
        if (!inserted)
            ++merged;
    }
    if (merged == 0)
        return 0;
    std::vector<uint32_t> compact(m.positions.size(), UINT32_MAX);
    std::vector<Point3f> pos;
    std::vector<Normal3f> nor;
    const bool hasNormals = m.normals.size() == m.positions.size();
    for (size_t i = 0; i < m.positions.size(); ++i) {
        if (remap[i] != i)
            continue;
        compact[i] = uint32_t(pos.size());
        pos.push_back(m.positions[i]);
        if (hasNormals)
            nor.push_back(m.normals[i]);
    }
    for (auto& t : m.triangles)
        for (auto& v : t)
            v = compact[remap[v]];
    m.positions = std::move(pos);
    m.normals = std::move(nor);
    return merged;
}

}  // namespace

MeshReport validateMesh(TriangleMesh& mesh, const std::string& name) {
    MeshReport r;
    r.inputTriangles = mesh.triangles.size();
    const size_t nv = mesh.positions.size();
    for (size_t i = 0; i < nv; ++i)
        if (!isFinite(mesh.positions[i]))
            LUCENT_THROW(ValueError, name, ": vertex ", i,
                         " has a non-finite (NaN/Inf) coordinate");
    for (size_t f = 0; f < mesh.triangles.size(); ++f)
        for (uint32_t v : mesh.triangles[f])
            if (v >= nv)
                LUCENT_THROW(ValueError, name, ": face ", f, " uses vertex ", v, " but there are ",
                             nv, " vertices");
    const bool normalsValid =
        mesh.normals.size() == nv &&
        std::all_of(mesh.normals.begin(), mesh.normals.end(), [](const Normal3f& n) {
            return isFinite(n) && std::abs(glm::length(n) - 1.f) < 1e-2f;
        });

    // Degenerate faces: repeated vertex or zero area (relative to the squared bounding size, so
    // the test is scale-free; 1e-14 is far below float precision of real triangles).
    const float diag2 = [&] {
        const Vector3f e = mesh.bounds().extent();
        return glm::dot(e, e);
    }();
    std::vector<std::array<uint32_t, 3>> kept;
    kept.reserve(mesh.triangles.size());
    std::unordered_map<uint64_t, std::vector<size_t>> bySorted;
    for (const auto& t : mesh.triangles) {
        const Point3f& a = mesh.positions[t[0]];
        const Point3f& b = mesh.positions[t[1]];
        const Point3f& c = mesh.positions[t[2]];
        const float area2 = glm::length(glm::cross(b - a, c - a));
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || !(area2 > 1e-14f * diag2)) {
            ++r.degenerateDropped;
            continue;
        }
        std::array<uint32_t, 3> s = t;
        std::sort(s.begin(), s.end());
        const uint64_t h = (uint64_t(s[0]) * 0x9E3779B97F4A7C15ull) ^
                           (uint64_t(s[1]) * 0xC2B2AE3D27D4EB4Full) ^ uint64_t(s[2]);
        auto& bucket = bySorted[h];
        const bool dup = std::any_of(bucket.begin(), bucket.end(), [&](size_t k) {
            std::array<uint32_t, 3> o = kept[k];
            std::sort(o.begin(), o.end());
            return o == s;
        });
        if (dup) {
            ++r.duplicateDropped;
            continue;
        }
        bucket.push_back(kept.size());
        kept.push_back(t);
    }
    if (kept.empty())
        LUCENT_THROW(ValueError, name, ": contains no valid triangles (", r.inputTriangles,
                     " faces read, ", r.degenerateDropped, " degenerate)");
    mesh.triangles = std::move(kept);

    // Remove unreferenced vertices.
    std::vector<uint32_t> remap(nv, UINT32_MAX);
    uint32_t next = 0;
    for (const auto& t : mesh.triangles)
        for (uint32_t v : t)
            if (remap[v] == UINT32_MAX)
                remap[v] = next++;
    r.unreferencedDropped = nv - next;
    if (r.unreferencedDropped > 0) {
        std::vector<Point3f> pos(next);
        std::vector<Normal3f> nor(normalsValid ? next : 0);
        for (size_t i = 0; i < nv; ++i) {
            if (remap[i] == UINT32_MAX)
                continue;
            pos[remap[i]] = mesh.positions[i];
            if (normalsValid)
                nor[remap[i]] = mesh.normals[i];
        }
        mesh.positions = std::move(pos);
        mesh.normals = std::move(nor);
        for (auto& t : mesh.triangles)
            for (auto& v : t)
                v = remap[v];
    }
    if (!normalsValid) {
        computeVertexNormals(mesh);
        r.normalsComputed = true;
    }

    // Edge topology: 1 face → boundary (open mesh), > 2 faces → non-manifold.
    std::unordered_map<uint64_t, uint32_t> edgeFaces;
    edgeFaces.reserve(mesh.triangles.size() * 2);
    for (const auto& t : mesh.triangles)
        for (int e = 0; e < 3; ++e)
            ++edgeFaces[edgeKey(t[size_t(e)], t[size_t((e + 1) % 3)])];
    for (const auto& [key, count] : edgeFaces) {
        if (count == 1)
            ++r.boundaryEdges;
        if (count > 2)
            ++r.nonManifoldEdges;
    }

    auto warn = [&](auto&&... parts) {
        r.warnings.push_back(detail::concat(name, ": ", parts...));
    };
    if (r.degenerateDropped)
        warn("removed ", r.degenerateDropped, " degenerate face(s) (repeated vertex or zero area)");
    if (r.duplicateDropped)
        warn("removed ", r.duplicateDropped, " duplicate face(s)");
    if (r.unreferencedDropped)
        warn("removed ", r.unreferencedDropped, " unreferenced vertex(es)");
    if (r.boundaryEdges)
        warn("the mesh is open: ", r.boundaryEdges,
             " boundary edge(s); voxelisation uses robust ray voting, or use fillHoles()");
    if (r.nonManifoldEdges)
        warn(r.nonManifoldEdges, " non-manifold edge(s) (shared by more than two faces)");
    return r;
}

TriangleMesh loadMesh(const std::string& path, float scale, MeshReport* report) {
    LUCENT_CHECK(std::isfinite(scale) && scale > 0.f, "loadMesh: scale must be > 0, got ", scale);
    // A regular file within the import limits (a device such as /dev/zero would never end).
    const uint64_t size = checkInputFile(path, "mesh file");
    if (size == 0)
        LUCENT_THROW(IoError, "mesh file '", path, "' is empty");
    const std::string ext = lowerExtension(path);
    if (!isOpenMeshFormat(ext) && !isVtkFormat(ext))
        LUCENT_THROW(IoError, "mesh file '", path, "': unsupported extension '", ext,
                     "' (expected .obj, .ply, .off, .stl, .vtp or .vtk)");
    // The upstream readers trust the file: its structure is checked first (MeshValidate.h).
    const detail::ClaimedCounts claimed = detail::validateMeshFile(path, ext, size);
    detail::RawMesh raw;
    try {
        raw = isOpenMeshFormat(ext) ? detail::readOpenMesh(path) : detail::readVtk(path, claimed);
    } catch (const Error&) {
        throw;
    } catch (const std::bad_alloc&) {
        LUCENT_THROW(IoError, "mesh file '", path,
                     "': out of memory while reading (corrupt sizes?)");
    } catch (const std::exception& e) {
        LUCENT_THROW(IoError, "mesh file '", path, "': cannot be parsed (", e.what(), ")");
    }
    TriangleMesh& m = raw.mesh;
    const size_t welded = weldIdentical(m);
    for (auto& p : m.positions)
        p *= scale;
    MeshReport r;
    try {
        r = validateMesh(m, path);
    } catch (const ValueError& e) {
        LUCENT_THROW(IoError, "mesh file ", e.what());
    }
    if (welded)
        r.warnings.insert(r.warnings.begin(), detail::concat(path, ": merged ", welded,
                                                             " vertex(es) at identical positions"));
    if (raw.readerDroppedDegenerate) {
        r.degenerateDropped += raw.readerDroppedDegenerate;
        r.inputTriangles += raw.readerDroppedDegenerate;
        r.warnings.insert(r.warnings.begin(),
                          detail::concat(path, ": removed ", raw.readerDroppedDegenerate,
                                         " face(s) with a repeated vertex"));
    }
    if (raw.nonManifoldDetached)
        r.warnings.insert(r.warnings.begin(), detail::concat(path, ": ", raw.nonManifoldDetached,
                                                             " non-manifold face(s) in the file"));
    if (report)
        *report = std::move(r);
    return std::move(m);
}

void saveMesh(const TriangleMesh& mesh, const std::string& path, bool binary) {
    LUCENT_CHECK(!mesh.isEmpty(), "saveMesh: the mesh is empty ('", path, "')");
    const std::string ext = lowerExtension(path);
    if (isOpenMeshFormat(ext))
        detail::writeOpenMesh(mesh, path, binary);
    else if (isVtkFormat(ext))
        detail::writeVtk(mesh, path, binary);
    else
        LUCENT_THROW(IoError, "mesh file '", path, "': unsupported extension '", ext,
                     "' (expected .obj, .ply, .off, .stl, .vtp or .vtk)");
}

}  // namespace lucent

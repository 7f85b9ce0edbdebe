// SPDX-License-Identifier: MIT
/// @file
/// @brief Mesh loading/saving by extension, and validation with repair reports.

#include "Backends.h"

#include <lucent/core/Error.h>
#include <lucent/mesh/MeshIO.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <set>
#include <fstream>
#include <sstream>
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

/// Checks a PLY header strictly, and rejects files whose header claims more elements than the
/// file could hold (each element takes at least one byte in every encoding), before a reader
/// tries to allocate for them.
void checkHeader(const std::string& path, const std::string& ext, uintmax_t fileSize) {
    if (ext != ".ply" && ext != ".off" && ext != ".vtk")
        return;
    std::ifstream f(path, std::ios::binary);
    std::string head(8192, '\0');
    f.read(head.data(), std::streamsize(head.size()));
    head.resize(size_t(f.gcount()));
    std::istringstream in(head);
    std::string line;
    uintmax_t claimed = 0;
    bool offCounts = false;
    size_t lineNo = 0;
    bool inElement = false, sawEnd = false;
    auto add = [&](const std::string& token) {
        try {
            const double v = std::stod(token);
            if (v > 0)
                claimed += v > 1e18 ? uintmax_t(1e18) : uintmax_t(v);
        } catch (const std::exception&) {
        }
    };
    while (std::getline(in, line)) {
        std::istringstream words(line);
        std::string w0, w1, w2;
        words >> w0 >> w1 >> w2;
        if (ext == ".ply") {
            // A strict header check: OpenMesh's PLY reader crashes on some malformed headers
            // (e.g. a property before any element), found by fuzzing.
            static const std::set<std::string> TYPES = {
                "char",  "uchar",  "short", "ushort", "int",   "uint",   "int8",    "uint8",
                "int16", "uint16", "int32", "uint32", "float", "double", "float32", "float64"};
            auto bad = [&](const char* why) {
                LUCENT_THROW(IoError, "mesh file '", path, "': malformed PLY header (", why, "): '",
                             line, "'");
            };
            if (!line.empty() && line.back() == '\r')
                line.pop_back();
            if (lineNo++ == 0) {
                if (line != "ply")
                    bad("first line must be 'ply'");
                continue;
            }
            if (w0 == "format") {
                if (w1 != "ascii" && w1 != "binary_little_endian" && w1 != "binary_big_endian")
                    bad("unknown format");
            } else if (w0 == "element") {
                if (w1.empty() || w2.empty() ||
                    w2.find_first_not_of("0123456789") != std::string::npos)
                    bad("expected 'element <name> <count>'");
                add(w2);
                inElement = true;
            } else if (w0 == "property") {
                if (!inElement)
                    bad("property outside an element");
                std::string w3, w4;
                words >> w3 >> w4;
                const bool list = w1 == "list";
                if (list ? (!TYPES.count(w2) || !TYPES.count(w3) || w4.empty())
                         : (!TYPES.count(w1) || w2.empty()))
                    bad("expected 'property <type> <name>' or 'property list <type> <type> "
                        "<name>'");
            } else if (w0 == "end_header") {
                sawEnd = true;
                break;
            } else if (w0 != "comment" && w0 != "obj_info" && !w0.empty()) {
                bad("unknown keyword");
            }
        } else if (ext == ".off") {
            if (w0.empty() || w0[0] == '#')
                continue;
            if (!offCounts && w0.find("OFF") != std::string::npos) {
                offCounts = true;  // the counts follow on this line or the next one
                if (!w1.empty()) {
                    add(w1);
                    add(w2);
                    break;
                }
                continue;
            }
            if (offCounts) {
                add(w0);
                add(w1);
                break;
            }
        } else if (w0 == "POINTS" || w0 == "POLYGONS" || w0 == "TRIANGLE_STRIPS") {
            add(w1);
        }
    }
    if (ext == ".ply" && !sawEnd)
        LUCENT_THROW(IoError, "mesh file '", path, "': PLY header has no end_header in its first ",
                     head.size(), " bytes");
    if (claimed > fileSize)
        LUCENT_THROW(IoError, "mesh file '", path, "': its header claims ", claimed,
                     " elements but the file has only ", fileSize, " bytes (truncated or corrupt)");
}

}  // namespace

/// Walks the body of an ASCII PLY file token by token against its header (called after
/// checkHeader accepted the header). OpenMesh's ASCII PLY reader loops forever on some
/// truncated or corrupted bodies (a failed stream read is never detected; found by the fuzz
/// test), so every token it will read must be present and be a plain decimal number.
void checkAsciiPlyBody(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    struct Element {
        std::string name;
        uintmax_t count = 0;
        std::vector<bool> isList;  // per property
    };
    std::vector<Element> elements;
    std::string line;
    bool ascii = false;
    while (std::getline(f, line)) {
        if (!line.empty() && line.back() == '\r')
            line.pop_back();
        std::istringstream words(line);
        std::string w0, w1, w2;
        words >> w0 >> w1 >> w2;
        if (w0 == "format") {
            ascii = w1 == "ascii";
        } else if (w0 == "element") {
            elements.push_back({w1, uintmax_t(std::stoull(w2)), {}});
        } else if (w0 == "property" && !elements.empty()) {
            elements.back().isList.push_back(w1 == "list");
        } else if (w0 == "end_header") {
            break;
        }
    }
    if (!ascii)
        return;
    auto isPlainNumber = [](const std::string& t) {
        if (t.empty() || t.find_first_not_of("0123456789+-.eE") != std::string::npos)
            return false;
        char* end = nullptr;
        std::strtod(t.c_str(), &end);
        return end == t.c_str() + t.size();
    };
    std::string token;
    for (const Element& e : elements) {
        for (uintmax_t i = 0; i < e.count; ++i) {
            for (const bool list : e.isList) {
                uintmax_t n = 1;
                if (list) {
                    if (!(f >> token) || !isPlainNumber(token))
                        LUCENT_THROW(IoError, "mesh file '", path,
                                     "': ASCII PLY body is truncated or "
                                     "malformed in element '",
                                     e.name, "' ", i);
                    const double k = std::strtod(token.c_str(), nullptr);
                    if (!(k >= 0 && k <= 1e6) || k != std::floor(k))
                        LUCENT_THROW(IoError, "mesh file '", path, "': ASCII PLY list length '",
                                     token, "' in element '", e.name, "' ", i, " is invalid");
                    n = uintmax_t(k);
                }
                for (uintmax_t k = 0; k < n; ++k)
                    if (!(f >> token) || !isPlainNumber(token))
                        LUCENT_THROW(IoError, "mesh file '", path,
                                     "': ASCII PLY body is truncated or "
                                     "malformed in element '",
                                     e.name, "' ", i,
                                     (f ? std::string(" (token '") + token + "')" : std::string()));
            }
        }
    }
}

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
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
        LUCENT_THROW(IoError, "mesh file '", path, "' does not exist or is not a file");
    if (fs::file_size(path, ec) == 0)
        LUCENT_THROW(IoError, "mesh file '", path, "' is empty");
    const std::string ext = lowerExtension(path);
    if (!isOpenMeshFormat(ext) && !isVtkFormat(ext))
        LUCENT_THROW(IoError, "mesh file '", path, "': unsupported extension '", ext,
                     "' (expected .obj, .ply, .off, .stl, .vtp or .vtk)");
    checkHeader(path, ext, fs::file_size(path, ec));
    if (ext == ".ply")
        checkAsciiPlyBody(path);
    detail::RawMesh raw;
    try {
        raw = isOpenMeshFormat(ext) ? detail::readOpenMesh(path) : detail::readVtk(path);
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

// SPDX-License-Identifier: MIT
/// @file
/// @brief The OpenMesh boundary: OBJ/PLY/OFF/STL reading and writing, quadric decimation,
/// Loop subdivision and Laplacian smoothing.

#include "Backends.h"

#include <lucent/core/Error.h>
#include <lucent/core/FileIO.h>
#include <lucent/mesh/MeshEdit.h>

// OpenMesh requires its IO header before the mesh kernel.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <OpenMesh/Tools/Smoother/JacobiLaplaceSmootherT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>

#include <cctype>
#include <filesystem>
#include <mutex>
#include <sstream>

namespace lucent {
namespace {

using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;

OmMesh toOpenMesh(const TriangleMesh& mesh) {
    OmMesh om;
    om.request_vertex_normals();
    std::vector<OmMesh::VertexHandle> vh;
    vh.reserve(mesh.positions.size());
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        const Point3f& p = mesh.positions[i];
        vh.push_back(om.add_vertex(OmMesh::Point(p.x, p.y, p.z)));
        if (i < mesh.normals.size()) {
            const Normal3f& n = mesh.normals[i];
            om.set_normal(vh.back(), OmMesh::Normal(n.x, n.y, n.z));
        }
    }
    for (const auto& t : mesh.triangles) {
        LUCENT_CHECK(t[0] < vh.size() && t[1] < vh.size() && t[2] < vh.size(),
                     "mesh: triangle index out of range");
        om.add_face(vh[t[0]], vh[t[1]], vh[t[2]]);  // complex faces are skipped by OpenMesh
    }
    return om;
}

TriangleMesh fromOpenMesh(const OmMesh& om, bool useNormals) {
    TriangleMesh m;
    m.positions.reserve(om.n_vertices());
    for (const auto v : om.vertices()) {
        const auto& p = om.point(v);
        m.positions.emplace_back(p[0], p[1], p[2]);
        if (useNormals) {
            const auto& n = om.normal(v);
            m.normals.emplace_back(n[0], n[1], n[2]);
        }
    }
    m.triangles.reserve(om.n_faces());
    for (const auto f : om.faces()) {
        std::array<uint32_t, 3> t{};
        int k = 0;
        for (const auto v : om.fv_range(f)) {
            if (k < 3)
                t[size_t(k)] = uint32_t(v.idx());
            ++k;
        }
        if (k == 3)
            m.triangles.push_back(t);
    }
    if (!useNormals)
        computeVertexNormals(m);
    return m;
}

/// A stream connected once, for the life of the process, to OpenMesh's error stream; what it
/// receives goes to the current target string (or nowhere). OpenMesh's mostream::disconnect
/// does not free the 16-byte target that connect allocates, so connecting per load leaked
/// (LeakSanitizer: OpenMesh::mostream::connect).
class ErrorCapture : private std::streambuf {
public:
    ErrorCapture() : m_stream(this) { ::omerr().connect(m_stream); }
    void setTarget(std::string* target) { m_target = target; }

private:
    int_type overflow(int_type c) override {
        if (m_target && !traits_type::eq_int_type(c, traits_type::eof()))
            m_target->push_back(traits_type::to_char_type(c));
        return traits_type::not_eof(c);
    }
    std::streamsize xsputn(const char* s, std::streamsize n) override {
        if (m_target)
            m_target->append(s, size_t(n));
        return n;
    }

    std::ostream m_stream;
    std::string* m_target = nullptr;
};

ErrorCapture& errorCapture() {
    // Never destroyed: OpenMesh's error stream, a static in its library, keeps a reference to
    // it until the very end of the process.
    static ErrorCapture* capture = new ErrorCapture;
    return *capture;
}

}  // namespace

namespace detail {

RawMesh readOpenMesh(const std::string& path) {
    OmMesh om;
    om.request_face_status();
    OpenMesh::IO::Options opt;
    // OBJ normals are per face corner (`f v//vn`), and OpenMesh 9's OBJ importer writes them
    // out of bounds when a corrupt face refers to a missing vertex (heap corruption, found by
    // fuzzing): for OBJ the normals are recomputed from the geometry instead.
    std::string ext = std::filesystem::path(path).extension().string();
    for (auto& ch : ext)
        ch = char(std::tolower(static_cast<unsigned char>(ch)));
    if (ext != ".obj") {
        om.request_vertex_normals();
        opt += OpenMesh::IO::Options::VertexNormal;
    }
    // OpenMesh's importer reports the faces it rejects only on its error stream: listen to it
    // (a process-wide stream, hence the lock) to count them.
    static std::mutex s_logMutex;
    std::string messages;
    bool ok = false;
    {
        const std::lock_guard<std::mutex> lock(s_logMutex);
        // Stops listening even when the reader throws (the log is a local).
        struct Listen {
            explicit Listen(std::string& log) { errorCapture().setTarget(&log); }
            ~Listen() {
                ::omerr().flush();
                errorCapture().setTarget(nullptr);
            }
        } listen(messages);
        ok = OpenMesh::IO::read_mesh(om, path, opt);
    }
    if (!ok)
        LUCENT_THROW(IoError, "mesh file '", path, "': cannot be parsed (unreadable or malformed)");
    auto count = [&](const char* what) {
        size_t n = 0;
        for (size_t at = messages.find(what); at != std::string::npos;
             at = messages.find(what, at + 1))
            ++n;
        return n;
    };
    if (const size_t bad = count("invalid vertex index"))
        LUCENT_THROW(IoError, "mesh file '", path, "': ", bad,
                     " face(s) refer to vertices that could not be read (malformed or NaN/Inf "
                     "coordinates)");
    RawMesh raw;
    raw.readerDroppedDegenerate = count("equal vertices");
    raw.hasNormals = om.has_vertex_normals() && opt.check(OpenMesh::IO::Options::VertexNormal);
    for (const auto f : om.faces())
        if (om.status(f).fixed_nonmanifold())
            ++raw.nonManifoldDetached;
    raw.mesh = fromOpenMesh(om, raw.hasNormals);
    return raw;
}

void writeOpenMesh(const TriangleMesh& mesh, const std::string& path, bool binary) {
    OmMesh om = toOpenMesh(mesh);
    OpenMesh::IO::Options opt;
    std::string ext = std::filesystem::path(path).extension().string();
    for (auto& ch : ext)
        ch = char(std::tolower(static_cast<unsigned char>(ch)));
    // STL stores face normals only (OpenMesh's STL writer refuses vertex normals).
    if (ext != ".stl")
        opt += OpenMesh::IO::Options::VertexNormal;
    // Binary only where documented (PLY, STL): binary OFF is not read back (MeshValidate.h).
    if (binary && (ext == ".ply" || ext == ".stl"))
        opt += OpenMesh::IO::Options::Binary;
    // Encoded in memory, then written through the checked atomic writer (OpenMesh's file
    // output does not report a full disk).
    std::ostringstream bytes(std::ios::binary);
    if (!OpenMesh::IO::write_mesh(om, bytes, ext.substr(1), opt) || bytes.str().empty())
        LUCENT_THROW(IoError, "mesh file '", path, "': cannot be encoded");
    writeFileAtomically(path, bytes.str());
}

}  // namespace detail

TriangleMesh decimate(const TriangleMesh& mesh, size_t targetTriangles) {
    LUCENT_CHECK(!mesh.isEmpty(), "decimate: the mesh is empty");
    LUCENT_CHECK(targetTriangles >= 4, "decimate: targetTriangles must be ≥ 4, got ",
                 targetTriangles);
    OmMesh om = toOpenMesh(mesh);
    om.request_vertex_status();
    om.request_edge_status();
    om.request_face_status();
    om.request_face_normals();
    om.update_face_normals();
    using Decimater = OpenMesh::Decimater::DecimaterT<OmMesh>;
    using Quadric = OpenMesh::Decimater::ModQuadricT<OmMesh>::Handle;
    Decimater dec(om);
    Quadric hq;
    dec.add(hq);
    dec.module(hq).unset_max_err();
    if (!dec.initialize())
        LUCENT_THROW(Error, "decimate: OpenMesh decimater failed to initialise");
    dec.decimate_to_faces(0, targetTriangles);
    om.garbage_collection();
    return fromOpenMesh(om, false);
}

TriangleMesh subdivideLoop(const TriangleMesh& mesh, int iterations) {
    LUCENT_CHECK(!mesh.isEmpty(), "subdivideLoop: the mesh is empty");
    LUCENT_CHECK(iterations >= 1 && iterations <= 5,
                 "subdivideLoop: iterations must be in [1, 5], got ", iterations);
    OmMesh om = toOpenMesh(mesh);
    OpenMesh::Subdivider::Uniform::LoopT<OmMesh> loop;
    loop.attach(om);
    loop(size_t(iterations));
    loop.detach();
    return fromOpenMesh(om, false);
}

TriangleMesh smoothLaplacian(const TriangleMesh& mesh, int iterations) {
    LUCENT_CHECK(!mesh.isEmpty(), "smoothLaplacian: the mesh is empty");
    LUCENT_CHECK(iterations >= 1 && iterations <= 1000,
                 "smoothLaplacian: iterations must be in [1, 1000], got ", iterations);
    OmMesh om = toOpenMesh(mesh);
    om.request_vertex_status();
    om.request_face_normals();
    om.update_normals();
    OpenMesh::Smoother::JacobiLaplaceSmootherT<OmMesh> smoother(om);
    smoother.initialize(OpenMesh::Smoother::SmootherT<OmMesh>::Tangential_and_Normal,
                        OpenMesh::Smoother::SmootherT<OmMesh>::C0);
    smoother.smooth(unsigned(iterations));
    return fromOpenMesh(om, false);
}

}  // namespace lucent

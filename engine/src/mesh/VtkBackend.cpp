// SPDX-License-Identifier: MIT
/// @file
/// @brief The VTK boundary (geometry modules only, never VTK's Qt modules): .vtp/.vtk reading
/// and writing, hole filling, cleaning and largest-component extraction.

#include "Backends.h"

#include <lucent/core/Error.h>
#include <lucent/core/FileIO.h>
#include <lucent/core/Isolate.h>
#include <lucent/mesh/MeshEdit.h>

#include <vtkCallbackCommand.h>
#include <vtkCellArray.h>
#include <vtkCommand.h>
#include <vtkCleanPolyData.h>
#include <vtkDataArray.h>
#include <vtkFillHolesFilter.h>
#include <vtkFloatArray.h>
#include <vtkIdList.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataConnectivityFilter.h>
#include <vtkPolyDataNormals.h>
#include <vtkPolyDataReader.h>
#include <vtkPolyDataWriter.h>
#include <vtkSmartPointer.h>
#include <vtkTriangleFilter.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <vector>

namespace lucent {
namespace {

template <typename T>
using Ptr = vtkSmartPointer<T>;

Ptr<vtkPolyData> toVtk(const TriangleMesh& mesh) {
    auto points = Ptr<vtkPoints>::New();
    points->SetDataTypeToFloat();
    points->SetNumberOfPoints(vtkIdType(mesh.positions.size()));
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        const Point3f& p = mesh.positions[i];
        points->SetPoint(vtkIdType(i), p.x, p.y, p.z);
    }
    auto polys = Ptr<vtkCellArray>::New();
    for (const auto& t : mesh.triangles) {
        const vtkIdType ids[3] = {vtkIdType(t[0]), vtkIdType(t[1]), vtkIdType(t[2])};
        polys->InsertNextCell(3, ids);
    }
    auto pd = Ptr<vtkPolyData>::New();
    pd->SetPoints(points);
    pd->SetPolys(polys);
    if (mesh.normals.size() == mesh.positions.size()) {
        auto normals = Ptr<vtkFloatArray>::New();
        normals->SetName("Normals");
        normals->SetNumberOfComponents(3);
        normals->SetNumberOfTuples(vtkIdType(mesh.normals.size()));
        for (size_t i = 0; i < mesh.normals.size(); ++i) {
            const Normal3f& n = mesh.normals[i];
            const float v[3] = {n.x, n.y, n.z};
            normals->SetTypedTuple(vtkIdType(i), v);
        }
        pd->GetPointData()->SetNormals(normals);
    }
    return pd;
}

/// True when every cell of `pd` refers to existing points (VTK's filters do not check, and a
/// corrupt file makes vtkTriangleFilter read out of bounds: found by fuzzing).
bool cellsValid(vtkPolyData* pd) {
    const vtkIdType np = pd->GetNumberOfPoints();
    for (vtkCellArray* cells : {pd->GetVerts(), pd->GetLines(), pd->GetPolys(), pd->GetStrips()}) {
        if (!cells)
            continue;
        if (!cells->IsValid())  // offsets monotone and within the connectivity array
            return false;
        auto ids = Ptr<vtkIdList>::New();
        cells->InitTraversal();
        while (cells->GetNextCell(ids))
            for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k)
                if (ids->GetId(k) < 0 || ids->GetId(k) >= np)
                    return false;
    }
    return true;
}

/// Triangulates `input` and converts it; `hasNormals` tells whether point normals came along.
TriangleMesh fromVtk(vtkPolyData* input, bool* hasNormals = nullptr) {
    auto tri = Ptr<vtkTriangleFilter>::New();
    tri->SetInputData(input);
    tri->PassVertsOff();
    tri->PassLinesOff();
    tri->Update();
    vtkPolyData* pd = tri->GetOutput();
    TriangleMesh m;
    const vtkIdType np = pd->GetNumberOfPoints();
    m.positions.resize(size_t(np));
    for (vtkIdType i = 0; i < np; ++i) {
        double p[3];
        pd->GetPoint(i, p);
        m.positions[size_t(i)] = Point3f(float(p[0]), float(p[1]), float(p[2]));
    }
    vtkDataArray* normals = pd->GetPointData() ? pd->GetPointData()->GetNormals() : nullptr;
    const bool useNormals =
        normals && normals->GetNumberOfComponents() == 3 && normals->GetNumberOfTuples() == np;
    if (useNormals) {
        m.normals.resize(size_t(np));
        for (vtkIdType i = 0; i < np; ++i) {
            double n[3];
            normals->GetTuple(i, n);
            m.normals[size_t(i)] = Normal3f(float(n[0]), float(n[1]), float(n[2]));
        }
    }
    vtkCellArray* polys = pd->GetPolys();
    auto ids = Ptr<vtkIdList>::New();
    polys->InitTraversal();
    while (polys->GetNextCell(ids)) {
        if (ids->GetNumberOfIds() != 3)
            continue;
        m.triangles.push_back(
            {uint32_t(ids->GetId(0)), uint32_t(ids->GetId(1)), uint32_t(ids->GetId(2))});
    }
    if (hasNormals)
        *hasNormals = useNormals;
    if (!useNormals)
        computeVertexNormals(m);
    return m;
}

/// Removes points no cell uses (filters such as connectivity keep them).
TriangleMesh cleaned(vtkAlgorithmOutput* port, double tolerance) {
    auto clean = Ptr<vtkCleanPolyData>::New();
    clean->SetInputConnection(port);
    clean->SetToleranceIsAbsolute(true);
    clean->SetAbsoluteTolerance(tolerance);
    clean->PointMergingOn();
    clean->Update();
    return fromVtk(clean->GetOutput());
}

}  // namespace

namespace detail {

namespace {

/// What the child process sends back: the reader's output as plain arrays.
struct VtkArrays {
    std::vector<float> points;                  ///< 3 per point
    std::vector<float> normals;                 ///< 3 per point, or empty
    std::vector<int64_t> polyOffsets, polyIds;  ///< cell k: ids [offsets[k], offsets[k+1])
    std::vector<int64_t> stripOffsets, stripIds;
};

template <typename T>
void putArray(std::string& out, const std::vector<T>& v) {
    const uint64_t n = v.size();
    out.append(reinterpret_cast<const char*>(&n), sizeof n);
    out.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

template <typename T>
void getArray(const std::string& in, size_t& pos, std::vector<T>& v) {
    uint64_t n = 0;
    if (in.size() - pos < sizeof n)
        LUCENT_THROW(IoError, "VTK reader result is truncated");
    std::memcpy(&n, in.data() + pos, sizeof n);
    pos += sizeof n;
    if (n > (in.size() - pos) / sizeof(T))
        LUCENT_THROW(IoError, "VTK reader result is truncated");
    v.resize(size_t(n));
    if (n > 0)  // an empty vector's data() may be null, which memcpy must not get
        std::memcpy(v.data(), in.data() + pos, size_t(n) * sizeof(T));
    pos += size_t(n) * sizeof(T);
}

void exportCells(vtkCellArray* cells, std::vector<int64_t>& offsets, std::vector<int64_t>& ids) {
    offsets.assign(1, 0);
    ids.clear();
    if (!cells)
        return;
    auto list = Ptr<vtkIdList>::New();
    cells->InitTraversal();
    while (cells->GetNextCell(list)) {
        for (vtkIdType k = 0; k < list->GetNumberOfIds(); ++k)
            ids.push_back(int64_t(list->GetId(k)));
        offsets.push_back(int64_t(ids.size()));
    }
}

Ptr<vtkCellArray> importCells(const std::vector<int64_t>& offsets,
                              const std::vector<int64_t>& ids) {
    auto cells = Ptr<vtkCellArray>::New();
    std::vector<vtkIdType> cell;
    for (size_t k = 0; k + 1 < offsets.size(); ++k) {
        if (offsets[k] < 0 || offsets[k] > offsets[k + 1] || uint64_t(offsets[k + 1]) > ids.size())
            LUCENT_THROW(IoError, "VTK reader result has inconsistent cells");
        cell.assign(ids.begin() + offsets[k], ids.begin() + offsets[k + 1]);
        cells->InsertNextCell(vtkIdType(cell.size()), cell.data());
    }
    return cells;
}

/// A 3-component array as floats, tuple after tuple.
std::vector<float> flatten3(vtkDataArray* array) {
    const vtkIdType n = array->GetNumberOfTuples();
    std::vector<float> out(size_t(n) * 3);
    for (vtkIdType i = 0; i < n; ++i) {
        double v[3];
        array->GetTuple(i, v);
        for (int k = 0; k < 3; ++k)
            out[size_t(i) * 3 + size_t(k)] = float(v[k]);
    }
    return out;
}

/// Collects the messages of VTK's error events (its readers report most problems only there,
/// e.g. a truncated data array, and still produce an output).
class ErrorLog : public vtkCommand {
public:
    static ErrorLog* New() { return new ErrorLog; }
    void Execute(vtkObject*, unsigned long, void* data) override {
        if (messages.empty() && data)
            messages = static_cast<const char*>(data);
        ++count;
    }
    std::string messages;
    int count = 0;
};

/// Runs in the child process: the VTK reader only (no filters, no thread pools).
std::string readVtkArrays(const std::string& path) {
    // The problems are collected by the observer and reported by the parent: VTK's own log
    // lines on stderr would only repeat them.
    vtkObject::GlobalWarningDisplayOff();
    const std::string ext = std::filesystem::path(path).extension().string();
    auto errors = Ptr<ErrorLog>::New();
    vtkPolyData* pd = nullptr;
    Ptr<vtkAlgorithm> keep;
    if (ext == ".vtp" || ext == ".VTP") {
        auto reader = Ptr<vtkXMLPolyDataReader>::New();
        if (!reader->CanReadFile(path.c_str()))
            LUCENT_THROW(IoError, "not a VTK XML PolyData file");
        reader->AddObserver(vtkCommand::ErrorEvent, errors);
        reader->SetFileName(path.c_str());
        reader->Update();
        if (reader->GetErrorCode() != 0 || errors->count > 0)
            LUCENT_THROW(IoError, "VTK could not parse it", errors->messages.empty() ? "" : ": ",
                         errors->messages);
        pd = reader->GetOutput();
        keep = reader;
    } else {
        auto reader = Ptr<vtkPolyDataReader>::New();
        reader->AddObserver(vtkCommand::ErrorEvent, errors);
        reader->SetFileName(path.c_str());
        if (!reader->IsFilePolyData())
            LUCENT_THROW(IoError, "not a legacy VTK POLYDATA file");
        reader->Update();
        if (reader->GetErrorCode() != 0 || errors->count > 0)
            LUCENT_THROW(IoError, "VTK could not parse it", errors->messages.empty() ? "" : ": ",
                         errors->messages);
        pd = reader->GetOutput();
        keep = reader;
    }
    if (!pd || !pd->GetPoints())
        LUCENT_THROW(IoError, "VTK found no points");
    VtkArrays a;
    const vtkIdType np = pd->GetNumberOfPoints();
    a.points = flatten3(pd->GetPoints()->GetData());
    vtkDataArray* normals = pd->GetPointData() ? pd->GetPointData()->GetNormals() : nullptr;
    if (normals && normals->GetNumberOfComponents() == 3 && normals->GetNumberOfTuples() == np)
        a.normals = flatten3(normals);
    for (vtkCellArray* cells : {pd->GetPolys(), pd->GetStrips()})
        if (cells && !cells->IsValid())
            LUCENT_THROW(IoError, "cells with inconsistent offsets (corrupt)");
    exportCells(pd->GetPolys(), a.polyOffsets, a.polyIds);
    exportCells(pd->GetStrips(), a.stripOffsets, a.stripIds);
    std::string out;
    putArray(out, a.points);
    putArray(out, a.normals);
    putArray(out, a.polyOffsets);
    putArray(out, a.polyIds);
    putArray(out, a.stripOffsets);
    putArray(out, a.stripIds);
    return out;
}

}  // namespace

RawMesh readVtk(const std::string& path, const ClaimedCounts& claimed) {
    // VTK 9.1's readers trust the sizes in a file (a corrupt compression header made the XML
    // reader allocate 4-13 GB and run for minutes; the legacy reader can crash): they run in a
    // child process with memory and CPU limits (lucent/core/Isolate.h).
    const std::string bytes =
        runIsolated("mesh file '" + path + "': VTK reader", [&] { return readVtkArrays(path); });
    VtkArrays a;
    size_t pos = 0;
    getArray(bytes, pos, a.points);
    getArray(bytes, pos, a.normals);
    getArray(bytes, pos, a.polyOffsets);
    getArray(bytes, pos, a.polyIds);
    getArray(bytes, pos, a.stripOffsets);
    getArray(bytes, pos, a.stripIds);
    const uint64_t np = a.points.size() / 3;
    const uint64_t npolys = a.polyOffsets.empty() ? 0 : a.polyOffsets.size() - 1;
    // A truncated file can read "successfully" with fewer elements than its header claims.
    if (claimed.points && np != claimed.points)
        LUCENT_THROW(IoError, "mesh file '", path, "': the header claims ", claimed.points,
                     " points but VTK read ", np, " (truncated or corrupt)");
    if (claimed.polygons && npolys != claimed.polygons)
        LUCENT_THROW(IoError, "mesh file '", path, "': the header claims ", claimed.polygons,
                     " polygons but VTK read ", npolys, " (truncated or corrupt)");

    auto points = Ptr<vtkPoints>::New();
    points->SetDataTypeToFloat();
    points->SetNumberOfPoints(vtkIdType(np));
    for (uint64_t i = 0; i < np; ++i)
        points->SetPoint(vtkIdType(i), a.points[3 * i], a.points[3 * i + 1], a.points[3 * i + 2]);
    auto pd = Ptr<vtkPolyData>::New();
    pd->SetPoints(points);
    pd->SetPolys(importCells(a.polyOffsets, a.polyIds));
    pd->SetStrips(importCells(a.stripOffsets, a.stripIds));
    if (a.normals.size() == a.points.size() && !a.normals.empty()) {
        auto normals = Ptr<vtkFloatArray>::New();
        normals->SetName("Normals");
        normals->SetNumberOfComponents(3);
        normals->SetNumberOfTuples(vtkIdType(np));
        for (uint64_t i = 0; i < np; ++i)
            normals->SetTypedTuple(vtkIdType(i), &a.normals[3 * i]);
        pd->GetPointData()->SetNormals(normals);
    }
    if (!cellsValid(pd))
        LUCENT_THROW(IoError, "mesh file '", path, "': cells refer to missing points (corrupt)");
    RawMesh raw;
    raw.mesh = fromVtk(pd, &raw.hasNormals);
    return raw;
}

void writeVtk(const TriangleMesh& mesh, const std::string& path, bool binary) {
    auto pd = toVtk(mesh);
    const std::string ext = std::filesystem::path(path).extension().string();
    int ok = 0;
    std::string bytes;
    // Written to memory, then through the checked atomic writer (VTK's own file output does
    // not report a full disk).
    if (ext == ".vtp" || ext == ".VTP") {
        auto w = Ptr<vtkXMLPolyDataWriter>::New();
        w->WriteToOutputStringOn();
        w->SetInputData(pd);
        if (binary)
            w->SetDataModeToAppended();
        else
            w->SetDataModeToAscii();
        ok = w->Write();
        bytes = w->GetOutputString();
    } else {
        auto w = Ptr<vtkPolyDataWriter>::New();
        w->WriteToOutputStringOn();
        w->SetInputData(pd);
        if (binary)
            w->SetFileTypeToBinary();
        else
            w->SetFileTypeToASCII();
        ok = w->Write();
        bytes = w->GetOutputStdString();
    }
    if (!ok || bytes.empty())
        LUCENT_THROW(IoError, "mesh file '", path, "': VTK could not encode it");
    writeFileAtomically(path, bytes);
}

}  // namespace detail

TriangleMesh fillHoles(const TriangleMesh& mesh, float maxHoleSize) {
    LUCENT_CHECK(!mesh.isEmpty(), "fillHoles: the mesh is empty");
    LUCENT_CHECK(std::isfinite(maxHoleSize) && maxHoleSize > 0.f,
                 "fillHoles: maxHoleSize must be > 0 mm, got ", maxHoleSize);
    auto fill = Ptr<vtkFillHolesFilter>::New();
    fill->SetInputData(toVtk(mesh));
    fill->SetHoleSize(maxHoleSize);
    // The filter's patches may be oriented either way: make orientation consistent with the
    // rest of the mesh (vtkPolyDataNormals consistency pass, no splitting at sharp edges).
    auto orient = Ptr<vtkPolyDataNormals>::New();
    orient->SetInputConnection(fill->GetOutputPort());
    orient->ConsistencyOn();
    orient->SplittingOff();
    orient->ComputePointNormalsOn();
    return cleaned(orient->GetOutputPort(), 0.0);
}

TriangleMesh cleanMesh(const TriangleMesh& mesh, float tolerance) {
    LUCENT_CHECK(!mesh.isEmpty(), "cleanMesh: the mesh is empty");
    LUCENT_CHECK(std::isfinite(tolerance) && tolerance >= 0.f,
                 "cleanMesh: tolerance must be ≥ 0 mm, got ", tolerance);
    auto src = Ptr<vtkTriangleFilter>::New();  // a pipeline source for cleaned()
    src->SetInputData(toVtk(mesh));
    return cleaned(src->GetOutputPort(), double(tolerance));
}

TriangleMesh keepLargestComponent(const TriangleMesh& mesh) {
    LUCENT_CHECK(!mesh.isEmpty(), "keepLargestComponent: the mesh is empty");
    auto conn = Ptr<vtkPolyDataConnectivityFilter>::New();
    conn->SetInputData(toVtk(mesh));
    conn->SetExtractionModeToLargestRegion();
    return cleaned(conn->GetOutputPort(), 0.0);
}

}  // namespace lucent

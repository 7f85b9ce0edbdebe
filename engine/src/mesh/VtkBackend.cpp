// SPDX-License-Identifier: MIT
/// @file
/// @brief The VTK boundary (geometry modules only, never VTK's Qt modules): .vtp/.vtk reading
/// and writing, hole filling, cleaning and largest-component extraction.

#include "Backends.h"

#include <lucent/core/Error.h>
#include <lucent/mesh/MeshEdit.h>

#include <vtkCellArray.h>
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
#include <filesystem>

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

RawMesh readVtk(const std::string& path) {
    const std::string ext = std::filesystem::path(path).extension().string();
    Ptr<vtkPolyData> pd;
    if (ext == ".vtp" || ext == ".VTP") {
        auto reader = Ptr<vtkXMLPolyDataReader>::New();
        if (!reader->CanReadFile(path.c_str()))
            LUCENT_THROW(IoError, "mesh file '", path, "': not a VTK XML PolyData file");
        reader->SetFileName(path.c_str());
        reader->Update();
        if (reader->GetErrorCode() != 0 || !reader->GetOutput())
            LUCENT_THROW(IoError, "mesh file '", path, "': VTK could not parse it");
        pd = reader->GetOutput();
    } else {
        auto reader = Ptr<vtkPolyDataReader>::New();
        reader->SetFileName(path.c_str());
        if (!reader->IsFilePolyData())
            LUCENT_THROW(IoError, "mesh file '", path, "': not a legacy VTK POLYDATA file");
        reader->Update();
        if (reader->GetErrorCode() != 0 || !reader->GetOutput())
            LUCENT_THROW(IoError, "mesh file '", path, "': VTK could not parse it");
        pd = reader->GetOutput();
    }
    if (!pd->GetPoints() || !cellsValid(pd))
        LUCENT_THROW(IoError, "mesh file '", path, "': cells refer to missing points (corrupt)");
    RawMesh raw;
    raw.mesh = fromVtk(pd, &raw.hasNormals);
    return raw;
}

void writeVtk(const TriangleMesh& mesh, const std::string& path, bool binary) {
    auto pd = toVtk(mesh);
    const std::string ext = std::filesystem::path(path).extension().string();
    int ok = 0;
    if (ext == ".vtp" || ext == ".VTP") {
        auto w = Ptr<vtkXMLPolyDataWriter>::New();
        w->SetFileName(path.c_str());
        w->SetInputData(pd);
        if (binary)
            w->SetDataModeToAppended();
        else
            w->SetDataModeToAscii();
        ok = w->Write();
    } else {
        auto w = Ptr<vtkPolyDataWriter>::New();
        w->SetFileName(path.c_str());
        w->SetInputData(pd);
        if (binary)
            w->SetFileTypeToBinary();
        else
            w->SetFileTypeToASCII();
        ok = w->Write();
    }
    if (!ok)
        LUCENT_THROW(IoError, "mesh file '", path, "': cannot be written");
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

// SPDX-License-Identifier: MIT
/// @file
/// @brief Writes the legacy VTK regression inputs vtk_tetra_*.vtk (tests/data/robust/README.md)
/// with VTK's own vtkPolyDataWriter: a closed tetrahedron with point normals, a cell scalar and
/// the L2 norm range of its points (a METADATA block), in every version (4.2: cells as counts
/// and ids; 5.1: OFFSETS/CONNECTIVITY) and encoding (ASCII, BINARY) VTK 9.1 writes, and four
/// corrupt twins of each: a point id past the points, a point count past the end of the file,
/// the file cut in the middle of its cells, and inconsistent cells (a cell size past its
/// list in 4.2, decreasing offsets in 5.1). Built on demand:
///
///     cmake --build --preset ci --target make_vtk_tetra
///     build/ci/tests/unit/mesh/make_vtk_tetra tests/data/robust

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkFloatArray.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataWriter.h>
#include <vtkTypeInt64Array.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>

namespace {

/// The tetrahedron (outward, counter-clockwise faces); `lastId` replaces the last point id of
/// the last face and `offsets` the cell offsets (version 5.1 only), for the corrupt twins.
vtkNew<vtkPolyData> tetrahedron(vtkIdType lastId, const vtkTypeInt64 offsets[5]) {
    const double corners[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    vtkNew<vtkPoints> points;
    vtkNew<vtkFloatArray> normals;
    normals->SetName("Normals");
    normals->SetNumberOfComponents(3);
    const double centre = 0.25;  // the centroid is (1/4, 1/4, 1/4)
    for (const auto& c : corners) {
        points->InsertNextPoint(c);
        const double d[3] = {c[0] - centre, c[1] - centre, c[2] - centre};
        const double length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        normals->InsertNextTuple3(d[0] / length, d[1] / length, d[2] / length);
    }
    double range[2];
    points->GetData()->GetRange(range, -1);  // stores L2_NORM_RANGE: the writer's METADATA
    vtkNew<vtkTypeInt64Array> offsetArray, connectivity;
    const vtkTypeInt64 ids[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, vtkTypeInt64(lastId)};
    for (int k = 0; k < 5; ++k)
        offsetArray->InsertNextValue(offsets[k]);
    for (vtkTypeInt64 id : ids)
        connectivity->InsertNextValue(id);
    vtkNew<vtkCellArray> polys;
    polys->SetData(offsetArray, connectivity);
    vtkNew<vtkIntArray> face;
    face->SetName("face");
    for (int k = 0; k < 4; ++k)
        face->InsertNextValue(k);
    vtkNew<vtkPolyData> pd;
    pd->SetPoints(points);
    pd->SetPolys(polys);
    pd->GetPointData()->SetNormals(normals);
    pd->GetCellData()->SetScalars(face);
    return pd;
}

std::string write(vtkPolyData* pd, int version, bool binary) {
    vtkNew<vtkPolyDataWriter> writer;
    writer->SetInputData(pd);
    writer->SetFileVersion(version);
    if (binary)
        writer->SetFileTypeToBinary();
    else
        writer->SetFileTypeToASCII();
    writer->WriteToOutputStringOn();
    if (!writer->Write())
        throw std::runtime_error("vtkPolyDataWriter failed");
    return writer->GetOutputStdString();
}

void save(const std::string& folder, const std::string& name, const std::string& bytes) {
    std::ofstream out(folder + "/" + name, std::ios::binary | std::ios::trunc);
    out << bytes;
    if (!out)
        throw std::runtime_error("cannot write " + folder + "/" + name);
    std::cout << name << " (" << bytes.size() << " bytes)\n";
}

/// Replaces the first `from` at or after `after` in `s`.
std::string replaced(std::string s, const std::string& after, const std::string& from,
                     const std::string& to) {
    const size_t at = s.find(from, s.find(after));
    if (at == std::string::npos)
        throw std::runtime_error("'" + from + "' not found after '" + after + "'");
    return s.replace(at, from.size(), to);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::cerr << "usage: make_vtk_tetra OUTPUT_FOLDER\n";
        return 2;
    }
    const std::string folder = argv[1];
    const vtkTypeInt64 offsets[5] = {0, 3, 6, 9, 12};
    const vtkTypeInt64 decreasing[5] = {0, 3, 9, 6, 12};
    try {
        for (int version : {42, 51}) {
            for (bool binary : {false, true}) {
                const std::string stem = std::string("vtk_tetra_v") + std::to_string(version) +
                                         (binary ? "_binary" : "_ascii");
                const std::string valid = write(tetrahedron(3, offsets), version, binary);
                save(folder, stem + ".vtk", valid);
                save(folder, stem + "_id_past_points.vtk",
                     write(tetrahedron(1000, offsets), version, binary));
                save(folder, stem + "_count_past_end.vtk",
                     replaced(valid, "", "POINTS 4 ", "POINTS 400000 "));
                // Cut in the middle of the last cell section's data.
                const size_t cells = valid.find(version == 42 ? "POLYGONS" : "CONNECTIVITY");
                const size_t data = valid.find('\n', cells) + 1;
                save(folder, stem + "_truncated.vtk", valid.substr(0, data + 20));
                if (version == 51) {
                    save(folder, stem + "_offsets_decreasing.vtk",
                         write(tetrahedron(3, decreasing), version, binary));
                } else {
                    // The first cell's size 3 becomes 16: past the list of 16 entries.
                    const std::string three = binary ? std::string("\0\0\0\3", 4) : "3 ";
                    const std::string sixteen = binary ? std::string("\0\0\0\x10", 4) : "16 ";
                    std::string bad = valid;
                    bad.replace(data, three.size(), sixteen);
                    if (valid.compare(data, three.size(), three) != 0)
                        throw std::runtime_error("unexpected cell list in " + stem);
                    save(folder, stem + "_cell_size_past_list.vtk", bad);
                }
            }
        }
    } catch (const std::exception& e) {
        std::cerr << "make_vtk_tetra: " << e.what() << "\n";
        return 1;
    }
    return 0;
}

#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Writes the generated seed inputs of the fuzz targets into a folder: a closed octahedron
(6 vertices, 8 triangles, radius 10 mm) in every mesh encoding Lucent reads, so that each mesh
target starts from a small valid file of each variant (ASCII and binary PLY/STL/VTK, the three
VTK XML data modes, zlib-compressed appended data), and the project and stale-checksum VDB
seeds. tests/fuzz/CMakeLists.txt runs it at configure time (into <build>/fuzz/seeds/<target>)
and adds the regression inputs of tests/data as further seeds.

    python3 tests/fuzz/make_seeds.py OUTPUT_FOLDER
"""
import base64
import os
import struct
import sys
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SEEDS = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.getcwd(), "seeds")
R = 10.0
VERTS = [(R, 0, 0), (-R, 0, 0), (0, R, 0), (0, -R, 0), (0, 0, R), (0, 0, -R)]
# Outward, counter-clockwise.
FACES = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]


def write(target, name, data):
    folder = os.path.join(SEEDS, target)
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, name), "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)


def normal(f):
    a, b, c = (VERTS[i] for i in f)
    u = [b[k] - a[k] for k in range(3)]
    v = [c[k] - a[k] for k in range(3)]
    n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    length = sum(x * x for x in n) ** 0.5
    return [x / length for x in n]


def obj():
    lines = ["# octahedron"] + ["v %g %g %g" % v for v in VERTS]
    lines += ["vn %g %g %g" % tuple(x / R for x in v) for v in VERTS]
    lines += ["f %d//%d %d//%d %d//%d" % (a + 1, a + 1, b + 1, b + 1, c + 1, c + 1)
              for a, b, c in FACES]
    write("mesh_obj", "octahedron.obj", "\n".join(lines) + "\n")
    # A cube of quads with negative (relative) indices and a group line.
    cube = ["o cube", "g side"]
    cube += ["v %d %d %d" % (x, y, z) for x in (0, 5) for y in (0, 5) for z in (0, 5)]
    quads = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]
    cube += ["f " + " ".join(str(i - 9) for i in q) for q in quads]
    write("mesh_obj", "cube_quads.obj", "\n".join(cube) + "\n")


def off():
    lines = ["OFF", "%d %d 0" % (len(VERTS), len(FACES))]
    lines += ["%g %g %g" % v for v in VERTS] + ["3 %d %d %d" % f for f in FACES]
    write("mesh_off", "octahedron.off", "\n".join(lines) + "\n")


def ply():
    head = ["ply", "format %s 1.0", "comment octahedron", "element vertex %d" % len(VERTS),
            "property float x", "property float y", "property float z",
            "element face %d" % len(FACES), "property list uchar int vertex_indices",
            "end_header"]
    ascii_body = ["%g %g %g" % v for v in VERTS] + ["3 %d %d %d" % f for f in FACES]
    write("mesh_ply", "octahedron_ascii.ply",
          "\n".join(head).replace("%s", "ascii") + "\n" + "\n".join(ascii_body) + "\n")
    for order, name in (("<", "binary_little_endian"), (">", "binary_big_endian")):
        body = b"".join(struct.pack(order + "3f", *v) for v in VERTS)
        body += b"".join(struct.pack(order + "B3i", 3, *f) for f in FACES)
        write("mesh_ply", "octahedron_%s.ply" % name,
              ("\n".join(head).replace("%s", name) + "\n").encode() + body)


def stl():
    lines = ["solid octahedron"]
    for f in FACES:
        lines.append("  facet normal %g %g %g" % tuple(normal(f)))
        lines.append("    outer loop")
        lines += ["      vertex %g %g %g" % VERTS[i] for i in f]
        lines += ["    endloop", "  endfacet"]
    lines.append("endsolid octahedron")
    write("mesh_stl", "octahedron_ascii.stl", "\n".join(lines) + "\n")
    body = b"octahedron".ljust(80, b" ") + struct.pack("<I", len(FACES))
    for f in FACES:
        body += struct.pack("<3f", *normal(f))
        for i in f:
            body += struct.pack("<3f", *VERTS[i])
        body += struct.pack("<H", 0)
    write("mesh_stl", "octahedron_binary.stl", body)


def vtk_legacy():
    head = ["# vtk DataFile Version 4.2", "octahedron", "%s", "DATASET POLYDATA",
            "POINTS %d float" % len(VERTS)]
    ascii_lines = list(head)
    ascii_lines[2] = "ASCII"
    ascii_lines += ["%g %g %g" % v for v in VERTS]
    ascii_lines += ["POLYGONS %d %d" % (len(FACES), 4 * len(FACES))]
    ascii_lines += ["3 %d %d %d" % f for f in FACES]
    ascii_lines += ["POINT_DATA %d" % len(VERTS), "NORMALS Normals float"]
    ascii_lines += ["%g %g %g" % tuple(x / R for x in v) for v in VERTS]
    write("mesh_vtk", "octahedron_ascii.vtk", "\n".join(ascii_lines) + "\n")
    # VTK 4.2 legacy binary: big-endian values; polygons as "n i j k" int32 records.
    binary = list(head)
    binary[2] = "BINARY"
    data = ("\n".join(binary) + "\n").encode()
    data += b"".join(struct.pack(">3f", *v) for v in VERTS)
    data += ("\nPOLYGONS %d %d\n" % (len(FACES), 4 * len(FACES))).encode()
    data += b"".join(struct.pack(">4i", 3, *f) for f in FACES) + b"\n"
    write("mesh_vtk", "octahedron_binary.vtk", data)


def vtp():
    points = [x for v in VERTS for x in v]
    conn = [i for f in FACES for i in f]
    offs = [3 * (k + 1) for k in range(len(FACES))]
    arrays = [("Float32", "Points", 3, struct.pack("<%df" % len(points), *points)),
              ("Int64", "connectivity", 1, struct.pack("<%dq" % len(conn), *conn)),
              ("Int64", "offsets", 1, struct.pack("<%dq" % len(offs), *offs))]

    def document(tags, compressor="", appended=b""):
        attrs = ' compressor="vtkZLibDataCompressor"' if compressor else ""
        text = ('<?xml version="1.0"?>\n<VTKFile type="PolyData" version="1.0" '
                'byte_order="LittleEndian" header_type="UInt32"%s>\n  <PolyData>\n'
                '    <Piece NumberOfPoints="%d" NumberOfVerts="0" NumberOfLines="0" '
                'NumberOfStrips="0" NumberOfPolys="%d">\n      <Points>\n        %s\n'
                '      </Points>\n      <Polys>\n        %s\n        %s\n      </Polys>\n'
                '    </Piece>\n  </PolyData>\n' % (attrs, len(VERTS), len(FACES), *tags))
        if appended:
            return text.encode() + b'  <AppendedData encoding="raw">\n   _' + appended + \
                b"\n  </AppendedData>\n</VTKFile>\n"
        return (text + "</VTKFile>\n").encode()

    def tag(a, fmt, payload="", offset=None):
        kind, name, comps, _ = a
        extra = ' NumberOfComponents="%d"' % comps if comps > 1 else ""
        if offset is not None:
            return ('<DataArray type="%s" Name="%s"%s format="appended" offset="%d"/>'
                    % (kind, name, extra, offset))
        return ('<DataArray type="%s" Name="%s"%s format="%s">%s</DataArray>'
                % (kind, name, extra, fmt, payload))

    def ascii_values(a):
        kind, _, _, raw = a
        code = "f" if kind == "Float32" else "q"
        values = struct.unpack("<%d%s" % (len(raw) // struct.calcsize(code), code), raw)
        return " ".join("%g" % v for v in values)

    write("mesh_vtp", "octahedron_ascii.vtp",
          document([tag(a, "ascii", ascii_values(a)) for a in arrays]))
    write("mesh_vtp", "octahedron_base64.vtp", document(
        [tag(a, "binary", base64.b64encode(struct.pack("<I", len(a[3])) + a[3]).decode())
         for a in arrays]))
    blob, tags = b"", []
    for a in arrays:
        tags.append(tag(a, "", offset=len(blob)))
        blob += struct.pack("<I", len(a[3])) + a[3]
    write("mesh_vtp", "octahedron_appended_raw.vtp", document(tags, appended=blob))
    blob, tags = b"", []
    for a in arrays:
        packed = zlib.compress(a[3])
        tags.append(tag(a, "", offset=len(blob)))
        # One block: count, uncompressed block size, size of the last block, compressed sizes.
        blob += struct.pack("<4I", 1, len(a[3]), len(a[3]), len(packed)) + packed
    write("mesh_vtp", "octahedron_appended_zlib.vtp",
          document(tags, compressor="zlib", appended=blob))


def vdb_and_project():
    with open(os.path.join(ROOT, "tests", "data", "robust", "material_sphere16.vdb"), "rb") as f:
        vdb = bytearray(f.read())
    # Header: magic (8), file version (4), library version (8), has grid offsets (1), then the
    # 36-character UUID. Another UUID is what a file rewritten by another tool has: the Lucent
    # checksum is then ignored, so mutations reach the integrity walk and the content checks.
    stale = bytearray(vdb)
    stale[21] = ord("0") if stale[21] != ord("0") else ord("1")
    write("vdb", "material_sphere16_stale_checksum.vdb", bytes(stale))
    project = ('{\n  "version": 1,\n  "mesh": {"file": "sphere_closed.off", "scale": 1.0},\n'
               '  "material": {"vdb": "project.vdb"},\n  "resolution": 16,\n  "eta": 1.3,\n'
               '  "lights": [{"type": "spot", "position": [30, 30, 30], "direction": [-1, -1, -1],'
               ' "intensity": [1e4, 1e4, 1e4], "inner_deg": 10, "outer_deg": 20}],\n'
               '  "environment": {"radiance": [0.1, 0.1, 0.1]},\n'
               '  "camera": {"position": [0, 0, 60], "target": [0, 0, 0], "up": [0, 1, 0],'
               ' "width": 8, "height": 8, "near": 0.1, "far": 1000, "fov_y_deg": 40}\n}\n')
    separator = b"\n=== project.vdb ===\n"  # must match SIDECAR_SEPARATOR in fuzz_project.cpp
    write("project", "project.bin", project.encode() + separator + bytes(vdb))
    write("project", "project_stale_checksum.bin", project.encode() + separator + bytes(stale))


if __name__ == "__main__":
    obj()
    off()
    ply()
    stl()
    vtk_legacy()
    vtp()
    vdb_and_project()

#!/usr/bin/env python3
"""Writes a curvilinear grid in every .vts encoding (with VTK's own writer) and as Plot3D
(called by tests/curvilinear.rs).

usage: write_curvilinear.py IN.json OUTDIR
IN.json: {"dims": [nx, ny, nz], "points": [[x, y, z], ...] (x fastest),
          "fields": {"name": [...], ...}, "order": ["name", ...]}
(at least five fields for the .q file; "order" is the order of the arrays and variables)
Writes into OUTDIR:
* <mode>.vts for every mode in MODES (Float64 points and fields);
* twin.vts (Float32, appended raw zlib) and its Plot3D twins, all Float32:
  twin.xyz + twin.q (big-endian, no record markers, whole: as the blunt-fin files),
  rec.xyz + rec.f (little-endian, Fortran record markers, planes, 2 variables, IBLANK).
Prints the file names.
"""
import json
import struct
import sys

import numpy as np
import vtk
from vtk.util.numpy_support import numpy_to_vtk

MODES = {
    # name: (data mode, compressor, encode appended, header UInt64, big endian)
    "ascii": ("ascii", None, False, False, False),
    "binary": ("binary", None, False, False, False),
    "binary_zlib": ("binary", "zlib", False, False, False),
    "binary_zlib64": ("binary", "zlib", False, True, False),
    "appended_raw": ("appended", None, False, False, False),
    "appended_raw_zlib": ("appended", "zlib", False, False, False),
    "appended_raw64_be": ("appended", None, False, True, True),
    "appended_b64": ("appended", None, True, False, False),
    "appended_b64_zlib": ("appended", "zlib", True, False, False),
}


def grid(dims, pts, fields, dtype):
    g = vtk.vtkStructuredGrid()
    g.SetDimensions(*dims)
    p = vtk.vtkPoints()
    p.SetData(numpy_to_vtk(np.ascontiguousarray(pts, dtype=dtype), deep=True))
    g.SetPoints(p)
    for name, v in fields.items():
        a = numpy_to_vtk(np.ascontiguousarray(v, dtype=dtype), deep=True)
        a.SetName(name)
        g.GetPointData().AddArray(a)
    return g


def write_vts(path, g, mode):
    data, comp, encode, h64, be = mode
    w = vtk.vtkXMLStructuredGridWriter()
    w.SetFileName(path)
    w.SetInputData(g)
    {"ascii": w.SetDataModeToAscii, "binary": w.SetDataModeToBinary,
     "appended": w.SetDataModeToAppended}[data]()
    w.SetCompressorTypeToZLib() if comp else w.SetCompressorTypeToNone()
    if comp:
        w.SetBlockSize(4096)  # several blocks, a short last one
    w.SetEncodeAppendedData(1 if encode else 0)
    w.SetHeaderTypeToUInt64() if h64 else w.SetHeaderTypeToUInt32()
    w.SetByteOrderToBigEndian() if be else w.SetByteOrderToLittleEndian()
    assert w.Write() == 1, path


def rec(endian, payload):
    return struct.pack(endian + "i", len(payload)) + payload + struct.pack(endian + "i", len(payload))


def plot3d(out, dims, pts, fields):
    nx, ny, nz = dims
    names = list(fields)
    # blunt-fin style: big-endian, no markers, whole
    xyz = np.asarray(pts, ">f4")
    with open(f"{out}/twin.xyz", "wb") as f:
        f.write(struct.pack(">3i", *dims))
        for a in range(3):
            f.write(xyz[:, a].tobytes())
    with open(f"{out}/twin.q", "wb") as f:
        f.write(struct.pack(">3i", *dims))
        f.write(np.asarray([0.3, 5.0, 1e6, 0.0], ">f4").tobytes())
        for name in names[:5]:
            f.write(np.asarray(fields[name], ">f4").tobytes())
    # little-endian, Fortran records, planes, IBLANK
    xyz = np.asarray(pts, "<f4").reshape(nz, ny * nx, 3)
    with open(f"{out}/rec.xyz", "wb") as f:
        f.write(rec("<", struct.pack("<3i", *dims)))
        for k in range(nz):
            plane = b"".join(xyz[k, :, a].tobytes() for a in range(3))
            plane += np.ones(nx * ny, "<i4").tobytes()
            f.write(rec("<", plane))
    with open(f"{out}/rec.f", "wb") as f:
        f.write(rec("<", struct.pack("<4i", nx, ny, nz, 2)))
        for k in range(nz):
            plane = b"".join(
                np.asarray(fields[n], "<f4").reshape(nz, -1)[k].tobytes() for n in names[:2]
            )
            f.write(rec("<", plane))


def main():
    spec = json.load(open(sys.argv[1]))
    out = sys.argv[2]
    dims, pts = spec["dims"], spec["points"]
    fields = {n: spec["fields"][n] for n in spec["order"]}
    g = grid(dims, pts, fields, np.float64)
    for name, mode in MODES.items():
        write_vts(f"{out}/{name}.vts", g, mode)
        print(f"{name}.vts")
    write_vts(f"{out}/twin.vts", grid(dims, pts, fields, np.float32), ("appended", "zlib", False, False, False))
    plot3d(out, dims, pts, fields)
    print("twin.vts twin.xyz twin.q rec.xyz rec.f")


main()

#!/usr/bin/env python3
"""VTK peer for the tptd-mesh benchmark.

  mesh:      python3 vtk_peer.py mesh INPUT OUT.vtu [--alpha A] [--beta B]
  inverted:  python3 vtk_peer.py inverted MESH.vtu

`mesh` is timed end to end by run.py as a fresh process (interpreter start,
`import vtk`, read, clip, write), exactly like tptd-mesh.  It

  1. reads the volume (.npy with numpy, .nii/.nii.gz with nibabel), casts to
     float32 (tptd-mesh converts to f64 internally; VTK is given the cheaper
     type) and wraps it zero-copy in a vtkImageData (unit spacing, origin 0);
  2. vtkClipVolume with Mixed3DCellGeneration(0) (tetrahedra only):
       [A, inf)   value A, InsideOut off
       (-inf, B]  value B, InsideOut on
       [A, B]     value A, then vtkClipDataSet(value B, InsideOut on) on the
                  tet output; that clip emits wedges, so vtkDataSetTriangleFilter
                  (TetrahedraOnly) turns everything back into tets;
  3. writes binary (appended raw) .vtu with vtkXMLUnstructuredGridWriter.

It prints one JSON line on stdout: cell counts by type and stage timings.

`inverted` counts tets with negative signed volume (VTK convention: (p0,p1,p2)
counter-clockwise seen from p3) in any tet .vtu, with numpy; not timed.
"""
import json
import sys
import time
import warnings

warnings.filterwarnings("ignore", category=DeprecationWarning)

T0 = time.perf_counter()


def read_volume(path):
    import numpy as np
    if path.endswith(".npy"):
        a = np.load(path, mmap_mode="r")
        # C order, last axis fastest -> VTK x = last numpy axis
        a = np.ascontiguousarray(a, dtype=np.float32)
        dims = a.shape[::-1]
        flat = a.reshape(-1)
    elif path.endswith(".nii") or path.endswith(".nii.gz"):
        import nibabel as nib
        img = nib.load(path)
        a = np.asarray(img.dataobj)
        while a.ndim > 3 and a.shape[-1] == 1:
            a = a[..., 0]
        # NIfTI: first index (i) fastest -> Fortran ravel, VTK x = i
        dims = a.shape
        flat = np.asarray(a, dtype=np.float32).ravel(order="F")
    else:
        raise SystemExit("vtk_peer: unsupported input " + path)
    return dims, np.ascontiguousarray(flat)


def cell_type_counts(ug):
    import numpy as np
    from vtkmodules.util.numpy_support import vtk_to_numpy
    n = ug.GetNumberOfCells()
    if n == 0:
        return {}
    types = vtk_to_numpy(ug.GetCellTypesArray())
    vals, counts = np.unique(types, return_counts=True)
    names = {10: "tetra", 13: "wedge", 14: "pyramid", 12: "hexahedron", 5: "triangle", 3: "line", 1: "vertex"}
    return {names.get(int(v), str(int(v))): int(c) for v, c in zip(vals, counts)}


def mesh(inp, out, alpha, beta):
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkFiltersGeneral import vtkClipVolume, vtkClipDataSet
    from vtkmodules.vtkFiltersGeneral import vtkDataSetTriangleFilter
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridWriter
    from vtkmodules.util.numpy_support import numpy_to_vtk
    t_import = time.perf_counter()

    dims, flat = read_volume(inp)
    img = vtkImageData()
    img.SetDimensions(*[int(d) for d in dims])
    img.SetSpacing(1.0, 1.0, 1.0)
    img.SetOrigin(0.0, 0.0, 0.0)
    arr = numpy_to_vtk(flat, deep=0)
    arr.SetName("f")
    img.GetPointData().SetScalars(arr)
    t_read = time.perf_counter()

    clip = vtkClipVolume()
    clip.SetInputData(img)
    clip.SetMixed3DCellGeneration(0)
    clip.GenerateClipScalarsOff()
    if alpha is not None:
        clip.SetValue(alpha)
        clip.InsideOutOff()
    else:
        clip.SetValue(beta)
        clip.InsideOutOn()
    clip.Update()
    ug = clip.GetOutput()
    stages = {"clip1": time.perf_counter() - t_read}
    if alpha is not None and beta is not None:
        t1 = time.perf_counter()
        c2 = vtkClipDataSet()
        c2.SetInputData(ug)
        c2.SetValue(beta)
        c2.InsideOutOn()
        c2.Update()
        after_clip2 = cell_type_counts(c2.GetOutput())
        t2 = time.perf_counter()
        tri = vtkDataSetTriangleFilter()
        tri.SetInputConnection(c2.GetOutputPort())
        tri.TetrahedraOnlyOn()
        tri.Update()
        ug = tri.GetOutput()
        stages["clip2"] = t2 - t1
        stages["to_tets"] = time.perf_counter() - t2
        stages["clip2_cell_types"] = after_clip2
    t_mesh = time.perf_counter()

    w = vtkXMLUnstructuredGridWriter()
    w.SetFileName(out)
    w.SetInputData(ug)
    w.SetDataModeToAppended()
    w.EncodeAppendedDataOff()
    w.SetCompressorTypeToNone()
    if w.Write() != 1:
        raise SystemExit("vtk_peer: write failed")
    t_write = time.perf_counter()

    print(json.dumps({
        "nodes": ug.GetNumberOfPoints(),
        "cells_out": ug.GetNumberOfCells(),
        "cell_types": cell_type_counts(ug),
        "dims": [int(d) for d in dims],
        "timings": {"startup_import": t_import - T0, "read": t_read - t_import,
                    "mesh": t_mesh - t_read, "write": t_write - t_mesh, "total": t_write - T0,
                    "stages": stages},
    }))


def inverted(path):
    import numpy as np
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
    from vtkmodules.util.numpy_support import vtk_to_numpy
    r = vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    ug = r.GetOutput()
    pts = vtk_to_numpy(ug.GetPoints().GetData()).astype(np.float64)
    types = vtk_to_numpy(ug.GetCellTypesArray())
    cells = ug.GetCells()
    conn = vtk_to_numpy(cells.GetConnectivityArray())
    offs = vtk_to_numpy(cells.GetOffsetsArray())
    is_tet = types == 10
    if not np.all(np.diff(offs)[is_tet] == 4):
        raise SystemExit("vtk_peer: inconsistent tet offsets")
    starts = offs[:-1][is_tet]
    idx = conn[starts[:, None] + np.arange(4)[None, :]]
    vol = np.zeros(len(idx))
    chunk = 4_000_000
    for s in range(0, len(idx), chunk):
        q = pts[idx[s:s + chunk]]
        e1, e2, e3 = q[:, 1] - q[:, 0], q[:, 2] - q[:, 0], q[:, 3] - q[:, 0]
        vol[s:s + chunk] = np.einsum("ij,ij->i", np.cross(e1, e2), e3) / 6.0
    print(json.dumps({
        "tets": int(len(vol)),
        "non_tets": int((~is_tet).sum()),
        "negative": int((vol < 0).sum()),
        "negative_gt_1e-6": int((vol < -1e-6).sum()),   # clearly inverted (> 1e-6 voxel volumes)
        "zero": int((vol == 0).sum()),
        "positive": int((vol > 0).sum()),
        "total_volume": float(vol.sum()),
        "abs_volume": float(np.abs(vol).sum()),
    }))


def main(argv):
    if len(argv) >= 2 and argv[1] == "inverted":
        return inverted(argv[2])
    if len(argv) >= 4 and argv[1] == "mesh":
        inp, out = argv[2], argv[3]
        alpha = beta = None
        rest = argv[4:]
        i = 0
        while i < len(rest):
            if rest[i] == "--alpha":
                alpha = float(rest[i + 1]); i += 2
            elif rest[i] == "--beta":
                beta = float(rest[i + 1]); i += 2
            else:
                raise SystemExit("vtk_peer: unknown argument " + rest[i])
        if alpha is None and beta is None:
            raise SystemExit("vtk_peer: need --alpha and/or --beta")
        return mesh(inp, out, alpha, beta)
    raise SystemExit(__doc__)


if __name__ == "__main__":
    main(sys.argv)

#!/usr/bin/env python3
"""Write time and size of each .vtu encoding: tptd-mesh against VTK's own XML writer.

For each volume, tptd-mesh meshes the interval once per encoding (--vtu-encoding base64,
zlib, raw; -j 2, --no-analysis) and its write time is read from the JSON report. The raw
mesh is then read with VTK and written again by vtkXMLUnstructuredGridWriter in the same
three encodings (appended data; zlib level 5, 32 KiB blocks, VTK's defaults), timed in the
same run. Meshes go to a temporary folder and are deleted.

Usage:
  python3 benchmarks/make_data.py --sizes 256      # the noisy volume
  python3 benchmarks/vtu_encodings.py [--bin target/release/tptd-mesh]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
ENCODINGS = ["base64", "zlib", "raw"]


def volumes():
    import nilearn
    mni = os.path.join(os.path.dirname(nilearn.__file__), "datasets", "data")
    return [
        ("MNI152 white matter [127.5, inf)",
         os.path.join(mni, "mni_icbm152_wm_tal_nlin_sym_09a_converted.nii.gz"), ["--alpha", "127.5"]),
        ("noisy distance field 256³ [-2, 2]",
         os.path.join(HERE, "data", "noisy_256.npy"), ["--alpha", "-2", "--beta", "2"]),
    ]


def vtk_write(grid, path, encoding):
    import vtk
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetFileName(path)
    w.SetInputData(grid)
    w.SetDataModeToAppended()
    w.SetHeaderTypeToUInt64()
    w.SetEncodeAppendedData(encoding != "raw")
    if encoding == "zlib":
        w.SetCompressorTypeToZLib()
        w.SetCompressionLevel(5)
    else:
        w.SetCompressorTypeToNone()
    t = time.perf_counter()
    ok = w.Write()
    secs = time.perf_counter() - t
    assert ok == 1, f"VTK failed to write {path}"
    return secs, os.path.getsize(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=os.path.join(REPO, "target", "release", "tptd-mesh"))
    args = ap.parse_args()
    import vtk
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, path, interval in volumes():
            if not os.path.isfile(path):
                print(f"missing {path} (run benchmarks/make_data.py)", file=sys.stderr)
                continue
            ours = {}
            for enc in ENCODINGS:
                out = os.path.join(tmp, f"m.{enc}.vtu")
                rep = os.path.join(tmp, "r.json")
                subprocess.run([args.bin, path, "-o", out, "--vtu-encoding", enc, "-j", "2",
                                "--no-analysis", "-q", "--report", rep] + interval, check=True)
                with open(rep) as f:
                    r = json.load(f)
                ours[enc] = (r["timings_seconds"]["write"], os.path.getsize(out), r["tets"])
            reader = vtk.vtkXMLUnstructuredGridReader()
            reader.SetFileName(os.path.join(tmp, "m.raw.vtu"))
            reader.Update()
            grid = reader.GetOutput()
            for enc in ENCODINGS:
                vs, vsize = vtk_write(grid, os.path.join(tmp, f"vtk.{enc}.vtu"), enc)
                s, size, tets = ours[enc]
                rows.append((name, tets, enc, s, size, vs, vsize))
                os.remove(os.path.join(tmp, f"vtk.{enc}.vtu"))
            for enc in ENCODINGS:
                os.remove(os.path.join(tmp, f"m.{enc}.vtu"))
    print("| volume | tets | encoding | tptd-mesh write s | size MB | VTK write s | VTK size MB |")
    print("|---|--:|---|--:|--:|--:|--:|")
    for name, tets, enc, s, size, vs, vsize in rows:
        print(f"| {name} | {tets / 1e6:.2f} M | {enc} | {s:.2f} | {size / 1e6:.0f} | {vs:.2f} | {vsize / 1e6:.0f} |")


if __name__ == "__main__":
    main()

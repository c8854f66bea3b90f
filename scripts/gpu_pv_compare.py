# SPDX-License-Identifier: BSD-3-Clause
"""Every PNG under GPU_DIR against the PNG of the same relative path under CPU_DIR (pvpython: VTK's
PNG reader and numpy): the largest difference over every channel of every pixel must be at most
TOLERANCE/255 (scripts/gpu_pv_check.sh, the same frame cast on the GPU and on the CPU). vtkTesting's
own outputs (*.diff.png, *.valid*.png) are left out. One "[pv gpu-vs-cpu]" line per image; exit
status 1 when an image differs more, has no CPU counterpart or differs in size, or when there is
none to compare.

    pvpython gpu_pv_compare.py CPU_DIR GPU_DIR TOLERANCE
"""
import os
import sys

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOImage import vtkPNGReader


def read(png):
    r = vtkPNGReader()
    r.SetFileName(png)
    r.Update()
    image = r.GetOutput()
    w, h, _ = image.GetDimensions()
    a = vtk_to_numpy(image.GetPointData().GetScalars())
    return a.reshape(h, w, -1)[:, :, :3].astype(int)


def main():
    cpu_dir, gpu_dir, tolerance = sys.argv[1], sys.argv[2], int(sys.argv[3])
    compared = worst_all = bad = 0
    for folder, _, files in sorted(os.walk(gpu_dir)):
        for name in sorted(files):
            if not name.endswith(".png") or ".diff." in name or ".valid" in name:
                continue
            gpu = os.path.join(folder, name)
            rel = os.path.relpath(gpu, gpu_dir)
            cpu = os.path.join(cpu_dir, rel)
            if not os.path.isfile(cpu):
                print("[pv gpu-vs-cpu] %s: no CPU image FAILED" % rel)
                bad += 1
                continue
            a, b = read(gpu), read(cpu)
            if a.shape != b.shape:
                print("[pv gpu-vs-cpu] %s: %s against the CPU's %s FAILED" % (rel, a.shape, b.shape))
                bad += 1
                continue
            d = np.abs(a - b)
            worst = int(d.max())
            lit = int((np.abs(a - a[0, 0]).max(axis=2) > 8).sum())  # pixels unlike the corner's
            ok = worst <= tolerance
            print("[pv gpu-vs-cpu] %s: max |diff| %d/255, %d channel values differ, %d pixels drawn "
                  "(bar %d/255)%s" % (rel, worst, int((d > 0).sum()), lit, tolerance, "" if ok else " FAILED"))
            compared += 1
            worst_all = max(worst_all, worst)
            bad += 0 if ok else 1
    print("%d images compared, worst %d/255, %d failed" % (compared, worst_all, bad))
    sys.exit(1 if bad or compared == 0 else 0)


if __name__ == "__main__":
    main()

# SPDX-License-Identifier: BSD-3-Clause
"""One encode by the plugin's filter and writer, run by TestAFAMEncodeMPI.py under pvbatch on one
process or under mpirun on several ranks:

    pvbatch afam_encode_case.py PLUGIN OUT.afam RESULT.json CASE [ARRAY | FOLDER]

CASE wavelet: ParaView's Wavelet over [-40, 39] x [-37, 40] x [-35, 36] (80 x 78 x 72; ParaView
splits it along x, its longest axis), 3 levels of 5 finest blocks. CASE masked: the same Wavelet
with missing samples marked three ways (MASK_SCRIPT, on each rank's piece), encoded with
MissingValue -999. CASE rank0, allempty, hole: a
programmable source whose only piece is rank 0's (20 x 18 x 16); allempty says the whole
extent is empty, hole that it is one plane taller than that piece. CASE series: the .vti files of
FOLDER as a file series (ParaView's XML reader reads each rank's piece of each step), encoded as
one run of its steps, 2 levels of 2 finest blocks. RESULT.json (rank 0): the piece
the first rank encoded from, the bytes it read from other ranks and the encode's wall time."""
import glob
import json
import os
import sys
import time

from paraview.simple import (LoadPlugin, ProgrammableFilter, ProgrammableSource, SaveData, Wavelet,
                             XMLImageDataReader)

plugin, out, result, case = sys.argv[1:5]
array = sys.argv[5] if len(sys.argv) > 5 else None
LoadPlugin(plugin, remote=False, ns=globals())

PIECE_SCRIPT = """
import math
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkParallelCore import vtkMultiProcessController
controller = vtkMultiProcessController.GetGlobalController()
if controller is None or controller.GetLocalProcessId() == 0:
    out = self.GetOutput()
    out.SetExtent(0, 19, 0, 17, 0, 15)
    values = vtkFloatArray()
    values.SetName("f")
    values.SetNumberOfTuples(20 * 18 * 16)
    for i in range(20 * 18 * 16):
        x, y, z = i % 20, (i // 20) % 18, i // 360
        values.SetValue(i, math.sin(0.3 * x) * math.cos(0.2 * y) + 0.05 * z)
    out.GetPointData().SetScalars(values)
"""
# Missing samples of the Wavelet, marked three ways: NaN in a ball of radius 12 at the centre, 0 in
# vtkValidPointMask (signed char) where x > 25, and -999 where y > 30 (MissingValue).
MASK_SCRIPT = """
import numpy as np
from vtkmodules.util import numpy_support as ns
image = self.GetInputDataObject(0, 0)
out = self.GetOutputDataObject(0)
out.ShallowCopy(image)
e, o, s = image.GetExtent(), image.GetOrigin(), image.GetSpacing()
z, y, x = np.meshgrid(*[o[a] + s[a] * np.arange(e[2 * a], e[2 * a + 1] + 1) for a in (2, 1, 0)],
                      indexing="ij")
x, y, z = x.ravel(), y.ravel(), z.ravel()
v = ns.vtk_to_numpy(image.GetPointData().GetArray("RTData")).astype(np.float32)
ball = x * x + y * y + z * z < 144
v[ball] = np.nan
v[(y > 30) & ~ball] = -999
values = ns.numpy_to_vtk(v, deep=1)
values.SetName("RTData")
mask = ns.numpy_to_vtk((x <= 25).astype(np.int8), deep=1)
mask.SetName("vtkValidPointMask")
out.GetPointData().SetScalars(values)
out.GetPointData().AddArray(mask)
"""
WHOLE = {"rank0": "0, 19, 0, 17, 0, 15", "allempty": "0, -1, 0, -1, 0, -1", "hole": "0, 19, 0, 17, 0, 16"}

if case in ("wavelet", "masked"):
    source = Wavelet(WholeExtent=[-40, 39, -37, 40, -35, 36])
    levels, blocks = 3, 5
    if case == "masked":
        source = ProgrammableFilter(Input=source, Script=MASK_SCRIPT)
elif case == "series":
    source = XMLImageDataReader(FileName=sorted(glob.glob(os.path.join(array, "*.vti"))))
    levels, blocks = 2, 2
    array = None
else:
    source = ProgrammableSource(
        OutputDataSetType="vtkImageData", Script=PIECE_SCRIPT,
        ScriptRequestInformation="executive = self.GetExecutive()\n"
        "executive.GetOutputInformation(0).Set(executive.WHOLE_EXTENT(), %s)\n" % WHOLE[case])
    levels, blocks = 2, 2  # the active scalars: the array is unknown before the script runs
encoder = AdaptiveFAMEncoder(Input=source, ErrorBound=1e-3, RelativeBound=1,  # noqa: F821 (plugin)
                             Levels=levels, BlocksPerAxis=blocks, NumberOfThreads=1)
if case in ("wavelet", "masked"):
    encoder.Scalars = ["POINTS", array or "RTData"]
if case == "masked":
    encoder.UseMissingValue = 1
    encoder.MissingValue = -999
t0 = time.time()
SaveData(out, proxy=encoder)
seconds = time.time() - t0
encoder.UpdatePropertyInformation()
with open(result, "w") as f:
    json.dump({"piece": list(encoder.GetProperty("LastPieceExtent").GetData()),
               "remote_bytes": encoder.GetProperty("LastRemoteBytesRead").GetData(),
               "seconds": seconds}, f)

# SPDX-License-Identifier: BSD-3-Clause
"""One encode by the plugin's filter and writer, run by TestAFAMEncodeMPI.py under pvbatch on one
process or under mpirun on several ranks:

    pvbatch afam_encode_case.py PLUGIN OUT.afam RESULT.json CASE [ARRAY | FOLDER]

CASE wavelet: ParaView's Wavelet over [-40, 39] x [-37, 40] x [-35, 36] (80 x 78 x 72; ParaView
splits it along x, its longest axis), 3 levels of 5 finest blocks. CASE rank0, allempty, hole: a
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

from paraview.simple import LoadPlugin, ProgrammableSource, SaveData, Wavelet, XMLImageDataReader

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
WHOLE = {"rank0": "0, 19, 0, 17, 0, 15", "allempty": "0, -1, 0, -1, 0, -1", "hole": "0, 19, 0, 17, 0, 16"}

if case == "wavelet":
    source = Wavelet(WholeExtent=[-40, 39, -37, 40, -35, 36])
    levels, blocks = 3, 5
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
if case == "wavelet":
    encoder.Scalars = ["POINTS", array or "RTData"]
t0 = time.time()
SaveData(out, proxy=encoder)
seconds = time.time() - t0
encoder.UpdatePropertyInformation()
with open(result, "w") as f:
    json.dump({"piece": list(encoder.GetProperty("LastPieceExtent").GetData()),
               "remote_bytes": encoder.GetProperty("LastRemoteBytesRead").GetData(),
               "seconds": seconds}, f)

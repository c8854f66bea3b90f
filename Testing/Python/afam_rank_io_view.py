# SPDX-License-Identifier: BSD-3-Clause
"""Run by TestAFAMRankIO.py as `pvbatch --symmetric afam_rank_io_view.py FILE.afam OUT.json` (one
rank, or several under mpirun): every rank renders one cold frame of FILE with the test camera and
reports the bytes of micro-models its own mapper read, the blocks it drew and the image; rank 0
writes the per-rank figures to OUT.json. Then the images of two more views: maximum intensity
blending, and the camera inside the volume (composite)."""
import json
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

from paraview import servermanager  # noqa: E402
from paraview.simple import CreateView, GetSettingsProxy, OpenDataFile, Render, SaveScreenshot, Show  # noqa: E402

path, result = sys.argv[1], sys.argv[2]
controller = servermanager.vtkProcessModule.GetProcessModule().GetGlobalController()
rank, ranks = controller.GetLocalProcessId(), controller.GetNumberOfProcesses()
u.load_plugin(globals())
GetSettingsProxy("RenderViewSettings").UseFXAA = 0  # the ranks' blend itself, not FXAA's smoothing
view = CreateView("RenderView")
u.setup_view(view)
display = Show(OpenDataFile(path), view)
display.Representation = "Adaptive-FAM Volume"
u.apply_transfer_function(display)
display.AFAMPrefetcher = "None"  # bytes of this view only, nothing read ahead for the next
Render(view)
# symmetric mode: each rank's information properties come from its own representation
display.UpdatePropertyInformation()
mine = [display.GetPropertyValue(name) for name in
        ("AFAMLastBytesRead", "AFAMLastVisibleBlocks", "AFAMLastCacheMisses")]
from vtkmodules.vtkCommonCore import vtkIdTypeArray  # noqa: E402
local, gathered = vtkIdTypeArray(), vtkIdTypeArray()
for value in mine:
    local.InsertNextValue(int(value))
controller.AllGather(local, gathered)
png = os.path.join(os.path.dirname(result), "rank_io_%d.png" % ranks)
SaveScreenshot(png, view, ImageResolution=[301, 300])
display.AFAMBlendMode = "Maximum Intensity"
Render(view)
mip = os.path.join(os.path.dirname(result), "rank_io_%d_mip.png" % ranks)
SaveScreenshot(mip, view, ImageResolution=[301, 300])
display.AFAMBlendMode = "Composite"
view.CameraPosition = [6.0, 4.0, 9.0]  # inside the volume ([-20, 20]^3), looking at its centre
Render(view)
inside = os.path.join(os.path.dirname(result), "rank_io_%d_inside.png" % ranks)
SaveScreenshot(inside, view, ImageResolution=[301, 300])
if rank == 0:
    per_rank = [[gathered.GetValue(3 * r + k) for k in range(3)] for r in range(ranks)]
    with open(result, "w") as f:
        json.dump({"ranks": ranks, "bytes_read": [p[0] for p in per_rank],
                   "visible_blocks": [p[1] for p in per_rank], "misses": [p[2] for p in per_rank],
                   "image": png, "mip": mip, "inside": inside}, f)
    print("ranks %d: bytes read per rank %s, blocks drawn per rank %s"
          % (ranks, [p[0] for p in per_rank], [p[1] for p in per_rank]), flush=True)

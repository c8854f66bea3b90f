# SPDX-License-Identifier: BSD-3-Clause
"""Run by TestAFAMRankFiles.py as `pvbatch afam_rank_files_view.py FILE.afam OUT.png` under mpirun,
each rank in its own working directory, FILE a relative path: each rank opens what its directory
holds under that name, as ranks on different nodes open what their node holds. Renders one frame of
the "Adaptive-FAM Volume" display and saves it."""
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

from paraview.simple import CreateView, OpenDataFile, Render, SaveScreenshot, Show  # noqa: E402

path, png = sys.argv[1], sys.argv[2]
u.load_plugin(globals())
view = CreateView("RenderView")
u.setup_view(view)
display = Show(OpenDataFile(path), view)
display.Representation = "Adaptive-FAM Volume"
u.apply_transfer_function(display)
Render(view)
SaveScreenshot(png, view, ImageResolution=[301, 300])
print("AFAM-RANK-FILES-RENDERED", flush=True)

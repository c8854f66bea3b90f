# SPDX-License-Identifier: BSD-3-Clause
"""mpirun -np 2 pvbatch: the .afam file written by TestAFAMPipeline, rendered with the
"Adaptive-FAM Volume" representation on 2 ranks, must match the one-rank baseline."""
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))  # the GUI defines no __file__
import afam_test_util as u  # noqa: E402

from paraview import servermanager  # noqa: E402
from paraview.simple import CreateView, OpenDataFile, Render, SaveScreenshot, Show  # noqa: E402

ranks = servermanager.vtkProcessModule.GetProcessModule().GetNumberOfLocalPartitions()
if ranks < 2:
    u.fail("expected at least 2 MPI ranks, got %d" % ranks)
u.load_plugin(globals())
path = os.path.join(u.shared_dir(), "wavelet.afam")
if not os.path.isfile(path):
    u.fail("missing %s (made by AFAM.Python.Pipeline)" % path)
model = OpenDataFile(path)
view = CreateView("RenderView")
u.setup_view(view)
display = Show(model, view)
display.Representation = "Adaptive-FAM Volume"
u.apply_transfer_function(display)
Render(view)
png = os.path.join(u.out_dir(), "TestAFAMMPI.png")
SaveScreenshot(png, view, ImageResolution=[301, 300])
print("rendered on %d ranks" % ranks)
u.compare_with_baseline(png, "TestAFAMPipeline.png")

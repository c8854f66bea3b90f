# SPDX-License-Identifier: BSD-3-Clause
"""Run inside the ParaView GUI (paraview --script=... --exit under Xvfb): open the .afam file made by
TestAFAMPipeline, show it with "Adaptive-FAM Volume", take a screenshot, check it is not blank."""
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))  # the GUI defines no __file__
import afam_test_util as u  # noqa: E402

from paraview.simple import GetActiveViewOrCreate, OpenDataFile, Render, SaveScreenshot, Show  # noqa: E402

u.load_plugin(globals())
path = os.path.join(u.shared_dir(), "wavelet.afam")
if not os.path.isfile(path):
    u.fail("missing %s (made by AFAM.Python.Pipeline)" % path)
model = OpenDataFile(path)
view = GetActiveViewOrCreate("RenderView")
u.setup_view(view, size=(400, 400))
display = Show(model, view)
display.Representation = "Adaptive-FAM Volume"
u.apply_transfer_function(display)
Render(view)
png = os.path.join(u.out_dir(), "TestAFAMGUI.png")
SaveScreenshot(png, view, ImageResolution=[400, 400])
count = u.non_blank(png)
display.UpdatePropertyInformation()
frames = display.GetPropertyValue("AFAMNumberOfFrames")
print("GUI screenshot: %d non-background pixels, %s frames" % (count, frames), flush=True)
if count < 2000 or not frames:
    u.fail("GUI screenshot is blank (%d pixels differ from the background)" % count)
print("AFAM-GUI-OK", flush=True)

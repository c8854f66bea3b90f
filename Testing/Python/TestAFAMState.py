# SPDX-License-Identifier: BSD-3-Clause
"""pvbatch: an .afam shows itself as "Adaptive-FAM Volume" in a render view (the reader's
representation hint), and a ParaView state with that representation saves and loads back:
after ResetSession + LoadState the view shows the same representation with the same Adaptive-FAM
settings and draws the same image (no pixel differs by more than 2/255)."""
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

from paraview.simple import (CreateView, GetActiveViewOrCreate, GetDisplayProperties,  # noqa: E402
                             GetSources, LoadState, Render, ResetSession, SaveScreenshot,
                             SaveState, Show)

u.load_plugin(globals())
out = u.out_dir()
path = os.path.join(out, "state_wavelet.afam")
_, encoder = u.encode_wavelet(globals(), [-20, 20, -20, 20, -20, 20], 3, 4, 0.005, path)
model = AdaptiveFAMReader(FileName=path)  # noqa: F821
view = CreateView("RenderView")
u.setup_view(view)
display = Show(model, view)
# The reader's hint: a render view shows the model set as "Adaptive-FAM Volume", not an outline.
print("shown as %s" % display.Representation)
if display.Representation != "Adaptive-FAM Volume":
    u.fail("Show gave %s, not the reader's default 'Adaptive-FAM Volume'" % display.Representation)
u.apply_transfer_function(display)
display.AFAMSampleDistance = 0.75
device = u.render_device("CPU")  # a value other than the default, which the state must keep
display.AFAMRenderDevice = device
Render(view)
before = os.path.join(out, "before.png")
SaveScreenshot(before, view, ImageResolution=[301, 300])
if u.non_blank(before) < 500:
    u.fail("the volume was not drawn before SaveState")
state = os.path.join(out, "afam.pvsm")
SaveState(state)

ResetSession()  # the plugin stays loaded in this process
LoadState(state)
view = GetActiveViewOrCreate("RenderView")
readers = [s for s in GetSources().values() if s.GetXMLName() == "AFAMReader"]
if len(readers) != 1:
    u.fail("the loaded state has %d Adaptive-FAM readers" % len(readers))
display = GetDisplayProperties(readers[0], view)
print("loaded: representation %s, LOD %s, sample distance %s, device %s" % (
    display.Representation, display.AFAMLodPolicy, display.AFAMSampleDistance, display.AFAMRenderDevice))
if display.Representation != "Adaptive-FAM Volume":
    u.fail("representation after LoadState: %s" % display.Representation)
if display.AFAMSampleDistance != 0.75 or display.AFAMLodPolicy != "Screen-space error" \
        or display.AFAMRenderDevice != device:
    u.fail("Adaptive-FAM settings were not restored")
Render(view)
after = os.path.join(out, "after.png")
SaveScreenshot(after, view, ImageResolution=[301, 300])
fraction, worst = u.differing_fraction(after, before, 2)
print("after LoadState: %.4f %% of pixels differ by more than 2/255 (largest %d/255)" % (100 * fraction, worst))
if fraction > 0:
    u.fail("the image after LoadState differs from the one before SaveState")

# SPDX-License-Identifier: BSD-3-Clause
"""pvpython: what an interactive frame under the Interactive Miss Budget leaves behind, as the
display and the server-side frame statistics report it (issue 44):
- a budget of 0 on a cold cache: the frame draws what is resident (the coarsest level, loaded
  before the first image) and waits for nothing: the finest blocks it selects are behind, each
  drawn from a resident coarser level (stand-ins == blocks behind > 0, bytes behind > 0; loading
  the dozens of finest blocks takes far longer than the frame takes to place what is resident);
- AFAMFrameStatistics sums the same figures over the ranks (one rank here: equal);
- the still frame after it is exact (0, 0, 0), and so is an interactive frame with a budget of -1."""
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

from paraview import servermanager  # noqa: E402
from paraview.simple import CreateView, OpenDataFile, Show  # noqa: E402

u.load_plugin(globals())
out = u.out_dir()
path = os.path.join(out, "wavelet_budget.afam")
u.encode_wavelet(globals(), [-40, 40, -40, 40, -40, 40], 3, 8, 0.001, path)
view = CreateView("RenderView")
u.setup_view(view, size=(400, 400))
view.CameraPosition = [100.0, 80.0, 140.0]
display = Show(OpenDataFile(path), view)
display.Representation = "Adaptive-FAM Volume"
u.apply_transfer_function(display)
display.AFAMAutoAdjustImageScale = 0  # interactive frames full size: the finest level is drawn
display.AFAMInteractiveMissBudget = 0
NAMES = ("StandInBlocks", "BlocksBehind", "BytesBehind")


def behind():
    display.UpdatePropertyInformation()
    return tuple(display.GetPropertyValue("AFAMLast" + name) for name in NAMES)


def gathered():
    statistics = servermanager.misc.AFAMFrameStatistics(Representation=display)
    statistics.SMProxy.InvokeCommand("Gather")
    statistics.SMProxy.UpdatePropertyInformation()
    return tuple(statistics.GetPropertyValue("Total" + name) for name in NAMES)


view.InteractiveRender()
first = behind()
print("interactive frame, budget 0: stand-ins %d, blocks behind %d, bytes behind %d" % first)
print("visible blocks %d, caching %.4f s" % (display.GetPropertyValue("AFAMLastVisibleBlocks"),
                                             display.GetPropertyValue("AFAMLastCachingTime")))
if not (first[1] > 0 and first[0] == first[1] and first[2] > 0):
    u.fail("a budget of 0 left nothing behind, or a block without a stand-in: %s" % (first,))
if gathered() != first:
    u.fail("the frame statistics %s differ from the display's %s" % (gathered(), first))
view.StillRender()
if behind() != (0, 0, 0) or gathered() != (0, 0, 0):
    u.fail("the still frame is not exact: %s, gathered %s" % (behind(), gathered()))
display.AFAMInteractiveMissBudget = -1
view.CameraPosition = [-100.0, 80.0, 140.0]
view.InteractiveRender()
if behind() != (0, 0, 0):
    u.fail("an interactive frame with a budget of -1 left %s behind" % (behind(),))
print("AFAM-FRAME-BUDGET-OK")

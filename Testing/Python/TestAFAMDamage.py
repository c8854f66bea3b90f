# SPDX-License-Identifier: BSD-3-Clause
"""pvbatch: damage stays local. A copy of a 3-level file with 8 bytes overwritten at 1.5%, 10%,
45% and 75% of its length (moved past the header and index when the spot falls there), drawn with
every default of the "Adaptive-FAM Volume" representation at six 300 x 300 views: at least 80% of
the intact file's foreground pixels, and between 1 and 4 messages about damage over the 6 frames
(each damaged block is reported once, never on every frame)."""
import os
import re
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

from paraview.simple import CreateView, OpenDataFile, Render, SaveScreenshot, Show  # noqa: E402

u.load_plugin(globals())
out = u.out_dir()
good, bad = u.damaged_wavelet(globals(), 3, (0.015, 0.10, 0.45, 0.75))


def render_six(path, tag):
    view = CreateView("RenderView")
    u.setup_view(view, (300, 300))
    display = Show(OpenDataFile(path), view)
    display.Representation = "Adaptive-FAM Volume"
    u.apply_transfer_function(display)
    display.AFAMLodPolicy = "Screen-space error"
    pixels = 0
    for k in range(6):
        view.CameraPosition = [[62, 48, 86], [-62, 48, 86], [86, -48, 62], [0, 100, 10], [-70, -40, -70], [50, 50, -90]][k]
        Render(view)
        png = os.path.join(out, "%s_%d.png" % (tag, k))
        SaveScreenshot(png, view, ImageResolution=[300, 300])
        pixels += u.non_blank(png)
    return pixels


intact = render_six(good, "intact")
damaged, text = u.captured_messages(lambda: render_six(bad, "damaged"))
reports = sum(1 for m in text.split("Warning: In ")[1:] if "payload checksum mismatch" in m)
blocks = re.findall(r"payload checksum mismatch at (level \d+ block \([0-9, ]+\))", text)
print("foreground: damaged %d of intact %d (%.1f%%); %d damage messages over 6 frames naming %s"
      % (damaged, intact, 100.0 * damaged / max(intact, 1), reports, blocks))
if len(blocks) != len(set(blocks)):
    u.fail("a damaged block was reported more than once: %s" % blocks)
print(" ".join(text.split())[:600])
if damaged < 0.8 * intact:
    u.fail("the damaged file keeps %d of %d foreground pixels (bar 80%%)" % (damaged, intact))
if not 1 <= reports <= 4:
    u.fail("%d messages about damage over 6 frames (bar: 1 to 4)" % reports)
if "afam verify" not in text or bad not in text:
    u.fail("the damage message does not name the file and `afam verify`: %s" % text)

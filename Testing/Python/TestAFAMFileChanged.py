# SPDX-License-Identifier: BSD-3-Clause
"""pvbatch: a file another process changes while it is shown is noticed at the next frame.
- Rewritten in place with another encoding: one warning saying the file changed and was opened
  again, and the frame shows the new file only (identical to a fresh view of it; no block of the
  old file is drawn beside the new ones).
- Then cut to 60% of its length: one error naming the change and the truncation over four frames,
  no crash."""
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

from paraview.simple import CreateView, OpenDataFile, Render, SaveData, SaveScreenshot, Show, Wavelet  # noqa: E402

u.load_plugin(globals())
out = u.out_dir()
path = os.path.join(out, "shown.afam")
other = os.path.join(out, "other.afam")
u.encode_wavelet(globals(), [-20, 20, -20, 20, -20, 20], 3, 4, 0.005, path)
# Another volume on the same grid (the Wavelet with another maximum): same geometry, new values.
encoder = AdaptiveFAMEncoder(Input=Wavelet(WholeExtent=[-20, 20, -20, 20, -20, 20], Maximum=180),  # noqa: F821
                             Levels=3, BlocksPerAxis=4, ErrorBound=0.005)
SaveData(other, proxy=encoder)


def shot(view, tag):
    Render(view)
    png = os.path.join(out, "%s.png" % tag)
    SaveScreenshot(png, view, ImageResolution=[301, 300])
    return png


def show(file_path):
    view = CreateView("RenderView")
    u.setup_view(view)
    display = Show(OpenDataFile(file_path), view)
    display.Representation = "Adaptive-FAM Volume"
    u.apply_transfer_function(display)
    display.AFAMRenderDevice = u.render_device("CPU")
    return view


def count(text, kind):
    return len(text.split(kind + ": In ")) - 1


view = show(path)
before = shot(view, "before")
with open(other, "rb") as f:
    new_bytes = f.read()
with open(path, "r+b") as f:  # in place: same inode, as `cp` does
    f.truncate(0)
    f.write(new_bytes)
after, text = u.captured_messages(lambda: shot(view, "after_rewrite"))
fresh = shot(show(other), "fresh_other")
changed, stale = u.differing_fraction(after, before, 2)[0], u.differing_fraction(after, fresh, 2)
print("rewritten: %d warnings, %d errors; %.3f %% of pixels differ from before, %.3f %% (largest %d/255) "
      "from a fresh view of the new file" % (count(text, "Warning"), count(text, "ERROR"), 100 * changed,
                                             100 * stale[0], stale[1]))
print(" ".join(text.split())[:400])
if count(text, "Warning") != 1 or count(text, "ERROR") != 0 or "changed since it was opened" not in text \
        or "opened again" not in text or path not in text:
    u.fail("the in-place rewrite gave %d warnings and %d errors: %s" % (count(text, "Warning"), count(text, "ERROR"), text))
if changed < 0.01:
    u.fail("the frame after the rewrite still shows the old file")
if stale[0] > 0:
    u.fail("the frame after the rewrite differs from a fresh view of the new file (old blocks drawn?)")

size = os.path.getsize(path)
with open(path, "r+b") as f:
    f.truncate(int(0.6 * size))
_, text = u.captured_messages(lambda: [shot(view, "truncated_%d" % k) for k in range(4)])
print("truncated: %d errors, %d warnings over 4 frames: %s" % (count(text, "ERROR"), count(text, "Warning"),
                                                                " ".join(text.split())[:400]))
if count(text, "ERROR") != 1 or count(text, "Warning") != 0 or "truncated" not in text \
        or "changed since it was opened" not in text:
    u.fail("truncating the shown file gave %d errors and %d warnings over 4 frames"
           % (count(text, "ERROR"), count(text, "Warning")))

# SPDX-License-Identifier: BSD-3-Clause
"""pvbatch: load the plugin; a wrong file gives an error, not a crash; encode a Wavelet with the
Adaptive-FAM Encoder, save it with the writer, reopen it with OpenDataFile; the encoder's and the
reader's bounds are the Wavelet's [-20, 20]^3 (also for a sub-extent input); render it with the
"Adaptive-FAM Volume" representation under a fixed camera, compare with the baseline, read the frame
statistics, and check it is drawn where ParaView's own Volume representation draws the Wavelet.
Leaves wavelet.afam in the shared test folder for the MPI and GUI tests."""
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))  # the GUI defines no __file__
import afam_test_util as u  # noqa: E402

from paraview.simple import (ColorBy, CreateView, ExtractSubset, Hide, OpenDataFile, Render,  # noqa: E402
                             SaveData, SaveScreenshot, Show, Wavelet)
from paraview import servermanager  # noqa: E402

u.load_plugin(globals())
out = u.out_dir()

# 1. A wrong file: an error message and an empty output, and the process goes on.
bad = os.path.join(out, "not_an_afam.afam")
with open(bad, "wb") as f:
    f.write(b"this is not an afam file" * 10)
# Claimed by the reader (named .afam), which says once what is wrong with it; no data, no crash.
def open_bad():
    opened = OpenDataFile(bad)
    opened.UpdatePipeline()
    return opened


reader, said = u.captured_messages(open_bad)
if reader.GetDataInformation().GetNumberOfDataSets() != 0:
    u.fail("a corrupt file produced data")
if said.count("ERROR:") != 1 or "not an .afam file" not in said or bad not in said:
    u.fail("not one error naming the wrong file: %s" % said)
print("wrong file: error reported, no data, no crash")

# 2. Encode, save, reopen.
wavelet = Wavelet(WholeExtent=[-20, 20, -20, 20, -20, 20])
encoder = AdaptiveFAMEncoder(Input=wavelet, Levels=3, BlocksPerAxis=4, ErrorBound=0.005)  # noqa: F821
encoder.Scalars = ["POINTS", "RTData"]
encoder.UpdatePipeline()
leaves = encoder.GetDataInformation().GetNumberOfDataSets()
expected = 3 + 1  # levels 2, 1, 0 (a leaf each) and the value-range probe
if leaves != expected:
    u.fail("encoder produced %d leaves, expected %d" % (leaves, expected))
path = os.path.join(u.shared_dir(), "wavelet.afam")
if os.path.exists(path):
    os.remove(path)
SaveData(path, proxy=encoder)
if not os.path.isfile(path) or os.path.getsize(path) < 1024:
    u.fail("the writer did not produce %s" % path)
model = OpenDataFile(path)
model.UpdatePipeline()
if model.GetDataInformation().GetNumberOfDataSets() != expected:
    u.fail("reopened file has %d leaves" % model.GetDataInformation().GetNumberOfDataSets())


def model_rows(proxy):
    """Per level: the field-data rows of its leaf as (entry, level, ncp, rmse, stored bytes) tuples."""
    tree = servermanager.Fetch(proxy)
    levels = []
    for level in range(tree.GetNumberOfBlocks() - 1):
        fd = tree.GetBlock(level).GetFieldData()
        cols = [fd.GetArray(n) for n in ("AFAM_EntryIndex", "AFAM_Level", "AFAM_NCP", "AFAM_RMSE", "AFAM_StoredBytes")]
        levels.append([(int(cols[0].GetTuple1(r)), int(cols[1].GetTuple1(r)), cols[2].GetTuple3(r),
                        cols[3].GetTuple1(r), int(cols[4].GetTuple1(r))) for r in range(cols[0].GetNumberOfTuples())])
    return levels


# One row per model, in file order (coarsest level first), within the bound; the reader's rows are
# the encoder's.
encoded_rows = model_rows(encoder)
if [len(rows) for rows in encoded_rows] != [1, 8, 64]:
    u.fail("rows per level %s, expected [1, 8, 64]" % [len(rows) for rows in encoded_rows])
flat = [row for rows in encoded_rows for row in rows]
if [row[0] for row in flat] != list(range(73)) or any(row[1] != lv for lv, rows in enumerate(encoded_rows)
                                                        for row in rows):
    u.fail("entry or level columns out of order: %s" % flat[:10])
encoder.UpdatePropertyInformation()
bound = encoder.GetProperty("LastBound").GetData()  # 0.005 of the Wavelet's value range
if not 0 < bound < 5 or any(min(row[2]) < 3 or row[3] > bound for row in flat):
    u.fail("a model row has NCP below degree + 1 or RMSE above the bound %g: %s" % (bound, flat))
# The stored bytes fill the file's payload area (docs/FORMAT.md): its size less the 1024-byte
# header and the 40-byte entries, less the padding that aligns each payload to 4 bytes (and the area
# to at most 64).
stored = sum(row[4] for row in flat)
if not 0 <= os.path.getsize(path) - 1024 - 73 * 40 - stored < 64 + 3 * 73:
    u.fail("stored bytes %d do not fit the %d-byte file" % (stored, os.path.getsize(path)))
if model_rows(model) != encoded_rows:
    u.fail("the reopened file's model rows differ from the encoder's")
print("model rows: 1 + 8 + 64, NCP %d..%d, max RMSE %.4g, bound %.4g, %d stored bytes of %d" % (
    min(min(r[2]) for r in flat), max(max(r[2]) for r in flat), max(r[3] for r in flat), bound, stored,
    os.path.getsize(path)))

# The models sit where the Wavelet is: the file's origin is the world position of the first sample
# (origin + extent minimum x spacing), so bounds survive encoder -> writer -> reader.
wavelet_bounds = wavelet.GetDataInformation().GetBounds()
for name, proxy in (("encoder", encoder), ("reader", model)):
    b = proxy.GetDataInformation().GetBounds()
    print("%s bounds %s, Wavelet bounds %s" % (name, b, wavelet_bounds))
    if max(abs(x - y) for x, y in zip(b, wavelet_bounds)) > 1e-9:
        u.fail("%s bounds %s differ from the Wavelet's %s" % (name, b, wavelet_bounds))
if max(abs(x - y) for x, y in zip(wavelet_bounds, [-20, 20, -20, 20, -20, 20])) > 1e-9:
    u.fail("Wavelet bounds %s, expected [-20, 20]^3" % (wavelet_bounds,))
# A sub-extent (what one piece of a split Wavelet delivers) keeps its own place too.
sub = Wavelet(WholeExtent=[-20, 20, -20, 20, -20, 20])
sub_voi = ExtractSubset(Input=sub, VOI=[-10, 15, -20, 0, 5, 20])
sub_encoder = AdaptiveFAMEncoder(Input=sub_voi, Levels=1, BlocksPerAxis=1, ErrorBound=0.05)  # noqa: F821
sub_encoder.Scalars = ["POINTS", "RTData"]
sub_encoder.UpdatePipeline()
sub_bounds = sub_encoder.GetDataInformation().GetBounds()
print("sub-extent encoder bounds %s" % (sub_bounds,))
if max(abs(x - y) for x, y in zip(sub_bounds, [-10, 15, -20, 0, 5, 20])) > 1e-9:
    u.fail("sub-extent encoder bounds %s, expected [-10, 15, -20, 0, 5, 20]" % (sub_bounds,))

# 3. Render with the representation and compare.
view = CreateView("RenderView")
u.setup_view(view)
display = Show(model, view)
if "Adaptive-FAM Volume" not in display.Representation.Available:
    u.fail("representation not offered: %s" % display.Representation.Available)
display.Representation = "Adaptive-FAM Volume"
u.apply_transfer_function(display)
Render(view)
png = os.path.join(out, "TestAFAMPipeline.png")
SaveScreenshot(png, view, ImageResolution=[301, 300])

display.UpdatePropertyInformation()
frames = display.GetPropertyValue("AFAMNumberOfFrames")
total = display.GetPropertyValue("AFAMLastTotalTime")
render = display.GetPropertyValue("AFAMLastRenderTime")
visible = display.GetPropertyValue("AFAMLastVisibleBlocks")
print("statistics: frames=%s total=%.4fs raycast=%.4fs caching=%.4fs visible=%s culled=%s hits=%s misses=%s" % (
    frames, total, render, display.GetPropertyValue("AFAMLastCachingTime"), visible,
    display.GetPropertyValue("AFAMLastCulledBlocks"), display.GetPropertyValue("AFAMLastCacheHits"),
    display.GetPropertyValue("AFAMLastCacheMisses")))
if not frames or frames < 1 or not visible or visible < 1 or not total or total <= 0:
    u.fail("the mapper did not render (statistics above)")
# Interactive image scaling is on by default; a still render (pvbatch renders are still) is full size.
scale = display.GetPropertyValue("AFAMLastImageScale")
print("interactive image scaling %s (minimum %s), last image scale %s" % (
    display.AFAMAutoAdjustImageScale, display.AFAMMinimumImageScale, scale))
if display.AFAMAutoAdjustImageScale != 1 or abs(display.AFAMMinimumImageScale - 0.25) > 1e-12 or scale != 1.0:
    u.fail("interactive image scaling defaults or the still frame's scale are wrong")
# Interactive frames wait 20 ms for their misses by default; still renders wait for every block.
print("interactive miss budget %s ms" % display.AFAMInteractiveMissBudget)
if abs(display.AFAMInteractiveMissBudget - 20) > 1e-12:
    u.fail("the interactive miss budget's default is not 20 ms")
display.AFAMInteractiveMissBudget = 5
Render(view)
if abs(display.AFAMInteractiveMissBudget - 5) > 1e-12:
    u.fail("the interactive miss budget did not take 5 ms")
display.AFAMInteractiveMissBudget = 20
u.compare_with_baseline(png, "TestAFAMPipeline.png")

# 4. Same place as ParaView's own Volume representation of the Wavelet, same view and colours: the
# non-background pixels' box and centroid agree within a few pixels.
Hide(model, view)
reference = Show(wavelet, view)
reference.Representation = "Volume"
ColorBy(reference, ("POINTS", "RTData"))  # the lookup table and opacity set above
reference.ScalarOpacityUnitDistance = 2.0
Render(view)
png_ref = os.path.join(out, "TestAFAMPipeline_paraview_volume.png")
SaveScreenshot(png_ref, view, ImageResolution=[301, 300])
afam_box = u.foreground_box(png)
paraview_box = u.foreground_box(png_ref)
print("foreground (x0, y0, x1, y1, cx, cy): Adaptive-FAM %s, ParaView Volume %s" % (afam_box, paraview_box))
if max(abs(a - b) for a, b in zip(afam_box, paraview_box)) > 6:
    u.fail("the volume is not where ParaView's Volume representation draws the Wavelet")

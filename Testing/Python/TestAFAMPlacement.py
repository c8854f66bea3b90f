# SPDX-License-Identifier: BSD-3-Clause
"""pvbatch: the "Adaptive-FAM Volume" representation draws a volume where ParaView's own Volume
representation draws the same data, for a non-cubic volume (61 x 17 x 31 samples), for the same
volume moved, rotated and scaled non-uniformly through the display's Position / Orientation /
Scale, and under parallel projection. Compared: the foreground's bounding box and centroid in
pixels (afam_test_util.foreground_box), which a volume drawn stretched, unmoved or with the wrong
projection misses by tens of pixels."""
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

from paraview.simple import ColorBy, CreateView, OpenDataFile, Render, SaveScreenshot, Show  # noqa: E402

u.load_plugin(globals())
out = u.out_dir()

path = os.path.join(out, "wavelet_61x17x31.afam")
wavelet, _ = u.encode_wavelet(globals(), [-30, 30, -8, 8, -15, 15], 2, 2, 0.005, path)
model = OpenDataFile(path)
model.UpdatePipeline()
b = model.GetDataInformation().GetBounds()
if max(abs(x - y) for x, y in zip(b, [-30, 30, -8, 8, -15, 15])) > 1e-9:
    u.fail("encoded bounds %s, expected the Wavelet's [-30, 30, -8, 8, -15, 15]" % (b,))

view = CreateView("RenderView")
u.setup_view(view)
view.CameraPosition = [100.0, 78.0, 138.0]  # farther than the shared view: the volume stays inside the image
afam = Show(model, view)
afam.Representation = "Adaptive-FAM Volume"
u.apply_transfer_function(afam)
afam.AFAMLodPolicy = "Screen-space error"
reference = Show(wavelet, view)
reference.Representation = "Volume"
ColorBy(reference, ("POINTS", "RTData"))  # the colour and opacity maps set above
reference.ScalarOpacityUnitDistance = 2.0

cases = [
    ("non-cubic", dict(), False),
    ("moved, rotated, scaled", dict(Position=[6.0, -5.0, 3.0], Orientation=[10.0, 0.0, 35.0],
                                    Scale=[1.0, 1.8, 0.8]), False),
    ("parallel projection", dict(), True),
    ("parallel projection, transformed", dict(Position=[-4.0, 3.0, 0.0], Orientation=[0.0, 25.0, 0.0],
                                               Scale=[0.7, 1.5, 1.0]), True),
]
worst = 0
for name, transform, parallel in cases:
    for display in (afam, reference):
        display.Position = transform.get("Position", [0.0, 0.0, 0.0])
        display.Orientation = transform.get("Orientation", [0.0, 0.0, 0.0])
        display.Scale = transform.get("Scale", [1.0, 1.0, 1.0])
    view.CameraParallelProjection = 1 if parallel else 0
    view.CameraParallelScale = 40.0
    boxes = []
    for shown, hidden, tag in ((afam, reference, "afam"), (reference, afam, "paraview")):
        hidden.Visibility = 0
        shown.Visibility = 1
        Render(view)
        png = os.path.join(out, "placement_%s_%s.png" % (name.replace(" ", "_").replace(",", ""), tag))
        SaveScreenshot(png, view, ImageResolution=[301, 300])
        boxes.append(u.foreground_box(png))
    diff = max(abs(a - c) for a, c in zip(*boxes))
    worst = max(worst, diff)
    print("%-34s foreground (x0, y0, x1, y1, cx, cy): Adaptive-FAM %s, ParaView Volume %s, "
          "largest difference %.1f px" % (name, boxes[0], boxes[1], diff))
    if diff > 6:
        u.fail("%s: the volume is not drawn where ParaView's Volume representation draws it" % name)
    width, height = boxes[0][2] - boxes[0][0], boxes[0][3] - boxes[0][1]
    if width < 40 or height < 20:
        u.fail("%s: the volume covers only %d x %d pixels; the check needs a real footprint" %
               (name, width, height))
print("placement OK: largest box/centroid difference %.1f px over %d cases" % (worst, len(cases)))

# A screenshot three times the view's size: VTK renders it as 3 x 3 tiles of the view's size
# (narrower view angle, WindowCenter moved per tile). It must be the same picture, three times
# larger: its foreground box and centroid, divided by 3, within 2 px of the view-size image.
for display in (afam, reference):
    display.Position, display.Orientation, display.Scale = [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 1.0, 1.0]
view.CameraParallelProjection = 0
reference.Visibility = 0
afam.Visibility = 1
Render(view)
small = os.path.join(out, "placement_screenshot_1x.png")
large = os.path.join(out, "placement_screenshot_3x.png")
SaveScreenshot(small, view, ImageResolution=[301, 300])
SaveScreenshot(large, view, ImageResolution=[903, 900])
b1, b3 = u.foreground_box(small), u.foreground_box(large)
scaled = tuple(round(v / 3.0, 1) for v in b3)
diff = max(abs(a - c) for a, c in zip(b1, scaled))
print("3x screenshot: foreground %s, divided by 3 %s, view-size image %s, largest difference %.1f px"
      % (b3, scaled, b1, diff))
if diff > 2:
    u.fail("the 3x screenshot is not the view-size picture enlarged (tiles rendered wrongly)")

# A singular transform (zero scale): an error naming it, nothing drawn, no crash.
from paraview import servermanager  # noqa: E402
from vtkmodules.vtkCommonCore import vtkOutputWindow, vtkStringOutputWindow  # noqa: E402
messages = vtkStringOutputWindow()
previous = vtkOutputWindow.GetInstance()
vtkOutputWindow.SetInstance(messages)
reference.Visibility = 0
afam.Visibility = 1
afam.Position, afam.Orientation, afam.Scale = [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 0.0, 1.0]
view.CameraParallelProjection = 0
Render(view)
png = os.path.join(out, "placement_singular.png")
SaveScreenshot(png, view, ImageResolution=[301, 300])
vtkOutputWindow.SetInstance(previous)
text = messages.GetOutput()
print("zero scale: %d foreground pixels; messages: %s" % (u.non_blank(png), text.strip().splitlines()[-1:]))
if "singular" not in text:
    u.fail("a zero Scale gave no error naming the singular transform")
if u.non_blank(png) > 0:
    u.fail("a zero Scale still drew something")

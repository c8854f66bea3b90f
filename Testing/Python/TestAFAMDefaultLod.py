# SPDX-License-Identifier: BSD-3-Clause
"""pvbatch: with every default of the "Adaptive-FAM Volume" representation (screen-space LOD, a
one-pixel budget), a volume at ParaView's reset camera, 400 x 400, looks like ParaView's own
"Volume" of the same samples (same colour and opacity maps): SSIM >= 0.95 (`afam compare`). The
paper's distance bands, one property away, are measured and printed for comparison."""
import os
import re
import subprocess
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

from paraview.simple import (ColorBy, CreateView, Delete, GetColorTransferFunction,  # noqa: E402
                             GetOpacityTransferFunction, ImageReader, OpenDataFile, Render,
                             SaveScreenshot, Show)

u.load_plugin(globals())
out = u.out_dir()
afam = u.env("AFAM_EXE")
n = 81
raw = os.path.join(out, "ml.raw")
path = os.path.join(out, "ml.afam")
subprocess.run([afam, "ml", "--size", str(n), raw], check=True, stdout=subprocess.DEVNULL)
subprocess.run([afam, "encode", raw, path, "--dims", "%d,%d,%d" % (n, n, n), "--type", "float32",
                "--error-bound", "1e-2", "--relative", "--levels", "3", "--blocks", "8"],
               check=True, stdout=subprocess.DEVNULL)
image = ImageReader(FileNames=[raw])
image.DataScalarType = "float"
image.DataByteOrder = "LittleEndian"
image.DataExtent = [0, n - 1, 0, n - 1, 0, n - 1]
image.ScalarArrayName = "values"
model = OpenDataFile(path)


def shot(source, representation, tag, policy=None):
    view = CreateView("RenderView")
    view.ViewSize = [400, 400]
    view.OrientationAxesVisibility = 0
    display = Show(source, view)
    display.Representation = representation
    ColorBy(display, ("POINTS", "values"))  # one colour and opacity map, shared by name
    GetColorTransferFunction("values").RescaleTransferFunction(0.0, 1.0)
    GetOpacityTransferFunction("values").RescaleTransferFunction(0.0, 1.0)
    if policy:
        display.AFAMLodPolicy = policy
    view.ResetCamera()
    Render(view)
    png = os.path.join(out, "%s.png" % tag)
    SaveScreenshot(png, view, ImageResolution=[400, 400])
    Delete(view)
    return png


def ssim(png, reference):
    text = subprocess.run([afam, "compare", png, reference], check=True, capture_output=True, text=True).stdout
    return float(re.search(r"ssim=([0-9.]+)", text).group(1))


reference = shot(image, "Volume", "paraview_volume")
default = ssim(shot(model, "Adaptive-FAM Volume", "afam_default"), reference)
bands = ssim(shot(model, "Adaptive-FAM Volume", "afam_distance_bands", "Distance bands"), reference)
print("SSIM against ParaView's Volume at the reset camera: defaults %.4f, distance bands %.4f"
      % (default, bands))
if default < 0.95:
    u.fail("the default LOD gives SSIM %.4f against ParaView's Volume (bar 0.95)" % default)

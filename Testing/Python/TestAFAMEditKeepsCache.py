# SPDX-License-Identifier: BSD-3-Clause
"""pvbatch: editing what a person edits while looking keeps the renderer's cache. Marschner-Lobb
256^3 (made with `afam ml`, encoded with `afam encode`: 3 levels, 8 blocks per axis, 1 % relative
RMSE), opened with OpenDataFile and shown as "Adaptive-FAM Volume" with a camera close enough that
at least 100 micro-models are visible. After the first frame, five edits of the opacity and colour
maps, a shading change and a sample-distance change each render with 0 cache misses and every
visible model a hit, without building the renderer again (and, where the GPU casts, without
uploading a model to its pool). A change of the cache budget, a resource, does build a new one:
the statistics can tell the two apart."""
import os
import subprocess
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

from paraview.simple import (ColorBy, CreateView, GetColorTransferFunction,  # noqa: E402
                             GetOpacityTransferFunction, OpenDataFile, Render, Show)

SIZE = 256


def make_volume():
    """ML SIZE^3 encoded once per build folder (shared between runs)."""
    afam = u.env("AFAM_EXE")
    path = os.path.join(u.shared_dir(), "ml%d_l3_b8.afam" % SIZE)
    if os.path.isfile(path):
        return path
    raw = os.path.join(u.out_dir(), "ml%d.raw" % SIZE)
    subprocess.run([afam, "ml", "--size", str(SIZE), raw], check=True)
    tmp = path + ".part"
    subprocess.run([afam, "encode", raw, tmp, "--dims", "%d,%d,%d" % (SIZE, SIZE, SIZE),
                    "--levels", "3", "--blocks", "8", "--error-bound", "1e-2", "--relative",
                    "--quiet"], check=True)
    os.remove(raw)
    os.replace(tmp, path)
    return path


u.load_plugin(globals())
model = OpenDataFile(make_volume())
model.UpdatePipeline()
array = model.PointData.keys()[0] if model.PointData.keys() else None
if array is None:
    u.fail("the reader names no point array")
view = CreateView("RenderView")
view.ViewSize = [300, 300]
view.OrientationAxesVisibility = 0
display = Show(model, view)
display.Representation = "Adaptive-FAM Volume"
display.AFAMLodPolicy = "Screen-space error"  # the finest level the screen can show
display.AFAMRenderDevice = "GPU" if os.environ.get("AFAM_TEST_DEVICE") == "gpu" else "CPU"
ColorBy(display, ("POINTS", array))
lo, hi = model.PointData[array].GetRange()
lut = GetColorTransferFunction(array)
pwf = GetOpacityTransferFunction(array)
lut.RGBPoints = [lo, 0.2, 0.3, 0.8, 0.5 * (lo + hi), 0.9, 0.9, 0.9, hi, 0.8, 0.1, 0.1]
ramp_from = lo + 0.45 * (hi - lo)  # transparent below: TF culling removes blocks entirely below it
pwf.Points = [lo, 0.0, 0.5, 0.0, ramp_from, 0.0, 0.5, 0.0, hi, 0.5, 0.5, 0.0]
display.ScalarOpacityUnitDistance = 4.0
# Inside the corner region of the volume, looking at its centre: many finest models are near.
view.CameraPosition = [200.0, 170.0, 330.0]
view.CameraFocalPoint = [128.0, 128.0, 128.0]
view.CameraViewUp = [0.0, 1.0, 0.0]
view.CameraViewAngle = 40.0
Render(view)


def stats():
    display.UpdatePropertyInformation()
    names = ("AFAMLastVisibleBlocks", "AFAMLastCacheHits", "AFAMLastCacheMisses",
             "AFAMNumberOfRendererBuilds", "AFAMLastUsedGpu", "AFAMLastGpuModelsUploaded",
             "AFAMNumberOfFrames", "AFAMLastCacheBytes")
    return dict((n[4:], display.GetPropertyValue(n)) for n in names)


first = stats()
print("first frame: %s" % first)
if first["LastVisibleBlocks"] < 100:
    u.fail("only %d micro-models visible; the test needs at least 100" % first["LastVisibleBlocks"])
if first["NumberOfRendererBuilds"] != 1:
    u.fail("the first frames should build the renderer once")


def set_pwf_alpha(index, alpha):
    points = list(pwf.Points)
    points[4 * index + 1] = alpha
    pwf.Points = points


def set_lut_rgb(index, rgb):
    points = list(lut.RGBPoints)
    points[4 * index + 1:4 * index + 4] = rgb
    lut.RGBPoints = points


# Each edit keeps the opacity zero where it was zero, so the same models stay visible.
edits = [
    ("opacity at the top 0.5 -> 0.8", lambda: set_pwf_alpha(2, 0.8)),
    ("middle colour -> green", lambda: set_lut_rgb(1, [0.1, 0.8, 0.2])),
    ("opacity at the top 0.8 -> 0.3", lambda: set_pwf_alpha(2, 0.3)),
    ("low colour -> yellow", lambda: set_lut_rgb(0, [0.9, 0.9, 0.1])),
    ("high colour -> white", lambda: set_lut_rgb(2, [1.0, 1.0, 1.0])),
    ("shading on", lambda: setattr(display, "Shade", 1)),
    ("sample distance 0.5 (world units)", lambda: setattr(display, "AFAMSampleDistance", 0.5)),
]
for name, edit in edits:
    edit()
    Render(view)
    s = stats()
    print("%s: %s" % (name, s))
    if s["LastCacheMisses"] != 0:
        u.fail("%s: %d cache misses (expected 0)" % (name, s["LastCacheMisses"]))
    if s["LastCacheHits"] != first["LastVisibleBlocks"] or s["LastVisibleBlocks"] != first["LastVisibleBlocks"]:
        u.fail("%s: %d hits for %d visible models (first frame: %d visible)" % (
            name, s["LastCacheHits"], s["LastVisibleBlocks"], first["LastVisibleBlocks"]))
    if s["NumberOfRendererBuilds"] != 1:
        u.fail("%s: the renderer was built again (%d builds)" % (name, s["NumberOfRendererBuilds"]))
    if s["LastUsedGpu"] and s["LastGpuModelsUploaded"] != 0:
        u.fail("%s: %d models uploaded to the GPU pool again" % (name, s["LastGpuModelsUploaded"]))

# The control: a new cache budget is a new resource, so the renderer (and cache) are new.
display.AFAMCacheBudgetMB = 256
Render(view)
s = stats()
print("cache budget 256 MB: %s" % s)
if s["NumberOfRendererBuilds"] != 2 or s["LastCacheMisses"] != s["LastVisibleBlocks"]:
    u.fail("a new cache budget should build a new renderer that reads every visible model")
# What the cache holds is reported, and keeps the budget (MB: 10^6 bytes).
if not (0 < s["LastCacheBytes"] <= 256e6 and first["LastCacheBytes"] > 0):
    u.fail("AFAMLastCacheBytes %d (first frame %d) for a 256 MB budget" % (
        s["LastCacheBytes"], first["LastCacheBytes"]))
print("%d edits rendered from the cache (%d models each), %s" % (
    len(edits), first["LastVisibleBlocks"], "GPU pool kept" if first["LastUsedGpu"] else "CPU"))

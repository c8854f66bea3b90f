# SPDX-License-Identifier: BSD-3-Clause
"""Helpers shared by the plugin's pvpython/pvbatch/GUI tests (see CMakeLists.txt for the env)."""
import os
import shutil
import sys


def fail(message):
    """Print the marker ctest fails on and exit non-zero."""
    print("AFAM-TEST-FAIL: %s" % message, flush=True)
    sys.exit(1)


def env(name):
    value = os.environ.get(name, "")
    if not value:
        fail("environment variable %s not set (run through ctest)" % name)
    return value


def out_dir():
    d = env("AFAM_TEST_OUT")
    os.makedirs(d, exist_ok=True)
    return d


def shared_dir():
    """Folder shared between tests of one build (fixture files)."""
    d = os.path.join(os.path.dirname(env("AFAM_TEST_OUT")), "shared")
    os.makedirs(d, exist_ok=True)
    return d


def load_plugin(ns):
    from paraview.simple import LoadPlugin
    plugin = env("AFAM_PLUGIN")
    if not os.path.isfile(plugin):
        fail("plugin not found: %s" % plugin)
    LoadPlugin(plugin, remote=False, ns=ns)


def setup_view(view, size=(301, 300)):
    """The fixed view every image test uses (Wavelet extent [-20, 20]^3)."""
    view.ViewSize = list(size)
    view.OrientationAxesVisibility = 0
    view.Background = [0.1, 0.1, 0.15]
    try:
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    view.CameraPosition = [62.0, 48.0, 86.0]
    view.CameraFocalPoint = [0.0, 0.0, 0.0]
    view.CameraViewUp = [0.0, 1.0, 0.0]
    view.CameraViewAngle = 30.0


def apply_transfer_function(display, array="RTData", lo=37.35, hi=276.8):
    """Colour and opacity maps set explicitly, so baselines do not depend on presets."""
    from paraview.simple import ColorBy, GetColorTransferFunction, GetOpacityTransferFunction
    ColorBy(display, ("POINTS", array))
    lut = GetColorTransferFunction(array)
    lut.RGBPoints = [lo, 0.23, 0.30, 0.75, 0.5 * (lo + hi), 0.87, 0.87, 0.87, hi, 0.71, 0.02, 0.15]
    lut.ColorSpace = "RGB"
    pwf = GetOpacityTransferFunction(array)
    pwf.Points = [lo, 0.0, 0.5, 0.0, 0.5 * (lo + hi), 0.05, 0.5, 0.0, hi, 0.6, 0.5, 0.0]
    display.ScalarOpacityUnitDistance = 2.0
    # screen-space LOD picks finer levels than the distance bands at this small view
    display.AFAMLodPolicy = "Screen-space error"


def compare_with_baseline(png, name, threshold=15.0):
    """vtkTesting image comparison; a missing baseline fails and leaves the image to review."""
    from vtkmodules.vtkTestingRendering import vtkTesting
    baseline = os.path.join(env("AFAM_BASELINE"), name)
    if not os.path.isfile(baseline):
        fail("no baseline %s; review %s and copy it there" % (baseline, png))
    t = vtkTesting()
    t.AddArgument("-T")
    t.AddArgument(out_dir())
    t.AddArgument("-V")
    t.AddArgument(baseline)
    result = t.RegressionTest(png, threshold)
    if result != vtkTesting.PASSED:
        fail("image %s differs from baseline %s (see %s)" % (png, baseline, out_dir()))
    print("image matches baseline %s" % name)


def non_blank(png, background=(0.1, 0.1, 0.15), min_pixels=500):
    """Number of pixels that differ from the background colour by more than 8/255."""
    from vtkmodules.vtkIOImage import vtkPNGReader
    from vtkmodules.util.numpy_support import vtk_to_numpy
    r = vtkPNGReader()
    r.SetFileName(png)
    r.Update()
    pixels = vtk_to_numpy(r.GetOutput().GetPointData().GetScalars())[:, :3].astype(float)
    bg = [255.0 * c for c in background]
    diff = abs(pixels - bg).max(axis=1)
    count = int((diff > 8).sum())
    return count

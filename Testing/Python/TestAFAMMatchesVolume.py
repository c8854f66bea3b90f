# SPDX-License-Identifier: BSD-3-Clause
"""pvpython: the picture a ParaView user expects, with every default of both representations.
- A real scan (neghip, 66^3 uint8) encoded at 1e-3, OpenDataFile + Show, beside ParaView's own
  "Volume" of the raw file, same camera, 500 x 500, ParaView's default colour map (Cool to Warm,
  Diverging) and opacity ramp: SSIM >= 0.97, mean |RGB difference| <= 4/255 over the pixels either
  image covers, and ParaView's background stays background (mean <= 3/255).
- No banding: the default image within PSNR 38 dB of the same view at an eighth of the default
  sample distance.
- Every colour space of vtkColorTransferFunction: an opaque constant region is drawn in the colour
  MapValue gives its value (within 1/255), above-range colour included."""
import os
import re
import subprocess
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

from paraview.simple import (ColorBy, CreateView, GetColorTransferFunction,  # noqa: E402
                             GetOpacityTransferFunction, ImageReader, OpenDataFile, Render,
                             SaveScreenshot, Show)

u.load_plugin(globals())
out = u.out_dir()
afam = u.env("AFAM_EXE")
volumes = os.path.join(os.path.dirname(os.path.abspath(u.__file__)), "..", "Data", "volumes")
SIZE = 500


def raw_reader(raw, dims, scalar_type):
    image = ImageReader(FileNames=[raw])
    image.DataScalarType = scalar_type
    image.DataByteOrder = "LittleEndian"
    image.DataExtent = [0, dims[0] - 1, 0, dims[1] - 1, 0, dims[2] - 1]
    image.ScalarArrayName = "values"
    return image


def encode(raw, dims, type_name, path):
    subprocess.run([afam, "encode", raw, path, "--dims", "%d,%d,%d" % tuple(dims), "--type", type_name,
                    "--error-bound", "1e-3", "--relative"], check=True, stdout=subprocess.DEVNULL)


def view():
    v = CreateView("RenderView")
    v.ViewSize = [SIZE, SIZE]
    v.OrientationAxesVisibility = 0
    return v


def shot(v, tag):
    Render(v)
    png = os.path.join(out, tag + ".png")
    SaveScreenshot(png, v, ImageResolution=[SIZE, SIZE])
    return png


def same_camera(dst, src):
    for p in ("CameraPosition", "CameraFocalPoint", "CameraViewUp", "CameraViewAngle"):
        setattr(dst, p, getattr(src, p))


def compare(png, reference):
    text = subprocess.run([afam, "compare", png, reference], check=True, capture_output=True,
                          text=True).stdout
    return float(re.search(r"psnr=([0-9.inf]+)", text).group(1)), float(re.search(r"ssim=([0-9.]+)", text).group(1))


def against_paraview():
    dims = (66, 66, 66)
    raw = os.path.join(volumes, "neghip_66x66x66_uint8.raw")
    path = os.path.join(out, "neghip.afam")
    encode(raw, dims, "uint8", path)
    pv_view = view()
    volume = Show(raw_reader(raw, dims, "unsigned char"), pv_view)
    volume.Representation = "Volume"
    ColorBy(volume, ("POINTS", "values"))
    volume.RescaleTransferFunctionToDataRange(False, True)
    pv_view.ResetCamera()
    reference = shot(pv_view, "paraview_volume")
    afam_view = view()
    display = Show(OpenDataFile(path), afam_view)  # every default
    same_camera(afam_view, pv_view)
    png = shot(afam_view, "afam_default")
    _, ssim = compare(png, reference)
    a, b = u.read_rgb(png).astype(float), u.read_rgb(reference).astype(float)
    background = abs(b - [255 * c for c in pv_view.Background]).max(axis=2) <= 3
    covered = ~background | (abs(a - [255 * c for c in afam_view.Background]).max(axis=2) > 3)
    diff = abs(a - b).mean(axis=2)
    print("against ParaView's Volume: SSIM %.4f, mean |RGB diff| %.2f/255 over %d covered pixels, "
          "%.2f/255 over ParaView's background" % (ssim, diff[covered].mean(), covered.sum(),
                                                   diff[background].mean()), flush=True)
    if ssim < 0.97 or diff[covered].mean() > 4 or diff[background].mean() > 3:
        u.fail("the default image is not ParaView's Volume's (bars: SSIM 0.97, 4/255, 3/255)")
    return afam_view, display, png


def no_banding(afam_view, display, png):
    display.AFAMSampleDistance = 1.0 / 8  # the default is the finest spacing (1)
    fine = shot(afam_view, "afam_eighth_sample_distance")
    display.AFAMSampleDistance = 0
    psnr, _ = compare(png, fine)
    print("default image against an eighth of its sample distance: PSNR %.2f dB" % psnr, flush=True)
    if psnr < 38:
        u.fail("the default image is %.2f dB from a finely sampled one (bar 38 dB)" % psnr)


def colour_spaces():
    """A 16^3 field, constant 40 but for one corner sample at 100 (the file's range 40..100):
    from the far side of the corner, every pixel of the centre sees the constant, opaque."""
    import numpy as np
    n = 16
    values = np.full((n, n, n), 40, dtype=np.uint8)
    values[n - 1, n - 1, n - 1] = 100
    raw = os.path.join(out, "constant_16x16x16_uint8.raw")
    values.tofile(raw)
    path = os.path.join(out, "constant.afam")
    encode(raw, (n, n, n), "uint8", path)
    v = view()
    display = Show(OpenDataFile(path), v)
    display.AFAMDrawMissingValues = 0
    array = display.ColorArrayName[1]
    lut, pwf = GetColorTransferFunction(array), GetOpacityTransferFunction(array)
    pwf.Points = [0.0, 1.0, 0.5, 0.0, 255.0, 1.0, 0.5, 0.0]
    v.CameraPosition, v.CameraFocalPoint, v.CameraViewUp = [7.5, 7.5, -40], [7.5, 7.5, 7.5], [0, 1, 0]
    cases = [(space, False) for space in ("RGB", "HSV", "Lab", "Lab/CIEDE2000", "Diverging", "Step")]
    cases.append(("Diverging", True))
    for space, above in cases:
        lut.ColorSpace = space
        lut.RGBPoints = [0.0, 0.23, 0.30, 0.75, 70.0, 0.87, 0.87, 0.87, 100.0, 0.71, 0.02, 0.15]
        lut.UseAboveRangeColor = 1 if above else 0
        lut.AboveRangeColor = [0.1, 0.9, 0.2]
        if above:
            lut.RGBPoints = [0.0, 0.23, 0.30, 0.75, 20.0, 0.87, 0.87, 0.87, 30.0, 0.71, 0.02, 0.15]
        rgb = [0.0, 0.0, 0.0]
        lut.GetClientSideObject().GetColor(40.0, rgb)  # what MapValue maps, before its rounding
        want = [255 * c for c in rgb]
        got = u.read_rgb(shot(v, "constant_%s%s" % (space.replace("/", "_"), "_above" if above else "")))
        centre = got[SIZE // 2 - 20:SIZE // 2 + 20, SIZE // 2 - 20:SIZE // 2 + 20].reshape(-1, 3)
        worst = float(abs(centre - want).max())
        print("%s%s: MapValue(40) %s, drawn %s, largest difference %.2f/255" % (
            space, " above range" if above else "", [round(c, 1) for c in want],
            centre.mean(axis=0).round(1).tolist(), worst), flush=True)
        if worst > 1.0:
            u.fail("colour space %s: the constant region is drawn %.2f/255 from MapValue" % (space, worst))


afam_view, display, png = against_paraview()
no_banding(afam_view, display, png)
colour_spaces()
print("AFAM-MATCHES-VOLUME-OK")

# SPDX-License-Identifier: BSD-3-Clause
"""pvpython (and, with AFAM_TEST_GUI set, the ParaView GUI): the volume shows itself.
- OpenDataFile + Show in a render view: "Adaptive-FAM Volume", coloured by the file's point scalar,
  with the colour map and opacity ramp ParaView's own "Volume" gets when it is picked (same preset
  points, both rescaled to the data range), and a coloured picture.
- Outline, ColorBy(display, None), then SetRepresentationType("Adaptive-FAM Volume") (what the
  GUI's representation combo box calls): coloured again.
- The encoder's output: picking "Adaptive-FAM Volume" by hand colours it too."""
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))  # the GUI defines no __file__
import afam_test_util as u  # noqa: E402

from paraview.simple import (ColorBy, CreateView, GetActiveViewOrCreate, GetColorTransferFunction,  # noqa: E402
                             GetOpacityTransferFunction, OpenDataFile, Render, ResetSession,
                             SaveScreenshot, Show, Wavelet)

GUI = bool(os.environ.get("AFAM_TEST_GUI"))
u.load_plugin(globals())
out = u.out_dir()
path = os.path.join(out, "show_coloured.afam")
u.encode_wavelet(globals(), [-20, 20, -20, 20, -20, 20], 3, 4, 0.005, path)


def colour_array(display):
    return tuple(display.ColorArrayName)


def maps(array):
    """The colour map's points and the opacity ramp's, positions normalised to [0, 1]."""
    def normalised(points, stride):
        lo, hi = points[0], points[-stride]
        return [round((p - lo) / (hi - lo), 4) if i % stride == 0 else round(p, 4)
                for i, p in enumerate(points)], (lo, hi)
    rgb, rgb_range = normalised(list(GetColorTransferFunction(array).RGBPoints), 4)
    alpha, alpha_range = normalised(list(GetOpacityTransferFunction(array).Points), 4)
    return rgb, alpha, rgb_range, alpha_range


def coloured_pixels(png):
    """Foreground pixels whose channels differ by more than 40/255 (not grey)."""
    rgb = u.read_rgb(png)
    spread = rgb.max(axis=2) - rgb.min(axis=2)
    return int(((spread > 40) & u.foreground_mask(png)).sum())


def check_coloured(display, view, tag):
    rep, array = display.Representation, colour_array(display)
    Render(view)
    png = os.path.join(out, "%s.png" % tag)
    SaveScreenshot(png, view, ImageResolution=[301, 300])
    fg, coloured = u.non_blank(png), coloured_pixels(png)
    print("%s: representation %r, ColorArrayName %s, %d foreground pixels, %d coloured"
          % (tag, rep, array, fg, coloured), flush=True)
    if rep != "Adaptive-FAM Volume":
        u.fail("%s: representation %r, not 'Adaptive-FAM Volume'" % (tag, rep))
    if array != ("POINTS", "RTData"):
        u.fail("%s: ColorArrayName %s, not the file's point scalar RTData" % (tag, array))
    if fg < 2000 or coloured < fg // 5:
        u.fail("%s: %d foreground pixels of which %d coloured: the volume is not drawn in colour"
               % (tag, fg, coloured))


view = GetActiveViewOrCreate("RenderView") if GUI else CreateView("RenderView")  # the GUI's own view
u.setup_view(view)
model = OpenDataFile(path)
display = Show(model, view)
print("representation proxy: %s" % display.GetXMLName())
if display.GetXMLName() != "AFAMRepresentation":
    u.fail("Show created %s, not the reader's AFAMRepresentation" % display.GetXMLName())
check_coloured(display, view, "after_show")
afam_rgb, afam_alpha, afam_rgb_range, afam_alpha_range = maps("RTData")

# ParaView's stock representation proxy with the type set as a plain property (what Show gave
# before): no colouring, and the measure above says so.
if not GUI:
    plain_view = CreateView("RenderView")
    u.setup_view(plain_view)
    plain = Show(model, plain_view, "UniformGridRepresentation")
    plain.Representation = "Adaptive-FAM Volume"
    Render(plain_view)
    grey = os.path.join(out, "uncoloured.png")
    SaveScreenshot(grey, plain_view, ImageResolution=[301, 300])
    print("stock proxy: ColorArrayName %s, %d foreground pixels, %d coloured"
          % (colour_array(plain), u.non_blank(grey), coloured_pixels(grey)), flush=True)
    if coloured_pixels(grey) > u.non_blank(grey) // 100:
        u.fail("the uncoloured volume counts as coloured: the check cannot fail")

display.SetRepresentationType("Outline")
ColorBy(display, None)
if colour_array(display)[1]:
    u.fail("ColorBy(display, None) left %s" % (colour_array(display),))
display.SetRepresentationType("Adaptive-FAM Volume")
check_coloured(display, view, "picked_again")

# The encoder's output gets the same representation proxy: picking the volume colours it.
encoder = AdaptiveFAMEncoder(Input=Wavelet(WholeExtent=[-10, 10, -10, 10, -10, 10]), Levels=2)  # noqa: F821
encoded = Show(encoder, view)
display.Visibility = 0
if encoded.GetXMLName() != "AFAMRepresentation":
    u.fail("the encoder's output is shown with %s" % encoded.GetXMLName())
ColorBy(encoded, None)
encoded.SetRepresentationType("Adaptive-FAM Volume")
print("encoder output picked: ColorArrayName %s" % (colour_array(encoded),))
if colour_array(encoded) != ("POINTS", "RTData"):
    u.fail("picking 'Adaptive-FAM Volume' on the encoder's output left ColorArrayName %s"
           % (colour_array(encoded),))

# ParaView's own "Volume" in a fresh session: the same colour map and opacity ramp.
if not GUI:  # ResetSession would close the GUI's own windows
    ResetSession()
    view = CreateView("RenderView")
    wavelet = Wavelet(WholeExtent=[-20, 20, -20, 20, -20, 20])
    reference = Show(wavelet, view)
    reference.SetRepresentationType("Volume")
    pv_rgb, pv_alpha, pv_rgb_range, pv_alpha_range = maps("RTData")
    print("colour map range: Adaptive-FAM %s, ParaView's Volume %s; opacity ramp: %s / %s"
          % (afam_rgb_range, pv_rgb_range, afam_alpha, pv_alpha))
    if afam_rgb != pv_rgb or afam_alpha != pv_alpha:
        u.fail("colour or opacity maps differ from ParaView's Volume:\n%s\n%s\n%s\n%s"
               % (afam_rgb, pv_rgb, afam_alpha, pv_alpha))
    for a, b in zip(afam_rgb_range + afam_alpha_range, pv_rgb_range + pv_alpha_range):
        if abs(a - b) > 1e-3 * abs(b) + 1e-6:
            u.fail("transfer-function ranges differ from ParaView's Volume: %s %s / %s %s"
                   % (afam_rgb_range, afam_alpha_range, pv_rgb_range, pv_alpha_range))
print("AFAM-SHOW-COLOURED-OK", flush=True)

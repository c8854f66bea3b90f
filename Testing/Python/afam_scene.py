# SPDX-License-Identifier: BSD-3-Clause
"""The client-server tests' scene and image comparison, shared by the pvpython and GUI clients."""
import os

import afam_test_util as u

SIZE = [301, 300]
SHOT = [420, 380]  # a screenshot larger than the view: tiles rendered on the server


def scene(path, out, name, view, ball=False, statistics=None):
    """Render the file (and a sphere) in `view` with the test camera; write <name>.png (view size)
    and, for the volume alone, <name>_shot.png (SHOT). With `statistics` (a dict), the first, cold
    frame's figures over the server ranks go to statistics[name]. Returns the image paths."""
    from paraview.simple import OpenDataFile, Render, SaveScreenshot, Show, Sphere
    u.setup_view(view, SIZE)
    display = Show(OpenDataFile(path), view)
    display.Representation = "Adaptive-FAM Volume"
    u.apply_transfer_function(display)
    display.AFAMPrefetcher = "None"  # bytes read for this view only
    if ball:
        sphere = Sphere(Center=[6.0, 4.0, 8.0], Radius=9.0, ThetaResolution=48, PhiResolution=48)
        Show(sphere, view).DiffuseColor = [0.9, 0.8, 0.2]
    Render(view)
    if statistics is not None:
        import afam_client
        statistics[name] = afam_client.frame_statistics(display)
    images = [(os.path.join(out, name + ".png"), SIZE)]
    if not ball:
        images.append((os.path.join(out, name + "_shot.png"), SHOT))
    for png, size in images:
        SaveScreenshot(png, view, ImageResolution=size)
    return [png for png, _ in images]


def same_image(png, reference, out, tolerance, fraction_allowed):
    """The comparison of the VTK tests (vtkTesting, threshold 0), then at most fraction_allowed of
    the pixels off by more than tolerance/255 in some channel."""
    from vtkmodules.vtkTestingRendering import vtkTesting
    t = vtkTesting()
    for arg in ("-T", out, "-V", reference):
        t.AddArgument(arg)
    if t.RegressionTest(png, 0.0) != vtkTesting.PASSED:
        u.fail("%s differs from %s (vtkTesting, threshold 0; see %s)" % (png, reference, out))
    fraction, worst = u.differing_fraction(png, reference, tolerance)
    print("%s: %.3f %% of pixels differ from builtin by more than %d/255, largest %d/255"
          % (os.path.basename(png), 100 * fraction, tolerance, worst), flush=True)
    if fraction > fraction_allowed:
        u.fail("%s differs from %s in %.3f %% of its pixels (largest %d/255)"
               % (png, reference, 100 * fraction, worst))

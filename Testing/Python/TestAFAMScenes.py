# SPDX-License-Identifier: BSD-3-Clause
"""pvbatch: ParaView's render view around the "Adaptive-FAM Volume" representation, one scene at a
time, each saved as an image (scripts/gpu_pv_check.sh casts them on the CPU and on the GPU and
compares the two; CI checks the figures below on the CPU):
- depth compositing with an opaque slice through the volume (a Slice of the same Wavelet) and with
  an opaque sphere inside it: rays stop at them (AFAMLastDepthLimitedPixels), none stop without them;
- the four blend modes: four different images;
- a screenshot twice the view's size: the volume drawn where the view draws it, scaled;
- the still and interactive renders of one view: the interactive frame is drawn (whatever its
  scale), and the still frame after it equals the still frame before it.
With AFAM_TEST_NO_GPU=1 (the GPU asked for where none can be used: no CUDA in the plugin, no
driver, or CUDA hidden): every frame cast on the CPU, one warning that says why, and the image the
CPU draws."""
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

from paraview.simple import (CreateView, Hide, OpenDataFile, Render, SaveScreenshot, Show, Slice,  # noqa: E402
                             Sphere)

u.load_plugin(globals())
out = u.out_dir()
path = os.path.join(out, "wavelet_scenes.afam")
wavelet, _ = u.encode_wavelet(globals(), [-20, 20, -20, 20, -20, 20], 3, 4, 0.005, path)
model = OpenDataFile(path)
view = CreateView("RenderView")
u.setup_view(view)
display = Show(model, view)
display.Representation = "Adaptive-FAM Volume"
u.apply_transfer_function(display)
NO_GPU = os.environ.get("AFAM_TEST_NO_GPU") == "1"


def stat(name):
    display.UpdatePropertyInformation()
    return display.GetPropertyValue(name)


def shot(name, resolution=(301, 300)):
    png = os.path.join(out, name + ".png")
    SaveScreenshot(png, view, ImageResolution=list(resolution))
    return png


def no_gpu():
    # The GPU asked for where it cannot be used: CPU frames, one warning naming why, the CPU's image.
    display.AFAMRenderDevice = "GPU"
    _, messages = u.captured_messages(lambda: [Render(view) for _ in range(3)])
    gpu_png = shot("no_gpu_asked_gpu")
    warnings = messages.count("RenderDevice is GPU but")
    used, why = stat("AFAMLastUsedGpu"), stat("AFAMLastDeviceMessage")
    display.AFAMRenderDevice = "CPU"
    cpu_png = shot("no_gpu_asked_cpu")
    fraction, worst = u.differing_fraction(gpu_png, cpu_png, 0)
    print("no-gpu: cast on the GPU %d, %d warning(s) in 3 frames (%s), %d pixels drawn, largest "
          "difference from the CPU frame %d/255" % (used, warnings, why, u.non_blank(gpu_png), worst))
    if used != 0 or warnings != 1 or not why or u.non_blank(gpu_png) < 2000 or worst != 0:
        u.fail("the GPU asked for where none is usable: expected CPU frames equal to the CPU's and one warning")


def scenes():
    # 1. Depth compositing: an opaque slice (z = 0 plane of the same Wavelet), then an opaque sphere.
    Render(view)
    alone = stat("AFAMLastDepthLimitedPixels")
    shot("volume")
    cut = Slice(Input=wavelet)
    cut.SliceType = "Plane"
    cut.SliceType.Origin = [0.0, 0.0, 0.0]
    cut.SliceType.Normal = [0.0, 0.0, 1.0]
    cut_display = Show(cut, view)
    cut_display.ColorArrayName = [None, ""]
    cut_display.DiffuseColor = [0.85, 0.85, 0.85]
    Render(view)
    sliced = stat("AFAMLastDepthLimitedPixels")
    shot("slice")
    Hide(cut, view)
    ball = Sphere(Center=[4.0, 2.0, 6.0], Radius=8.0, ThetaResolution=48, PhiResolution=48)
    ball_display = Show(ball, view)
    ball_display.DiffuseColor = [0.9, 0.8, 0.2]
    Render(view)
    sphered = stat("AFAMLastDepthLimitedPixels")
    shot("sphere")
    Hide(ball, view)
    print("depth-limited pixels: volume alone %d, with the slice %d, with the sphere %d" % (alone, sliced, sphered))
    if alone != 0 or sliced < 5000 or sphered < 2000:
        u.fail("depth compositing: rays stopped at %d / %d / %d pixels (alone must be 0; slice >= 5000; "
               "sphere >= 2000)" % (alone, sliced, sphered))

    # 2. Blend modes: four different images.
    pngs = {}
    for mode in ("Composite", "Maximum Intensity", "Minimum Intensity", "Average Intensity"):
        display.AFAMBlendMode = mode
        Render(view)
        pngs[mode] = shot("blend_" + mode.split()[0].lower())
    display.AFAMBlendMode = "Composite"
    modes = list(pngs)
    for i, a in enumerate(modes):
        for b in modes[i + 1:]:
            fraction, worst = u.differing_fraction(pngs[a], pngs[b], 8)
            print("blend %s against %s: %.1f %% of pixels differ by more than 8/255 (largest %d/255)"
                  % (a, b, 100 * fraction, worst))
            if fraction < 0.02:
                u.fail("blend modes %s and %s give nearly the same image" % (a, b))

    # 3. A screenshot twice the view's size: the same picture, scaled (foreground box and centroid).
    small = shot("still")
    large = shot("large", (602, 600))
    box_small, box_large = u.foreground_box(small), u.foreground_box(large)
    print("foreground box: view %s, screenshot 602x600 %s" % (box_small, box_large))
    if max(abs(2 * a - b) for a, b in zip(box_small, box_large)) > 6:
        u.fail("the larger screenshot does not draw the volume where the view does, scaled by 2")
    if stat("AFAMLastImageScale") != 1.0:
        u.fail("a screenshot frame was cast at image scale %s" % stat("AFAMLastImageScale"))

    # 4. Still and interactive renders of one view: the still frame after interacting is the first.
    view.StillRender()
    u.check_frames(view, "StillRender")
    before = shot("still_before")
    view.CameraPosition = [60.0, 50.0, 86.0]
    view.InteractiveRender()
    u.check_frames(view, "InteractiveRender")
    interactive_scale = stat("AFAMLastImageScale")
    view.CameraPosition = [62.0, 48.0, 86.0]
    view.StillRender()
    u.check_frames(view, "StillRender")
    still_scale = stat("AFAMLastImageScale")
    after = shot("still_after")
    fraction, worst = u.differing_fraction(before, after, 0)
    print("interactive frame at image scale %.3f, still frame after it %.3f; still frames before and after "
          "differ by at most %d/255" % (interactive_scale, still_scale, worst))
    if not 0.05 <= interactive_scale <= 1.0 or still_scale != 1.0 or worst > 0:
        u.fail("still / interactive renders: scales %s / %s, still frames differ by %d/255"
               % (interactive_scale, still_scale, worst))


# (no sys.exit: pvbatch 5.11 crashes on it at exit)
(no_gpu if NO_GPU else scenes)()
print("AFAM-SCENES-OK")

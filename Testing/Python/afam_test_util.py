# SPDX-License-Identifier: BSD-3-Clause
"""Helpers shared by the plugin's pvpython/pvbatch/GUI tests (see CMakeLists.txt for the env)."""
import os
import shutil
import sys


def device_under_test():
    """"gpu" or "cpu" when AFAM_TEST_DEVICE names one (scripts/gpu_pv_check.sh), else None (CI)."""
    device = os.environ.get("AFAM_TEST_DEVICE", "").lower()
    return device if device in ("gpu", "cpu") else None


def render_device(default):
    """The AFAMRenderDevice a test that picks one should pick: the device under test when
    AFAM_TEST_DEVICE names one (scripts/gpu_pv_check.sh), else `default`."""
    device = device_under_test()
    return device.upper() if device else default


def _afam_displays(view):
    """The visible "Adaptive-FAM Volume" displays of `view` (none for a layout or no view)."""
    try:
        representations = list(view.Representations)
    except AttributeError:
        return []
    return [r for r in representations if r.GetProperty("AFAMLastUsedGpu") is not None
            and r.GetProperty("Representation") is not None and r.Representation == "Adaptive-FAM Volume"
            and r.Visibility]


_frames_seen = {}  # display proxy id -> (frames, renderer builds) at the last check


def check_frames(view, what):
    """With AFAM_TEST_DEVICE: each visible Adaptive-FAM display of `view` set to that device drew its
    last frame there; with gpu and AFAM_TEST_INTEROP=1 (OpenGL on the NVIDIA driver) also through
    CUDA-OpenGL interop, the frame that built the renderer included. One "[pv frame]" line per
    display; fails otherwise."""
    device = device_under_test()
    if device is None:
        return
    need_interop = device == "gpu" and os.environ.get("AFAM_TEST_INTEROP") == "1"
    from paraview import servermanager
    if servermanager.ActiveConnection is not None and servermanager.ActiveConnection.IsRemote():
        _check_server_frames(view, what, device, need_interop)
        return
    for display in _afam_displays(view):
        display.UpdatePropertyInformation()
        value = display.GetPropertyValue
        frames, builds = value("AFAMNumberOfFrames"), value("AFAMNumberOfRendererBuilds")
        key = display.GetGlobalIDAsString()
        last_frames, last_builds = _frames_seen.get(key, (0, 0))
        _frames_seen[key] = (frames, builds)
        if frames == last_frames:
            continue  # nothing drawn by this display since the last check
        chosen = str(display.AFAMRenderDevice).strip("'\"")
        used_gpu, on_device = value("AFAMLastUsedGpu"), value("AFAMLastImageOnDevice")
        built = builds > last_builds and frames == last_frames + 1
        print("[pv frame] %s: device %s, frame %d, cast on the GPU %d, through interop %d%s%s" % (
            what, chosen, frames, used_gpu, on_device, " (renderer built in this frame)" if built else "",
            "" if on_device or not used_gpu else "; interop: %s" % value("AFAMLastInteropProblem")), flush=True)
        if chosen != device.upper():
            continue  # the test itself picked the other device for this display
        if device == "cpu" and used_gpu:
            fail("%s: the display asked for the CPU cast on the GPU" % what)
        if device == "gpu" and not used_gpu:
            fail("%s: cast on the CPU though the GPU was asked for: %s" % (what, value("AFAMLastDeviceMessage")))
        if need_interop and not on_device:
            fail("%s: cast on the GPU but not drawn through interop: %s" % (what, value("AFAMLastInteropProblem")))


def _check_server_frames(view, what, device, need_interop):
    """check_frames for a view rendered by a pvserver: the client's copy of a display never renders,
    so the last frame is read from the server's ranks (afam_client.frame_statistics): every rank
    that drew blocks cast them on the device under test (and, with need_interop, drew them through
    interop)."""
    import afam_client  # Apps/pvbatch, on the client tests' path
    for display in _afam_displays(view):
        chosen = str(display.AFAMRenderDevice).strip("'\"")
        stats = afam_client.frame_statistics(display)
        ranks, drawing = stats["NumberOfRanks"], stats["RanksDrawingBlocks"]
        on_gpu, interop = stats["RanksOnGpu"], stats["RanksThroughInterop"]
        print("[pv frame] %s (pvserver, %d rank(s), %d drawing blocks): device %s, ranks cast on the "
              "GPU %d, through interop %d" % (what, ranks, drawing, chosen, on_gpu, interop), flush=True)
        if chosen != device.upper():
            continue
        if device == "cpu" and on_gpu:
            fail("%s: %d server rank(s) cast on the GPU though the CPU was asked for" % (what, on_gpu))
        if device == "gpu" and (drawing < 1 or on_gpu < drawing):
            fail("%s: %d of the %d server ranks drawing blocks cast on the GPU" % (what, on_gpu, drawing))
        if need_interop and interop < drawing:
            fail("%s: %d of the %d server ranks drawing blocks drew through interop" % (what, interop, drawing))


def _install_device_hook():
    """AFAM_TEST_DEVICE=gpu|cpu: paraview.simple's Show sets AFAMRenderDevice on every display that
    has it, and its Render and SaveScreenshot check the frames drawn (check_frames). Installed when
    this module is imported, so that the tests' own `from paraview.simple import ...` (after it)
    get the wrapped functions."""
    device = device_under_test()
    if device is None:
        return
    import paraview.simple as simple
    if getattr(simple, "_afam_device_hook", False):
        return
    show, render, screenshot = simple.Show, simple.Render, simple.SaveScreenshot

    def Show(*args, **kwargs):
        display = show(*args, **kwargs)
        if display is not None and display.GetProperty("AFAMRenderDevice") is not None:
            display.AFAMRenderDevice = device.upper()
        return display

    def Render(view=None, **kwargs):
        result = render(view, **kwargs)
        check_frames(view or simple.GetActiveView(), "Render")
        return result

    def SaveScreenshot(filename, viewOrLayout=None, *args, **kwargs):
        result = screenshot(filename, viewOrLayout, *args, **kwargs)
        check_frames(viewOrLayout or simple.GetActiveView(), "SaveScreenshot %s" % os.path.basename(filename))
        return result

    simple.Show, simple.Render, simple.SaveScreenshot = Show, Render, SaveScreenshot
    simple._afam_device_hook = True
    print("[pv frame] AFAM_TEST_DEVICE=%s: displays cast on the %s%s" % (
        device, device.upper(), ", drawn through interop" if os.environ.get("AFAM_TEST_INTEROP") == "1" else ""),
        flush=True)


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


def encode_wavelet(ns, extent, levels, blocks, bound, path):
    """A Wavelet over `extent`, encoded by the plugin's AdaptiveFAMEncoder (taken from `ns`, the
    namespace load_plugin filled) and saved to `path` (an old file is removed first). Returns
    (wavelet, encoder)."""
    from paraview.simple import SaveData, Wavelet
    wavelet = Wavelet(WholeExtent=list(extent))
    encoder = ns["AdaptiveFAMEncoder"](Input=wavelet, Levels=levels, BlocksPerAxis=blocks, ErrorBound=bound)
    encoder.Scalars = ["POINTS", "RTData"]
    if os.path.exists(path):
        os.remove(path)
    SaveData(path, proxy=encoder)
    return wavelet, encoder


def damaged_copy(good, bad, entries, fractions):
    """A copy of the .afam file `good` at `bad` with 8 bytes inverted at each fraction of its
    length, moved past the header and the index (`entries` entries) when the spot falls there."""
    data = bytearray(open(good, "rb").read())
    payload_start = (1024 + 40 * entries + 63) // 64 * 64  # docs/FORMAT.md: header, index, payloads
    for fraction in fractions:
        at = max(int(fraction * len(data)), payload_start)
        for k in range(8):
            data[at + k] ^= 0xFF
    with open(bad, "wb") as f:
        f.write(bytes(data))


def damaged_wavelet(ns, levels, fractions):
    """A Wavelet over [-20, 20]^3 encoded with `levels` levels of 4 finest blocks per axis and a
    0.5% bound (encode_wavelet), saved as intact.afam in out_dir(), and damaged.afam, its copy
    damaged at `fractions` of its length (damaged_copy). Returns both paths."""
    good = os.path.join(out_dir(), "intact.afam")
    bad = os.path.join(out_dir(), "damaged.afam")
    encode_wavelet(ns, [-20, 20, -20, 20, -20, 20], levels, 4, 0.005, good)
    damaged_copy(good, bad, sum(max(1, 4 >> k) ** 3 for k in range(levels)), fractions)
    return good, bad


def captured_messages(action):
    """(action()'s result, the text of the VTK messages it gave). pvpython's print goes to the
    output window too, so it is captured only meanwhile."""
    from vtkmodules.vtkCommonCore import vtkOutputWindow, vtkStringOutputWindow
    console = vtkOutputWindow.GetInstance()
    messages = vtkStringOutputWindow()
    vtkOutputWindow.SetInstance(messages)
    try:
        result = action()
    finally:
        vtkOutputWindow.SetInstance(console)
    return result, messages.GetOutput()


def setup_view(view, size=(301, 300)):
    """The fixed view every image test uses (Wavelet extent [-20, 20]^3, centred on the origin).
    paraview.simple's first Render would reset the camera to the data's bounds, which hides where
    the volume is drawn; the camera below stays, so the images show the volume's placement."""
    from paraview.simple import _DisableFirstRenderCameraReset
    _DisableFirstRenderCameraReset()
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
    """Colour and opacity maps set explicitly, so baselines do not depend on presets (the colour
    map in ParaView's default colour space, Diverging, as a user has it)."""
    from paraview.simple import ColorBy, GetColorTransferFunction, GetOpacityTransferFunction
    ColorBy(display, ("POINTS", array))
    lut = GetColorTransferFunction(array)
    lut.RGBPoints = [lo, 0.23, 0.30, 0.75, 0.5 * (lo + hi), 0.87, 0.87, 0.87, hi, 0.71, 0.02, 0.15]
    pwf = GetOpacityTransferFunction(array)
    pwf.Points = [lo, 0.0, 0.5, 0.0, 0.5 * (lo + hi), 0.05, 0.5, 0.0, hi, 0.6, 0.5, 0.0]
    display.ScalarOpacityUnitDistance = 2.0
    # screen-space LOD picks finer levels than the distance bands at this small view
    display.AFAMLodPolicy = "Screen-space error"


def compare_with_baseline(png, name, threshold=15.0, placement_tolerance=3):
    """vtkTesting image comparison plus the foreground's box and centroid (pixels); a missing
    baseline fails and leaves the image to review."""
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
    # vtkImageDifference's per-pixel threshold (105 by default, with neighbourhood averaging) passes
    # smooth volume images even when the volume is drawn elsewhere: compare where it is drawn too.
    got, want = foreground_box(png), foreground_box(baseline)
    if max(abs(a - b) for a, b in zip(got, want)) > placement_tolerance:
        fail("image %s: foreground box/centroid %s, baseline %s %s" % (png, got, name, want))
    # Strict: under 0.5% of the pixels may differ by more than 24/255 in some channel.
    fraction, worst = differing_fraction(png, baseline, 24)
    print("strict comparison: %.3f %% of pixels differ by more than 24/255 (bar 0.5 %%), largest %d/255"
          % (100 * fraction, worst))
    if fraction > 0.005:
        fail("image %s differs from baseline %s in %.2f %% of its pixels" % (png, name, 100 * fraction))
    print("image matches baseline %s" % name)


def read_rgb(png):
    """(rows, columns, 3) integer array of a PNG, bottom row first."""
    from vtkmodules.vtkIOImage import vtkPNGReader
    from vtkmodules.util.numpy_support import vtk_to_numpy
    r = vtkPNGReader()
    r.SetFileName(png)
    r.Update()
    w, h, _ = r.GetOutput().GetDimensions()
    return vtk_to_numpy(r.GetOutput().GetPointData().GetScalars())[:, :3].astype(int).reshape(h, w, 3)


def differing_fraction(png, baseline, tolerance):
    """Fraction of pixels whose largest channel difference exceeds tolerance, and the largest."""
    a, b = read_rgb(png), read_rgb(baseline)
    if a.shape != b.shape:
        fail("image %s is %s, baseline %s is %s" % (png, a.shape, baseline, b.shape))
    d = abs(a - b).max(axis=2)
    return float((d > tolerance).mean()), int(d.max())


def foreground_mask(png, background=(0.1, 0.1, 0.15), tolerance=8):
    """Boolean (rows, columns) array, bottom row first: pixels that differ from the background
    colour by more than tolerance/255 in some channel."""
    import numpy as np
    pixels = read_rgb(png).astype(float)
    bg = np.array([255.0 * c for c in background])
    return np.abs(pixels - bg).max(axis=2) > tolerance


def foreground_box(png, background=(0.1, 0.1, 0.15), tolerance=8):
    """(x0, y0, x1, y1, cx, cy) of the foreground (foreground_mask): its bounding box and
    centroid, in pixels."""
    import numpy as np
    ys, xs = np.nonzero(foreground_mask(png, background, tolerance))
    if xs.size == 0:
        fail("%s shows nothing but the background" % png)
    return (int(xs.min()), int(ys.min()), int(xs.max()), int(ys.max()),
            round(float(xs.mean()), 1), round(float(ys.mean()), 1))


def non_blank(png, background=(0.1, 0.1, 0.15), min_pixels=500):
    """Number of pixels that differ from the background colour by more than 8/255."""
    return int(foreground_mask(png, background, 8).sum())


def raws_to_vti(raws, dims, name):
    """Each float32 raw file of `raws` (x fastest) written as a .vti file beside it, its scalars
    named `name`: a file series ParaView reads. Returns the .vti paths, in the same order."""
    from vtkmodules.vtkIOImage import vtkImageReader2
    from vtkmodules.vtkIOXML import vtkXMLImageDataWriter
    written = []
    for raw in raws:
        reader = vtkImageReader2()
        reader.SetFileName(raw)
        reader.SetFileDimensionality(3)
        reader.SetFileLowerLeft(True)  # rows as stored, not flipped
        reader.SetDataScalarTypeToFloat()
        reader.SetDataByteOrderToLittleEndian()
        reader.SetDataExtent(0, dims[0] - 1, 0, dims[1] - 1, 0, dims[2] - 1)
        reader.Update()
        reader.GetOutput().GetPointData().GetScalars().SetName(name)
        written.append(os.path.splitext(raw)[0] + ".vti")
        writer = vtkXMLImageDataWriter()
        writer.SetInputData(reader.GetOutput())
        writer.SetFileName(written[-1])
        writer.Write()
    return written


def afam_models(path):
    """The partition and micro-models of an .afam file (docs/FORMAT.md), for comparing encodes:
    (header bytes 24..176 and 240..444: dims, origin, spacing, value range, bound, partition, mode;
    not the scalar name or checksums), and per model its index entry but the payload offset (NCP,
    kind, value range, errors, checksum, size) with its stored bytes."""
    import struct
    with open(path, "rb") as f:
        data = f.read()
    entries = struct.unpack_from("<Q", data, 144)[0]
    header = data[24:140] + data[144:152] + data[240:444]
    models = []
    for e in range(entries):
        at = 1024 + 40 * e
        offset, = struct.unpack_from("<Q", data, at)
        stored, = struct.unpack_from("<I", data, at + 36)
        models.append((data[at + 8:at + 40], data[offset:offset + stored]))
    return header, models


def compare_models(path, reference):
    """None when the two files hold the same micro-models (afam_models), else what differs first."""
    (h1, m1), (h2, m2) = afam_models(path), afam_models(reference)
    if h1 != h2:
        return "headers differ (dims, range, bound or partition)"
    if len(m1) != len(m2):
        return "%d models against %d" % (len(m1), len(m2))
    for i, (a, b) in enumerate(zip(m1, m2)):
        if a[0] != b[0]:
            return "model %d: index entries differ (NCP, kind, range, errors or checksum)" % i
        if a[1] != b[1]:
            return "model %d: stored bytes differ" % i
    return None


_install_device_hook()

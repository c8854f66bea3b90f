# SPDX-License-Identifier: BSD-3-Clause
"""The README's main job, rendering side (pvbatch): points of view of a trajectory file rendered
through the Adaptive-FAM ParaView plugin ("Adaptive-FAM Volume" representation), next to Core's
`afam render` of the same view and, optionally, ParaView's own "Volume" representation of the raw
volume; every image is scored against the analytic Marschner-Lobb ground truth.

    xvfb-run -a -s "-screen 0 1280x1024x24 -noreset" pvbatch afam_demo.py \\
        --plugin AdaptiveFAM.so --afam afam --trajectory walk.dat --out DIR \\
        --method adaptive=ml_adaptive.afam --method fixed=ml_fixed.afam --method ds=ml_ds.afam \\
        [--raw ml.raw] [--views 0,100,200] [--size 256] [--repeats 3] [--sample-distance 0.005]

Same view everywhere: the pose -> camera conversion of Core's Camera::fromPose (eye at
distance * (sin t cos p, sin t sin p, cos t) in the normalised frame where the volume spans
[-1, 1]^3, looking at the centre, up = (-sin p, cos p, 0), view angle 2 atan(1/8)), mapped to world
coordinates through the volume's bounds the way vtkAFAMVolumeMapper maps them back. Same transfer
function everywhere: Core's preset (TransferFunction::preset over the file's value range, the one
`afam render` uses), set as ParaView colour/opacity maps. Same sample distance (normalised units).

Timing: one warm-up render, then the median of --repeats renders (wall clock of Render(view) in
this process; for `afam render`, its printed render_ms + caching_ms, one process per repeat).
Writes DIR/<renderer>_<method>_<view>.png, DIR/gt_<view>.png, DIR/report.csv and prints a table.
"""
import argparse
import csv
import math
import os
import re
import statistics
import subprocess
import sys
import time


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--plugin", required=True, help="AdaptiveFAM.so")
    p.add_argument("--afam", required=True, help="the afam command line")
    p.add_argument("--trajectory", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--method", action="append", required=True, metavar="NAME=FILE.afam")
    p.add_argument("--raw", help="float32 volume for ParaView's own Volume representation")
    p.add_argument("--views", default="0,100,200")
    p.add_argument("--size", type=int, default=256)
    p.add_argument("--repeats", type=int, default=3, help="timed renders after one warm-up")
    p.add_argument("--cli-repeats", type=int, default=None, help="afam render runs (default --repeats)")
    p.add_argument("--sample-distance", type=float, default=0.005, help="normalised units")
    p.add_argument("--threads", type=int, default=0, help="ray-casting threads, 0 = all cores")
    a = p.parse_args()
    a.views = [int(v) for v in a.views.split(",") if v]
    a.methods = []
    for m in a.method:
        name, _, path = m.partition("=")
        if not path or not os.path.isfile(path):
            sys.exit("afam_demo: --method %s: expected NAME=FILE.afam of an existing file" % m)
        a.methods.append((name, os.path.abspath(path)))
    if a.cli_repeats is None:
        a.cli_repeats = a.repeats
    return a


def run(cmd):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)
    if r.returncode != 0:
        sys.exit("afam_demo: failed (%d): %s\n%s" % (r.returncode, " ".join(cmd), r.stdout))
    return r.stdout


def field(text, key):
    m = re.search(r"\b%s=([^\s]+)" % re.escape(key), text)
    return m.group(1) if m else None


def compare(afam, test, reference):
    out = run([afam, "compare", test, reference])
    return float(field(out, "psnr")), float(field(out, "ssim"))


def value_range(afam, path):
    m = re.search(r"range=\[([^,\]]+), ([^\]]+)\]", run([afam, "info", path]))
    lo, hi = float(m.group(1)), float(m.group(2))
    return lo, (hi if hi > lo else lo + 1.0)


PRESET_COLOUR_NODES = 256  # nodes of the colour map that stands for Core's preset


def preset_tf(lo, hi):
    """Core's TransferFunction::preset(lo, hi) (Core/src/scene/transfer_function.cpp) as ParaView
    RGBPoints / opacity Points, and its reference distance (normalised units). The preset's colours
    are interpolated in RGB between its five nodes (what `afam render` and the ground truth draw);
    a ParaView colour map interpolates between its nodes in its own colour space (Diverging by
    default), so the map gets the preset's colour at PRESET_COLOUR_NODES evenly spaced values:
    between nodes that close, every colour space draws the preset within 8-bit rounding, and the
    map keeps ParaView's default colour space."""
    at = lambda f: lo + f * (hi - lo)  # noqa: E731
    colors = [(0.0, 0.10, 0.20, 0.90), (0.25, 0.15, 0.45, 1.00), (0.5, 0.20, 0.90, 0.35),
              (0.75, 1.00, 0.55, 0.10), (1.0, 0.90, 0.10, 0.10)]
    alphas = [(0.0, 0.0), (0.15, 0.0), (0.2, 0.0), (0.25, 0.015), (0.3, 0.0), (0.45, 0.0), (0.5, 0.03),
              (0.55, 0.0), (0.7, 0.0), (0.75, 0.12), (0.8, 0.0), (1.0, 0.0)]

    def colour(f):  # RGB interpolation between the preset's nodes
        for (f0, *c0), (f1, *c1) in zip(colors, colors[1:]):
            if f <= f1:
                t = (f - f0) / (f1 - f0)
                return [a + t * (b - a) for a, b in zip(c0, c1)]
        return list(colors[-1][1:])

    fractions = [i / (PRESET_COLOUR_NODES - 1) for i in range(PRESET_COLOUR_NODES)]
    rgb = [x for f in fractions for x in [at(f)] + colour(f)]
    pts = [x for f, a in alphas for x in (at(f), a, 0.5, 0.0)]
    return rgb, pts, 0.01


def pose_camera(trajectory, index):
    """Core's loadTrajectory + Camera::fromPose in the normalised frame: eye, up, view angle."""
    import struct
    with open(trajectory, "rb") as f:
        data = f.read()
    n = len(data) // 12
    if not 0 <= index < n:
        sys.exit("afam_demo: view %d outside [0, %d)" % (index, n))
    vals = struct.unpack("<%df" % (3 * n), data[:12 * n])
    d, t, p = vals[index], math.radians(vals[n + index]), math.radians(vals[2 * n + index])
    eye = [d * math.sin(t) * math.cos(p), d * math.sin(t) * math.sin(p), d * math.cos(t)]
    up = [-math.sin(p), math.cos(p), 0.0]
    return eye, up, math.degrees(2.0 * math.atan(0.125))


class Scene:
    """One pvbatch render view set up like `afam render`'s frame (black background, no axes)."""

    def __init__(self, size):
        import paraview.simple as ps
        from paraview.simple import CreateView
        if hasattr(ps, "_DisableFirstRenderCameraReset"):
            ps._DisableFirstRenderCameraReset()  # the first Render() would reset our camera
        self.size = size
        self.view = CreateView("RenderView")
        v = self.view
        v.ViewSize = [size, size]
        v.OrientationAxesVisibility = 0
        try:
            v.UseColorPaletteForBackground = 0
        except AttributeError:
            pass
        v.Background = [0.0, 0.0, 0.0]
        # Core shades with a headlight only (raycast.hpp): ParaView's light kit off, one headlight.
        from paraview.simple import AddLight
        v.UseLight = 0
        light = AddLight(view=v)
        light.Coords = "Headlight"
        light.Type = "Directional"
        light.Intensity = 1.0

    def set_camera(self, bounds, eye_n, up_n, angle):
        center = [0.5 * (bounds[2 * a] + bounds[2 * a + 1]) for a in range(3)]
        half = [max(0.5 * (bounds[2 * a + 1] - bounds[2 * a]), 1e-12) for a in range(3)]
        v = self.view
        v.CameraPosition = [center[a] + half[a] * eye_n[a] for a in range(3)]
        v.CameraFocalPoint = center
        v.CameraViewUp = [up_n[a] * half[a] for a in range(3)]
        v.CameraViewAngle = angle
        v.CameraParallelProjection = 0
        return sum(half) / 3.0

    def show(self, source, representation):
        """Shows SOURCE in this view with REPRESENTATION; returns the display and world bounds."""
        from paraview.simple import Show
        source.UpdatePipeline()
        display = Show(source, self.view)
        display.Representation = representation
        return display, source.GetDataInformation().GetBounds()

    def point_of_view(self, trajectory, index, display, source, bounds, lo, hi):
        """Camera of trajectory pose INDEX and Core's preset transfer function; returns the mean
        half extent of the volume (world units per normalised unit)."""
        eye, up, angle = pose_camera(trajectory, index)
        mean_half = self.set_camera(bounds, eye, up, angle)
        apply_tf(display, point_array(source), lo, hi, preset_tf(lo, hi)[2] * mean_half)
        return mean_half

    def warm_up(self):
        """Pipeline update, file open, renderer construction and cache fill happen here."""
        from paraview.simple import Render
        Render(self.view)

    def timed_render(self):
        """Wall-clock milliseconds of one Render() of the view."""
        from paraview.simple import Render
        t0 = time.perf_counter()
        Render(self.view)
        return 1e3 * (time.perf_counter() - t0)

    def save(self, png):
        from paraview.simple import SaveScreenshot
        SaveScreenshot(png, self.view, ImageResolution=[self.size, self.size], TransparentBackground=0)


def apply_tf(display, array, lo, hi, unit_distance):
    from paraview.simple import ColorBy, GetColorTransferFunction, GetOpacityTransferFunction
    ColorBy(display, ("POINTS", array))
    rgb, pts, _ = preset_tf(lo, hi)
    lut = GetColorTransferFunction(array)
    lut.AutomaticRescaleRangeMode = "Never"
    lut.RGBPoints = rgb
    pwf = GetOpacityTransferFunction(array)
    pwf.Points = pts
    display.ScalarOpacityUnitDistance = unit_distance
    display.Shade = 1


def point_array(source):
    """Name of the source's first point array (the scalars the transfer function maps)."""
    info = source.GetPointDataInformation()
    if info.GetNumberOfArrays() == 0:
        sys.exit("afam_demo: %s has no point array to colour by" % source.GetXMLLabel())
    return info.GetArray(0).GetName()


def main():
    a = parse_args()
    os.makedirs(a.out, exist_ok=True)
    from paraview.simple import Hide, ImageReader, LoadPlugin, OpenDataFile
    LoadPlugin(a.plugin, remote=False, ns=globals())
    scene = Scene(a.size)
    size = "%d,%d" % (a.size, a.size)
    rows = []

    # The plugin (the .afam file opened in ParaView, "Adaptive-FAM Volume" representation) and
    # Core's own front end (`afam render`, one process per run) on the same view, their runs
    # interleaved so that a change of machine load hits both alike. The first `afam render` of a
    # view also writes the analytic ground truth.
    gt = {}
    for name, path in a.methods:
        lo, hi = value_range(a.afam, path)
        reader = OpenDataFile(path)
        display, bounds = scene.show(reader, "Adaptive-FAM Volume")
        for v in a.views:
            mean_half = scene.point_of_view(a.trajectory, v, display, reader, bounds, lo, hi)
            display.AFAMSampleDistance = a.sample_distance * mean_half
            display.AFAMThreads = a.threads
            display.AFAMLodPolicy = "Distance bands"  # the paper's policy, as `afam render` uses
            scene.warm_up()
            cli_png = os.path.join(a.out, "afam_%s_%d.png" % (name, v))
            plugin, core, cli = [], [], []
            for r in range(max(a.repeats, a.cli_repeats)):
                if r < a.cli_repeats:
                    cmd = [a.afam, "render", path, "--trajectory", a.trajectory, "--view", str(v),
                           "--size", size, "--out", cli_png, "--sample-distance", str(a.sample_distance),
                           "--threads", str(a.threads)]
                    if v not in gt:
                        gt[v] = os.path.join(a.out, "gt_%d.png" % v)
                        cmd += ["--ground-truth-ml", "--gt-out", gt[v]]
                    out = run(cmd)
                    cli.append(float(field(out, "render_ms")) + float(field(out, "caching_ms")))
                if r < a.repeats:
                    plugin.append(scene.timed_render())
                    display.UpdatePropertyInformation()
                    core.append(1e3 * (display.GetPropertyValue("AFAMLastRenderTime") +
                                       display.GetPropertyValue("AFAMLastCachingTime")))
            png = os.path.join(a.out, "plugin_%s_%d.png" % (name, v))
            scene.save(png)
            rows.append(dict(renderer="afam render", method=name, view=v, png=cli_png, times=cli))
            rows.append(dict(renderer="plugin", method=name, view=v, png=png, times=plugin,
                             core_ms=statistics.median(core)))
            print("%-8s view %3d: plugin %8.1f ms (Core inside %.1f ms), afam render %8.1f ms" % (
                name, v, statistics.median(plugin), statistics.median(core), statistics.median(cli)),
                flush=True)
        Hide(reader, scene.view)

    # ParaView's own Volume representation of the raw volume, same camera and transfer function.
    if a.raw:
        n = round((os.path.getsize(a.raw) // 4) ** (1.0 / 3.0))
        if n ** 3 * 4 != os.path.getsize(a.raw):
            sys.exit("afam_demo: %s is not a float32 N^3 volume" % a.raw)
        lo, hi = value_range(a.afam, a.methods[0][1])
        raw = ImageReader(FileNames=[os.path.abspath(a.raw)])
        raw.DataScalarType = "float"
        raw.DataByteOrder = "LittleEndian"
        raw.DataExtent = [0, n - 1, 0, n - 1, 0, n - 1]
        display, bounds = scene.show(raw, "Volume")
        for v in a.views:
            scene.point_of_view(a.trajectory, v, display, raw, bounds, lo, hi)
            scene.warm_up()
            times = [scene.timed_render() for _ in range(a.repeats)]
            png = os.path.join(a.out, "paraview_raw_%d.png" % v)
            scene.save(png)
            rows.append(dict(renderer="ParaView Volume", method="raw", view=v, png=png, times=times))
            print("ParaView     %-8s view %3d  %8.1f ms" % ("raw", v, statistics.median(times)), flush=True)
        Hide(raw, scene.view)

    # Scores against the analytic ground truth; the plugin also against afam render's image, and
    # its time as a multiple of afam render's on the same view.
    cli = {(r["method"], r["view"]): r for r in rows if r["renderer"] == "afam render"}
    for r in rows:
        r["median"] = statistics.median(r["times"])
        r["psnr"], r["ssim"] = compare(a.afam, r["png"], gt[r["view"]])
        r["vs_cli"] = r["ratio"] = ""
        if r["renderer"] == "plugin":
            ref = cli[(r["method"], r["view"])]
            r["vs_cli"] = "%.2f" % compare(a.afam, r["png"], ref["png"])[0]
            r["ratio"] = "%.2f" % (statistics.median(r["times"]) / statistics.median(ref["times"]))
    report = os.path.join(a.out, "report.csv")
    columns = ["renderer", "method", "view", "median_ms", "min_ms", "renders", "psnr", "ssim",
               "psnr_vs_afam_render", "time_vs_afam_render", "core_ms_in_plugin", "image"]
    with open(report, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(columns)
        for r in rows:
            w.writerow([r["renderer"], r["method"], r["view"], "%.1f" % r["median"], "%.1f" % min(r["times"]),
                        len(r["times"]), "%.2f" % r["psnr"], "%.4f" % r["ssim"], r["vs_cli"], r["ratio"],
                        "%.1f" % r["core_ms"] if "core_ms" in r else "", os.path.basename(r["png"])])
    print()
    fmt = "%-16s %-8s %5s %10s %8s %8s %7s %11s %7s"
    print(fmt % ("renderer", "method", "view", "median_ms", "core_ms", "psnr", "ssim", "vs_afam_dB", "time_x"))
    for r in rows:
        print(fmt % (r["renderer"], r["method"], r["view"], "%.1f" % r["median"],
                     "%.1f" % r["core_ms"] if "core_ms" in r else "", "%.2f" % r["psnr"],
                     "%.4f" % r["ssim"], r["vs_cli"], r["ratio"]))
    print("median_ms: wall clock per render (afam render: its render_ms + caching_ms); core_ms: Core's")
    print("share inside the plugin; psnr/ssim against the analytic ground truth; vs_afam_dB: plugin")
    print("image against afam render's (>= 96: equal up to 8-bit rounding of a few pixels); time_x:")
    print("plugin median / afam render median on the same view. Report: %s" % report)

if __name__ == "__main__":  # afam_demo_real.py imports the helpers above
    main()

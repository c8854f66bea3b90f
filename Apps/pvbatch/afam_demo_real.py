# SPDX-License-Identifier: BSD-3-Clause
"""The README's main job, real-volume part (pvbatch): one of the repository's corpus volumes,
encoded with `afam encode`, rendered through the Adaptive-FAM ParaView plugin ("Adaptive-FAM
Volume" representation) next to ParaView's own "Volume" representation of the raw file, on the same
points of view with the same transfer function (Core's preset over the volume's range). There is no
analytic ground truth for real data: the error printed is the data's (`afam verify --against`,
finest level) and the plugin's image against ParaView's, with the sizes of both files.

    xvfb-run -a -s "-screen 0 1280x1024x24 -noreset" pvbatch afam_demo_real.py \\
        --plugin AdaptiveFAM.so --afam afam --file neghip.afam --raw neghip_66x66x66_uint8.raw \\
        --trajectory orbit.dat --out DIR [--views 0,4,8] [--size 256] [--repeats 3]

The raw file's name gives its dims and type (name_XxYxZ_type.raw, as `afam encode` reads it).
Writes DIR/real_plugin_<view>.png, DIR/real_paraview_<view>.png, DIR/report_real.csv, prints a table.
"""
import argparse
import csv
import os
import re
import statistics
import sys

import afam_demo as demo  # Scene, run, field, compare, value_range: one copy of the shared steps

RAW_TYPES = {"uint8": "unsigned char", "int16": "short", "uint16": "unsigned short", "float32": "float",
             "float64": "double"}
RAW_SIZES = {"uint8": 1, "int16": 2, "uint16": 2, "float32": 4, "float64": 8}


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--plugin", required=True, help="AdaptiveFAM.so")
    p.add_argument("--afam", required=True, help="the afam command line")
    p.add_argument("--file", required=True, help="the .afam file encoded from --raw")
    p.add_argument("--raw", required=True, help="name_XxYxZ_type.raw")
    p.add_argument("--trajectory", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--views", default="0,4,8")
    p.add_argument("--size", type=int, default=256)
    p.add_argument("--repeats", type=int, default=3, help="timed renders after one warm-up")
    p.add_argument("--sample-distance", type=float, default=0.005, help="normalised units")
    p.add_argument("--threads", type=int, default=0, help="ray-casting threads, 0 = all cores")
    a = p.parse_args()
    a.views = [int(v) for v in a.views.split(",") if v]
    for path in (a.file, a.raw, a.trajectory):
        if not os.path.isfile(path):
            sys.exit("afam_demo_real: %s: no such file" % path)
    return a


def raw_reader(path):
    """ParaView's ImageReader over a name_XxYxZ_type.raw file (little-endian, x fastest)."""
    from paraview.simple import ImageReader
    m = re.search(r"_(\d+)x(\d+)x(\d+)_(%s)\.raw$" % "|".join(RAW_TYPES), path)
    if not m:
        sys.exit("afam_demo_real: %s does not follow name_XxYxZ_type.raw" % path)
    dims = [int(m.group(i)) for i in (1, 2, 3)]
    reader = ImageReader(FileNames=[os.path.abspath(path)])
    reader.DataScalarType = RAW_TYPES[m.group(4)]
    reader.DataByteOrder = "LittleEndian"
    reader.DataExtent = [0, dims[0] - 1, 0, dims[1] - 1, 0, dims[2] - 1]
    return reader


def render_views(a, scene, source, representation, prefix, lo, hi, plugin):
    """Renders every view of SOURCE; returns one row per view (png, render times)."""
    from paraview.simple import Hide
    display, bounds = scene.show(source, representation)
    rows = []
    for v in a.views:
        mean_half = scene.point_of_view(a.trajectory, v, display, source, bounds, lo, hi)
        if plugin:
            display.AFAMSampleDistance = a.sample_distance * mean_half
            display.AFAMThreads = a.threads
        scene.warm_up()
        times = [scene.timed_render() for _ in range(a.repeats)]
        png = os.path.join(a.out, "real_%s_%d.png" % (prefix, v))
        scene.save(png)
        rows.append(dict(view=v, png=png, median=statistics.median(times)))
    Hide(source, scene.view)
    return rows


def main():
    a = parse_args()
    os.makedirs(a.out, exist_ok=True)
    from paraview.simple import LoadPlugin, OpenDataFile
    LoadPlugin(a.plugin, remote=False, ns=globals())
    scene = demo.Scene(a.size)
    lo, hi = demo.value_range(a.afam, a.file)
    verify = demo.run([a.afam, "verify", a.file, "--against", a.raw])
    rmse, max_error = float(demo.field(verify, "rmse")), float(demo.field(verify, "max_error"))
    plugin = render_views(a, scene, OpenDataFile(a.file), "Adaptive-FAM Volume", "plugin", lo, hi, True)
    paraview = render_views(a, scene, raw_reader(a.raw), "Volume", "paraview", lo, hi, False)
    raw_bytes, afam_bytes = os.path.getsize(a.raw), os.path.getsize(a.file)
    name = os.path.basename(a.raw)
    report = os.path.join(a.out, "report_real.csv")
    fmt = "%-5s %12s %14s %8s %8s %7s"
    print()
    float32_bytes = raw_bytes // RAW_SIZES[re.search(r"_([a-z0-9]+)\.raw$", name).group(1)] * 4
    print("%s: raw %d bytes, .afam %d bytes (ratio %.2f; %.2f against float32); data error (finest level) "
          "rmse %.4g = %.3g%% of the range, max %.4g" % (name, raw_bytes, afam_bytes, raw_bytes / afam_bytes,
                                                        float32_bytes / afam_bytes, rmse, 100.0 * rmse / (hi - lo),
                                                        max_error))
    print(fmt % ("view", "plugin_ms", "paraview_ms", "psnr", "ssim", "images"))
    with open(report, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["volume", "view", "raw_bytes", "afam_bytes", "ratio", "rmse", "max_error", "plugin_ms",
                    "paraview_volume_ms", "psnr_plugin_vs_paraview", "ssim_plugin_vs_paraview"])
        for p, q in zip(plugin, paraview):
            psnr, ssim = demo.compare(a.afam, p["png"], q["png"])
            w.writerow([name, p["view"], raw_bytes, afam_bytes, "%.3f" % (raw_bytes / afam_bytes), "%.6g" % rmse,
                        "%.6g" % max_error, "%.1f" % p["median"], "%.1f" % q["median"], "%.2f" % psnr,
                        "%.4f" % ssim])
            print(fmt % (p["view"], "%.1f" % p["median"], "%.1f" % q["median"], "%.2f" % psnr, "%.4f" % ssim,
                         "real_plugin_%d.png / real_paraview_%d.png" % (p["view"], p["view"])))
    print("psnr/ssim: the plugin's image against ParaView's Volume representation of the raw file "
          "(two renderers, so not 99 dB even for exact data). Report: %s" % report, flush=True)


if __name__ == "__main__":
    main()

# SPDX-License-Identifier: BSD-3-Clause
"""Still-render time of the "Adaptive-FAM Volume" representation as a pvpython client sees it:
builtin, pvserver with 1 rank, pvserver with 2 ranks (mpirun), same file, views and image size, at
the default remote-render threshold. Prints one table (median and first frame, seconds).

    xvfb-run -a -s "-screen 0 1280x1024x24 -noreset" pvpython --force-offscreen-rendering \\
        Testing/Benchmarks/client_server.py build/lib/paraview-5.11/plugins/AdaptiveFAM/AdaptiveFAM.so \\
        [--extent 40] [--size 512] [--views 6]
"""
import argparse
import math
import os
import statistics
import sys
import tempfile
import time

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(here, "..", "Python"))
sys.path.insert(0, os.path.join(here, "..", "..", "Apps", "pvbatch"))
import afam_client  # noqa: E402
import afam_server  # noqa: E402

from paraview.simple import (CreateView, Delete, Disconnect, LoadPlugin, OpenDataFile, Render,  # noqa: E402
                             SaveData, Show, Wavelet)


def parse():
    p = argparse.ArgumentParser()
    p.add_argument("plugin")
    p.add_argument("--extent", type=int, default=40, help="Wavelet extent [-E, E]^3 (40: 81^3)")
    p.add_argument("--size", type=int, default=512)
    p.add_argument("--views", type=int, default=6)
    return p.parse_args()


def encode(ns, extent, path):
    wavelet = Wavelet(WholeExtent=[-extent, extent] * 3)
    encoder = ns["AdaptiveFAMEncoder"](Input=wavelet, ErrorBound=0.005)
    encoder.Scalars = ["POINTS", "RTData"]
    SaveData(path, proxy=encoder)


def timed_views(path, extent, size, views):
    """Seconds per still render over an orbit of `views` cameras (first one cold)."""
    from paraview.simple import ColorBy, GetColorTransferFunction, GetOpacityTransferFunction
    view = CreateView("RenderView")
    view.ViewSize = [size, size]
    display = Show(OpenDataFile(path), view)
    display.Representation = "Adaptive-FAM Volume"
    ColorBy(display, ("POINTS", "RTData"))
    GetColorTransferFunction("RTData").RescaleTransferFunction(37.35, 276.8)
    GetOpacityTransferFunction("RTData").RescaleTransferFunction(37.35, 276.8)
    seconds = []
    for k in range(views):
        a = 2 * math.pi * k / views
        view.CameraPosition = [3.5 * extent * math.cos(a), 1.2 * extent, 3.5 * extent * math.sin(a)]
        view.CameraFocalPoint = [0, 0, 0]
        view.CameraViewUp = [0, 1, 0]
        start = time.perf_counter()
        Render(view)
        seconds.append(time.perf_counter() - start)
    Delete(view)
    return seconds


def main():
    a = parse()
    work = tempfile.mkdtemp(prefix="afam_cs_bench_")
    path = os.path.join(work, "wavelet.afam")
    LoadPlugin(a.plugin, remote=False, ns=globals())
    encode(globals(), a.extent, path)
    rows = [("builtin", timed_views(path, a.extent, a.size, a.views))]
    Disconnect()
    for ranks in (1, 2):
        with afam_server.PVServer("pvserver", ranks, os.path.join(work, "pvserver%d.log" % ranks)) as s:
            afam_client.connect("127.0.0.1", s.port, a.plugin, ns=globals())
            rows.append(("pvserver %d rank%s" % (ranks, "s" if ranks > 1 else ""),
                         timed_views(path, a.extent, a.size, a.views)))
            Disconnect()
    side = 2 * a.extent + 1
    print("\nWavelet %d^3, %d x %d, %d views, default remote-render threshold" % (side, a.size, a.size, a.views))
    print("| mode | first frame (s) | median of the others (s) |")
    print("|---|---|---|")
    for name, seconds in rows:
        print("| %s | %.3f | %.3f |" % (name, seconds[0], statistics.median(seconds[1:])))


main()

# SPDX-License-Identifier: BSD-3-Clause
"""Resident memory of ParaView playing a run (issue 28's bar: playing 100 steps keeps resident
memory within the cache budget plus 10%), in pvbatch:

    pvbatch Testing/Benchmarks/playback_memory.py PLUGIN AFAM_EXE WORK [--dims 64,64,64]
            [--steps 100] [--budgets 16,64] [--size 400]

A Gray-Scott run (`afam simulate`, saved every 20 iterations) is encoded as one .afam run at a
relative RMSE of 1e-2, opened with OpenDataFile and shown as "Adaptive-FAM Volume" (CPU) with the
representation's cache budget set; the animation scene plays every step once (view time = the
step's time, Render). VmRSS (/proc/self/status) is read after the first frame and after each
step. Baseline in the same process, same view: the first step rendered as many times (no step
change), which is what VTK and ParaView themselves add while frames are drawn. One line per
budget: the run's decoded size, RSS after the first frame, peak and final growth over it, the
baseline's growth, and growth beyond the baseline against the budget."""
import argparse
import glob
import os
import subprocess

from paraview.simple import (GetActiveViewOrCreate, GetAnimationScene, Hide, LoadPlugin,
                             OpenDataFile, Render, Show)

parser = argparse.ArgumentParser()
parser.add_argument("plugin")
parser.add_argument("afam")
parser.add_argument("work")
parser.add_argument("--dims", default="64,64,64")
parser.add_argument("--steps", type=int, default=100)
parser.add_argument("--budgets", default="16,64")
parser.add_argument("--size", type=int, default=400)
args = parser.parse_args()
LoadPlugin(args.plugin, remote=False, ns=globals())


def rss_mb():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


os.makedirs(args.work, exist_ok=True)
prefix = os.path.join(args.work, "gs")
if len(glob.glob(prefix + "_*_float32.raw")) != args.steps:
    subprocess.check_call([args.afam, "simulate", prefix, "--dims", args.dims, "--steps",
                           str(args.steps), "--every", "20", "--warmup", "2000"],
                          stdout=subprocess.DEVNULL)
raws = sorted(glob.glob(prefix + "_*_float32.raw"))
run = os.path.join(args.work, "run.afam")
if not os.path.exists(run):
    subprocess.check_call([args.afam, "encode"] + raws + [run, "--error-bound", "1e-2",
                                                          "--relative", "--quiet"])
dims = [int(d) for d in args.dims.split(",")]
decoded_mb = args.steps * dims[0] * dims[1] * dims[2] * 4 * 8.0 / 7.0 / 2**20  # all levels
view = GetActiveViewOrCreate("RenderView")
view.ViewSize = [args.size, args.size]
print("run: %d steps of %s, %.1f MB on disk, about %.0f MB decoded (all levels, float32)"
      % (args.steps, args.dims, os.path.getsize(run) / 2**20, decoded_mb), flush=True)
print("RSS and the cache in MiB; the representation's budget (Cache Budget (MB)) in 10^6 bytes")
print("| cache budget | RSS after first frame | peak growth | final growth | baseline growth "
      "(%d frames of one step) | growth beyond baseline | cache's own peak | within budget + 10%% |"
      % args.steps)
print("|---|---|---|---|---|---|---|---|")
for budget in [float(b) for b in args.budgets.split(",")]:
    reader = OpenDataFile(run)
    display = Show(reader, view)
    display.Representation = "Adaptive-FAM Volume"
    display.AFAMCacheBudgetMB = budget
    scene = GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    times = list(reader.TimestepValues)
    view.ViewTime = times[0]
    view.ResetCamera()
    Render(view)
    first = rss_mb()
    for _ in range(len(times)):  # baseline: frames without a step change
        Render(view)
    baseline = rss_mb() - first
    peak = cache_peak = 0.0  # growth over the first frame: the baseline's, then the playback's
    for t in times:
        view.ViewTime = t
        Render(view)
        peak = max(peak, rss_mb() - first)
        display.UpdatePropertyInformation()
        cache_peak = max(cache_peak, display.GetProperty("AFAMLastCacheBytes").GetData() / 2**20)
    final = rss_mb() - first
    beyond = max(peak - baseline, 0.0)
    print("| %g MB | %.1f MiB | %.1f MiB | %.1f MiB | %.1f MiB | %.1f MiB | %.1f MiB | %s |"
          % (budget, first, peak, final, baseline, beyond, cache_peak,
             "yes" if beyond <= 1.1 * budget * 1e6 / 2**20 else "no"), flush=True)
    Hide(reader, view)
    del display, reader

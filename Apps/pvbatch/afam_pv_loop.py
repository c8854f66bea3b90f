# SPDX-License-Identifier: BSD-3-Clause
"""Frame times in ParaView's own render loop (pvbatch, paraview.simple's Render() per point of view)
on the views BenchAFAMRenderLoop and `afam replay` render, so that the three can be set side by side
on the same file, views and image size (scripts/gpu_pv_check.sh):

    pvbatch --no-mpi afam_pv_loop.py --plugin AdaptiveFAM.so (--file F.afam | --raw R.raw
        --value-range-of F.afam) --trajectory T.dat [--size 1024] [--frames N] [--cache-mb 220]
        [--device gpu|cpu|auto] [--cold] [--csv OUT.csv] [--connect PORT]
        [--miss-budget-ms B [--lod screen|distance]]

--file shows the .afam file with the "Adaptive-FAM Volume" representation set like BenchAFAMRenderLoop
(Core's preset transfer function over the file's value range, opacity unit 0.01 and sample distance
0.005 in the normalised frame, shading on, the paper's distance-band LOD, a cache of --cache-mb);
--raw shows an N^3 float32 raw file with ParaView's own "Volume" representation (its GPU ray caster)
and the same transfer function, shading and views. Each pose of the path becomes the camera of Core's
Camera::fromPose (afam_demo.pose_camera). --cold evicts the file from the page cache before every
frame. Frame 0 is the first image: timed from the reader's creation (and from Show) to its Render()
done; the medians and 95th percentile are over frames 1..N-1, each Render() plus the window's
WaitForCompletion. With the Adaptive-FAM representation, each frame's device and image path are read
back (frames cast on the GPU, frames drawn through CUDA-OpenGL interop). Under mpirun (pvbatch of
several ranks, each drawing its box) the mapper time of the slowest rank is read back too
(afam_client.frame_statistics). Last line: name=value pairs, starting "pv_render_loop".
--miss-budget-ms B (an .afam file): every frame after the first is an interactive render
(view.InteractiveRender()) under the representation's Interactive Miss Budget B at full image size
(no interactive scaling), as a user moving the camera gets them, with the LOD of --lod (default the
representation's default, screen-space error); each frame's caching time (its wait for misses, the
budget's subject), stand-ins and blocks behind are read back, and the last line adds the worst
caching time after the first frame and the stand-ins in all (issue 44).
--connect PORT (run in pvpython): the same through a pvserver listening on 127.0.0.1:PORT (the
plugin loaded on both sides, remote rendering always), each Render() timed on the client, the image
delivered to it included; a frame counts as cast on the GPU (through interop) when every server rank
that drew blocks did so (afam_client.frame_statistics), its mapper time is the slowest rank's.
"""
import argparse
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import afam_client  # noqa: E402  (connect, frame_statistics)
import afam_demo  # noqa: E402  (Scene, pose_camera, apply_tf, point_array)


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--plugin", required=True)
    p.add_argument("--file")
    p.add_argument("--raw")
    p.add_argument("--value-range-of", dest="range_of")
    p.add_argument("--trajectory", required=True)
    p.add_argument("--size", type=int, default=1024)
    p.add_argument("--frames", type=int, default=0)
    p.add_argument("--cache-mb", type=float, default=220.0)
    p.add_argument("--device", default="gpu", choices=("gpu", "cpu", "auto"))
    p.add_argument("--cold", action="store_true")
    p.add_argument("--csv")
    p.add_argument("--connect", type=int, default=0)
    p.add_argument("--miss-budget-ms", dest="budget", type=float, default=None)
    p.add_argument("--lod", choices=("screen", "distance"), default=None)
    a = p.parse_args()
    if bool(a.file) == bool(a.raw) or (a.raw and not a.range_of):
        p.error("give --file, or --raw with --value-range-of")
    if a.budget is not None and (not a.file or a.connect or a.budget < 0):
        p.error("--miss-budget-ms takes a budget >= 0, with --file and without --connect")
    return a


def quantile(values, q):
    v = sorted(values)
    rank = max(1, int(-(-q * len(v) // 1)))  # nearest rank, as BenchRenderLoopScene.h's Quantile
    return v[min(len(v), rank) - 1]


def main():
    a = parse_args()
    from paraview.simple import GetSettingsProxy, ImageReader, LoadPlugin, OpenDataFile, Render
    if a.connect:
        afam_client.connect("127.0.0.1", a.connect, a.plugin, ns=globals())
        GetSettingsProxy("RenderViewSettings").RemoteRenderThreshold = 0.0  # the server renders
    else:
        LoadPlugin(a.plugin, remote=False, ns=globals())
    n_poses = os.path.getsize(a.trajectory) // 12
    frames = min(a.frames, n_poses) if a.frames > 0 else n_poses
    scene = afam_demo.Scene(a.size)
    view = scene.view
    window = view.GetRenderWindow()
    source_path = a.file or a.raw
    from paraview import servermanager
    ranks = 1 if a.connect else servermanager.vtkProcessModule.GetProcessModule().GetNumberOfLocalPartitions()

    def evict():
        fd = os.open(source_path, os.O_RDONLY)
        try:
            os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)
        finally:
            os.close(fd)

    if a.file:
        lo, hi = None, None
    else:
        probe = OpenDataFile(a.range_of)
        probe.UpdatePipeline()
        lo, hi = probe.PointData[afam_demo.point_array(probe)].GetRange()
    if a.cold:
        evict()
    t_open = time.perf_counter()
    if a.file:
        source = OpenDataFile(a.file)
    else:
        n = round((os.path.getsize(a.raw) // 4) ** (1.0 / 3.0))
        if n ** 3 * 4 != os.path.getsize(a.raw):
            sys.exit("afam_pv_loop: %s is not a float32 N^3 volume" % a.raw)
        source = ImageReader(FileNames=[os.path.abspath(a.raw)])
        source.DataScalarType = "float"
        source.DataByteOrder = "LittleEndian"
        source.DataExtent = [0, n - 1, 0, n - 1, 0, n - 1]
    t_show = time.perf_counter()
    display, bounds = scene.show(source, "Adaptive-FAM Volume" if a.file else "Volume")
    if a.file:
        lo, hi = source.PointData[afam_demo.point_array(source)].GetRange()
    eye, up, angle = afam_demo.pose_camera(a.trajectory, 0)
    mean_half = scene.set_camera(bounds, eye, up, angle)
    afam_demo.apply_tf(display, afam_demo.point_array(source), lo, hi, 0.01 * mean_half)
    if a.file:
        display.AFAMSampleDistance = 0.005 * mean_half
        if a.budget is None or a.lod == "distance":
            display.AFAMLodPolicy = "Distance bands"
        elif a.lod == "screen":
            display.AFAMLodPolicy = "Screen-space error"
        if a.budget is not None:
            display.AFAMInteractiveMissBudget = a.budget
            display.AFAMAutoAdjustImageScale = 0
        display.AFAMCacheBudgetMB = a.cache_mb
        display.AFAMRenderDevice = {"gpu": "GPU", "cpu": "CPU", "auto": "Auto"}[a.device]

    rows = []
    for i in range(frames):
        if i > 0:
            eye, up, angle = afam_demo.pose_camera(a.trajectory, i)
            scene.set_camera(bounds, eye, up, angle)
            if a.cold:
                evict()
        t0 = time.perf_counter()
        if a.budget is not None and i > 0:
            view.InteractiveRender()
        else:
            Render(view)
        window.WaitForCompletion()
        t1 = time.perf_counter()
        row = {"pov": i, "render_ms": 1e3 * (t1 - t0)}
        if i == 0:
            row["first_image_ms"] = 1e3 * (t1 - t_open)
            row["show_to_image_ms"] = 1e3 * (t1 - t_show)
        if a.file and a.connect:  # the server's ranks (the client's copy of the display never renders)
            st = afam_client.frame_statistics(display)
            drawing = max(1, st["RanksDrawingBlocks"])
            row.update(mapper_ms=1e3 * st["MaxTotalTime"], cast_ms="", caching_ms="",
                       gpu=int(st["RanksOnGpu"] >= drawing), interop=int(st["RanksThroughInterop"] >= drawing),
                       visible=int(st["TotalVisibleBlocks"]), misses="", scale=st["MinImageScale"])
        elif a.file:
            display.UpdatePropertyInformation()
            get = display.GetPropertyValue
            row.update(mapper_ms=1e3 * get("AFAMLastTotalTime"), cast_ms=1e3 * get("AFAMLastRenderTime"),
                       caching_ms=1e3 * get("AFAMLastCachingTime"), gpu=int(get("AFAMLastUsedGpu")),
                       interop=int(get("AFAMLastImageOnDevice")), visible=int(get("AFAMLastVisibleBlocks")),
                       misses=int(get("AFAMLastCacheMisses")), scale=get("AFAMLastImageScale"),
                       stand_ins=int(get("AFAMLastStandInBlocks")), behind=int(get("AFAMLastBlocksBehind")))
            if ranks > 1:  # pvbatch under mpirun: the slowest rank's mapper, and who drew
                st = afam_client.frame_statistics(display)
                row.update(slowest_mapper_ms=1e3 * st["MaxTotalTime"], drawing=int(st["RanksDrawingBlocks"]),
                           max_read=int(st["MaxBytesRead"]), total_read=int(st["TotalBytesRead"]))
            if i == 0 and not row["gpu"] and a.device == "gpu":
                print("afam_pv_loop: the first frame was cast on the CPU: %s" % get("AFAMLastDeviceMessage"))
        rows.append(row)
    if a.csv:
        columns = ["pov", "render_ms", "mapper_ms", "cast_ms", "caching_ms", "gpu", "interop", "visible",
                   "misses", "scale", "stand_ins", "behind", "slowest_mapper_ms", "drawing", "max_read",
                   "total_read"]
        with open(a.csv, "w") as f:
            f.write(",".join(columns) + "\n")
            for r in rows:
                f.write(",".join(str(r.get(c, "")) for c in columns) + "\n")
    timed = [r["render_ms"] for r in rows[1:]] or [rows[0]["render_ms"]]
    med = statistics.median(timed)
    fields = dict(
        representation="afam" if a.file else "paraview_volume", frames=len(rows), size=a.size,
        server_port=a.connect,
        cold=int(a.cold), device=a.device if a.file else "opengl",
        first_image_ms="%.1f" % rows[0]["first_image_ms"], show_to_image_ms="%.1f" % rows[0]["show_to_image_ms"],
        median_render_ms="%.3f" % med, p95_render_ms="%.3f" % quantile(timed, 0.95),
        fps="%.1f" % (1e3 / med if med > 0 else 0))
    if a.file:
        fields.update(gpu_frames=sum(r["gpu"] for r in rows), interop_frames=sum(r["interop"] for r in rows),
                      median_mapper_ms="%.3f" % statistics.median(r["mapper_ms"] for r in rows[1:] or rows),
                      median_cast_ms=("%.3f" % statistics.median(r["cast_ms"] for r in rows[1:] or rows)
                                      if not a.connect else "-"),
                      full_scale_frames=sum(1 for r in rows if r["scale"] == 1.0))
    if a.file and ranks > 1:
        fields.update(ranks=ranks, median_slowest_mapper_ms="%.3f" % statistics.median(
                          r["slowest_mapper_ms"] for r in rows[1:] or rows),
                      min_ranks_drawing=min(r["drawing"] for r in rows))
    if a.budget is not None:
        fields.update(miss_budget_ms=a.budget, lod=a.lod or "screen",
                      max_caching_after_first_ms="%.3f" % max(r["caching_ms"] for r in rows[1:] or rows),
                      stand_in_blocks=sum(r["stand_ins"] for r in rows),
                      p95_over_median="%.2f" % (quantile(timed, 0.95) / med if med > 0 else 0))
    info = window.ReportCapabilities() or ""
    for line in info.splitlines():
        if "renderer string" in line or "version string" in line:
            print("gl: %s" % line.strip())
    print("pv_render_loop " + " ".join("%s=%s" % kv for kv in fields.items()), flush=True)
    if a.file and a.device == "gpu" and fields["gpu_frames"] != len(rows):
        print("afam_pv_loop: %d of %d frames were cast on the CPU" % (len(rows) - fields["gpu_frames"], len(rows)))
        sys.exit(1)


if __name__ == "__main__":
    main()

# SPDX-License-Identifier: BSD-3-Clause
"""pvpython client, pvserver with AFAM_SERVER_RANKS ranks (started here on the loopback interface and
a free port, stopped by its process id). The "Adaptive-FAM Volume" representation of a small file
must give the image builtin mode gives, under the default remote-render threshold (where ParaView
would render on the client, which cannot draw the volume) and with the threshold at 0, in the view
and in a SaveScreenshot larger than the view: every pixel within 8/255 for the volume alone with
ParaView's default image delivery ("vtkLZ4Compressor 0 3", whose colour mask drops low bits of each
channel), and within 2/255 when the server sends its images losslessly
(RenderViewSettings.CompressorConfig "vtkLZ4Compressor 0 0"; 3/255 with several ranks, whose
images IceT blends after rounding each to 8 bits). ParaView's FXAA (on by default) runs
on the client over the whole delivered image, the volume included, while builtin mode applies it
before volumes: the volume's own image must hold no pixel-scale steps for FXAA to smooth. It did
when whole ray samples switched on and off where the box faces cut the sample lattice (a grid on
the faces, 3/255 off on a few pixels); with the ray's end samples weighted by the length they stand
for (raycast.hpp, endWeight) the view and the screenshot equal builtin's (measured 0/255, 1 and 2
ranks, CPU ray caster under Mesa; on the GPU machine NVIDIA's OpenGL still moves one pixel of a
steep, smooth gradient by 3/255, and this check fails there). With the client's FXAA off, the
lossless view must equal builtin's exactly with one rank (the plugin's image, untouched: 0/255 under
Mesa and on the GPU machine, CPU and GPU frames), and within 2/255 with several (each rank draws its
box; 8-bit rounding before the blend). With an
opaque sphere inside it (depth compositing, default threshold): the VTK tests' comparison at
threshold 0, and at most 0.5 % of the pixels (the sphere's antialiased rim) off by more than 24/255.
The frame statistics summed over the server ranks (afam_client.frame_statistics): every rank drew,
none read more than 1.3/N of the bytes builtin mode reads for the same cold view, all of them
together at least builtin's and at most 1.3x; an interactive frame is drawn smaller on
the server and a still one whole. The Wavelet encoded on the server's ranks (split among them) and
saved from the client holds builtin's micro-models. A file missing on the server gives a clear error
on the client."""
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
sys.path.insert(0, os.path.join(os.environ.get("AFAM_TEST_SCRIPTS", ""), "..", "..", "Apps", "pvbatch"))
import afam_client  # noqa: E402
import afam_scene  # noqa: E402
import afam_server  # noqa: E402
import afam_test_util as u  # noqa: E402

from paraview import servermanager  # noqa: E402
from paraview.simple import CreateView, Disconnect, GetSettingsProxy, LoadPlugin, OpenDataFile, Show  # noqa: E402

ranks = int(u.env("AFAM_SERVER_RANKS"))
pvserver = u.env("AFAM_PVSERVER")
out = u.out_dir()
plugin = u.env("AFAM_PLUGIN")
statistics = {}


def render(name, threshold=None, ball=False):
    if threshold is not None:
        GetSettingsProxy("RenderViewSettings").RemoteRenderThreshold = threshold
    return afam_scene.scene(path, out, name, CreateView("RenderView"), ball, statistics)


# 1. The reference: builtin mode, same script, same file.
LoadPlugin(plugin, remote=False, ns=globals())
path = os.path.join(out, "wavelet_cs.afam")
u.encode_wavelet(globals(), [-20, 20, -20, 20, -20, 20], 3, 4, 0.005, path)
BARS = {False: (8, 0.0), True: (24, 0.005)}  # tolerance, fraction allowed; see the docstring
LOSSLESS = "vtkLZ4Compressor 0 0"  # ParaView's default, "vtkLZ4Compressor 0 3", masks colour bits
builtin = {ball: render("builtin_ball%d" % ball, ball=ball) for ball in (False, True)}
if u.non_blank(builtin[False][0]) < 2000:
    u.fail("the builtin image shows almost nothing")
Disconnect()

# 2. The same under pvserver.
with afam_server.PVServer(pvserver, ranks, os.path.join(out, "pvserver.log"),
                          mpirun=os.environ.get("AFAM_MPIRUN", "")) as server:
    print("pvserver with %d rank(s) on 127.0.0.1:%d (pid %d)" % (ranks, server.port, server.process.pid),
          flush=True)
    afam_client.connect("127.0.0.1", server.port, plugin, ns=globals())
    remote_ranks = servermanager.ActiveConnection.GetNumberOfDataPartitions()
    if remote_ranks != ranks:
        u.fail("the server has %d ranks, expected %d" % (remote_ranks, ranks))
    settings = GetSettingsProxy("RenderViewSettings")
    default_threshold = settings.RemoteRenderThreshold
    # the sphere once, at the default threshold (the volume alone is the sharper comparison)
    for threshold, name, ball in ((None, "default", False), (None, "default", True),
                                  (0.0, "threshold0", False)):
        images = render("server%d_%s_ball%d" % (ranks, name, ball), threshold, ball)
        for png, reference in zip(images, builtin[ball]):
            afam_scene.same_image(png, reference, out, *BARS[ball])
    # The volume alone with the images sent losslessly: what the plugin draws on the server; and
    # with the client's FXAA off (builtin mode's FXAA runs before volumes, so it never touches
    # them): the server's image, exactly builtin's.
    default_compressor, default_fxaa = settings.CompressorConfig, settings.UseFXAA
    settings.CompressorConfig = LOSSLESS
    settings.UseFXAA = 0
    images = render("server%d_lossless_nofxaa" % ranks, default_threshold)
    for png, reference in zip(images, builtin[False]):
        # One rank: the plugin's image, untouched. Several: each rank's image of its box is
        # rounded to 8 bits before IceT blends them (the blend of the unrounded images equals one
        # rank's within 1/255: RankRenderers in the Core tests).
        afam_scene.same_image(png, reference, out, 0 if ranks == 1 else 2, 0.0)
    settings.UseFXAA = default_fxaa
    for threshold, name in ((default_threshold, "default"), (0.0, "threshold0")):
        images = render("server%d_%s_lossless" % (ranks, name), threshold)
        for png, reference in zip(images, builtin[False]):
            # several ranks: their rounding (above) under the client's FXAA
            afam_scene.same_image(png, reference, out, 2 if ranks == 1 else 3, 0.0)
    settings.CompressorConfig = default_compressor

    # Frame statistics over the server ranks: the bytes one builtin process reads for the same
    # cold view, within 1.1x, and every rank took part.
    got, want = statistics["server%d_default_ball0" % ranks], statistics["builtin_ball0"]
    print("frame statistics: builtin %s; server %s" % (want, got), flush=True)
    if got["NumberOfRanks"] != ranks or got["TotalBytesRead"] <= 0:
        u.fail("frame statistics over %d ranks: %s" % (ranks, got))
    # Every rank draws its box (a coarse block that spans boxes is read and drawn by each of
    # their ranks, within its own box): all ranks took part, no rank read more than 1.3/N of
    # builtin's bytes, and together they read every block builtin read.
    if got["RanksDrawingBlocks"] != ranks:
        u.fail("%d of the %d server ranks drew blocks" % (got["RanksDrawingBlocks"], ranks))
    if got["MaxBytesRead"] > 1.3 / ranks * want["TotalBytesRead"]:
        u.fail("a server rank read %d bytes, more than 1.3/%d of builtin's %d"
               % (got["MaxBytesRead"], ranks, want["TotalBytesRead"]))
    if not want["TotalBytesRead"] <= got["TotalBytesRead"] <= 1.3 * want["TotalBytesRead"]:
        u.fail("the server ranks read %d bytes, builtin %d" % (got["TotalBytesRead"], want["TotalBytesRead"]))
    if not want["TotalVisibleBlocks"] <= got["TotalVisibleBlocks"] <= ranks * want["TotalVisibleBlocks"]:
        u.fail("the server ranks drew %d blocks, builtin %d" % (got["TotalVisibleBlocks"], want["TotalVisibleBlocks"]))
    # The ranks that drew blocks cast them where builtin mode cast its frame on this machine (the
    # CPU without a GPU; the GPU, through interop with NVIDIA's OpenGL, on the GPU machine).
    if got["RanksOnGpu"] != got["RanksDrawingBlocks"] * want["RanksOnGpu"] \
            or got["RanksThroughInterop"] != got["RanksDrawingBlocks"] * want["RanksThroughInterop"]:
        u.fail("server ranks on the GPU / through interop %d / %d of %d drawing, builtin %d / %d" % (
            got["RanksOnGpu"], got["RanksThroughInterop"], got["RanksDrawingBlocks"], want["RanksOnGpu"],
            want["RanksThroughInterop"]))

    # Interaction: on the server an interactive frame shrinks the image to meet the frame budget
    # and a still frame draws it whole (CPU ray caster; at 1000 x 1000 a full frame is over budget).
    view = CreateView("RenderView")
    u.setup_view(view, [1000, 1000])
    display = Show(OpenDataFile(path), view)
    display.Representation = "Adaptive-FAM Volume"
    u.apply_transfer_function(display)
    display.AFAMRenderDevice = "CPU"
    view.StillRender()  # the mapper learns the cost of a pixel
    view.CameraPosition = [60.0, 50.0, 86.0]
    view.InteractiveRender()
    interactive = afam_client.frame_statistics(display)
    view.StillRender()
    still = afam_client.frame_statistics(display)
    print("image scale on the server: interactive %.3f (%.3f s), still %.3f (%.3f s)"
          % (interactive["MinImageScale"], interactive["MaxTotalTime"], still["MinImageScale"],
             still["MaxTotalTime"]), flush=True)
    if not interactive["MinImageScale"] < 1.0 or still["MinImageScale"] != 1.0:
        u.fail("interaction scaling on the server: interactive %s, still %s" % (interactive, still))

    # Encoding on the server's ranks (the Wavelet split among them), saved by the client's SaveData:
    # the micro-models of the builtin encode.
    encoded_here = os.path.join(out, "wavelet_cs_server%d.afam" % ranks)
    _, server_encoder = u.encode_wavelet(globals(), [-20, 20, -20, 20, -20, 20], 3, 4, 0.005, encoded_here)
    difference = u.compare_models(encoded_here, path)
    if difference:
        u.fail("the encode on %d server rank(s) differs from builtin's: %s" % (ranks, difference))
    server_encoder.UpdatePropertyInformation()
    piece = list(server_encoder.GetProperty("LastPieceExtent").GetData())  # rank 0's
    print("encode on %d server rank(s): %d micro-models identical to builtin's; rank 0's piece %s"
          % (ranks, len(u.afam_models(encoded_here)[1]), piece), flush=True)
    if (piece == [-20, 20, -20, 20, -20, 20]) != (ranks == 1):
        u.fail("rank 0 encoded the piece %s of the Wavelet on %d rank(s)" % (piece, ranks))

    # 3. A file the server does not have: the client hears why.
    missing = os.path.join(out, "no_such_file.afam")
    try:
        reader = OpenDataFile(missing)
        if reader is not None:
            u.fail("OpenDataFile returned a reader for a file missing on the server")
        print("missing file: OpenDataFile returned None", flush=True)
    except RuntimeError as e:
        message = str(e)
        print("missing file: %s" % message.strip(), flush=True)
        if "no_such_file.afam" not in message:
            u.fail("the error for a missing file does not name it: %s" % message)
    Disconnect()
print("AFAM client-server: %d rank(s), images equal to builtin" % ranks)

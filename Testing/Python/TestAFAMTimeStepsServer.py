# SPDX-License-Identifier: BSD-3-Clause
"""pvpython client of a pvserver (one rank, loopback): a run of time steps
(Testing/Data/format/gs24_run5_levels2_blocks2_v3.afam: residuals, references and a key step)
opened on the server reports its TimestepValues to the client, and at every time reached through
the animation scene the client's image is builtin mode's step, not another's.
Tolerance: pvserver's image of this data differs from builtin's by up to 24/255 in 1.5% of the
pixels for a one-step file of step 0 just as for the run (measured, 2026-11-25; the Wavelet of the
client-server test, at lower contrast: 8/255), so each image must be within 30/255 of builtin's
at the same time everywhere, while steps 0 and 4 differ by more than that."""
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
sys.path.insert(0, os.path.join(os.environ.get("AFAM_TEST_SCRIPTS", ""), "..", "..", "Apps", "pvbatch"))
import afam_client  # noqa: E402
import afam_server  # noqa: E402
import afam_test_util as u  # noqa: E402

from paraview.simple import (CreateView, Delete, Disconnect, GetAnimationScene, LoadPlugin,  # noqa: E402
                             OpenDataFile, Render, SaveScreenshot, Show)

out = u.out_dir()
plugin = u.env("AFAM_PLUGIN")
run = os.path.join(u.env("AFAM_BASELINE"), "..", "format", "gs24_run5_levels2_blocks2_v3.afam")
TIMES = [0.0, 1.0, 2.0, 3.0, 4.0]
TOLERANCE = 30


def play(tag):
    """Every step through the animation scene; the screenshots' paths."""
    view = CreateView("RenderView")
    u.setup_view(view)
    view.CameraFocalPoint = [11.5, 11.5, 11.5]
    view.CameraPosition = [11.5 + 40.0, 11.5 + 32.0, 11.5 + 46.0]
    reader = OpenDataFile(run)
    times = list(reader.TimestepValues)
    if times != TIMES:
        u.fail("%s: the run's TimestepValues are %s" % (tag, times))
    display = Show(reader, view)
    display.Representation = "Adaptive-FAM Volume"
    display.AFAMRenderDevice = "CPU"
    u.apply_transfer_function(display, "gs", 0.0, 0.38)  # the run's array
    scene = GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    shots = []
    for t in TIMES:
        scene.AnimationTime = t
        Render(view)
        shots.append(os.path.join(out, "%s_t%g.png" % (tag, t)))
        SaveScreenshot(shots[-1], view)
    Delete(view)
    return shots


LoadPlugin(plugin, remote=False, ns=globals())
builtin = play("builtin")
if not all(u.non_blank(png) for png in builtin):
    u.fail("a builtin step is blank")
fraction, worst = u.differing_fraction(builtin[0], builtin[4], TOLERANCE)
print("builtin steps 0 and 4: %.3f of the pixels differ by more than %d/255 (largest %d/255)"
      % (fraction, TOLERANCE, worst), flush=True)
if fraction == 0:
    u.fail("steps 0 and 4 draw images within %d/255: the test could not tell steps apart"
           % TOLERANCE)
Disconnect()

with afam_server.PVServer(u.env("AFAM_PVSERVER"), 1, os.path.join(out, "pvserver.log")) as server:
    afam_client.connect("127.0.0.1", server.port, plugin, ns=globals())
    remote = play("server")
    for t, png, reference in zip(TIMES, remote, builtin):
        fraction, worst = u.differing_fraction(png, reference, TOLERANCE)
        print("time %g: server against builtin, largest difference %d/255" % (t, worst), flush=True)
        if fraction > 0:
            u.fail("time %g: the server's image is off builtin's by %d/255" % (t, worst))
    other, _ = u.differing_fraction(remote[0], builtin[4], TOLERANCE)
    if other == 0:
        u.fail("the server's step 0 looks like builtin's step 4")
    Disconnect()
print("AFAM-TIME-STEPS-SERVER-OK", flush=True)

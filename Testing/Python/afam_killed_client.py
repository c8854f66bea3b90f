# SPDX-License-Identifier: BSD-3-Clause
"""Run by TestAFAMServerFaults.py: `pvpython afam_killed_client.py PORT RANK_PID FILE.afam`. Connects
to the pvserver on PORT, renders FILE, kills one server rank (RANK_PID, SIGKILL: a crashed process
or a lost node) and renders again; ParaView then reports the lost connection on this client."""
import os
import signal
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
sys.path.insert(0, os.path.join(os.environ.get("AFAM_TEST_SCRIPTS", ""), "..", "..", "Apps", "pvbatch"))
import afam_client  # noqa: E402
import afam_test_util as u  # noqa: E402

from paraview.simple import CreateView, OpenDataFile, Render, Show  # noqa: E402

port, rank_pid, path = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
afam_client.connect("127.0.0.1", port, u.env("AFAM_PLUGIN"), ns=globals())
view = CreateView("RenderView")
u.setup_view(view)
display = Show(OpenDataFile(path), view)
display.Representation = "Adaptive-FAM Volume"
Render(view)
print("AFAM-RENDERED-BEFORE-KILL", flush=True)
os.kill(rank_pid, signal.SIGKILL)
view.CameraPosition = [40.0, 60.0, 80.0]
Render(view)
print("AFAM-CLIENT-RETURNED", flush=True)

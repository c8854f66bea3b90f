# SPDX-License-Identifier: BSD-3-Clause
"""Faults of a client-server session, each with a clear message and no hang:
- the plugin loaded on the client but not on the server: afam_client.connect says so, the server
  keeps running;
- different plugin versions on client and server: the message names both;
- a server rank killed mid-session (2 ranks under mpirun): the client, in its own process, reports
  the lost connection and ends within the time limit (ParaView's client may abort there, see
  below), and mpirun stops the other rank."""
import os
import subprocess
import sys
import time

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
sys.path.insert(0, os.path.join(os.environ.get("AFAM_TEST_SCRIPTS", ""), "..", "..", "Apps", "pvbatch"))
import afam_client  # noqa: E402
import afam_server  # noqa: E402
import afam_test_util as u  # noqa: E402

from paraview.simple import Disconnect, LoadPlugin  # noqa: E402

out = u.out_dir()
plugin = u.env("AFAM_PLUGIN")
pvserver = u.env("AFAM_PVSERVER")
mpirun = u.env("AFAM_MPIRUN")
CLIENT_LIMIT = 60.0

# 1. Plugin on the client only.
LoadPlugin(plugin, remote=False, ns=globals())
path = os.path.join(out, "wavelet_faults.afam")
u.encode_wavelet(globals(), [-20, 20, -20, 20, -20, 20], 2, 2, 0.01, path)
Disconnect()
with afam_server.PVServer(pvserver, 1, os.path.join(out, "pvserver_no_plugin.log")) as server:
    try:  # this process loaded the plugin above; the server never did
        afam_client.connect("127.0.0.1", server.port, ns=globals())
        u.fail("connect() accepted a server without the plugin")
    except RuntimeError as e:
        print("plugin missing on the server: %s" % e, flush=True)
        if "not loaded on the server" not in str(e):
            u.fail("unclear message: %s" % e)
    if server.process.poll() is not None:
        u.fail("the server stopped after a client without its plugin connected")
    Disconnect()

# 2. Versions that differ (the comparison itself; one build has one version).
try:
    afam_client.check_plugin({"AdaptiveFAM": "0.1.0"}, {"AdaptiveFAM": "0.0.9"}, "host:1")
    u.fail("different plugin versions accepted")
except RuntimeError as e:
    print("different versions: %s" % e, flush=True)
    if "0.1.0" not in str(e) or "0.0.9" not in str(e):
        u.fail("the version message does not name both versions: %s" % e)

# 3. A rank killed mid-session.
with afam_server.PVServer(pvserver, 2, os.path.join(out, "pvserver_killed.log"), mpirun=mpirun) as server:
    ranks = afam_server.descendants(server.process.pid)
    if len(ranks) != 2:
        u.fail("expected 2 pvserver ranks under mpirun, found %s" % ranks)
    child = [u.env("AFAM_PVPYTHON"), "--force-offscreen-rendering",
             os.path.join(u.env("AFAM_TEST_SCRIPTS"), "afam_killed_client.py"),
             str(server.port), str(max(ranks)), path]
    start = time.time()
    try:
        done = subprocess.run(child, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                              timeout=CLIENT_LIMIT, env=afam_server.launcher_environment())
    except subprocess.TimeoutExpired:
        u.fail("the client hung for %.0f s after a server rank was killed" % CLIENT_LIMIT)
    seconds = time.time() - start
    with open(os.path.join(out, "killed_client.log"), "w") as f:
        f.write(done.stdout)
    lines = [line for line in done.stdout.splitlines()
             if "ERR|" in line or "FATL|" in line or "AFAM-" in line or "rror" in line]
    print("\n".join(lines[:12]), flush=True)
    if "AFAM-RENDERED-BEFORE-KILL" not in done.stdout:
        u.fail("the client did not render before the kill")
    # ParaView 5.11's client either logs the broken connection (vtkSocket) and returns, or, when
    # the kill lands during a frame, fails an assertion in vtkSynchronizedRenderers on the empty
    # image it received and aborts (seen in about half the runs); both end well within the limit.
    reported = [line for line in lines if "ERR|" in line or "FATL|" in line]
    if not reported:
        u.fail("the client did not report the lost server")
    ending = "returned" if "AFAM-CLIENT-RETURNED" in done.stdout else "stopped"
    print("client %s %.1f s after start (exit status %d); first report: %s"
          % (ending, seconds, done.returncode, reported[0].strip()), flush=True)
    deadline = time.time() + 20
    while server.process.poll() is None and time.time() < deadline:
        time.sleep(0.2)
    if server.process.poll() is None:
        u.fail("mpirun kept the other rank running 20 s after one rank was killed")
    while any(os.path.exists("/proc/%d" % pid) for pid in ranks) and time.time() < deadline:
        time.sleep(0.2)
    left = [pid for pid in ranks if os.path.exists("/proc/%d" % pid)]
    if left:
        u.fail("server ranks %s still running 20 s after one rank was killed" % left)
    print("mpirun and both server ranks ended %.1f s after the client started" % (time.time() - start))
print("AFAM server faults: clear messages, nothing hung")

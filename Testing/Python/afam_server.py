# SPDX-License-Identifier: BSD-3-Clause
"""A pvserver (one rank, or several under mpirun) started for one test: on a free port of the
loopback interface, waited for until it accepts connections, stopped by its process id (and those of
the ranks mpirun started) however the test ends."""
import os
import signal
import socket
import subprocess
import time


def free_port():
    """A TCP port nobody listens on right now (the kernel picks it)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def server_command(pvserver, ranks, port, mpirun=""):
    """pvserver's command line for `ranks` ranks (mpirun for more than one; as root mpirun needs
    --allow-run-as-root)."""
    server = [pvserver, "--server-port=%d" % port]
    if ranks <= 1:
        return server
    launcher = [mpirun or "mpirun", "-np", str(ranks), "--oversubscribe"]
    if os.geteuid() == 0:
        launcher.append("--allow-run-as-root")
    return launcher + server


def launcher_environment():
    """This process's environment without the MPI runtime's variables: pvpython initialises MPI as
    a singleton, and an mpirun started with its OMPI_/PMIX_ variables exits at once with status 1."""
    return {k: v for k, v in os.environ.items()
            if not k.startswith(("OMPI_", "PMIX_", "OPAL_", "PRTE_", "HYDRA_", "PMI_"))}


def descendants(pid):
    """Process ids started by `pid`, recursively (read from /proc; empty once it is gone)."""
    found = []
    try:
        for task in os.listdir("/proc/%d/task" % pid):
            with open("/proc/%d/task/%s/children" % (pid, task)) as f:
                for child in f.read().split():
                    found.append(int(child))
                    found.extend(descendants(int(child)))
    except OSError:
        pass
    return found


class PVServer:
    """`with PVServer(pvserver, ranks, log) as server:` starts the server and stops it on exit;
    `env` adds variables to the server's environment (PV_PLUGIN_PATH, say). The server's TMPDIR is
    the log's folder: an encoder's temporary model file, which a server stopped by its process id
    leaves behind, stays in the test's output."""

    def __init__(self, pvserver, ranks, log_path, mpirun="", start_timeout=60.0, env=None):
        self.port = free_port()
        self.ranks = ranks
        self.log_path = log_path
        self.command = server_command(pvserver, ranks, self.port, mpirun)
        self.start_timeout = start_timeout
        self.env = dict(launcher_environment(), TMPDIR=os.path.dirname(os.path.abspath(log_path)), **(env or {}))
        self.process = None
        self.ranks_started = []  # pvserver ranks under mpirun, known once it accepts connections

    def __enter__(self):
        self.start()
        return self

    def __exit__(self, *exc):
        self.stop()
        return False

    def log(self):
        with open(self.log_path, errors="replace") as f:
            return f.read()

    def start(self):
        with open(self.log_path, "w") as log:
            self.process = subprocess.Popen(self.command, stdout=log, stderr=subprocess.STDOUT,
                                            stdin=subprocess.DEVNULL, env=self.env)
        deadline = time.time() + self.start_timeout
        while time.time() < deadline:
            if "Accepting connection" in self.log():
                self.ranks_started = descendants(self.process.pid)
                return
            if self.process.poll() is not None:
                raise RuntimeError("pvserver (%s) exited with %d before accepting connections:\n%s"
                                   % (" ".join(self.command), self.process.returncode, self.log()))
            time.sleep(0.2)
        self.stop()
        raise RuntimeError("pvserver did not accept connections within %.0f s:\n%s"
                           % (self.start_timeout, self.log()))

    def kill(self):
        """SIGKILL the server ranks (not the launcher): what a crash or a lost node looks like."""
        ranks = [p for p in descendants(self.process.pid)] or [self.process.pid]
        for pid in ranks:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass

    def stop(self, grace=10.0):
        """SIGTERM the launcher, then SIGKILL whatever of it and its ranks (those found now and at
        start, in case the launcher is gone already) is left after `grace` s."""
        if self.process is None:
            return
        children = set(descendants(self.process.pid)) | set(self.ranks_started)
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(grace)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(grace)
        for pid in children:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        self.process = None

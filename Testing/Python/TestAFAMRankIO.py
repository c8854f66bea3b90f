# SPDX-License-Identifier: BSD-3-Clause
"""Per-rank I/O: the same cold view of one file rendered by pvbatch on 1 rank and on 2 ranks
(mpirun, symmetric mode, so each rank reports its own frame statistics). Each rank reads only the
micro-models of the blocks it draws (a rank that draws none reads nothing), and the bytes read summed
over the 2 ranks are within 1.1x of the 1-rank figure. The file's coarsest level has one block, so
one of the 2 ranks gets no block from the reader: it must neither hang nor fail, and the 2-rank
image must equal the 1-rank image (every pixel within 8/255)."""
import json
import os
import subprocess
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_server  # noqa: E402
import afam_test_util as u  # noqa: E402

from paraview.simple import LoadPlugin  # noqa: E402

out = u.out_dir()
scripts = u.env("AFAM_TEST_SCRIPTS")
pvbatch = u.env("AFAM_PVBATCH")
mpirun = u.env("AFAM_MPIRUN")
LoadPlugin(u.env("AFAM_PLUGIN"), remote=False, ns=globals())
path = os.path.join(out, "wavelet_io.afam")
u.encode_wavelet(globals(), [-20, 20, -20, 20, -20, 20], 3, 4, 0.005, path)


def run(ranks):
    result = os.path.join(out, "rank_io_%d.json" % ranks)
    command = [pvbatch, "--symmetric", os.path.join(scripts, "afam_rank_io_view.py"), path, result]
    if ranks > 1:
        launcher = [mpirun, "-np", str(ranks), "--oversubscribe"]
        if os.geteuid() == 0:
            launcher.append("--allow-run-as-root")
        command = launcher + command
    done = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=150,
                          env=afam_server.launcher_environment())
    print(done.stdout, flush=True)
    if done.returncode != 0 or not os.path.isfile(result):
        u.fail("%d-rank render exited with %d (see above)" % (ranks, done.returncode))
    with open(result) as f:
        return json.load(f)


one, two = run(1), run(2)
reference, total = one["bytes_read"][0], sum(two["bytes_read"])
print("bytes read: 1 rank %d; 2 ranks %s, sum %d (%.3fx)" % (reference, two["bytes_read"], total,
                                                          total / max(reference, 1)))
if reference <= 0:
    u.fail("the 1-rank frame read nothing: the test view shows no block")
if total > 1.1 * reference:
    u.fail("2 ranks read %d bytes in all, more than 1.1x the 1-rank %d" % (total, reference))
for r, (read, drawn) in enumerate(zip(two["bytes_read"], two["visible_blocks"])):
    if drawn == 0 and read != 0:
        u.fail("rank %d draws no block but read %d bytes" % (r, read))
if sum(two["visible_blocks"]) != one["visible_blocks"][0]:
    u.fail("2 ranks drew %s blocks, 1 rank %d" % (two["visible_blocks"], one["visible_blocks"][0]))
fraction, worst = u.differing_fraction(two["image"], one["image"], 8)
print("2-rank image: %.3f %% of pixels differ from 1 rank by more than 8/255 (largest %d/255)"
      % (100 * fraction, worst))
if fraction > 0.0:
    u.fail("the 2-rank image differs from the 1-rank image")

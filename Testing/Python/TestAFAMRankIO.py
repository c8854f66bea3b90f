# SPDX-License-Identifier: BSD-3-Clause
"""Per-rank rendering and I/O: the same cold view of one file rendered by pvbatch on 1 rank and on 2
and 4 ranks (mpirun, symmetric mode, so each rank reports its own frame statistics). Each rank draws
its own box of the volume (afam::rankBox) and reads only the micro-models of the blocks that meet
it: every rank draws, none reads more than 1.3/N of the 1-rank bytes, all together read at least the
1-rank bytes and at most 1.3x, and the image IceT composites in visibility order equals the 1-rank
image (FXAA off; 2 ranks: every pixel within 2/255; 4 ranks: within 3/255, at most 0.1 % of the
pixels beyond 2/255, IceT's 8-bit blends truncating), as do the images of maximum intensity
blending (drawn whole by rank 0) and of a camera inside the volume."""
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


one = run(1)
reference = one["bytes_read"][0]
if reference <= 0:
    u.fail("the 1-rank frame read nothing: the test view shows no block")
for ranks in (2, 4):
    many = run(ranks)
    total = sum(many["bytes_read"])
    print("bytes read: 1 rank %d; %d ranks %s, sum %d (%.3fx); blocks drawn %s" % (
        reference, ranks, many["bytes_read"], total, total / reference, many["visible_blocks"]))
    for r, (read, drawn) in enumerate(zip(many["bytes_read"], many["visible_blocks"])):
        if drawn <= 0:
            u.fail("%d ranks: rank %d drew no block" % (ranks, r))
        if read > 1.3 / ranks * reference:
            u.fail("%d ranks: rank %d read %d bytes, more than 1.3/%d of the 1-rank %d"
                   % (ranks, r, read, ranks, reference))
    if not reference <= total <= 1.3 * reference:
        u.fail("%d ranks read %d bytes in all, the 1-rank %d" % (ranks, total, reference))
    if sum(many["visible_blocks"]) < one["visible_blocks"][0]:
        u.fail("%d ranks drew %s blocks, 1 rank %d" % (ranks, many["visible_blocks"], one["visible_blocks"][0]))
    for key in ("image", "mip", "inside"):
        fraction, worst = u.differing_fraction(many[key], one[key], 2)
        print("%d-rank %s: %.3f %% of pixels differ from 1 rank by more than 2/255 (largest %d/255)"
              % (ranks, key, 100 * fraction, worst))
        # IceT blends 8-bit images, truncating each product: a blend of N images may lose up to
        # N-1 more 1/255 steps than one image. 2 ranks: every pixel within 2/255; more: within
        # 3/255, and at most 0.1 % of the pixels beyond 2/255.
        if worst > (2 if ranks == 2 else 3) or fraction > (0.0 if ranks == 2 else 0.001):
            u.fail("the %d-rank %s differs from the 1-rank one" % (ranks, key))

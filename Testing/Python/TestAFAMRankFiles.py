# SPDX-License-Identifier: BSD-3-Clause
"""Ranks that do not open one file (issue 43's bad input): pvbatch on 2 ranks under mpirun, each
rank in its own working directory and the file named by a relative path, so that each opens what its
directory holds, as ranks on different nodes open what their node holds. The same file on both: no
error, and the image of one rank. Another encode on rank 1, or none: every rank reports one error
that names the ranks and the path, the volume is not drawn (the image is the empty view's), and
nothing hangs."""
import os
import shutil
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
first, other = os.path.join(out, "first.afam"), os.path.join(out, "other.afam")
u.encode_wavelet(globals(), [-20, 20, -20, 20, -20, 20], 2, 4, 0.005, first)
u.encode_wavelet(globals(), [-20, 20, -20, 20, -20, 20], 2, 4, 0.05, other)
view = os.path.join(scripts, "afam_rank_files_view.py")


def run(case, rank1_file):
    """Renders w.afam with rank 0 seeing `first` and rank 1 `rank1_file` (None: nothing)."""
    dirs = [os.path.join(out, case, "rank%d" % r) for r in (0, 1)]
    for d, source in zip(dirs, (first, rank1_file)):
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)
        if source:
            shutil.copyfile(source, os.path.join(d, "w.afam"))
    png = os.path.join(out, case + ".png")
    command = [mpirun]
    if os.geteuid() == 0:
        command.append("--allow-run-as-root")
    for r, d in enumerate(dirs):
        command += (["--oversubscribe", "-np", "1", "-wdir", d, pvbatch, view, "w.afam", png]
                    + ([":"] if r == 0 else []))
    done = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          timeout=150, env=afam_server.launcher_environment())
    print("--- %s (exit %d)\n%s" % (case, done.returncode, done.stdout), flush=True)
    if "AFAM-RANK-FILES-RENDERED" not in done.stdout:
        u.fail("%s: the render did not finish (exit %d)" % (case, done.returncode))
    return done.stdout, png


def disagreements(text):
    return [line for line in text.splitlines() if "ranks do not draw one file" in line]


same, same_png = run("same", first)
if disagreements(same):
    u.fail("the same file on both ranks was refused")
for case, source, says in (
        ("another", other, "rank 1 opened another w.afam than rank 0 did"),
        ("missing", None, "rank 1 could not open w.afam")):
    text, png = run(case, source)
    found = disagreements(text)
    for r in (0, 1):
        mine = [line for line in found if "rank %d of 2: the 2 ranks do not draw one file: " % r in line]
        if len(mine) != 1 or says not in mine[0]:
            u.fail("%s: rank %d should report once that %s; it said %s" % (case, r, says, mine))
    fraction, worst = u.differing_fraction(png, same_png, 8)
    print("%s: %.1f %% of the pixels differ from the drawn volume's by more than 8/255" % (case, 100 * fraction))
    if fraction < 0.05:
        u.fail("%s: the volume was drawn anyway" % case)
print("AFAM-RANK-FILES-OK")

# SPDX-License-Identifier: BSD-3-Clause
"""pvbatch: ParaView's own loop over a camera path under the Interactive Miss Budget
(Apps/pvbatch/afam_pv_loop.py --miss-budget-ms, issue 44), in a pvbatch of its own: with a budget of
0 on a cold cache every frame after the first is an interactive render that waits for nothing, so
its finest blocks are drawn from resident coarser levels (stand-ins in the loop's CSV and its last
line); the first frame, a still render, is exact (none)."""
import csv
import os
import shutil
import struct
import subprocess
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

u.load_plugin(globals())
out = u.out_dir()
path = os.path.join(out, "wavelet_loop.afam")
u.encode_wavelet(globals(), [-40, 40, -40, 40, -40, 40], 3, 8, 0.001, path)
# Six poses in the recorded paths' layout (all distances, then polar, then azimuth angles).
n = 6
trajectory = os.path.join(out, "six_views.dat")
with open(trajectory, "wb") as f:
    f.write(struct.pack("<%df" % (3 * n), *([2.5] * n + [60.0] * n + [40.0 * k for k in range(n)])))
loop = os.path.join(os.environ.get("AFAM_TEST_SCRIPTS", ""), "..", "..", "Apps", "pvbatch", "afam_pv_loop.py")
table = os.path.join(out, "loop.csv")
pvbatch = shutil.which("pvbatch") or u.fail("pvbatch not found")
run = subprocess.run([pvbatch, "--no-mpi", loop, "--plugin", os.environ["AFAM_PLUGIN"], "--file", path,
                      "--trajectory", trajectory, "--size", "96", "--device", "cpu", "--cold",
                      "--miss-budget-ms", "0", "--csv", table],
                     stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=240)
print(run.stdout)
last = [line for line in run.stdout.splitlines() if line.startswith("pv_render_loop ")]
if run.returncode != 0 or not last:
    u.fail("afam_pv_loop.py failed (rc %d)" % run.returncode)
fields = dict(kv.split("=", 1) for kv in last[-1].split()[1:])
rows = list(csv.DictReader(open(table)))
stand_ins = [int(r["stand_ins"]) for r in rows]
print("stand-ins per frame: %s" % stand_ins)
if len(rows) != n or fields.get("frames") != str(n) or fields.get("miss_budget_ms") != "0.0":
    u.fail("the loop did not render the %d views under the budget: %s" % (n, last[-1]))
if stand_ins[0] != 0:
    u.fail("the first frame (a still render) drew %d stand-ins" % stand_ins[0])
if sum(stand_ins[1:]) == 0 or int(fields["stand_in_blocks"]) != sum(stand_ins):
    u.fail("interactive frames under a budget of 0 drew no stand-in, or the total disagrees: %s" % last[-1])
if float(fields["max_caching_after_first_ms"]) < 0:
    u.fail("no caching time read back")
print("AFAM-LOOP-BUDGET-OK")

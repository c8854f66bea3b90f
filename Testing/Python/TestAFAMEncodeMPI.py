# SPDX-License-Identifier: BSD-3-Clause
"""Encoding under mpirun: the plugin's filter and writer on 2 (and 3) pvbatch ranks, each holding
only its piece of the volume, write one .afam file whose micro-models are, model by model (NCP per
axis, kind, errors, checksum, stored bytes), those of a one-process encode of the same volume:
  - ParaView's Wavelet (80 x 78 x 72, float), split along x by ParaView: the first rank's piece is
    half the volume and it reads samples from the other rank's piece;
  - the same Wavelet with missing samples (NaN in a ball, a vtkValidPointMask array, a fill value
    -999): the models of a one-process encode, and NaN exactly at the missing samples when decoded;
  - a uint8 raw volume through Apps/pvbatch/afam_encode.py (ParaView's raw reader reads each rank's
    piece; the ranks expose their uint8 samples and convert what they read), against the same
    script on one process and against `afam encode`;
  - an int16 volume on 3 ranks for 2 rows of blocks (one rank fits nothing), and a source whose
    only piece is rank 0's;
  - a time series (a .vti file series of a Gray-Scott run) encoded as one run coded in time on 2
    ranks: the file a one-process encode writes, byte for byte, every step within its bound;
  - bad input: a missing array, an empty whole extent and pieces that leave a hole give one clear
    error on every rank, no file and no hang (each run inside a time limit)."""
import glob
import json
import os
import subprocess
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_server  # noqa: E402
import afam_test_util as u  # noqa: E402

out = u.out_dir()
scripts = u.env("AFAM_TEST_SCRIPTS")
plugin = u.env("AFAM_PLUGIN")
pvbatch = u.env("AFAM_PVBATCH")
mpirun = u.env("AFAM_MPIRUN")
afam = u.env("AFAM_EXE")
case_script = os.path.join(scripts, "afam_encode_case.py")
encode_script = os.path.join(scripts, "..", "..", "Apps", "pvbatch", "afam_encode.py")
volumes = os.path.join(scripts, "..", "Data", "volumes")


def run(ranks, arguments, expect_ok=True):
    """pvbatch on `ranks` processes (mpirun when > 1); returns its output."""
    command = [pvbatch] + arguments
    if ranks > 1:
        launcher = [mpirun, "-np", str(ranks), "--oversubscribe"]
        if os.geteuid() == 0:
            launcher.append("--allow-run-as-root")
        command = launcher + command
    try:
        done = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=150,
                              env=afam_server.launcher_environment())
    except subprocess.TimeoutExpired:
        u.fail("%d-rank run did not end within 150 s: %s" % (ranks, " ".join(arguments)))
    if expect_ok and done.returncode != 0:
        print(done.stdout, flush=True)
        u.fail("%d-rank run exited with %d: %s" % (ranks, done.returncode, " ".join(arguments)))
    return done.stdout


def encode_case(ranks, case, name, array=None):
    path, result = os.path.join(out, name + ".afam"), os.path.join(out, name + ".json")
    for old in (path, result):
        if os.path.exists(old):
            os.remove(old)
    output = run(ranks, [case_script, plugin, path, result, case] + ([array] if array else []),
                 expect_ok=array is None)
    return path, result, output


def expect_same(path, reference, what):
    difference = u.compare_models(path, reference)
    if difference:
        u.fail("%s: %s" % (what, difference))
    print("%s: %d micro-models identical" % (what, len(u.afam_models(path)[1])), flush=True)


# Wavelet, split along x.
one, _, _ = encode_case(1, "wavelet", "wavelet_1")
two, two_json, _ = encode_case(2, "wavelet", "wavelet_2")
expect_same(two, one, "Wavelet, 2 ranks against 1 process")
with open(two_json) as f:
    rank0 = json.load(f)
print("rank 0: piece %s, %d bytes read from the other rank" % (rank0["piece"], rank0["remote_bytes"]), flush=True)
if rank0["piece"] == [-40, 39, -37, 40, -35, 36] or rank0["piece"][1] < rank0["piece"][0]:
    u.fail("rank 0's piece %s is not a part of the volume: the input was not distributed" % rank0["piece"])
if rank0["remote_bytes"] <= 0:
    u.fail("rank 0 read nothing from the other rank, yet its piece is half the volume")

# Missing samples on pieces: each rank marks its own (NaN, its piece of the mask, the fill value).
masked_1, _, _ = encode_case(1, "masked", "masked_1")
masked_2, _, _ = encode_case(2, "masked", "masked_2")
expect_same(masked_2, masked_1, "Wavelet with missing samples, 2 ranks against 1 process")
masked_info = subprocess.run([afam, "info", masked_2], capture_output=True, text=True).stdout
if "missing=value(-999)" not in masked_info:
    u.fail("the 2-rank file does not record MissingValue -999:\n%s" % masked_info)
decoded_raw = os.path.join(out, "masked_2_finest.raw")
subprocess.run([afam, "decode", masked_2, decoded_raw], check=True, stdout=subprocess.DEVNULL)
import numpy as np  # noqa: E402
z, y, x = np.meshgrid(np.arange(-35, 37), np.arange(-37, 41), np.arange(-40, 40), indexing="ij")
expected = (x * x + y * y + z * z < 144) | (x > 25) | (y > 30)
decoded = np.fromfile(decoded_raw, dtype="<f4").reshape(expected.shape)
wrong = int(np.count_nonzero(np.isnan(decoded) != expected))
print("masked Wavelet, 2 ranks: %d of %d samples missing, %d decoded otherwise" %
      (int(expected.sum()), expected.size, wrong), flush=True)
if wrong or not expected.any():
    u.fail("decoded NaN differ from the missing samples at %d points" % wrong)

# A uint8 raw volume through afam_encode.py, 1 process and 2 ranks, and `afam encode`.
raw = os.path.join(volumes, "ironProt_68x68x68_uint8.raw")
options = ["--levels", "2", "--blocks", "4", "--error-bound", "1e-3", "--relative", "--threads", "1"]
paths = {}
for ranks in (1, 2):
    paths[ranks] = os.path.join(out, "iron_%d.afam" % ranks)
    output = run(ranks, [encode_script, "--plugin", plugin, raw, paths[ranks]] + options)
    if "ranks=%d " % ranks not in output or "levels=2 blocks=4" not in output:
        u.fail("afam_encode.py on %d ranks: unexpected summary:\n%s" % (ranks, output))
cli = os.path.join(out, "iron_cli.afam")
subprocess.run([afam, "encode", raw, cli, "--quiet"] + options, check=True)
expect_same(paths[2], paths[1], "uint8 raw via afam_encode.py, 2 ranks against 1 process")
expect_same(paths[1], cli, "uint8 raw via afam_encode.py against afam encode")

# More ranks than rows of blocks, int16: 3 ranks, 2 rows at the finest level, 1 at the coarsest.
head = os.path.join(volumes, "headsq_quarter_64x64x93_int16.raw")
few = ["--levels", "2", "--blocks", "2", "--error-bound", "1e-2", "--relative", "--threads", "1"]
three, head_cli = os.path.join(out, "head_3.afam"), os.path.join(out, "head_cli.afam")
run(3, [encode_script, "--plugin", plugin, head, three] + few)
subprocess.run([afam, "encode", head, head_cli, "--quiet"] + few, check=True)
expect_same(three, head_cli, "int16 on 3 ranks for 2 rows of blocks against afam encode")

# Only rank 0 holds a piece: the other rank fits blocks from it.
alone, _, _ = encode_case(1, "rank0", "rank0_1")
spread, _, _ = encode_case(2, "rank0", "rank0_2")
expect_same(spread, alone, "one rank's piece, 2 ranks against 1 process")

# A time series: one run coded in time, the same file on 2 ranks as on one process.
series_dir = os.path.join(out, "series")
os.makedirs(series_dir, exist_ok=True)
gs_dims = (24, 28, 20)
subprocess.check_call([afam, "simulate", os.path.join(series_dir, "gs"), "--dims", "%d,%d,%d" % gs_dims,
                       "--steps", "4", "--every", "20", "--warmup", "300", "--seeds", "3"],
                      stdout=subprocess.DEVNULL)
gs_raws = sorted(glob.glob(os.path.join(series_dir, "gs_*_float32.raw")))
u.raws_to_vti(gs_raws, gs_dims, "v")
run_1, _, _ = encode_case(1, "series", "series_1", series_dir)
run_2, _, _ = encode_case(2, "series", "series_2", series_dir)
info = subprocess.run([afam, "info", run_2], capture_output=True, text=True).stdout
if "steps=4" not in info:
    u.fail("the 2-rank encode of a 4-step series is not a run of 4 steps:\n%s" % info)
with open(run_1, "rb") as a, open(run_2, "rb") as b:
    if a.read() != b.read():
        u.fail("the run encoded on 2 ranks differs from the one-process run")
verify = subprocess.run([afam, "verify", run_2, "--against"] + gs_raws, capture_output=True, text=True)
if verify.returncode != 0 or verify.stdout.count("step=") != 4:
    u.fail("a step of the 2-rank run breaks the bound:\n%s%s" % (verify.stdout, verify.stderr))
coded = [line for line in info.splitlines() if "references=" in line or "residuals=" in line]
print("series, 2 ranks: the one-process run byte for byte (%d bytes), every step verified; %s"
      % (os.path.getsize(run_2), "; ".join(coded[:4])), flush=True)
leftovers = glob.glob(os.path.join(out, "*.rank*")) + glob.glob("/tmp/afam-encoder-*.rank*")
if leftovers:
    u.fail("scratch runs were left behind: %s" % leftovers)

# Bad input: the same clear error on both ranks, no file.
for case, array, message in (
        ("wavelet", "nope", "encode: rank 0: the input has no point-data array 'nope'"),
        ("allempty", None, "the whole extent [0..-1, 0..-1, 0..-1] is empty"),
        ("hole", None, "no rank holds point (0, 0, 16) of the whole extent")):
    path, _, output = encode_case(2, case, "bad_" + case, array or "")
    for rank in (0, 1):
        if not any("[pvbatch.%d" % rank in line and message in line for line in output.splitlines()):
            print(output, flush=True)
            u.fail("%s: rank %d did not report '%s'" % (case, rank, message))
    if os.path.exists(path):
        u.fail("%s: a file was written despite the error" % case)
    print("%s: both ranks report '%s'; no file" % (case, message), flush=True)

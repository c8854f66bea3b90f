# SPDX-License-Identifier: BSD-3-Clause
"""pvbatch: the Adaptive-FAM Encoder on a time-varying input (a .vti file series of a Gray-Scott
run) encodes every step into one run, in order:
- its output has the input's TimestepValues, and its model file is a run of as many steps, each
  within the bound (`afam verify --against` the steps' samples);
- a new time on the output draws another step without encoding again (the same model file);
- the writer saves the whole run; the steps drawn differ;
- a fill value (UseMissingValue) marks missing samples at every step, each step's mask exact;
- with "Encode All Time Steps" off, only the step shown is encoded (a file of one step)."""
import glob
import os
import re
import subprocess
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

from paraview.simple import (GetActiveViewOrCreate, Render, SaveData, SaveScreenshot, Show,  # noqa: E402
                             XMLImageDataReader)

u.load_plugin(globals())
out = u.out_dir()


def model_file(proxy):
    proxy.UpdatePropertyInformation()
    return proxy.GetProperty("ModelFileName").GetData()


exe = u.env("AFAM_EXE")
dims = (24, 28, 20)
subprocess.check_call([exe, "simulate", os.path.join(out, "gs"), "--dims", "%d,%d,%d" % dims,
                       "--steps", "3", "--every", "40", "--warmup", "300", "--seeds", "3"],
                      stdout=subprocess.DEVNULL)
raws = sorted(glob.glob(os.path.join(out, "gs_*_float32.raw")))
series = u.raws_to_vti(raws, dims, "v")

source = XMLImageDataReader(FileName=series)
if list(source.TimestepValues) != [0.0, 1.0, 2.0]:
    u.fail("the .vti series reports times %s" % list(source.TimestepValues))
encoder = AdaptiveFAMEncoder(Input=source, Levels=2, BlocksPerAxis=2, ErrorBound=0.01)  # noqa: F821
encoder.UpdatePipeline(0.0)
times = list(encoder.TimestepValues)
model = model_file(encoder)
print("encoder output times %s, model file %s" % (times, model), flush=True)
if times != [0.0, 1.0, 2.0]:
    u.fail("the encoder's output times are %s" % times)
info = subprocess.run([exe, "info", model], capture_output=True, text=True).stdout
if "steps=3" not in info:
    u.fail("the model file is not a run of 3 steps:\n%s" % info)
verify = subprocess.run([exe, "verify", model, "--against"] + raws, capture_output=True,
                        text=True)
print(verify.stdout, flush=True)
if verify.returncode != 0 or verify.stdout.count("step=") != 3:
    u.fail("a step of the run breaks the bound:\n%s%s" % (verify.stdout, verify.stderr))

view = GetActiveViewOrCreate("RenderView")
u.setup_view(view)
view.CameraFocalPoint = [11.5, 13.5, 9.5]
view.CameraPosition = [11.5 + 40.0, 13.5 + 30.0, 9.5 + 45.0]
display = Show(encoder, view)
display.Representation = "Adaptive-FAM Volume"
u.apply_transfer_function(display, "v", 0.0, 0.45)
shots = []
for t in (0.0, 2.0):
    view.ViewTime = t
    Render(view)
    shots.append(os.path.join(out, "t%g.png" % t))
    SaveScreenshot(shots[-1], view)
    if model_file(encoder) != model:
        u.fail("time %g encoded the run again" % t)
    if not u.non_blank(shots[-1]):
        u.fail("time %g is blank" % t)
fraction, worst = u.differing_fraction(shots[0], shots[1], 2)
if fraction == 0:
    u.fail("times 0 and 2 draw the same image: the steps are not told apart")

saved = os.path.join(out, "saved.afam")
SaveData(saved, proxy=encoder)
if "steps=3" not in subprocess.run([exe, "info", saved], capture_output=True, text=True).stdout:
    u.fail("the writer did not save the whole run")

# A fill value marks missing samples at every step of a run: the file declares it from step 0 and
# every step keeps its mask exactly (`afam verify --against`: missing=N mask_mismatches=0).
holes = []
for k, raw in enumerate(raws):
    holes.append(os.path.join(out, "holes_%04d_%dx%dx%d_float32.raw" % ((k,) + dims)))
    subprocess.check_call([exe, "mask", raw, holes[-1], "--shape", "ball", "--fill", "-5"],
                          stdout=subprocess.DEVNULL)
masked_source = XMLImageDataReader(FileName=u.raws_to_vti(holes, dims, "v"))
masked = AdaptiveFAMEncoder(Input=masked_source, Levels=2, BlocksPerAxis=2,  # noqa: F821
                            ErrorBound=0.01, UseMissingValue=1, MissingValue=-5.0)
masked.UpdatePipeline(0.0)
masked_info = subprocess.run([exe, "info", model_file(masked)], capture_output=True, text=True).stdout
if "steps=3" not in masked_info or "missing=value(-5)" not in masked_info:
    u.fail("a run with a fill value:\n%s" % masked_info)
verify = subprocess.run([exe, "verify", model_file(masked), "--against"] + holes,
                        capture_output=True, text=True)
print(verify.stdout, flush=True)
if verify.returncode != 0 or len(re.findall(r"missing=[1-9][0-9]* mask_mismatches=0",
                                            verify.stdout)) != 3:
    u.fail("a step of the run with a fill value lost its mask:\n%s%s" % (verify.stdout, verify.stderr))

encoder.EncodeAllTimeSteps = 0
encoder.UpdatePipeline(1.0)
one = subprocess.run([exe, "info", model_file(encoder)],
                     capture_output=True, text=True).stdout
if "version=2" not in one:
    u.fail("with EncodeAllTimeSteps off the step shown should be encoded alone:\n%s" % one)
print("AFAM-ENCODE-TIME-STEPS-OK", flush=True)

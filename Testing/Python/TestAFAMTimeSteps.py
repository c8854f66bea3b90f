# SPDX-License-Identifier: BSD-3-Clause
"""pvbatch: a run of time steps in one .afam file (format version 3) in ParaView.
Two scans a and b (the repository's HeadMRVolume made larger, with different noise) are encoded
as the run a, b, a at times 0, 2.5 and 5 (every block stored in every step), and each on its own,
all at the same absolute bound.
- OpenDataFile gives the run's TimestepValues;
- the animation scene, driven by the data's time steps, shows at each time the image of the
  one-step file of that step (at most 2/255 apart), and step b's image is not step a's."""
import os
import subprocess
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

from paraview.simple import (GetActiveViewOrCreate, GetAnimationScene, Hide, OpenDataFile,  # noqa: E402
                             Render, SaveScreenshot, Show)

u.load_plugin(globals())
out = u.out_dir()
exe = u.env("AFAM_EXE")
head = os.path.join(u.env("AFAM_BASELINE"), "..", "volumes", "HeadMRVolume_48x62x42_uint8.raw")
scans = {}
for name, seed in (("a", 1), ("b", 2)):
    os.makedirs(os.path.join(out, name), exist_ok=True)
    scans[name] = os.path.join(out, name, "scan_40x48x36_uint8.raw")
    subprocess.check_call([exe, "enlarge", head, scans[name], "--dims", "40,48,36", "--seed",
                           str(seed), "--noise", "6"])
bound = ["--error-bound", "2.55"]
run = os.path.join(out, "run.afam")
# Key interval 1: every block of every step stored on its own, as in the one-step files (with
# references a step may keep the step before's model where it still meets the bound, a valid
# encoding that is not the one-step file's).
subprocess.check_call([exe, "encode", scans["a"], scans["b"], scans["a"], run, "--times",
                       "0,2.5,5", "--key-interval", "1", "--quiet"] + bound)
one = {}
for name in scans:
    one[name] = os.path.join(out, "one_%s.afam" % name)
    subprocess.check_call([exe, "encode", scans[name], one[name], "--quiet"] + bound)

view = GetActiveViewOrCreate("RenderView")
u.setup_view(view)
view.CameraFocalPoint = [19.5, 23.5, 17.5]
view.CameraPosition = [19.5 + 62.0, 23.5 + 48.0, 17.5 + 86.0]


def show(source):
    display = Show(source, view)
    display.Representation = "Adaptive-FAM Volume"
    u.apply_transfer_function(display, "scan", 0.0, 255.0)
    display.AFAMPrefetcher = "None"
    return display


reader = OpenDataFile(run)
times = list(reader.TimestepValues)
print("TimestepValues %s" % times, flush=True)
if times != [0.0, 2.5, 5.0]:
    u.fail("the run's TimestepValues are %s, not [0, 2.5, 5]" % times)
show(reader)
scene = GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
shots = {}
for t in times:
    scene.AnimationTime = t
    Render(view)
    shots[t] = os.path.join(out, "run_t%s.png" % t)
    SaveScreenshot(shots[t], view)
Hide(reader, view)
refs = {}
for name in one:
    source = OpenDataFile(one[name])
    show(source)
    Render(view)
    refs[name] = os.path.join(out, "one_%s.png" % name)
    SaveScreenshot(refs[name], view)
    Hide(source, view)
for t, name in ((0.0, "a"), (2.5, "b"), (5.0, "a")):
    fraction, worst = u.differing_fraction(shots[t], refs[name], 2)
    print("time %s against step %s's own file: largest difference %d/255" % (t, name, worst),
          flush=True)
    if fraction > 0:
        u.fail("time %s differs from the one-step file of %s by up to %d/255" % (t, name, worst))
fraction, worst = u.differing_fraction(shots[2.5], refs["a"], 2)
if fraction == 0:
    u.fail("step b's image is step a's: the time steps are not told apart")
if not u.non_blank(shots[2.5]):
    u.fail("the run's image at time 2.5 is blank")
print("AFAM-TIME-STEPS-OK", flush=True)

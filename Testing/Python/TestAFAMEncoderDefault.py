# SPDX-License-Identifier: BSD-3-Clause
"""pvbatch: the Adaptive-FAM Encoder on an image with one point array encodes it with no array
chosen (its Scalars property left as ParaView creates it), as ParaView's own filters take the
active scalars; with Bound Kind "Max error per sample" every sample is within the bound and the
output's field data says so (AFAM_BoundKind, AFAM_Bound)."""
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

from paraview.simple import Wavelet, servermanager  # noqa: E402

u.load_plugin(globals())
wavelet = Wavelet(WholeExtent=[0, 16, 0, 16, 0, 16])
encoder = AdaptiveFAMEncoder(Input=wavelet, Levels=2, BlocksPerAxis=2)  # noqa: F821
print("Scalars property as created: %s" % (encoder.GetProperty("SelectInputScalars").GetData(),))
encoder.UpdatePipeline()
leaves = encoder.GetDataInformation().GetNumberOfDataSets()
expected = 2 + 1  # levels 1 and 0 (a leaf each), and the value-range probe
print("encoded without a chosen array: %d leaves (expected %d)" % (leaves, expected))
if leaves != expected:
    u.fail("the encoder did not encode the image's only point array")

# The encode reports what it achieved beside the bound, per level.
encoder.UpdatePropertyInformation()
rmse = encoder.GetProperty("LastMaxRmse").GetData()
error = encoder.GetProperty("LastMaxError").GetData()
bound = encoder.GetProperty("LastBound").GetData()
report = encoder.GetProperty("LastLevelReport").GetData()
print("max block rmse %g, max error %g, bound %g\n%s" % (rmse, error, bound, report))
if not (0 < bound and 0 <= rmse <= bound and error >= rmse):
    u.fail("encoder statistics: rmse %g error %g bound %g" % (rmse, error, bound))
if report.count("level ") != 2 or "bound=" not in report:
    u.fail("per-level report: %r" % report)

# A pointwise bound (Bound Kind "Max error per sample"): every model's worst sample within the
# bound, and the output's field data says what the file keeps.
encoder.BoundKind = 1
encoder.UpdatePipeline()
encoder.UpdatePropertyInformation()
point_error = encoder.GetProperty("LastMaxError").GetData()
point_bound = encoder.GetProperty("LastBound").GetData()
tree = servermanager.Fetch(encoder)
kind = tree.GetFieldData().GetAbstractArray("AFAM_BoundKind").GetValue(0)
stored = tree.GetFieldData().GetArray("AFAM_Bound").GetValue(0)
print("pointwise: max error %g, bound %g, field data %s %g" % (point_error, point_bound, kind, stored))
if kind != "max_error" or not (0 < point_error <= point_bound * (1 + 1e-6)):
    u.fail("pointwise bound: max error %g bound %g kind %s" % (point_error, point_bound, kind))
if abs(stored - point_bound) > 1e-9 * point_bound:
    u.fail("AFAM_Bound %g is not the bound %g" % (stored, point_bound))
if error <= point_bound * 1.5:
    u.fail("the RMSE encode's worst sample (%g) is near the bound too: the test means nothing" % error)

# SPDX-License-Identifier: BSD-3-Clause
"""pvbatch: the reader's "Decoded Level" of a damaged file does not fail whole. Payloads of the
finest level damaged (8 bytes inverted in two of them): the decode still gives the whole grid, one
warning naming both blocks and `afam verify`, the damaged blocks' samples taken from the nearest
intact coarser level (no NaN, RMSE against the intact file's under 5% of the value range), every
other sample exactly the intact file's."""
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

import numpy as np  # noqa: E402
from paraview import servermanager  # noqa: E402
from vtkmodules.numpy_interface import dataset_adapter as dsa  # noqa: E402

u.load_plugin(globals())
# The finest level's payloads come after the coarse level's: two spots near the end.
good, bad = u.damaged_wavelet(globals(), 2, (0.80, 0.95))


def decode(path):
    reader = AdaptiveFAMReader(FileName=path, DecodeLevel=1)  # noqa: F821

    def update():
        reader.UpdatePipeline()
        return servermanager.Fetch(reader, idx=1)
    image, text = u.captured_messages(update)
    values = dsa.WrapDataObject(image).PointData["RTData"] if image.GetNumberOfPoints() else None
    return image.GetNumberOfPoints(), values, text


n_good, intact, _ = decode(good)
n_bad, damaged, text = decode(bad)
print("decoded: intact %d points, damaged %d points; messages: %s" % (n_good, n_bad, " ".join(text.split())[:500]))
if n_bad != n_good or n_good != 41 ** 3:
    u.fail("the damaged file's decode has %d points, the intact one's %d (expected %d)" % (n_bad, n_good, 41 ** 3))
warnings = len(text.split("Warning: In ")) - 1
errors = len(text.split("ERROR: In ")) - 1 + len(text.split("Error: In ")) - 1
named = text.count("payload checksum mismatch at level 1 block")
if warnings != 1 or errors != 0 or named != 2 or "afam verify" not in text:
    u.fail("expected one warning naming 2 damaged blocks and `afam verify`: %d warnings, %d errors, %d named"
           % (warnings, errors, named))
differs = np.asarray(damaged) != np.asarray(intact)
rmse = float(np.sqrt(np.mean((np.asarray(damaged)[differs] - np.asarray(intact)[differs]) ** 2))) if differs.any() else 0.0
value_range = float(np.max(intact) - np.min(intact))
print("%d samples differ from the intact decode (two blocks hold at most %d), RMSE %.4f (%.3f %% of the range), "
      "NaN %d" % (int(differs.sum()), 2 * 11 ** 3, rmse, 100 * rmse / value_range, int(np.isnan(damaged).sum())))
if not 0 < differs.sum() <= 2 * 11 ** 3:
    u.fail("%d samples differ from the intact decode" % int(differs.sum()))
if np.isnan(damaged).any() or rmse > 0.05 * value_range:
    u.fail("damaged blocks not filled from the coarser level (RMSE %.4f, range %.1f)" % (rmse, value_range))

# SPDX-License-Identifier: BSD-3-Clause
"""pvpython: the colour array of an .afam file (and of the encoding filter's output) is whole, not
"<name> (partial)" (ParaView's colour widget says partial when vtkPVArrayInformation::GetIsPartial
is true: some leaf with points lacks the array), and what ParaView computes by default from the data
information is what it was before the level leaves carried the array:
- the number of points and cells (every level's leaf spans the volume's grid, plus the 2x2x2 "Value
  range" leaf), the bounds, hence the default Scalar Opacity Unit Distance (ParaView's BoundsDomain,
  mode approximate_cell_length: diagonal / cbrt(cells));
- the array's range (the file's value range), hence the colour map's and the opacity ramp's;
- the representation ("Adaptive-FAM Volume", coloured by the array);
- no memory spent on the leaves' arrays (they hold NaN and no storage), also after rendering."""
import math
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

from paraview import servermanager  # noqa: E402
from paraview.simple import (CreateView, GetColorTransferFunction, GetOpacityTransferFunction,  # noqa: E402
                             OpenDataFile, Render, Show, Wavelet)

u.load_plugin(globals())
out = u.out_dir()
path = os.path.join(out, "colour_array.afam")
EXTENT = [-20, 20, -20, 20, -10, 30]  # 41^3 samples, 40^3 cells, spacing 1
LEVELS = 3
u.encode_wavelet(globals(), EXTENT, LEVELS, 4, 0.005, path)


def close(a, b, tolerance=1e-9):
    return abs(a - b) <= tolerance * max(1.0, abs(b))


def check_whole(source, what):
    """The array's information as the colour widget reads it: present, not partial."""
    info = source.GetPointDataInformation().GetArray("RTData")
    if info is None:
        u.fail("%s: no RTData point array in the data information" % what)
    partial = info.GetIsPartial()
    print("%s: RTData partial %d, range %s" % (what, partial, info.GetRange()), flush=True)
    if partial:
        u.fail("%s: the colour array is partial (the panel says 'RTData (partial)')" % what)
    return info


reader = OpenDataFile(path)
reader.UpdatePipeline()
data = reader.GetDataInformation()
tree = data.DataInformation
points, cells = tree.GetNumberOfPoints(), tree.GetNumberOfCells()
bounds = tree.GetBounds()
memory_kb = tree.GetMemorySize()
print("data information: %d points, %d cells, %d data sets, bounds %s, %d KB"
      % (points, cells, tree.GetNumberOfDataSets(), bounds, memory_kb), flush=True)
grid_points, grid_cells = 41 ** 3, 40 ** 3
if points != LEVELS * grid_points + 8 or cells != LEVELS * grid_cells + 1:
    u.fail("%d points and %d cells; the leaves span %d x %d + 8 points and %d x %d + 1 cells"
           % (points, cells, LEVELS, grid_points, LEVELS, grid_cells))
if list(bounds) != [float(e) for e in EXTENT]:
    u.fail("bounds %s, not the volume's %s" % (bounds, EXTENT))
if memory_kb > 64:
    u.fail("the model set takes %d KB in memory: the leaves' arrays hold values" % memory_kb)

info = check_whole(reader, "reader")
# The file's value range, from the root's field data (the leaves have a column of the same name).
file_range = list(servermanager.Fetch(reader).GetFieldData().GetArray("AFAM_ValueRange").GetTuple2(0))
if not (close(info.GetRange()[0], file_range[0]) and close(info.GetRange()[1], file_range[1])):
    u.fail("array range %s, not the file's value range %s" % (info.GetRange(), file_range))

view = CreateView("RenderView")
view.ViewSize = [200, 200]
display = Show(reader, view)
Render(view)
if display.Representation != "Adaptive-FAM Volume" or tuple(display.ColorArrayName) != ("POINTS", "RTData"):
    u.fail("Show gave %r coloured by %s" % (display.Representation, tuple(display.ColorArrayName)))
array_list = display.GetProperty("ColorArrayName").SMProperty.GetDomain("array_list")
names = [array_list.GetString(i) for i in range(array_list.GetNumberOfStrings())]
if names != ["RTData"]:
    u.fail("the colour array list is %s" % names)
colour_info = display.SMProxy.GetArrayInformationForColorArray()
if colour_info is None or colour_info.GetIsPartial():
    u.fail("the representation's colour array information is %s"
           % ("missing" if colour_info is None else "partial"))

# The default Scalar Opacity Unit Distance: ParaView's approximate_cell_length of the data
# information above, 1.2009 for this file (as before the leaves carried the array).
diagonal = math.sqrt(sum((bounds[2 * a + 1] - bounds[2 * a]) ** 2 for a in range(3)))
expected_soud = diagonal / (LEVELS * grid_cells + 1) ** (1.0 / 3.0)
soud = display.ScalarOpacityUnitDistance
print("default Scalar Opacity Unit Distance %.10f (diagonal / cbrt(cells) %.10f)" % (soud, expected_soud),
      flush=True)
if not close(soud, expected_soud, 1e-6) or not close(soud, 1.2009348702, 1e-8):
    u.fail("default Scalar Opacity Unit Distance %.10f, expected %.10f" % (soud, expected_soud))

# The colour map and opacity ramp span the file's range.
lut, pwf = GetColorTransferFunction("RTData"), GetOpacityTransferFunction("RTData")
lut_range = [lut.RGBPoints[0], lut.RGBPoints[-4]]
pwf_range = [pwf.Points[0], pwf.Points[-4]]
print("colour map range %s, opacity ramp range %s, file %s" % (lut_range, pwf_range, file_range), flush=True)
for r in (lut_range, pwf_range):
    if not (close(r[0], file_range[0], 1e-6) and close(r[1], file_range[1], 1e-6)):
        u.fail("transfer-function range %s, not the file's %s" % (r, file_range))

# Rendering spent no memory on the leaves' arrays.
reader.GetDataInformation().Update()
after_kb = reader.GetDataInformation().DataInformation.GetMemorySize()
print("after rendering: %d KB" % after_kb, flush=True)
if after_kb > memory_kb + 8:
    u.fail("the model set grew from %d to %d KB while shown" % (memory_kb, after_kb))

# The encoding filter's output: the same tree, the same whole array.
encoder = AdaptiveFAMEncoder(Input=Wavelet(WholeExtent=EXTENT), Levels=2, BlocksPerAxis=4)  # noqa: F821
encoder.Scalars = ["POINTS", "RTData"]
encoder.UpdatePipeline()
check_whole(encoder, "encoder")
print("AFAM-COLOUR-ARRAY-OK", flush=True)

# SPDX-License-Identifier: BSD-3-Clause
"""pvbatch: the reader's second output ("Decoded Level") turns an .afam file into image data that
ordinary filters work on, and the reader honours pieces. A 41^3 Wavelet is encoded (2 levels, 4
finest blocks per axis, 0.5% RMSE bound) and saved; then
  - DecodeLevel -1 (default): port 1 is empty;
  - DecodeLevel 1 (finest): the volume's 41^3 grid, RMSE against the Wavelet within the bound;
    Slice and Contour of the decoded level match Slice and Contour of the Wavelet;
  - DecodeLevel 0: a 21^3 grid over the same bounds;
  - pieces: 2 pieces of port 1 are disjoint z-slabs that together equal the whole decode; 2 pieces
    of port 0 hold disjoint sets of micro-models, together all of them, with disjoint z-ranges."""
import os
import sys

sys.path.insert(0, os.environ.get("AFAM_TEST_SCRIPTS", ""))
import afam_test_util as u  # noqa: E402

import numpy as np  # noqa: E402
from paraview.simple import Contour, OutputPort, Slice  # noqa: E402
from paraview import servermanager  # noqa: E402
from vtkmodules.numpy_interface import dataset_adapter as dsa  # noqa: E402
from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline  # noqa: E402
from vtkmodules.vtkFiltersCore import vtkPassThrough  # noqa: E402

u.load_plugin(globals())
out = u.out_dir()

path = os.path.join(out, "wavelet_l2.afam")
wavelet, _ = u.encode_wavelet(globals(), [-20, 20, -20, 20, -20, 20], 2, 4, 0.005, path)
reader = AdaptiveFAMReader(FileName=path)  # noqa: F821


# 1. Nothing decoded by default.
decoded = OutputPort(reader, 1)
reader.UpdatePipeline()
n_default = reader.GetDataInformation(1).GetNumberOfPoints()
if n_default != 0:
    u.fail("DecodeLevel -1 produced %d points" % n_default)

# 2. The finest level: the Wavelet's grid and values within the error bound.
reader.DecodeLevel = 1
reader.UpdatePipeline()
info = reader.GetDataInformation(1)
if info.GetNumberOfPoints() != 41 ** 3:
    u.fail("finest level has %d points, expected 41^3" % info.GetNumberOfPoints())
bounds = info.GetBounds()
# World coordinates: the decoded grid, the models and the Wavelet share their bounds (the file's
# origin is the world position of the Wavelet's first sample, -20 on each axis).
file_bounds = reader.GetDataInformation(0).GetBounds()
wavelet_bounds = wavelet.GetDataInformation().GetBounds()
print("finest level bounds %s, models' bounds %s, Wavelet bounds %s" % (bounds, file_bounds, wavelet_bounds))
for name, b in (("finest level", bounds), ("models'", file_bounds)):
    if max(abs(x - y) for x, y in zip(b, wavelet_bounds)) > 1e-9:
        u.fail("%s bounds %s differ from the Wavelet's %s" % (name, b, wavelet_bounds))
if max(abs(x - y) for x, y in zip(wavelet_bounds, [-20, 20, -20, 20, -20, 20])) > 1e-9:
    u.fail("Wavelet bounds %s, expected [-20, 20]^3" % (wavelet_bounds,))
truth = dsa.WrapDataObject(servermanager.Fetch(wavelet)).PointData["RTData"]
got = dsa.WrapDataObject(servermanager.Fetch(reader, idx=1)).PointData["RTData"]
if got is None or len(got) != len(truth):
    u.fail("decoded level has no RTData array of the right size")
value_range = float(np.max(truth) - np.min(truth))
bound = 0.005 * value_range
err = (np.asarray(got, dtype=np.float64) - np.asarray(truth, dtype=np.float64)).reshape(41, 41, 41)
rmse = float(np.sqrt(np.mean(err ** 2)))
# The promise is per block: each of the 4^3 finest blocks (11 samples a side, neighbours sharing a
# face) within the bound on the 11^3 samples it stands for. The decoded level takes a shared
# sample from one block, so each block's squared error over the samples it gives the level is at
# most bound^2 x 11^3 (a level RMSE may exceed the bound by the overlap, (44/41)^1.5, and the
# check must not allow that).
owned = [(0, 10), (10, 20), (20, 30), (30, 41)]
worst = max(float(np.sum(err[z0:z1, y0:y1, x0:x1] ** 2)) / (bound ** 2 * 11 ** 3)
            for z0, z1 in owned for y0, y1 in owned for x0, x1 in owned)
print("finest level: RMSE %.4f, bound 0.005 x range %.1f = %.3f, worst block's share of its "
      "budget %.3f" % (rmse, value_range, bound, worst))
if not worst <= 1.0:
    u.fail("a decoded block's squared error is %.3f of what the bound allows it" % worst)
if rmse == 0.0:
    u.fail("decoded values are the input itself (nothing was decoded)")


def slice_and_contour(source, z):
    s = Slice(Input=source)
    s.SliceType = "Plane"
    s.SliceType.Origin = [0.0, 0.0, z]
    s.SliceType.Normal = [0.0, 0.0, 1.0]
    c = Contour(Input=source, ContourBy=["POINTS", "RTData"], Isosurfaces=[160.0])
    sd = dsa.WrapDataObject(servermanager.Fetch(s))
    cd = servermanager.Fetch(c)
    return sd.GetNumberOfPoints(), np.asarray(sd.PointData["RTData"]), cd.GetNumberOfPoints(), cd.GetBounds()


# Same world plane and isosurface on both: the decoded level where the Wavelet is.
ns, sv, nc, cb = slice_and_contour(decoded, 0.5)
ns0, sv0, nc0, cb0 = slice_and_contour(wavelet, 0.5)
print("slice: %d points (wavelet %d), max diff %.3f; contour: %d points (wavelet %d)" % (
    ns, ns0, float(np.max(np.abs(sv - sv0))) if ns == ns0 else -1, nc, nc0))
if ns != ns0 or ns < 1000:
    u.fail("slice of the decoded level has %d points, of the wavelet %d" % (ns, ns0))
if float(np.max(np.abs(sv - sv0))) > 0.05 * value_range:
    u.fail("slice values differ from the wavelet's by more than 5% of the range")
if nc < 100 or abs(nc - nc0) > 0.05 * nc0:
    u.fail("contour of the decoded level has %d points, of the wavelet %d" % (nc, nc0))
if max(abs(a - b) for a, b in zip(cb, cb0)) > 1.0:
    u.fail("contour bounds %s differ from the wavelet's %s" % (cb, cb0))

# 3. The coarse level: its own grid over the same bounds.
reader.DecodeLevel = 0
reader.UpdatePipeline()
info = reader.GetDataInformation(1)
if info.GetNumberOfPoints() != 21 ** 3:
    u.fail("level 0 has %d points, expected 21^3" % info.GetNumberOfPoints())
if max(abs(b - e) for b, e in zip(info.GetBounds(), wavelet_bounds)) > 1e-9:
    u.fail("level 0 bounds %s differ from the Wavelet's %s" % (info.GetBounds(), wavelet_bounds))

# 4. Pieces, on the reader object itself (what each MPI rank's pipeline asks for).
reader.DecodeLevel = 1
reader.UpdatePipeline()
alg = reader.GetClientSideObject()
whole = dsa.WrapDataObject(servermanager.Fetch(reader, idx=1)).PointData["RTData"]
whole = np.asarray(whole).reshape(41, 41, 41)  # z, y, x
extents = []
for piece in range(2):
    pt = vtkPassThrough()
    pt.SetInputConnection(alg.GetOutputPort(1))
    pt.UpdatePiece(piece, 2, 0)
    img = pt.GetOutput()
    ext = img.GetExtent()
    extents.append(ext)
    vals = np.asarray(dsa.WrapDataObject(img).PointData["RTData"])
    dims = [ext[1] - ext[0] + 1, ext[3] - ext[2] + 1, ext[5] - ext[4] + 1]
    if vals.size != dims[0] * dims[1] * dims[2] or vals.size == 41 ** 3:
        u.fail("piece %d of port 1: extent %s, %d values" % (piece, ext, vals.size))
    region = whole[ext[4]:ext[5] + 1, ext[2]:ext[3] + 1, ext[0]:ext[1] + 1]
    if not np.array_equal(vals.reshape(dims[2], dims[1], dims[0]), region):
        u.fail("piece %d of port 1 differs from the whole decode" % piece)
cells = [(e[1] - e[0]) * (e[3] - e[2]) * (e[5] - e[4]) for e in extents]
if sum(cells) != 40 ** 3:
    u.fail("port-1 pieces %s do not tile the grid" % (extents,))
print("port 1 pieces: %s" % (extents,))

models = []
for piece in range(2):
    alg.UpdatePiece(piece, 2, 0)
    mb = alg.GetOutputDataObject(0)
    it = mb.NewIterator()
    it.InitTraversal()
    entries, zr = set(), [1e30, -1e30]
    while not it.IsDoneWithTraversal():
        leaf = it.GetCurrentDataObject()
        fd = leaf.GetFieldData()
        if fd.GetArray("AFAM_EntryIndex") is not None:
            column = fd.GetArray("AFAM_EntryIndex")
            entries.update(int(column.GetTuple1(r)) for r in range(column.GetNumberOfTuples()))
            b = leaf.GetBounds()
            zr = [min(zr[0], b[4]), max(zr[1], b[5])]
        it.GoToNextItem()
    models.append((entries, zr))
    print("port 0 piece %d: %d models, z in [%g, %g]" % (piece, len(entries), zr[0], zr[1]))
all_models = 4 ** 3 + 2 ** 3
(e0, z0), (e1, z1) = models
if e0 & e1 or len(e0 | e1) != all_models or not e0 or not e1:
    u.fail("port-0 pieces are not a partition of the %d models: %d + %d" % (all_models, len(e0), len(e1)))
if not (z0[1] <= z1[0] or z1[1] <= z0[0]):
    u.fail("port-0 pieces overlap in z: %s %s" % (z0, z1))

# 5. A level the file does not have: an error, no data, no crash.
reader.DecodeLevel = 5
reader.UpdatePipeline()
if reader.GetDataInformation(1).GetNumberOfPoints() != 0:
    u.fail("DecodeLevel 5 of a 2-level file produced data")
print("AFAM decode-level test passed")

# SPDX-License-Identifier: BSD-3-Clause
"""Encodes any volume ParaView can read (VTK XML image data .vti, legacy .vtk, NRRD, MetaImage,
DICOM folders, netCDF, ...) or a raw file named name_XxYxZ_type.raw (as `afam encode` reads it)
into an .afam file, with the options of `afam encode` and a progress bar. ParaView's reader opens
the file; the Adaptive-FAM Encoder filter of the plugin encodes the chosen point array with Core's
encoder; the plugin's writer saves the .afam file (atomically, so a failed run leaves nothing
behind). Spacing and origin come from the data set.

    pvbatch afam_encode.py IN OUT.afam [--plugin AdaptiveFAM.so] [--array NAME]
        [--error-bound E] [--relative] [--levels L] [--blocks B] [--degree P]
        [--mode adaptive|inlevel|fixed|ds] [--ncp K] [--threads T] [--quiet]

Under `mpirun -np N pvbatch afam_encode.py ...` each rank reads only its piece of the volume and
fits a share of the blocks; rank 0 writes the one file, whose micro-models are those of a
one-process encode (--threads is then per rank).

The plugin is found from --plugin, else PV_PLUGIN_PATH, else the build tree next to this script
(build/lib/paraview-5.11/plugins/AdaptiveFAM/AdaptiveFAM.so). Exit status 1 on any error, with one
line on stderr naming the problem.
"""
import argparse
import os
import re
import struct
import sys
import time

MODES = {"adaptive": "Adaptive", "inlevel": "In-level", "fixed": "Fixed NCP", "ds": "Downsampled"}


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("input", help="a file ParaView can read")
    p.add_argument("output", help="the .afam file to write")
    p.add_argument("--plugin", help="AdaptiveFAM.so (default: PV_PLUGIN_PATH or the build tree)")
    p.add_argument("--array", help="point array to encode (default: the first one-component array)")
    p.add_argument("--error-bound", type=float, default=1e-4, help="RMSE bound per micro-block (1e-4)")
    p.add_argument("--relative", action="store_true", help="the bound is E * (max - min) of the volume")
    p.add_argument("--levels", type=int, default=0, help="levels of detail (0: from the dimensions)")
    p.add_argument("--blocks", type=int, default=0,
                   help="blocks per axis at the finest level (0: from the dimensions, blocks of ~64 samples)")
    p.add_argument("--degree", type=int, default=2, help="B-spline degree (2)")
    p.add_argument("--mode", choices=sorted(MODES), default="adaptive")
    p.add_argument("--ncp", type=int, default=0, help="NCP per axis for --mode fixed (0 = n)")
    p.add_argument("--threads", type=int, default=0, help="worker threads (0 = all cores)")
    p.add_argument("--quiet", action="store_true", help="print nothing on success")
    a = p.parse_args()
    if a.ncp and a.mode != "fixed":
        fail("--ncp needs --mode fixed")
    if not a.output.endswith(".afam"):
        fail("%s: the output must end in .afam" % a.output)
    return a


def fail(message):
    sys.stderr.write("afam_encode.py: error: %s\n" % message)
    sys.exit(1)


def find_plugin(given):
    if given:
        return given
    here = os.path.dirname(os.path.abspath(__file__))
    candidates = [os.path.join(d, "AdaptiveFAM.so") for d in os.environ.get("PV_PLUGIN_PATH", "").split(":") if d]
    candidates.append(os.path.join(here, "..", "..", "build", "lib", "paraview-5.11", "plugins", "AdaptiveFAM",
                                   "AdaptiveFAM.so"))
    for c in candidates:
        if os.path.isfile(c):
            return c
    fail("cannot find AdaptiveFAM.so: pass --plugin or set PV_PLUGIN_PATH")


class ProgressBar:
    """`afam encode`'s bar on stderr: redrawn in place on a terminal, every 10% otherwise."""

    def __init__(self, quiet):
        self.quiet, self.tty, self.shown, self.t0 = quiet, sys.stderr.isatty(), -1, time.time()

    def __call__(self, fraction):
        if self.quiet:
            return
        percent = int(100 * min(max(fraction, 0.0), 1.0))
        if percent == self.shown or (not self.tty and percent // 10 == self.shown // 10 and percent < 100):
            return
        self.shown = percent
        bar = "#" * (percent * 30 // 100)
        line = "encode [%-30s] %3d%% %6.1f s" % (bar, percent, time.time() - self.t0)
        sys.stderr.write(("\r" + line) if self.tty else (line + "\n"))
        if self.tty and percent == 100:
            sys.stderr.write("\n")
        sys.stderr.flush()


RAW_TYPES = {"uint8": "unsigned char", "int16": "short", "uint16": "unsigned short", "float32": "float",
             "float64": "double"}


def open_volume(path):
    """ParaView's reader for `path`; a raw file named name_XxYxZ_type.raw through ImageReader,
    which reads only each rank's piece."""
    from paraview.simple import ImageReader, OpenDataFile
    raw = re.match(r".*_(\d+)x(\d+)x(\d+)_(\w+)\.raw$", os.path.basename(path))
    if not raw:
        return OpenDataFile(path)
    if raw.group(4) not in RAW_TYPES:
        fail("%s: unknown sample type '%s' (%s)" % (path, raw.group(4), ", ".join(sorted(RAW_TYPES))))
    dims = [int(raw.group(i)) for i in (1, 2, 3)]
    return ImageReader(FileNames=[path], DataScalarType=RAW_TYPES[raw.group(4)], DataByteOrder="LittleEndian",
                       DataExtent=[0, dims[0] - 1, 0, dims[1] - 1, 0, dims[2] - 1])


def file_partition(path):
    """Levels and finest blocks per axis of an .afam file (docs/FORMAT.md: header offsets 120, 124)."""
    with open(path, "rb") as f:
        header = f.read(128)
    return struct.unpack_from("<ii", header, 120)


def pick_array(source, wanted):
    info = source.GetPointDataInformation()
    names = [(info.GetArray(i).GetName(), info.GetArray(i).GetNumberOfComponents())
             for i in range(info.GetNumberOfArrays())]
    if wanted:
        for name, comps in names:
            if name == wanted:
                if comps != 1:
                    fail("--array %s has %d components; a scalar array is needed" % (wanted, comps))
                return name
        fail("no point array '%s' (arrays: %s)" % (wanted, ", ".join(n for n, _ in names) or "none"))
    for name, comps in names:
        if comps == 1:
            return name
    fail("no one-component point array to encode (arrays: %s)" % (", ".join(n for n, _ in names) or "none"))


def main():
    a = parse_args()
    from paraview import servermanager
    ranks = servermanager.vtkProcessModule.GetProcessModule().GetNumberOfLocalPartitions()
    if not os.path.exists(a.input):
        fail("%s: no such file" % a.input)
    from paraview.simple import LoadPlugin, SaveData
    LoadPlugin(find_plugin(a.plugin), remote=False, ns=globals())
    reader = open_volume(a.input)
    if reader is None:
        fail("%s: ParaView has no reader for this file" % a.input)
    reader.UpdatePipeline()
    info = reader.GetDataInformation()
    if info.GetDataClassName() != "vtkImageData":
        fail("%s: ParaView reads it as %s; the encoder takes image data (resample it first)"
             % (a.input, info.GetDataClassName()))
    array = pick_array(reader, a.array)
    encoder = AdaptiveFAMEncoder(Input=reader, ErrorBound=a.error_bound,  # noqa: F821 (from the plugin)
                                 RelativeBound=int(a.relative), Levels=a.levels, BlocksPerAxis=a.blocks,
                                 Degree=a.degree, Mode=MODES[a.mode], FixedNcp=a.ncp, NumberOfThreads=a.threads)
    encoder.Scalars = ["POINTS", array]
    bar = ProgressBar(a.quiet)
    encoder.GetClientSideObject().AddObserver("ProgressEvent", lambda obj, event: bar(obj.GetProgress()))
    t0 = time.time()
    encoder.UpdatePipeline()
    seconds = time.time() - t0
    if encoder.GetDataInformation().GetNumberOfDataSets() == 0:
        fail("%s: the encoder produced no micro-models (see the VTK error above)" % a.input)
    bar(1.0)
    SaveData(os.path.abspath(a.output), proxy=encoder)
    if not os.path.isfile(a.output):
        fail("%s: the writer failed (see the VTK error above)" % a.output)
    if not a.quiet:
        extent = info.GetExtent()
        dims = [extent[2 * i + 1] - extent[2 * i] + 1 for i in range(3)]
        size = os.path.getsize(a.output)
        levels, blocks = file_partition(a.output)
        print("encoded %s (array %s, %dx%dx%d) -> %s" % (a.input, array, dims[0], dims[1], dims[2], a.output))
        print("mode=%s levels=%d blocks=%d degree=%d bound=%g%s ranks=%d seconds=%.3f bytes_out=%d "
              "ratio_float32=%.2f" % (a.mode, levels, blocks, a.degree, a.error_bound,
                                      " (relative)" if a.relative else "", ranks, seconds, size,
                                      4.0 * dims[0] * dims[1] * dims[2] / size))

if __name__ == "__main__":
    main()

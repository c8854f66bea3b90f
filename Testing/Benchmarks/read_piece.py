# SPDX-License-Identifier: BSD-3-Clause
"""The reference run of encode_mpi.sh: what `afam_encode.py` does before it encodes (ParaView, the
plugin, the reader: each rank holds its piece), then an encode of a 16^3 Wavelet on the same ranks
saved with the same writer (the encoder's and MPI's code pages are then resident, as in an encode;
its data is a few kB), so that the peak memory of an encode of IN minus this run's is the data the
encoder holds beside its piece of the volume.

    [mpirun -np N] pvbatch read_piece.py IN [--plugin AdaptiveFAM.so]
"""
import os
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "Apps", "pvbatch"))
import afam_encode  # noqa: E402


def main():
    args = sys.argv[1:]
    plugin = args[args.index("--plugin") + 1] if "--plugin" in args else None
    path = args[0]
    from paraview.simple import LoadPlugin
    LoadPlugin(afam_encode.find_plugin(plugin), remote=False, ns=globals())
    reader = afam_encode.open_volume(path)
    reader.UpdatePipeline()
    print("read %s: %d points on all ranks" % (path, reader.GetDataInformation().GetNumberOfPoints()))
    from paraview.simple import SaveData, Wavelet
    encoder = AdaptiveFAMEncoder(Input=Wavelet(WholeExtent=[0, 15, 0, 15, 0, 15]), Levels=2,  # noqa: F821
                                 BlocksPerAxis=2, NumberOfThreads=1)
    encoder.Scalars = ["POINTS", "RTData"]
    tiny = os.path.join(tempfile.mkdtemp(), "tiny.afam")
    SaveData(tiny, proxy=encoder)
    print("encoded a 16^3 Wavelet: %d bytes" % os.path.getsize(tiny))
    shutil.rmtree(os.path.dirname(tiny))


if __name__ == "__main__":
    main()

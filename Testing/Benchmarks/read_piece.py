# SPDX-License-Identifier: BSD-3-Clause
"""The reference run of encode_mpi.sh: what `afam_encode.py` does before it encodes (ParaView, the
plugin, the reader), and nothing after, so that the peak memory of an encode minus this run's is
what the encoder itself holds beside its piece of the volume.

    [mpirun -np N] pvbatch read_piece.py IN [--plugin AdaptiveFAM.so]
"""
import os
import sys

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


if __name__ == "__main__":
    main()

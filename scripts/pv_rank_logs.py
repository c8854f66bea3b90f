# SPDX-License-Identifier: BSD-3-Clause
"""Where each rank's frame goes in a parallel ParaView render, from the logs pvbatch writes with
PARAVIEW_LOG_RENDERING_VERBOSITY=INFO and --log=PREFIX,INFO (one file a rank: PREFIX.0, PREFIX.1, ...; PREFIX alone for one process without MPI):
per rank, the median over frames 2..N of the view's StillRender, IceT's draw callback (ICET_RENDER_TIME:
the rank's own render and the read-back of its image) and IceT's compositing (ICET_COMPOSITE_TIME, of
which blending, compressing and collecting), in milliseconds, as one Markdown table.

    python3 pv_rank_logs.py PREFIX [LABEL]
"""
import glob
import os
import re
import statistics
import sys

FIELDS = [("still", "StillRender"), ("icet_render", "ICET_RENDER_TIME"), ("composite", "ICET_COMPOSITE_TIME"),
          ("blend", "ICET_BLEND_TIME"), ("compress", "ICET_COMPRESS_TIME"), ("collect", "ICET_COLLECT_TIME")]
STILL = re.compile(r"\} ([0-9.]+) s: \S+: StillRender")
ICET = re.compile(r"(ICET_[A-Z_]+): ([0-9.eE+-]+)")


def rank_medians(path):
    values = {key: [] for key, _ in FIELDS}
    names = {name: key for key, name in FIELDS}
    with open(path, errors="replace") as f:
        for line in f:
            m = STILL.search(line)
            if m:
                values["still"].append(float(m.group(1)))
                continue
            m = ICET.search(line)
            if m and m.group(1) in names:
                values[names[m.group(1)]].append(float(m.group(2)))
    frames = len(values["still"])
    return frames, {k: (1e3 * statistics.median(v[1:] or v) if v else float("nan")) for k, v in values.items()}


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    prefix, label = sys.argv[1], (sys.argv[2] if len(sys.argv) > 2 else "")
    files = sorted(glob.glob(prefix + ".*"), key=lambda p: int(p.rsplit(".", 1)[1]) if p.rsplit(".", 1)[1].isdigit() else -1)
    files = [p for p in files if p.rsplit(".", 1)[1].isdigit()]
    if not files and os.path.isfile(prefix):  # one process without MPI: no rank suffix
        files = [prefix + ".0"] if os.path.isfile(prefix + ".0") else [prefix]
    if not files:
        sys.exit("pv_rank_logs: no %s.N files" % prefix)
    print("| %srank | frames | StillRender ms | IceT render (draw + read-back) ms | IceT composite ms | blend | compress | collect |"
          % ("run | " if label else ""))
    print("|%s---|---|---|---|---|---|---|---|" % ("---|" if label else ""))
    for p in files:
        frames, m = rank_medians(p)
        tail = p.rsplit(".", 1)[-1]
        rank = tail if p != prefix and tail.isdigit() else "0"
        print("| %s%s | %d | %s |" % (label + " | " if label else "", rank, frames,
                                     " | ".join("%.1f" % m[k] for k, _ in FIELDS)))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""What a run would cost if it were coded in time differently: two emulations through the `afam`
command line (no change to the encoder), on a folder of raw steps (name_XxYxZ_float32.raw, sorted
order = time order), at an absolute RMSE bound B (the `bound=` that `afam encode ... --relative`
prints for the run). Every step's decoded samples are checked against B. Prints the payload bytes
(`afam info` payload_bytes, no file overhead) of each scheme and fraction ALPHA:

  headroom   a step is coded alone at ALPHA*B (one-step `afam encode`); the steps after it are
             references (no payload) while the samples decoded for it stay within B of theirs.
  residual   step 0 coded alone at ALPHA*B; each later step is a reference when the samples
             decoded for the step before are within B of it, else its residual
             r = x_t - dec(t-1) is coded by `afam encode` as a volume of its own (its own kind and
             NCP) at ALPHA*B, and dec(t) = dec(t-1) + decode(r): a closed loop, errors do not add.

Plain Python 3 (no numpy); slow (seconds a step at 64^3).

usage: time_coding_what_if.py AFAM_EXE {headroom|residual} DIR BOUND ALPHA[,ALPHA...] [MAX_STEPS]
"""
import array
import glob
import os
import subprocess
import sys
import tempfile


def load(path):
    a = array.array("f")
    with open(path, "rb") as f:
        a.frombytes(f.read())
    if sys.byteorder != "little":
        a.byteswap()
    return a


def rmse(a, b):
    return (sum((x - y) ** 2 for x, y in zip(a, b)) / len(a)) ** 0.5


class Coder:
    def __init__(self, afam, dims, tmp):
        self.afam, self.dims, self.tmp = afam, dims, tmp

    def code(self, values, bound):
        """Payload bytes and decoded samples of `values` coded alone at `bound`."""
        src = os.path.join(self.tmp, f"in_{self.dims}_float32.raw")
        out = os.path.join(self.tmp, "c.afam")
        dec = os.path.join(self.tmp, f"dec_{self.dims}_float32.raw")
        with open(src, "wb") as f:
            values.tofile(f)
        subprocess.run([self.afam, "encode", src, out, "--error-bound", repr(bound), "--quiet"],
                       check=True)
        info = subprocess.run([self.afam, "info", out], capture_output=True, text=True,
                              check=True).stdout
        payload = int(info.split("payload_bytes=")[1].split()[0])
        subprocess.run([self.afam, "decode", out, dec], check=True, capture_output=True)
        return payload, load(dec)


def main():
    if len(sys.argv) < 6:
        raise SystemExit(__doc__)
    afam, scheme, folder, bound = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
    alphas = [float(a) for a in sys.argv[5].split(",")]
    steps = sorted(glob.glob(os.path.join(folder, "*.raw")))
    if len(sys.argv) > 6:
        steps = steps[: int(sys.argv[6])]
    if not steps:
        raise SystemExit(f"no .raw files in {folder}")
    dims = os.path.basename(steps[0]).rsplit("_", 2)[1]
    xs = [load(p) for p in steps]
    with tempfile.TemporaryDirectory() as tmp:
        coder = Coder(afam, dims, tmp)
        for alpha in alphas:
            total, refs, worst, per_step = 0, 0, 0.0, []
            dec = None
            for x in xs:
                if dec is not None and rmse(dec, x) <= bound:
                    refs += 1
                    per_step.append(0)
                elif dec is None or scheme == "headroom":
                    payload, dec = coder.code(x, alpha * bound)
                    total += payload
                    per_step.append(payload)
                elif scheme == "residual":
                    r = array.array("f", (p - q for p, q in zip(x, dec)))
                    payload, rd = coder.code(r, alpha * bound)
                    dec = array.array("f", (p + q for p, q in zip(dec, rd)))
                    total += payload
                    per_step.append(payload)
                else:
                    raise SystemExit(f"unknown scheme {scheme}")
                worst = max(worst, rmse(dec, x) / bound)
            print(f"{scheme} alpha={alpha}: steps={len(xs)} references={refs} payload={total} B "
                  f"worst_rmse/bound={worst:.4f} per_step={','.join(map(str, per_step))}",
                  flush=True)
            if worst > 1:
                raise SystemExit("a step breaks the bound")


if __name__ == "__main__":
    main()

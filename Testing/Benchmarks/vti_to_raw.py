#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Convert VTK XML image data (.vti) time steps to flat little-endian float32 raw files.

One point-data array of each input is written, x fastest, then y, then z, as
OUT/PREFIX_KKKK_XxYxZ_float32.raw (KKKK: the input's position in the order given, from 0), the
naming `afam encode` and Testing/Benchmarks/run_size.sh read (a folder of such files is a series).
Plain Python 3 (no VTK, no numpy): appended raw or base64 data, inline base64 or ascii data,
zlib-compressed or not, UInt32 or UInt64 headers, any numeric type (converted to float32).

usage: vti_to_raw.py --array NAME --out DIR --prefix PREFIX STEP.vti [STEP.vti ...]
       vti_to_raw.py --list STEP.vti        (names, types and ranges of the point-data arrays)
"""
import argparse
import array
import base64
import math
import os
import sys
import xml.etree.ElementTree as ET
import zlib

TYPES = {"Int8": "b", "UInt8": "B", "Int16": "h", "UInt16": "H", "Int32": "i", "UInt32": "I",
         "Int64": "q", "UInt64": "Q", "Float32": "f", "Float64": "d"}


def unpack(code, raw):
    a = array.array(code)
    a.frombytes(raw)
    if sys.byteorder != "little":
        a.byteswap()
    return a


class Vti:
    def __init__(self, path):
        data = open(path, "rb").read()
        # The XML part ends where the appended data starts (raw bytes are not XML).
        cut = data.find(b"<AppendedData")
        self.appended = b""
        if cut >= 0:
            head = data.find(b">", cut) + 1
            enc = data[cut:head]
            under = data.find(b"_", head) + 1
            end = data.rfind(b"</AppendedData>")
            self.appended = data[under:end]
            self.appended_base64 = b'encoding="base64"' in enc
            xml = data[:cut] + b"</VTKFile>"
        else:
            xml = data
        root = ET.fromstring(xml)
        if root.get("type") != "ImageData":
            raise SystemExit(f"{path}: not ImageData ({root.get('type')})")
        if root.get("byte_order", "LittleEndian") != "LittleEndian":
            raise SystemExit(f"{path}: big-endian files are not handled")
        self.header = "Q" if root.get("header_type", "UInt32") == "UInt64" else "I"
        self.compressed = root.get("compressor") is not None
        if self.compressed and root.get("compressor") != "vtkZLibDataCompressor":
            raise SystemExit(f"{path}: compressor {root.get('compressor')} is not handled")
        image = root.find("ImageData")
        ext = [int(v) for v in image.get("WholeExtent").split()]
        self.dims = (ext[1] - ext[0] + 1, ext[3] - ext[2] + 1, ext[5] - ext[4] + 1)
        pieces = image.findall("Piece")
        if len(pieces) != 1:
            raise SystemExit(f"{path}: {len(pieces)} pieces; one is handled")
        self.arrays = {a.get("Name"): a for a in pieces[0].find("PointData").findall("DataArray")}
        self.path = path

    def _decode(self, blob, is_base64):
        hs = array.array(self.header).itemsize
        if not self.compressed:
            if is_base64:
                head = base64.b64decode(blob[: 4 * math.ceil(hs / 3)])
                n = unpack(self.header, head[:hs])[0]
                return base64.b64decode(blob)[hs: hs + n]
            n = unpack(self.header, blob[:hs])[0]
            return blob[hs: hs + n]
        if is_base64:
            first = base64.b64decode(blob[: 4 * math.ceil(3 * hs / 3)])
            nblocks = unpack(self.header, first[:hs])[0]
            hlen = (3 + nblocks) * hs
            hb64 = 4 * math.ceil(hlen / 3)
            head = unpack(self.header, base64.b64decode(blob[:hb64])[:hlen])
            body = base64.b64decode(blob[hb64:])
        else:
            nblocks = unpack(self.header, blob[:hs])[0]
            hlen = (3 + nblocks) * hs
            head = unpack(self.header, blob[:hlen])
            body = blob[hlen:]
        out, at = [], 0
        for size in head[3: 3 + nblocks]:
            out.append(zlib.decompress(body[at: at + size]))
            at += size
        return b"".join(out)

    def values(self, name):
        a = self.arrays.get(name)
        if a is None:
            raise SystemExit(f"{self.path}: no point-data array {name} (has {', '.join(self.arrays)})")
        if int(a.get("NumberOfComponents", "1")) != 1:
            raise SystemExit(f"{self.path}: {name} has several components; one is handled")
        code = TYPES[a.get("type")]
        fmt = a.get("format")
        if fmt == "ascii":
            conv = float if code in "fd" else int
            return array.array(code, [conv(v) for v in a.text.split()])
        if fmt == "appended":
            off = int(a.get("offset"))
            raw = self._decode(self.appended[off:], self.appended_base64)
        else:  # binary: base64 inline
            raw = self._decode(a.text.strip().encode(), True)
        vals = unpack(code, raw)
        n = self.dims[0] * self.dims[1] * self.dims[2]
        if len(vals) != n:
            raise SystemExit(f"{self.path}: {name} has {len(vals)} values, the extent {n}")
        return vals


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("inputs", nargs="+")
    p.add_argument("--array")
    p.add_argument("--out")
    p.add_argument("--prefix", default="step")
    p.add_argument("--list", action="store_true")
    args = p.parse_args()
    if args.list:
        for path in args.inputs:
            v = Vti(path)
            for name, a in v.arrays.items():
                vals = v.values(name)
                print(f"{path}: {name} {a.get('type')} dims={v.dims} "
                      f"range={min(vals):.6g}..{max(vals):.6g}")
        return
    if not args.array or not args.out:
        p.error("--array and --out are needed (or --list)")
    os.makedirs(args.out, exist_ok=True)
    dims = None
    for k, path in enumerate(args.inputs):
        v = Vti(path)
        if dims is not None and v.dims != dims:
            raise SystemExit(f"{path}: dims {v.dims} differ from the first step's {dims}")
        dims = v.dims
        vals = v.values(args.array)
        bad = sum(1 for x in vals if not math.isfinite(x)) if vals.typecode in "fd" else 0
        if bad:
            raise SystemExit(f"{path}: {bad} values of {args.array} are not finite")
        out = array.array("f", vals) if vals.typecode != "f" else vals
        if sys.byteorder != "little":
            out.byteswap()
        name = f"{args.prefix}_{k:04d}_{dims[0]}x{dims[1]}x{dims[2]}_float32.raw"
        with open(os.path.join(args.out, name), "wb") as f:
            out.tofile(f)
        print(f"{path} -> {name} range={min(vals):.6g}..{max(vals):.6g}")


if __name__ == "__main__":
    main()

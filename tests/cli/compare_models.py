#!/usr/bin/env python3
"""Compares two safetensors files tensor by tensor (same names, dtypes and shapes) and reports the largest
difference, relative to max(1, the tensor's largest magnitude); exits 1 when it exceeds --tolerance. Also compares
two loss logs (CSV written by `occtrack train --loss-log`) step by step. Standard library only.

  compare_models.py --tolerance 1e-4 a.safetensors b.safetensors
  compare_models.py --tolerance 1e-4 --csv a.csv b.csv
"""
import argparse
import array
import csv
import json
import struct
import sys

FORMATS = {"F32": "f", "F64": "d", "I32": "i", "I64": "q"}


def read_safetensors(path):
    with open(path, "rb") as f:
        data = f.read()
    (size,) = struct.unpack("<Q", data[:8])
    header = json.loads(data[8:8 + size])
    body = data[8 + size:]
    tensors = {}
    for name, info in header.items():
        if name == "__metadata__":
            continue
        begin, end = info["data_offsets"]
        values = array.array(FORMATS[info["dtype"]])
        values.frombytes(body[begin:end])
        if sys.byteorder != "little":
            values.byteswap()
        tensors[name] = (info["dtype"], tuple(info["shape"]), values)
    return tensors


def read_log(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {int(r["step"]): {k: float(v) for k, v in r.items() if k != "step" and v != ""} for r in rows}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--tolerance", type=float, required=True)
    parser.add_argument("--csv", action="store_true", help="compare loss logs instead of models")
    parser.add_argument("a")
    parser.add_argument("b")
    args = parser.parse_args()
    worst, where = 0.0, "nothing"
    if args.csv:
        a, b = read_log(args.a), read_log(args.b)
        if sorted(a) != sorted(b) or not a:
            print(f"different steps: {len(a)} against {len(b)}")
            return 1
        for step in sorted(a):
            if sorted(a[step]) != sorted(b[step]):
                print(f"step {step}: columns {sorted(a[step])} against {sorted(b[step])}")
                return 1
            for term, value in a[step].items():
                d = abs(value - b[step][term]) / max(abs(value), 1e-3)
                if d > worst:
                    worst, where = d, f"step {step} {term} ({value:.9g} against {b[step][term]:.9g})"
        print(f"{len(a)} steps; largest relative difference {worst:.3g} at {where}")
    else:
        a, b = read_safetensors(args.a), read_safetensors(args.b)
        if sorted(a) != sorted(b) or not a:
            print(f"different tensors: {sorted(set(a) ^ set(b))}")
            return 1
        for name in sorted(a):
            (ta, sa, va), (tb, sb, vb) = a[name], b[name]
            if ta != tb or sa != sb:
                print(f"{name}: {ta}{list(sa)} against {tb}{list(sb)}")
                return 1
            scale = max([abs(x) for x in va] + [1.0])
            d = max([abs(x - y) for x, y in zip(va, vb)] + [0.0]) / scale
            if d > worst:
                worst, where = d, name
        print(f"{len(a)} tensors; largest difference {worst:.3g} (relative to max(1, largest magnitude)) in {where}")
    if not worst <= args.tolerance:
        print(f"exceeds the tolerance {args.tolerance:g}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

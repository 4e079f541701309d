#!/usr/bin/env python3
"""Plots training and validation losses from `occtrack train` logs as one SVG (standard library only).

Usage: scripts/plot_training.py --out FILE.svg [--term loss|mse] LOG[=LABEL] [LOG[=LABEL] ...]

Each log is what `occtrack train` prints (its progress lines, "step N/M  loss X (mse ...) ... | validation loss
Y (mse ...)"). Training losses are the means since the previous progress line; validation losses are drawn
as dots joined by a dashed line. The y axis is logarithmic.
"""
import argparse
import math
import re
import sys

import svg_figure

STEP = re.compile(r"step (\d+)/\d+\s+loss ([-\d.e+]+) \(mse ([-\d.e+]+)")
VALIDATION = re.compile(r"\| validation loss ([-\d.e+]+) \(mse ([-\d.e+]+)")
COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b"]


def read_log(path, term):
    column = 0 if term == "loss" else 1
    train, validation = [], []
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f.read().replace("\r", "\n").splitlines():
            m = STEP.search(line)
            if not m:
                continue
            step = int(m.group(1))
            train.append((step, float(m.group(2 + column))))
            v = VALIDATION.search(line)
            if v:
                validation.append((step, float(v.group(1 + column))))
    if not train:
        sys.exit(f"plot_training.py: no progress lines in {path}")
    return train, validation


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--term", choices=["loss", "mse"], default="loss")
    parser.add_argument("--title", default="")
    parser.add_argument("logs", nargs="+")
    args = parser.parse_args()
    series = []
    for item in args.logs:
        path, _, label = item.partition("=")
        series.append((label or path, *read_log(path, args.term)))

    points = [p for _, t, v in series for p in t + v if p[1] > 0]
    x_max = max(p[0] for p in points)
    y_min, y_max = min(p[1] for p in points), max(p[1] for p in points)
    lo, hi = math.floor(math.log10(y_min)), math.ceil(math.log10(y_max))
    if hi == lo:
        hi += 1
    width, height, left, right, top, bottom = 720, 420, 70, 190, 40, 50
    pw, ph = width - left - right, height - top - bottom

    def sx(x):
        return left + pw * x / x_max

    def sy(y):
        return top + ph * (1 - (math.log10(max(y, 10.0**lo)) - lo) / (hi - lo))

    title = args.title or f"training ({args.term}, solid) and validation (dashed) loss"
    out = svg_figure.begin(width, height, title, left, top - 15)
    for e in range(lo, hi + 1):
        y = sy(10.0**e)
        out.append(f'<line x1="{left}" x2="{left + pw}" y1="{y:.1f}" y2="{y:.1f}" stroke="#ddd"/>')
        out.append(f'<text x="{left - 8}" y="{y + 4:.1f}" text-anchor="end">1e{e}</text>')
    for i in range(6):
        x = x_max * i / 5
        out.append(f'<text x="{sx(x):.1f}" y="{top + ph + 18}" text-anchor="middle">{x:.0f}</text>')
    out.append(f'<text x="{left + pw / 2}" y="{height - 10}" text-anchor="middle">step</text>')
    out.append(f'<rect x="{left}" y="{top}" width="{pw}" height="{ph}" fill="none" stroke="#333"/>')
    for k, (label, train, validation) in enumerate(series):
        colour = COLOURS[k % len(COLOURS)]
        path = " ".join(f"{sx(x):.1f},{sy(y):.1f}" for x, y in train if y > 0)
        out.append(f'<polyline points="{path}" fill="none" stroke="{colour}" stroke-width="1.5"/>')
        if validation:
            path = " ".join(f"{sx(x):.1f},{sy(y):.1f}" for x, y in validation if y > 0)
            out.append(f'<polyline points="{path}" fill="none" stroke="{colour}" stroke-dasharray="5,3"/>')
            for x, y in validation:
                out.append(f'<circle cx="{sx(x):.1f}" cy="{sy(y):.1f}" r="3" fill="{colour}"/>')
        ly = top + 20 + 36 * k
        out.append(f'<line x1="{left + pw + 15}" x2="{left + pw + 40}" y1="{ly}" y2="{ly}" stroke="{colour}" '
                   f'stroke-width="2"/>')
        out.append(f'<text x="{left + pw + 45}" y="{ly + 4}">{label}</text>')
        if validation:
            out.append(f'<text x="{left + pw + 45}" y="{ly + 18}" fill="#555">validation {validation[-1][1]:.4g}</text>')
    svg_figure.save(args.out, out)


if __name__ == "__main__":
    main()

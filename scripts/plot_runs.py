#!/usr/bin/env python3
"""Plots suite runs of several planner configurations side by side as one SVG (standard library only).

Usage: scripts/plot_runs.py --out FILE.svg [--title T] LABEL=FILE.json[,FILE.json...] [LABEL=... ...]

Each FILE.json is what `occtrack bench suite --json` writes; one written with --sensor-seeds counts as one
run per noise draw it holds. For every suite that the files hold (in the order first met), the plot has a
group; in it, each label has a column with one dot per run (the time the target was hidden, summed over the
run's episodes) and a bar at the mean. Runs that differ only in the planner's seed show how much one run
says; a label whose dots sit apart from another's differs beyond luck. A run with a collision is drawn as a
cross. Globs are expanded, so LABEL='out/cvae-s*-*.json' takes every seed.
"""
import argparse
import glob
import json
import sys

import svg_figure

COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b"]


def read_runs(spec):
    label, sep, files = spec.partition("=")
    if not sep or not label or not files:
        sys.exit(f"plot_runs.py: expected LABEL=FILE.json[,FILE.json...], got {spec!r}")
    paths = []
    for pattern in files.split(","):
        found = sorted(glob.glob(pattern))
        if not found:
            sys.exit(f"plot_runs.py: {label}: no file matches {pattern}")
        paths += found
    runs = []
    for path in paths:
        try:
            with open(path, encoding="utf-8") as f:
                d = json.load(f)
            for run in d["draws"] if "draws" in d else [d]:
                episodes = run["episodes"]
                hidden = sum(float(e["occlusion_time_s"]) for e in episodes)
                collisions = sum(int(e["collisions"]) for e in episodes)
                runs.append((run["suite"], hidden, collisions))
        except (OSError, ValueError, KeyError, TypeError) as e:
            sys.exit(f"plot_runs.py: {path}: not a `bench suite --json` file ({e})")
    return label, runs


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--title", default="time hidden per suite run (dots: runs, bars: means)")
    parser.add_argument("series", nargs="+", help="LABEL=FILE.json[,FILE.json...] (globs allowed)")
    args = parser.parse_args()
    series = [read_runs(s) for s in args.series]
    suites = []
    for _, runs in series:
        for suite, _, _ in runs:
            if suite not in suites:
                suites.append(suite)
    y_max = max([h for _, runs in series for _, h, _ in runs] + [1.0]) * 1.08

    column, gap = 30, 44
    group = column * len(series)
    left, right, top, bottom = 60, 20, 40, 70
    legend = 18 * len(series) + 10
    width = left + right + len(suites) * group + (len(suites) - 1) * gap
    width = max(width, 420)
    height = 360 + legend
    ph = height - top - bottom - legend

    def sy(y):
        return top + ph * (1 - y / y_max)

    out = svg_figure.begin(width, height, args.title, left, top - 15)
    step = 10 ** max(0, len(str(int(y_max))) - 1)
    if y_max / step < 3:
        step /= 2
    tick = 0.0
    while tick <= y_max:
        y = sy(tick)
        out.append(f'<line x1="{left}" x2="{width - right}" y1="{y:.1f}" y2="{y:.1f}" stroke="#e4e4e4"/>')
        out.append(f'<text x="{left - 6}" y="{y + 4:.1f}" text-anchor="end">{tick:g}</text>')
        tick += step
    out.append(f'<text x="14" y="{top + ph / 2:.1f}" transform="rotate(-90 14 {top + ph / 2:.1f})" '
               f'text-anchor="middle">hidden (s)</text>')
    for g, suite in enumerate(suites):
        x0 = left + g * (group + gap)
        out.append(f'<text x="{x0 + group / 2:.1f}" y="{top + ph + 18}" text-anchor="middle">{suite}</text>')
        for k, (label, runs) in enumerate(series):
            colour = COLOURS[k % len(COLOURS)]
            values = [(h, c) for s, h, c in runs if s == suite]
            if not values:
                continue
            cx = x0 + column * k + column / 2
            for i, (h, c) in enumerate(values):
                x = cx + (i - (len(values) - 1) / 2) * 3.0
                if c > 0:
                    out.append(f'<path d="M{x - 4:.1f},{sy(h) - 4:.1f}l8,8m0,-8l-8,8" stroke="{colour}" '
                               f'stroke-width="2"/>')
                else:
                    out.append(f'<circle cx="{x:.1f}" cy="{sy(h):.1f}" r="3.2" fill="{colour}" '
                               f'fill-opacity="0.75"/>')
            mean = sum(h for h, _ in values) / len(values)
            out.append(f'<line x1="{cx - 10:.1f}" x2="{cx + 10:.1f}" y1="{sy(mean):.1f}" y2="{sy(mean):.1f}" '
                       f'stroke="{colour}" stroke-width="2.5"/>')
    out.append(f'<rect x="{left}" y="{top}" width="{width - left - right}" height="{ph}" fill="none" stroke="#333"/>')
    for k, (label, runs) in enumerate(series):
        colour = COLOURS[k % len(COLOURS)]
        ly = top + ph + 40 + 18 * k
        out.append(f'<circle cx="{left + 6}" cy="{ly - 4}" r="4" fill="{colour}"/>')
        out.append(f'<text x="{left + 16}" y="{ly}">{label} ({len(runs)} runs)</text>')
    svg_figure.save(args.out, out)


if __name__ == "__main__":
    main()

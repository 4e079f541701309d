#!/usr/bin/env python3
"""A close-up of a few seconds of an episode, drawn from its HTML replay (`occtrack run --html F`): the robot's
path coloured by the safety layer's choice at each cycle, the moving obstacles' paths, and robot and obstacles
outlined at the times asked for. For documentation figures of single events (a contact, a near miss).

    scripts/plot_replay_window.py REPLAY.html --from 43.5 --to 46.2 --marks 45.1,45.35,45.6 --out FIG.svg

Reads the replay's embedded data (src/io/html_replay.cpp writes it: centimetres and milliseconds). Standard
library only."""
import argparse
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import svg_figure  # noqa: E402

LAYER_COLOURS = {"plan": "#2a7ab9", "alternative": "#7bb8e0", "stop": "#999999", "evasive": "#e08a1e",
                 "best_effort": "#d62728", "brake": "#000000"}


def replay_data(path):
    text = open(path, encoding="utf-8").read()
    start = text.find('id="replay-data"')
    if start < 0:
        sys.exit(f"{path}: no replay data (is it an `occtrack run --html` page?)")
    start = text.index(">", start) + 1
    return json.loads(text[start:text.index("</script>", start)])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("replay")
    parser.add_argument("--from", dest="t0", type=float, required=True, help="seconds")
    parser.add_argument("--to", dest="t1", type=float, required=True, help="seconds")
    parser.add_argument("--marks", default="", help="comma-separated times (s) at which to outline robot and obstacles")
    parser.add_argument("--title", default="")
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    if not args.t1 > args.t0:
        sys.exit("--to must be after --from")
    marks = [float(m) for m in args.marks.split(",") if m.strip()]

    d = replay_data(args.replay)
    frames = d["frames"]
    times = [t / 1000.0 for t in frames["t"]]
    shown = [i for i, t in enumerate(times) if args.t0 <= t <= args.t1]
    if not shown:
        sys.exit(f"no frame between {args.t0} and {args.t1} s (the episode lasts {times[-1]} s)")
    moving = d["moving"]
    count = len(moving)

    def robot(i):
        return frames["robot"][2 * i] / 100.0, frames["robot"][2 * i + 1] / 100.0

    def obstacle(i, j):
        k = 2 * (i * count + j)
        return d["moving_xy"][k] / 100.0, d["moving_xy"][k + 1] / 100.0

    # The window: the robot's path and the moving obstacles that come within 3 m of it, plus a margin.
    points = [robot(i) for i in shown]
    near = [j for j in range(count)
            if min(math.dist(obstacle(i, j), robot(i)) for i in shown) < 3.0]
    for j in near:
        points += [obstacle(i, j) for i in shown]
    x_min = min(p[0] for p in points) - 1.0
    x_max = max(p[0] for p in points) + 1.0
    y_min = min(p[1] for p in points) - 1.0
    y_max = max(p[1] for p in points) + 1.0
    scale = 560.0 / max(x_max - x_min, y_max - y_min)  # pixels per metre
    left, top = 20, 40
    plot_width = (x_max - x_min) * scale
    width = max(int(left + plot_width) + 250, 8 * len(args.title) + 2 * left)
    height = int(top + (y_max - y_min) * scale) + 40

    def px(x, y):
        return left + (x - x_min) * scale, top + (y_max - y) * scale

    lines = svg_figure.begin(width, height, args.title, left, 24)
    lines.append(f'<clipPath id="window"><rect x="{left}" y="{top}" width="{plot_width:.1f}" '
                 f'height="{(y_max - y_min) * scale:.1f}"/></clipPath><g clip-path="url(#window)">')
    # Static obstacles in the window.
    for index, o in enumerate(d["obstacles"]):
        if index in moving:
            continue
        if o["kind"] == "circle":
            cx, cy = px(o["x"] / 100.0, o["y"] / 100.0)
            lines.append(f'<circle cx="{cx:.1f}" cy="{cy:.1f}" r="{o["r"] / 100.0 * scale:.1f}" fill="#dddddd"/>')
        elif o["kind"] == "box":
            c, s = math.cos(o["yaw"]), math.sin(o["yaw"])
            hw, hh = o["w"] / 200.0, o["h"] / 200.0
            corners = [px(o["x"] / 100.0 + c * u - s * v, o["y"] / 100.0 + s * u + c * v)
                       for u, v in ((-hw, -hh), (hw, -hh), (hw, hh), (-hw, hh))]
            lines.append('<polygon points="' + " ".join(f"{a:.1f},{b:.1f}" for a, b in corners) +
                         '" fill="#dddddd"/>')
    # Moving obstacles: their paths, and outlines at the marks.
    for j in near:
        path = " ".join("%.1f,%.1f" % px(*obstacle(i, j)) for i in shown)
        lines.append(f'<polyline points="{path}" fill="none" stroke="#555555" stroke-dasharray="4 3"/>')
        radius = d["obstacles"][moving[j]]["r"] / 100.0
        for t in marks:
            i = min(shown, key=lambda k: abs(times[k] - t))
            cx, cy = px(*obstacle(i, j))
            lines.append(f'<circle cx="{cx:.1f}" cy="{cy:.1f}" r="{radius * scale:.1f}" fill="none" '
                         f'stroke="#555555"/>')
            lines.append(f'<text x="{cx + radius * scale + 3:.1f}" y="{cy:.1f}" fill="#555555">{t:g} s</text>')
    # The robot's path, coloured by the layer's choice of the cycle in force.
    cycles = d["cycles"]
    cycle_times = [c["t"] / 1000.0 for c in cycles]
    choice_at = []
    k = 0
    for i in shown:
        while k + 1 < len(cycles) and cycle_times[k + 1] <= times[i]:
            k += 1
        choice_at.append(cycles[k].get("safety", "plan") if cycle_times[k] <= times[i] else "plan")
    for n in range(1, len(shown)):
        (x0, y0), (x1, y1) = px(*robot(shown[n - 1])), px(*robot(shown[n]))
        colour = LAYER_COLOURS.get(choice_at[n - 1], "#2a7ab9")
        lines.append(f'<line x1="{x0:.1f}" y1="{y0:.1f}" x2="{x1:.1f}" y2="{y1:.1f}" stroke="{colour}" '
                     f'stroke-width="3"/>')
    robot_radius = d["robot_radius"] / 100.0
    outlines = [px(*robot(min(shown, key=lambda k: abs(times[k] - t)))) for t in marks]
    for cx, cy in outlines:
        lines.append(f'<circle cx="{cx:.1f}" cy="{cy:.1f}" r="{robot_radius * scale:.1f}" fill="none" '
                     f'stroke="#2a7ab9"/>')
    if outlines:  # the robot's marks in one column below its outlines, which often nearly coincide
        label_x = min(cx for cx, _ in outlines) - robot_radius * scale
        label_y = max(cy for _, cy in outlines) + robot_radius * scale
        for n, t in enumerate(marks):
            lines.append(f'<text x="{label_x:.1f}" y="{label_y + 14 * (n + 1):.1f}" text-anchor="end" '
                         f'fill="#2a7ab9">robot {t:g} s</text>')
    lines.append("</g>")
    # Legend and a 1 m scale bar.
    lx = left + plot_width + 20
    lines.append(f'<text x="{lx}" y="{top + 10}">robot path, by the layer\'s choice:</text>')
    for n, (name, colour) in enumerate(LAYER_COLOURS.items()):
        y = top + 30 + 18 * n
        lines.append(f'<line x1="{lx}" y1="{y - 4}" x2="{lx + 24}" y2="{y - 4}" stroke="{colour}" stroke-width="3"/>')
        lines.append(f'<text x="{lx + 30}" y="{y}">{name.replace("_", " ")}</text>')
    y = top + 30 + 18 * len(LAYER_COLOURS) + 10
    lines.append(f'<line x1="{lx}" y1="{y - 4}" x2="{lx + 24}" y2="{y - 4}" stroke="#555555" stroke-dasharray="4 3"/>')
    lines.append(f'<text x="{lx + 30}" y="{y}">moving obstacle</text>')
    y += 30
    lines.append(f'<line x1="{lx}" y1="{y}" x2="{lx + scale:.1f}" y2="{y}" stroke="black" stroke-width="2"/>')
    lines.append(f'<text x="{lx}" y="{y + 16}">1 m</text>')
    lines.append(f'<text x="{lx}" y="{y + 40}">{args.t0:g} to {args.t1:g} s</text>')
    svg_figure.save(args.out, lines)


if __name__ == "__main__":
    main()

"""Checks `bench paper --sensor-seeds` (tests/CMakeLists.txt, cli.bench_paper_draws): every row ran once per
seed, in the order given; the row at one seed is the same run as `bench suite --sensor-seed` with the v2
tables' settings (computation times and measured latency aside; the paper run may hold fewer episodes); and the
spread under each suite's table is what the draws' own totals give.

Usage: check_paper_draws.py FOLDER ONE.json SEED_OF_ONE SEEDS (SEEDS comma-separated, as given)"""
import json
import math
import sys


def check(condition, message):
    if not condition:
        sys.exit("check_paper_draws: " + message)


def without_times(episodes):
    """The episodes without what is measured: computation times and the latency auto measured (both runs apply
    the command at the same physics step, so the episodes are the same)."""
    return [{k: v for k, v in e.items() if k not in ("compute_ms", "latency_ms")} for e in episodes]


folder = sys.argv[1]
one = json.load(open(sys.argv[2]))
one_seed = int(sys.argv[3])
seeds = [int(s) for s in sys.argv[4].split(",")]
d = json.load(open(folder + "/episodes.json"))
tables = open(folder + "/tables.md").read()

groups = {}
for run in d["runs"]:
    groups.setdefault((run["label"], run["compute_scale"], run["result"]["suite"]), []).append(run)
check(groups, "no runs")
for (label, scale, suite), runs in groups.items():
    check([r["sensor_seed"] for r in runs] == seeds, f"{label} x{scale} {suite}: seeds {[r['sensor_seed'] for r in runs]}")
    check(len({r["latency_ms"] for r in runs}) == 1, f"{label}: one latency for all draws (measured once)")
    totals = [sum(ep["occlusion_time_s"] for ep in r["result"]["episodes"]) for r in runs]
    mean = sum(totals) / len(totals)
    sd = math.sqrt(sum((t - mean) ** 2 for t in totals) / (len(totals) - 1)) if len(totals) > 1 else 0.0
    least, largest = min(totals), max(totals)
    collisions = sum(ep["collisions"] for r in runs for ep in r["result"]["episodes"])
    with_collision = sum(any(ep["collisions"] > 0 for ep in r["result"]["episodes"]) for r in runs)
    line = (f"| {label} | {scale:g} | {len(runs)} | {mean:.1f} / {sd:.1f} | {least:.1f} ({seeds[totals.index(least)]}) "
            f"| {largest:.1f} ({seeds[totals.index(largest)]}) |")
    check(line in tables, f"tables.md lacks the spread line '{line}'")
    check(f"| {collisions} ({with_collision}) |" in tables, f"collisions over the draws: {collisions} ({with_collision})")
    for r in runs:
        check(f"| {label} | {scale:g} | {r['sensor_seed']} |" in tables, f"the draw's row at seed {r['sensor_seed']}")
    same = runs[seeds.index(one_seed)]["result"]["episodes"]
    check(without_times(same) == without_times(one["episodes"][: len(same)]),
          f"{label}: the draw at seed {one_seed} is bench suite's run at --sensor-seed {one_seed}")
    print(f"check_paper_draws: {label} x{scale:g} {suite}: time hidden {totals}")

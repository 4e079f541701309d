"""Checks `bench suite --sensor-seeds` (tests/CMakeLists.txt, cli.bench_suite_draws): the file holds one suite
run per seed, in the order given, each the same as a run at that one --sensor-seed (computation times aside,
which are measured); the draws differ; the spread over them is what the draws' own totals give; and the
settings record the seeds.

Usage: check_draws_json.py DRAWS.json ONE.json SEED_OF_ONE SVG_DIR"""
import json
import math
import os
import sys


def check(condition, message):
    if not condition:
        sys.exit("check_draws_json: " + message)


def without_times(episodes):
    return [{k: v for k, v in e.items() if k != "compute_ms"} for e in episodes]


draws = json.load(open(sys.argv[1]))
one = json.load(open(sys.argv[2]))
one_seed = int(sys.argv[3])
svg_dir = sys.argv[4]

seeds = draws["sensor_seeds"]
check(seeds == [d["sensor_seed"] for d in draws["draws"]], f"draws in the seeds' order: {seeds}")
e = draws["settings"]["episode"]
check(e["sensor_seeds"] == seeds and e["sensor_seed"] is None, f"settings record the seeds: {e}")
check(one["settings"]["episode"]["sensor_seed"] == one_seed, "the single run's seed")
same = draws["draws"][seeds.index(one_seed)]
check(without_times(same["episodes"]) == without_times(one["episodes"]),
      f"the draw at seed {one_seed} is the run at --sensor-seed {one_seed}")

totals = [sum(ep["occlusion_time_s"] for ep in d["episodes"]) for d in draws["draws"]]
check(len(set(round(t, 6) for t in totals)) > 1, f"the draws differ: {totals}")
spread = draws["over_draws"]["occlusion_time_s"]
mean = sum(totals) / len(totals)
sd = math.sqrt(sum((t - mean) ** 2 for t in totals) / (len(totals) - 1))
check(abs(spread["mean"] - mean) < 1e-9 and abs(spread["sd"] - sd) < 1e-9, f"mean and sd: {spread} vs {totals}")
check(spread["min"] == min(totals) and spread["min_seed"] == seeds[totals.index(min(totals))], f"least: {spread}")
check(spread["max"] == max(totals) and spread["max_seed"] == seeds[totals.index(max(totals))], f"largest: {spread}")
check(draws["over_draws"]["draws"] == len(seeds), "the number of draws")

for s in seeds:
    folder = os.path.join(svg_dir, f"sensor-seed-{s}")
    figures = [f for f in os.listdir(folder) if f.endswith(".svg")] if os.path.isdir(folder) else []
    check(len(figures) == len(draws["draws"][0]["episodes"]), f"{folder}: one figure per episode, got {figures}")
print(f"check_draws_json: {len(seeds)} draws, time hidden {totals}")

"""Checks a `bench paper` output folder (tests/CMakeLists.txt, cli.bench_paper): each run's recorded settings,
and that the tables' header states the settings the runs recorded (the header is generated from the same
options, so the two cannot drift apart).

Usage: check_paper_header.py FOLDER EPISODES_PER_RUN [shield]: EPISODES_PER_RUN a comma-separated list;
"shield" when the runs were made with --shield (the safety layer on), else the planners alone."""
import json
import sys


def check(condition, message):
    if not condition:
        sys.exit("check_paper_header: " + message)


folder = sys.argv[1]
expected_episodes = [int(n) for n in sys.argv[2].split(",")]
expected_shield = len(sys.argv) > 3 and sys.argv[3] == "shield"
d = json.load(open(folder + "/episodes.json"))
check([len(r["result"]["episodes"]) for r in d["runs"]] == expected_episodes,
      f"episodes per run: {[len(r['result']['episodes']) for r in d['runs']]}")
header = "\n".join(d["settings"])
draw_seeds = []  # the sensor seeds of a run at several draws, in the order first run
for run in d["runs"]:
    if run["sensor_seed"] is not None and run["sensor_seed"] not in draw_seeds:
        draw_seeds.append(run["sensor_seed"])
tables = open(folder + "/tables.md").read()
for run in d["runs"]:
    p, e = run["settings"]["planner"], run["settings"]["episode"]
    check(e["tau_s"] == 0.25 and p["shield"] is expected_shield, f"the v2 tables' settings, shield: {p} {e}")
    check((run["sensor_seed"] is None) == (not draw_seeds), "every run or none is one of several draws")
    if draw_seeds:
        check(run["sensor_seed"] == e["sensor_seed"], f"the run's seed is the one it recorded: {run['sensor_seed']}")
        seeds_text = f"seeds: planner {p['seed']}, sensors {','.join(map(str, draw_seeds))} (every row once per draw"
    else:
        seeds_text = f"seeds: planner {p['seed']}, sensors {e['sensor_seed']} (one draw of each"
    for text in (f"first-order lag tau {e['tau_s']:g} s",
                 f"response time {p['response_time_s']:g} s",
                 f"LiDAR: {e['beams']} beams, Gaussian range noise sigma {e['lidar_noise_m']:g} m",
                 f"Gaussian noise {e['target_position_noise_m']:g} m on position, "
                 f"{e['target_velocity_noise_m_s']:g} m/s on velocity; target_observation {e['target_observation']}",
                 seeds_text,
                 "safety layer: " + ("on" if p["shield"] else "off"),
                 "target predictor: "):
        check(text in header, f"the header does not say '{text}':\n{header}")
        check(text in tables, f"tables.md does not say '{text}'")
    # "off" or "off, on for a, b": the usual state, and the rows that differ from it
    predictor_text = next(l for l in d["settings"] if "; target predictor: " in l).split("; target predictor: ")[1]
    usual, _, rest = predictor_text.partition(", ")
    exceptions = rest.split(" for ", 1)[1].split(", ") if rest else []
    check((usual == ("on" if p["predictor"] else "off")) != (run["label"] in exceptions),
          f"the header's predictor ('{predictor_text}') for {run['label']}, which ran with predictor {p['predictor']}")
    if p["name"] != "autochaser":  # the weight of the ranking the run used, on its planner's line
        line = next((l for l in d["settings"] if l.startswith(f"planner {run['label']}: ")), "")
        check(line.endswith(f"; ranking's tracking weight {p['tracking_weight']:g}"),
              f"the header's line for {run['label']} does not state its tracking weight {p['tracking_weight']:g}: "
              f"'{line}'")
        check("- " + line in tables, f"tables.md does not say '{line}'")
print("check_paper_header: the header states what every run recorded")

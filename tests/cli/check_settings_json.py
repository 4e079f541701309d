"""Checks that `bench suite --json` and `run --json` record the settings they ran with (tests/CMakeLists.txt,
cli.results_record_settings): the options given on the command line, and the defaults where none was given;
and that --sensor-seed reaches the simulated sensors (two follower runs with target-estimate noise, sensor seeds
1 and 2: the follower draws nothing itself, so only the noise can set them apart)."""
import json
import sys


def check(condition, message):
    if not condition:
        sys.exit("check_settings_json: " + message)


suite = json.load(open(sys.argv[1]))
run = json.load(open(sys.argv[2]))

s = suite["settings"]
p, e = s["planner"], s["episode"]
check(p["name"] == "follower" and p["seed"] == 7, f"planner: {p}")
check(p["shield"] is True and p["predictor"] is True, f"shield and predictor: {p}")
check(abs(p["response_time_s"] - 0.25) < 1e-12, f"response time follows --tau: {p}")
check(abs(p["shield_latency_s"] - 0.020) < 1e-12, f"the safety layer learns the latency: {p}")
check(abs(e["latency_ms"] - 20.0) < 1e-12 and abs(e["tau_s"] - 0.25) < 1e-12, f"latency and tau: {e}")
check(abs(e["lidar_noise_m"] - 0.01) < 1e-12 and e["beams"] is None and e["beam_dropout"] is None,
      f"sensor overrides (null: the scenario's): {e}")
check(abs(e["target_position_noise_m"] - 0.05) < 1e-12 and abs(e["target_velocity_noise_m_s"] - 0.1) < 1e-12,
      f"target noise: {e}")
check(e["target_observation"] == "line_of_sight" and e["compute_scale"] == 1.0, f"observation, scale: {e}")
check(e["sensor_seed"] == 3, f"sensor seed: {e}")
check(suite["created_by"].startswith("occtrack") and "bench suite" in suite["created_by"], suite["created_by"])
check(len(suite["episodes"]) > 0 and "summary" in suite, "the results are still there")

r = run["settings"]
check(r["planner"]["shield"] is False and r["planner"]["predictor"] is False, f"run: {r['planner']}")
check(r["episode"]["latency_ms"] is None and r["episode"]["tau_s"] == 0.0, f"run, v1 defaults: {r['episode']}")
check(r["episode"]["target_observation"] == "always", f"run: {r['episode']}")
check(r["episode"]["sensor_seed"] == 1, f"run, default sensor seed: {r['episode']}")
check(run["planner"] == "follower" and "occlusion_time_s" in run, "run: the metrics are still there")
noisy = [json.load(open(f)) for f in sys.argv[3:5]]
check([n["settings"]["episode"]["sensor_seed"] for n in noisy] == [1, 2], "the noisy runs' sensor seeds")
track = [n["tracking_distance"]["mean_m"] for n in noisy]
check(track[0] != track[1], f"sensor seeds 1 and 2 gave the same episode (mean tracking distance {track})")
print("check_settings_json: the files record their settings; the sensor seed changes the noise")

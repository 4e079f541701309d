#!/usr/bin/env bash
# End-to-end checks of the occtrack command-line tool.
#
#   bash tests/cli/test_cli.sh PATH/TO/occtrack PATH/TO/tests/data
#
# Runs `occtrack project` on the valid edge case and on broken copies of it (written to a temporary folder),
# and `occtrack bench projection` with good and bad options. Prints one line per check, then
# "N passed, M failed"; exits 1 when any check failed. Needs python3 (json module) to write and read JSON.
set -u

if [ $# -lt 2 ]; then
  echo "usage: $0 OCCTRACK_BINARY TEST_DATA_DIR" >&2
  exit 2
fi
occtrack=$1
data=$2
case_file="$data/conformance/projection/edge_b3_o5_k10.json"

if [ ! -x "$occtrack" ]; then
  echo "error: $occtrack is not an executable" >&2
  exit 2
fi
if [ ! -r "$case_file" ]; then
  echo "error: cannot read $case_file" >&2
  exit 2
fi
if ! command -v python3 >/dev/null 2>&1; then
  echo "error: python3 is needed to write and read JSON" >&2
  exit 2
fi

# shellcheck source=harness.sh
source "$(dirname "$0")/harness.sh" occtrack_cli

# Runs the tool with a time limit; leaves the exit status in $rc, the output in $tmp/out and $tmp/err.
run_tool() {
  if command -v timeout >/dev/null 2>&1; then
    timeout 120 "$occtrack" "$@" >"$tmp/out" 2>"$tmp/err" </dev/null
  else
    "$occtrack" "$@" >"$tmp/out" 2>"$tmp/err" </dev/null
  fi
  rc=$?
}

# The last lines of a captured file, made safe to print (no control characters, bounded length).
tail_of() { tail -n 5 -- "$1" 2>/dev/null | LC_ALL=C tr -c '[:print:]\n' '?' | cut -c1-300; }

# Writes a mutated copy of the valid case: mutate NAME 'python statements on d (the parsed document)'.
# Prints the new file's path.
mutate() {
  local out="$tmp/$1.json"
  if ! python3 - "$case_file" "$out" "$2" <<'PY'
import json, sys
src, dst, code = sys.argv[1], sys.argv[2], sys.argv[3]
with open(src) as f:
    d = json.load(f)
exec(code, {"d": d, "json": json})
with open(dst, "w") as f:
    json.dump(d, f)
PY
  then
    echo "error: could not write the mutated case $1" >&2
  fi
  printf '%s\n' "$out"
}

# json_check FILE 'python expression on d' -> exit 0 when FILE is JSON and the expression is true.
json_check() {
  python3 - "$1" "$2" <<'PY' 2>/dev/null
import json, math, sys
try:
    with open(sys.argv[1]) as f:
        d = json.load(f)
    ok = eval(sys.argv[2], {"d": d, "math": math, "isinstance": isinstance, "len": len, "all": all,
                            "float": float, "int": int, "dict": dict, "list": list})
except Exception:
    sys.exit(1)
sys.exit(0 if ok else 1)
PY
}

contains() { grep -F -q -- "$2" "$1" 2>/dev/null; }

# The shape of a projection result for the edge case: B = 3, 2n = 22, finite numbers.
result_ok='(isinstance(d, dict) and all(k in d for k in ("xi_init", "xi", "residual"))
  and len(d["xi"]) == 3 and all(len(r) == 22 for r in d["xi"]) and len(d["xi_init"]) == 3
  and all(len(r) == 22 for r in d["xi_init"]) and len(d["residual"]) == 3
  and all(isinstance(x, (int, float)) and math.isfinite(x) for r in d["xi"] for x in r)
  and all(isinstance(x, (int, float)) and math.isfinite(x) for x in d["residual"]))'

# ------------------------------------------------------------------------------------------------------------
# Valid runs.

run_tool project "$case_file"
if [ "$rc" -eq 0 ]; then pass "project valid case exits 0"; else fail "project valid case exits 0 (got $rc)" "$(tail_of "$tmp/err")"; fi
if json_check "$tmp/out" "$result_ok"; then
  pass "project valid case prints JSON with xi_init, xi, residual (3 x 22, 3) on stdout"
else
  fail "project valid case prints JSON with xi_init, xi, residual on stdout" "$(tail_of "$tmp/out")"
fi
if contains "$tmp/err" "PASS"; then pass "project valid case reports PASS against expected"; else fail "project valid case reports PASS" "$(tail_of "$tmp/err")"; fi

run_tool project "$case_file" --precision float
if [ "$rc" -eq 0 ]; then pass "project --precision float exits 0"; else fail "project --precision float exits 0 (got $rc)" "$(tail_of "$tmp/err")"; fi
if json_check "$tmp/out" "$result_ok"; then pass "project --precision float prints the result JSON"; else fail "project --precision float prints the result JSON" "$(tail_of "$tmp/out")"; fi

run_tool project "$case_file" --precision double --tolerance 1e-9
if [ "$rc" -eq 0 ]; then pass "project --precision double --tolerance 1e-9 exits 0"; else fail "project --precision double --tolerance 1e-9 exits 0 (got $rc)" "$(tail_of "$tmp/err")"; fi

result_file="$tmp/result.json"
run_tool project "$case_file" --out "$result_file"
if [ "$rc" -eq 0 ]; then pass "project --out exits 0"; else fail "project --out exits 0 (got $rc)" "$(tail_of "$tmp/err")"; fi
if [ -f "$result_file" ] && json_check "$result_file" "$result_ok"; then
  pass "project --out writes the result JSON to the file"
else
  fail "project --out writes the result JSON to the file" "$(tail_of "$result_file")"
fi
if contains "$tmp/out" "result written to"; then pass "project --out says where the result went"; else fail "project --out says where the result went" "$(tail_of "$tmp/out")"; fi

unwritable="$tmp/no_such_dir/result.json"
run_tool project "$case_file" --out "$unwritable"
if [ "$rc" -eq 1 ]; then pass "project --out into a missing folder exits 1"; else fail "project --out into a missing folder exits 1 (got $rc)" "$(tail_of "$tmp/err")"; fi
if contains "$tmp/err" "$unwritable"; then pass "project --out into a missing folder: stderr names the file"; else fail "project --out into a missing folder: stderr names the file" "$(tail_of "$tmp/err")"; fi

no_expected=$(mutate no_expected 'del d["expected"]')
run_tool project "$no_expected"
if [ "$rc" -eq 0 ] && json_check "$tmp/out" "$result_ok"; then
  pass "project on a case without expected outputs exits 0 with the result"
else
  fail "project on a case without expected outputs exits 0 (got $rc)" "$(tail_of "$tmp/err")"
fi

# ------------------------------------------------------------------------------------------------------------
# Broken cases: exit 1, and stderr names the file and the key.

expect_refused() {  # expect_refused LABEL CASE_PATH KEY [RULE]
  local label=$1 path=$2 key=$3 rule=${4:-}
  run_tool project "$path"
  if [ "$rc" -eq 1 ]; then pass "$label: exits 1"; else fail "$label: exits 1 (got $rc)" "$(tail_of "$tmp/err")"; fi
  if contains "$tmp/err" "$key"; then pass "$label: stderr names $key"; else fail "$label: stderr names $key" "$(tail_of "$tmp/err")"; fi
  if contains "$tmp/err" "$path"; then pass "$label: stderr names the file"; else fail "$label: stderr names the file $path" "$(tail_of "$tmp/err")"; fi
  if [ -n "$rule" ]; then
    if contains "$tmp/err" "$rule"; then pass "$label: stderr states the rule"; else fail "$label: stderr states \"$rule\"" "$(tail_of "$tmp/err")"; fi
  fi
  if [ -s "$tmp/out" ]; then fail "$label: nothing on stdout" "$(tail_of "$tmp/out")"; else pass "$label: nothing on stdout"; fi
}

expect_refused "missing config.horizon" "$(mutate missing_horizon 'del d["config"]["horizon"]')" \
  "config.horizon" "missing required key"
expect_refused "missing inputs.target" "$(mutate missing_target 'del d["inputs"]["target"]')" \
  "inputs.target" "missing required key"
expect_refused "missing format" "$(mutate missing_format 'del d["format"]')" "format" "missing required key"
expect_refused "unknown key in config" "$(mutate unknown_config 'd["config"]["batch"] = 3')" \
  "config.batch" "unknown key"
expect_refused "unknown key in inputs" "$(mutate unknown_inputs 'd["inputs"]["extra"] = []')" \
  "inputs.extra" "unknown key"
expect_refused "unknown top-level key" "$(mutate unknown_top 'd["comment"] = "x"')" "comment" "unknown key"
expect_refused "target row with 3 numbers" "$(mutate short_target 'd["inputs"]["target"][1].pop()')" \
  "inputs.target[1]" "expected 4 numbers, got 3"
expect_refused "distance_min with 2 samples" "$(mutate short_distance 'd["inputs"]["distance_min"].pop()')" \
  "inputs.distance_min" "expected 3 samples"
expect_refused "obstacles sample with 4 points" "$(mutate short_obstacles 'd["inputs"]["obstacles"][2].pop()')" \
  "inputs.obstacles[2]" "expected 5 points"
expect_refused "lambda0 row of 21" "$(mutate short_lambda 'd["inputs"]["lambda0"][0].pop()')" \
  "inputs.lambda0[0]" "expected 22 numbers, got 21"
expect_refused "\"nan\" string in target" "$(mutate nan_target 'd["inputs"]["target"][0][0] = "nan"')" \
  "inputs.target[0][0]" "must be a number"
expect_refused "null in obstacles" "$(mutate null_obstacle 'd["inputs"]["obstacles"][0][0][0] = None')" \
  "inputs.obstacles[0][0][0]" "must be a number"
expect_refused "negative config.steps" "$(mutate negative_steps 'd["config"]["steps"] = -5')" \
  "config.steps" "must be between 4 and 10000"
expect_refused "negative config.degree" "$(mutate negative_degree 'd["config"]["degree"] = -1')" \
  "config.degree" "must be between 5 and 30"
expect_refused "zero config.iterations" "$(mutate zero_iterations 'd["config"]["iterations"] = 0')" \
  "config.iterations" "must be between 1 and 1000000"
expect_refused "negative config.obstacle_radius" "$(mutate negative_radius 'd["config"]["obstacle_radius"] = -0.4')" \
  "config.obstacle_radius" "must be positive"
expect_refused "negative config.horizon" "$(mutate negative_horizon 'd["config"]["horizon"] = -5.0')" \
  "config.horizon" "must be positive"
expect_refused "speed_min above speed_max" \
  "$(mutate speed_bounds 'd["config"]["speed_min"] = 3.0; d["config"]["speed_max"] = 2.0')" \
  "config.speed_min" "must not exceed speed_max"
expect_refused "via_steps decreasing" "$(mutate via_decreasing 'd["config"]["via_steps"] = [74, 49]')" \
  "config.via_steps[1]" "must be greater than via_step_1"
expect_refused "via_steps outside the horizon" "$(mutate via_outside 'd["config"]["via_steps"] = [49, 150]')" \
  "config.via_steps[1]" "at most steps - 2"
expect_refused "wrong format tag" "$(mutate wrong_format 'd["format"] = "occtrack.projection-case.v0"')" \
  "format" "occtrack.projection-case.v1"

bad_text="$tmp/not_json.json"
head -c 500 "$case_file" >"$bad_text"
expect_refused "truncated JSON text" "$bad_text" "not valid JSON"

# 1e400 overflows a double; the JSON parser refuses it. The message must still name the file.
overflow="$tmp/overflow.json"
python3 - "$case_file" "$overflow" <<'PY' || echo "error: could not write $overflow" >&2
import json, sys
with open(sys.argv[1]) as f:
    d = json.load(f)
d["config"]["horizon"] = 12345.678
text = json.dumps(d).replace("12345.678", "1e400", 1)
with open(sys.argv[2], "w") as f:
    f.write(text)
PY
run_tool project "$overflow"
if [ "$rc" -eq 1 ]; then pass "number 1e400: exits 1"; else fail "number 1e400: exits 1 (got $rc)" "$(tail_of "$tmp/err")"; fi
if contains "$tmp/err" "$overflow"; then pass "number 1e400: stderr names the file"; else fail "number 1e400: stderr names the file $overflow" "$(tail_of "$tmp/err")"; fi

missing="$tmp/does_not_exist.json"
run_tool project "$missing"
if [ "$rc" -eq 1 ]; then pass "missing case file: exits 1"; else fail "missing case file: exits 1 (got $rc)" "$(tail_of "$tmp/err")"; fi
if contains "$tmp/err" "$missing"; then pass "missing case file: stderr names the file"; else fail "missing case file: stderr names the file" "$(tail_of "$tmp/err")"; fi

# A value that fits in double but not in float: refused by the float solve, naming the field.
float_overflow=$(mutate float_overflow 'd["inputs"]["target"][1][2] = 1e39')
run_tool project "$float_overflow" --precision float
if [ "$rc" -eq 1 ]; then pass "target 1e39 with --precision float: exits 1"; else fail "target 1e39 with --precision float: exits 1 (got $rc)" "$(tail_of "$tmp/err")"; fi
if contains "$tmp/err" "target"; then pass "target 1e39 with --precision float: stderr names target"; else fail "target 1e39 with --precision float: stderr names target" "$(tail_of "$tmp/err")"; fi

# ------------------------------------------------------------------------------------------------------------
# Bad options.

run_tool project "$case_file" --precision quad
if [ "$rc" -ne 0 ]; then pass "project --precision quad exits non-zero ($rc)"; else fail "project --precision quad exits non-zero"; fi
if contains "$tmp/err" "quad"; then pass "project --precision quad: stderr names the value"; else fail "project --precision quad: stderr names the value" "$(tail_of "$tmp/err")"; fi

run_tool project "$case_file" --tolerance -1
if [ "$rc" -ne 0 ]; then pass "project --tolerance -1 exits non-zero ($rc)"; else fail "project --tolerance -1 exits non-zero"; fi

run_tool project
if [ "$rc" -ne 0 ]; then pass "project without a case exits non-zero ($rc)"; else fail "project without a case exits non-zero"; fi

run_tool
if [ "$rc" -ne 0 ]; then pass "no subcommand exits non-zero ($rc)"; else fail "no subcommand exits non-zero"; fi

# ------------------------------------------------------------------------------------------------------------
# Mismatch against expected outputs: exit 3 and FAIL.

mismatch=$(mutate mismatch 'd["expected"]["residual"][0] += 1.0; d["expected"]["xi"][1][3] += 0.5')
run_tool project "$mismatch"
if [ "$rc" -eq 3 ]; then pass "wrong expected value: exits 3"; else fail "wrong expected value: exits 3 (got $rc)" "$(tail_of "$tmp/err")"; fi
if contains "$tmp/err" "FAIL" || contains "$tmp/out" "FAIL"; then pass "wrong expected value: prints FAIL"; else fail "wrong expected value: prints FAIL" "$(tail_of "$tmp/err")"; fi
if json_check "$tmp/out" "$result_ok"; then pass "wrong expected value: still prints the result JSON"; else fail "wrong expected value: still prints the result JSON" "$(tail_of "$tmp/out")"; fi

run_tool project "$mismatch" --out "$tmp/mismatch_result.json"
if [ "$rc" -eq 3 ] && contains "$tmp/out" "FAIL"; then pass "wrong expected value with --out: exits 3 and prints FAIL"; else fail "wrong expected value with --out: exits 3 and prints FAIL (got $rc)" "$(tail_of "$tmp/out")"; fi

# ------------------------------------------------------------------------------------------------------------
# Benchmark.

run_tool bench projection --batch 5 --repeats 3 --json
if [ "$rc" -eq 0 ]; then pass "bench projection --json exits 0"; else fail "bench projection --json exits 0 (got $rc)" "$(tail_of "$tmp/err")"; fi
if json_check "$tmp/out" 'isinstance(d, dict) and all(isinstance(d.get(k), (int, float)) and math.isfinite(d[k]) and d[k] >= 0 for k in ("median_ms", "p99_ms")) and d["p99_ms"] >= d["median_ms"] and d.get("batch") == 5 and d.get("repeats") == 3'; then
  pass "bench projection --json prints an object with median_ms <= p99_ms"
else
  fail "bench projection --json prints an object with median_ms and p99_ms" "$(tail_of "$tmp/out")"
fi

run_tool bench projection --batch 0
if [ "$rc" -ne 0 ]; then pass "bench projection --batch 0 exits non-zero ($rc)"; else fail "bench projection --batch 0 exits non-zero"; fi
if contains "$tmp/err" "--batch"; then pass "bench projection --batch 0: stderr names --batch"; else fail "bench projection --batch 0: stderr names --batch" "$(tail_of "$tmp/err")"; fi

run_tool bench projection --batch 2 --repeats 1 --precision half
if [ "$rc" -ne 0 ]; then pass "bench projection --precision half exits non-zero ($rc)"; else fail "bench projection --precision half exits non-zero"; fi

run_tool bench
if [ "$rc" -ne 0 ]; then pass "bench without a benchmark exits non-zero ($rc)"; else fail "bench without a benchmark exits non-zero"; fi

# ------------------------------------------------------------------------------------------------------------
# Episode options of Protocol v2 (apps/occtrack/episode_common.hpp): bad values are refused before anything
# runs, with a message naming the option; good ones run.

scenario_file="$data/scenarios/example.yaml"
expect_bad_option() {  # expect_bad_option OPTION VALUE TEXT
  run_tool run "$scenario_file" --planner follower "$1" "$2"
  if [ "$rc" -ne 0 ]; then pass "run $1 $2 exits non-zero ($rc)"; else fail "run $1 $2 exits non-zero"; fi
  if contains "$tmp/err" "$1: $3"; then pass "run $1 $2: stderr says \"$1: $3\""; else fail "run $1 $2: stderr says \"$1: $3\"" "$(tail_of "$tmp/err")"; fi
}
expect_bad_option --latency -5 "must be none, auto or a number of milliseconds >= 0, got -5"
expect_bad_option --latency soon "must be none, auto or a number"
expect_bad_option --compute-scale 0 "must be a number > 0, got 0"
expect_bad_option --tau -0.1 "must be a number >= 0, got -0.1"
expect_bad_option --beams 0 "must be an integer >= 1, got 0"
expect_bad_option --lidar-noise nan "must be a number >= 0, got nan"
expect_bad_option --beam-dropout 1.5 "must be in [0, 1], got 1.5"
expect_bad_option --beam-dropout -0.5 "must be in [0, 1], got -0.5"
expect_bad_option --target-noise 0.1 "must be POS,VEL"
expect_bad_option --target-noise 0.1,nan "must be POS,VEL"
expect_bad_option --target-observation sometimes "sometimes"
expect_bad_option --waypoints -1 "must be an integer >= 0, got -1"
expect_bad_option --tracking-weight -1 "must be in [0, 1e+06], got -1"
expect_bad_option --tracking-weight nan "must be in [0, 1e+06], got nan"

run_tool run "$scenario_file" --planner follower --latency auto --compute-scale 10 --tau 0.25 --beams 360 \
  --lidar-noise 0.01 --beam-dropout 0.1 --target-noise 0.05,0.1 --target-observation line_of_sight \
  --json "$tmp/episode_v2.json"
if [ "$rc" -eq 0 ]; then pass "run with every v2 option exits 0"; else fail "run with every v2 option exits 0 (got $rc)" "$(tail_of "$tmp/err")"; fi
if contains "$tmp/err" "latency auto: " && contains "$tmp/err" "x compute scale 10"; then
  pass "run --latency auto prints the measured latency"
else
  fail "run --latency auto prints the measured latency" "$(tail_of "$tmp/err")"
fi
if json_check "$tmp/episode_v2.json" 'd["compute_scale"] == 10 and d["latency_ms"] > 0 and isinstance(d["occlusion_stretches"], int) and d["longest_occlusion_s"] <= d["occlusion_time_s"] + 1e-9'; then
  pass "run --json records latency_ms, compute_scale, occlusion_stretches, longest_occlusion_s"
else
  fail "run --json records the v2 keys" "$(tail_of "$tmp/episode_v2.json")"
fi

# The safety layer is on by default; --no-shield runs the planner alone (the result JSON has "shield" counts
# only when the layer ran).
run_tool run "$scenario_file" --planner follower --json "$tmp/episode_shielded.json"
if [ "$rc" -eq 0 ] && json_check "$tmp/episode_shielded.json" 'sum(d["shield"].values()) > 0'; then
  pass "run goes through the safety layer by default"
else
  fail "run goes through the safety layer by default" "$(tail_of "$tmp/err")"
fi
run_tool run "$scenario_file" --planner follower --no-shield --json "$tmp/episode_bare.json"
if [ "$rc" -eq 0 ] && json_check "$tmp/episode_bare.json" '"shield" not in d'; then
  pass "run --no-shield runs the planner alone"
else
  fail "run --no-shield runs the planner alone" "$(tail_of "$tmp/err")"
fi

# The ranking's tracking weight: the planner's default (1 for the follower), or --tracking-weight, recorded.
run_tool run "$scenario_file" --planner follower --tracking-weight 2.5 --json "$tmp/episode_weighted.json"
if [ "$rc" -eq 0 ] && json_check "$tmp/episode_weighted.json" 'd["settings"]["planner"]["tracking_weight"] == 2.5' \
   && json_check "$tmp/episode_shielded.json" 'd["settings"]["planner"]["tracking_weight"] == 1' \
   && contains "$tmp/out" "tracking weight 2.5"; then
  pass "run records the tracking weight: the follower's 1, or --tracking-weight's"
else
  fail "run records the tracking weight" "$(tail_of "$tmp/err")"
fi


# The moving reach: unset, the planner's default (1 s for the cvae behind the layer, 0 for the follower),
# recorded with the value in effect; --moving-reach 0 turns it off.
run_tool run "$scenario_file" --planner cvae --json "$tmp/episode_reach.json"
if [ "$rc" -eq 0 ] && json_check "$tmp/episode_reach.json" 'd["settings"]["planner"]["moving_reach_s"] == 1' \
   && json_check "$tmp/episode_shielded.json" 'd["settings"]["planner"]["moving_reach_s"] == 0' \
   && contains "$tmp/out" "moving reach 1 s"; then
  pass "run records the moving reach in effect: the cvae's 1 s behind the layer, the follower's 0"
else
  fail "run records the moving reach in effect" "$(tail_of "$tmp/err")"
fi
run_tool run "$scenario_file" --planner cvae --moving-reach 0 --json "$tmp/episode_no_reach.json"
if [ "$rc" -eq 0 ] && json_check "$tmp/episode_no_reach.json" 'd["settings"]["planner"]["moving_reach_s"] == 0' \
   && ! contains "$tmp/out" "moving reach"; then
  pass "run --moving-reach 0 turns the cvae's default off"
else
  fail "run --moving-reach 0 turns the cvae's default off" "$(tail_of "$tmp/err")"
fi

# The layer's obstacle-speed envelope: 1 m/s unless --moving-speed-max raises it, recorded; a value outside
# its range is refused with the option named.
run_tool run "$scenario_file" --planner follower --moving-speed-max 1.5 --json "$tmp/episode_fast_movers.json"
if [ "$rc" -eq 0 ] \
   && json_check "$tmp/episode_fast_movers.json" 'd["settings"]["planner"]["moving_speed_max_m_s"] == 1.5' \
   && json_check "$tmp/episode_shielded.json" 'd["settings"]["planner"]["moving_speed_max_m_s"] == 1' \
   && contains "$tmp/out" "standoff 0.5 s, moving obstacles up to 1.5 m/s"; then
  pass "run records the layer's moving_speed_max: 1 m/s, or --moving-speed-max's"
else
  fail "run records the layer's moving_speed_max" "$(tail_of "$tmp/err")"
fi
if ! contains "$tmp/err" "faster than the safety layer assumes" && ! contains "$tmp/err" "faster than it assumes" \
   && json_check "$tmp/episode_fast_movers.json" 'd["beyond_envelope_cycles"] == 0'; then
  pass "run gives no envelope warning when the scenario's obstacles (0.7 m/s) are within it"
else
  fail "run gives no envelope warning within it" "$(tail_of "$tmp/err")"
fi
run_tool run "$scenario_file" --planner follower --moving-speed-max 0.5 --json "$tmp/episode_slow_envelope.json"
envelope_warning="warning: 1 scenario with moving obstacles faster than the safety layer assumes (0.7 m/s"
seen_warning="cycles the safety layer's estimates showed moving obstacles faster than it assumes (--moving-speed-max 0.5)"
if [ "$rc" -eq 0 ] && contains "$tmp/err" "$envelope_warning" && contains "$tmp/err" "$seen_warning" \
   && json_check "$tmp/episode_slow_envelope.json" 'd["beyond_envelope_cycles"] > 0'; then
  pass "run warns when the scenario's obstacles are faster than --moving-speed-max, from the file and from the scans"
else
  fail "run warns when the scenario's obstacles are faster than --moving-speed-max" "rc $rc; $(tail_of "$tmp/err")"
fi
run_tool run "$scenario_file" --planner follower --moving-speed-max 0
if [ "$rc" -ne 0 ] && contains "$tmp/err" "--moving-speed-max"; then
  pass "run refuses --moving-speed-max 0 by name"
else
  fail "run refuses --moving-speed-max 0 by name" "rc $rc; $(tail_of "$tmp/err")"
fi

# ------------------------------------------------------------------------------------------------------------
# scenario import: a recorded target path (nanosecond clock, named columns, as `rostopic echo -p` writes) made
# into a scenario of the paper's six-wall world, then run.
python3 - "$tmp/recording.csv" <<'PY'
import sys
with open(sys.argv[1], "w") as f:
    f.write("%time,field.header.seq,field.pose.pose.position.x,field.pose.pose.position.y\n")
    for i in range(1001):  # 10 s at 100 Hz, 1 m/s up the line x = 8 (east of the walls)
        t = i * 0.01
        f.write("%d,%d,%.4f,%.4f\n" % (1700000000000000000 + i * 10000000, i, 8.0, -5.0 + t))
PY
run_tool scenario import "$tmp/recording.csv" --world six-wall --out "$tmp/imported.yaml" --time-scale 1e-9 \
  --columns %time,field.pose.pose.position.x,field.pose.pose.position.y
if [ "$rc" -eq 0 ] && contains "$tmp/out" "1001 of its 1001 samples used, resampled every 0.1 s" \
   && contains "$tmp/out" "the robot starts at (8, -7)" && contains "$tmp/out" "101 waypoints over 10 s" \
   && ! contains "$tmp/err" "warning"; then
  pass "scenario import makes a scenario of a recorded path, the robot 2 m behind the target's start"
else
  fail "scenario import makes a scenario of a recorded path" "rc $rc; $(tail_of "$tmp/out"); $(tail_of "$tmp/err")"
fi
run_tool run "$tmp/imported.yaml" --planner follower
if [ "$rc" -eq 0 ] && contains "$tmp/out" "collisions"; then
  pass "run runs an imported scenario"
else
  fail "run runs an imported scenario" "rc $rc; $(tail_of "$tmp/err")"
fi
# The same path recorded in an odometry-like frame: origin at the world's (8, -5), x axis along the world's +y.
python3 - "$tmp/odom.csv" <<'PY'
import sys
with open(sys.argv[1], "w") as f:
    for i in range(1001):
        f.write("%.2f,%.4f,0\n" % (i * 0.01, i * 0.01))
PY
run_tool scenario import "$tmp/odom.csv" --world six-wall --out "$tmp/odom.yaml" --frame=8,-5,90 --name imported
if [ "$rc" -eq 0 ] && cmp -s "$tmp/odom.yaml" "$tmp/imported.yaml" && ! contains "$tmp/err" "warning"; then
  pass "scenario import --frame places a recording made in another frame"
else
  fail "scenario import --frame places a recording made in another frame" \
    "rc $rc; $(diff "$tmp/odom.yaml" "$tmp/imported.yaml" | head -5); $(tail_of "$tmp/err")"
fi
run_tool scenario import "$tmp/odom.csv" --world six-wall --out "$tmp/refused.yaml" --frame=8,-5
if [ "$rc" -eq 1 ] && contains "$tmp/err" "--frame: expected X,Y,DEG" && [ ! -e "$tmp/refused.yaml" ]; then
  pass "scenario import refuses a --frame without its angle"
else
  fail "scenario import refuses a --frame without its angle" "rc $rc; $(tail_of "$tmp/err")"
fi
printf '0 8 -5\n1 8 -4\n1 8 -3\n' > "$tmp/repeated_time.txt"
run_tool scenario import "$tmp/repeated_time.txt" --world six-wall --out "$tmp/refused.yaml"
if [ "$rc" -eq 1 ] && contains "$tmp/err" "repeated_time.txt: line 3: times must strictly increase" \
   && [ ! -e "$tmp/refused.yaml" ]; then
  pass "scenario import refuses times that do not increase, naming the line, and writes nothing"
else
  fail "scenario import refuses times that do not increase" "rc $rc; $(tail_of "$tmp/err")"
fi
run_tool scenario import "$tmp/recording.csv" --world six-wall --out "$tmp/refused.yaml" --columns %time,x,y
if [ "$rc" -eq 1 ] && contains "$tmp/err" "no column named 'x'"; then
  pass "scenario import refuses a column name the header does not have"
else
  fail "scenario import refuses a column name the header does not have" "rc $rc; $(tail_of "$tmp/err")"
fi
printf '0 0 0\n10 10 0\n' > "$tmp/through_walls.txt"
run_tool scenario import "$tmp/through_walls.txt" --world six-wall --out "$tmp/through_walls.yaml" --robot-start=-2,0
if [ "$rc" -eq 0 ] && contains "$tmp/err" "warning: the target's disk (radius 0.25 m) overlaps an obstacle" \
   && contains "$tmp/out" "the robot starts at (-2, 0)"; then
  pass "scenario import warns when the path runs through the world's obstacles, and takes --robot-start"
else
  fail "scenario import warns when the path runs through obstacles" "rc $rc; $(tail_of "$tmp/err")"
fi

# dataset generate --scenarios: the expert labels episodes on your own scenarios; a benchmark suite's are refused.
run_tool dataset generate --scenarios "$tmp/imported.yaml" --duration 1 --expert-samples 16 --expert-iterations 1 \
  --jobs 1 --out "$tmp/mine.safetensors"
if [ "$rc" -eq 0 ] && contains "$tmp/err" "dataset: 1 episodes on 1 scenario files (each its own length, at most 1 s" \
   && contains "$tmp/out" "20 rows from 1 episodes"; then
  pass "dataset generate labels episodes on a given scenario, for at most --duration"
else
  fail "dataset generate labels episodes on a given scenario" "rc $rc; $(tail_of "$tmp/out"); $(tail_of "$tmp/err")"
fi
run_tool dataset info "$tmp/mine.safetensors"
if [ "$rc" -eq 0 ] && contains "$tmp/out" '"scenarios":["imported"]' \
   && contains "$tmp/out" "--scenarios $tmp/imported.yaml"; then
  pass "dataset info shows the scenarios a file was made on"
else
  fail "dataset info shows the scenarios a file was made on" "rc $rc; $(tail_of "$tmp/out")"
fi
mkdir -p "$tmp/sixwall-2ms" && cp "$tmp/imported.yaml" "$tmp/sixwall-2ms/"
run_tool dataset generate --scenarios "$tmp/sixwall-2ms" --duration 1 --out "$tmp/refused.safetensors"
if [ "$rc" -eq 1 ] && contains "$tmp/err" "is in the folder of benchmark suite sixwall-2ms" \
   && [ ! -e "$tmp/refused.safetensors" ]; then
  pass "dataset generate refuses a benchmark suite's folder of scenarios"
else
  fail "dataset generate refuses a benchmark suite's folder of scenarios" "rc $rc; $(tail_of "$tmp/err")"
fi

finish

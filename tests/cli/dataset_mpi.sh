#!/usr/bin/env bash
# `occtrack dataset generate` under MPI (docs/scaling.md, "Demonstrations under MPI"): the file that 2, 3 and 5
# ranks write is byte for byte the one a plain process writes (4 episodes: 3 ranks do not divide them, 5 ranks
# leave one rank without an episode); a rank that fails at run time is named by rank 0 and the run ends with
# an error instead of hanging; a refused option is reported once.
#
#   bash tests/cli/dataset_mpi.sh MPIEXEC PATH/TO/occtrack PATH/TO/models/cvae.safetensors
#
# Prints one line per check, then "N passed, M failed"; exits 1 when any check failed.
set -u

if [ $# -lt 3 ]; then
  echo "usage: $0 MPIEXEC OCCTRACK_BINARY LEARNED_MODEL" >&2
  exit 2
fi
mpiexec=$1
occtrack=$(realpath -- "$2")  # absolute: the failure check starts ranks in other folders
model=$(realpath -- "$3")

# shellcheck source=harness.sh
source "$(dirname "$0")/harness.sh" occtrack_mpi

# As root in containers, and more ranks than cores: Open MPI refuses both unless told (other MPIs ignore the
# variables).
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
launch=("$mpiexec")
if "$mpiexec" --version 2>&1 | grep -Eq "Open MPI|OpenRTE"; then launch+=(--oversubscribe); fi

# A failed check shows the end of the command's output.
fail_showing_output() {
  local lines
  mapfile -t lines < <(tail -n 8 -- "$tmp/out" "$tmp/err" 2>/dev/null | cut -c1-300)
  fail "$1" "${lines[@]}"
}

# Runs a command with a time limit (a hang fails the check); leaves the exit status in $rc and the output in
# $tmp/out and $tmp/err.
run() {
  timeout 60 "$@" >"$tmp/out" 2>"$tmp/err" </dev/null
  rc=$?
}

# The "wrote FILE: N rows from E episodes" line, without the file name.
rows_line() { sed -n 's/^wrote [^:]*: \([0-9]* rows from [0-9]* episodes\).*/\1/p' "$tmp/out"; }

small=(dataset generate --episodes 4 --duration 1 --expert-samples 64 --expert-iterations 1)

run "$occtrack" "${small[@]}" --jobs 2 --out "$tmp/one.safetensors"
one_rows=$(rows_line)
if [ "$rc" -eq 0 ] && [ -s "$tmp/one.safetensors" ] && [ -n "$one_rows" ]; then
  pass "one process writes the file ($one_rows)"
else
  fail_showing_output "one process writes the file (exit $rc)"
fi

for ranks in 2 3 5; do
  out="$tmp/ranks$ranks.safetensors"
  run "${launch[@]}" -n "$ranks" "$occtrack" "${small[@]}" --out "$out"
  if [ "$rc" -eq 0 ] && cmp -s "$tmp/one.safetensors" "$out" && [ "$(rows_line)" = "$one_rows" ] &&
     grep -q "$ranks ranks, 1 jobs each" "$tmp/err"; then
    pass "$ranks ranks write the same bytes and the same summary"
  else
    fail_showing_output "$ranks ranks write the same bytes and the same summary (exit $rc)"
  fi
done

# Rank 1 starts in a folder without the driver's model (a node whose file system lacks it): it fails at run
# time, rank 0 finishes its own episodes, names rank 1 and writes nothing, and every rank exits non-zero.
mkdir -p "$tmp/with-model" "$tmp/without-model"
cp -- "$model" "$tmp/with-model/model.safetensors"
learned=("${small[@]}" --driver cvae --model model.safetensors --out out.safetensors)
run "${launch[@]}" -n 1 -wdir "$tmp/with-model" "$occtrack" "${learned[@]}" : \
                   -n 1 -wdir "$tmp/without-model" "$occtrack" "${learned[@]}"
if [ "$rc" -ne 0 ] && [ "$rc" -ne 124 ] && grep -q "rank 1 of 2: planner cvae: no model file at model.safetensors" "$tmp/err" &&
   [ ! -e "$tmp/with-model/out.safetensors" ] && [ ! -e "$tmp/without-model/out.safetensors" ]; then
  pass "a rank that fails is named, no file is written, the run exits non-zero"
else
  fail_showing_output "a rank that fails is named, no file is written, the run exits non-zero (exit $rc; 124: timed out)"
fi

# A refused option: every rank finds it before any communication, rank 0 alone says so.
run "${launch[@]}" -n 3 "$occtrack" "${small[@]}" --seed 1500 --out "$tmp/unused.safetensors"
if [ "$rc" -ne 0 ] && [ "$rc" -ne 124 ] && [ "$(grep -c "meet the benchmark's seeds 1000-1999" "$tmp/err")" -eq 1 ]; then
  pass "a refused option is reported once and the run exits non-zero"
else
  fail_showing_output "a refused option is reported once and the run exits non-zero (exit $rc; 124: timed out)"
fi

finish

#!/usr/bin/env bash
# Runs each fuzz target for a while on a writable copy of its seed corpus (fuzz/corpus/NAME) with its
# dictionary (fuzz/dict/NAME.dict). Exits non-zero when any target finds something (crash, sanitizer report,
# leak, timeout, out of memory, or an exception outside its contract), and prints where the input was saved.
#
#   fuzz/run.sh BUILD_DIR [SECONDS] [TARGET...]     # targets: scenario target_path projection_case safetensors
#                                                   # model_file dataset_file (default: all), SECONDS default 60
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
build="${1:?usage: fuzz/run.sh BUILD_DIR [SECONDS] [TARGET...]}"
seconds="${2:-60}"
shift $(($# < 2 ? $# : 2))
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(scenario target_path projection_case safetensors model_file dataset_file)

work="$(mktemp -d "${TMPDIR:-/tmp}/occtrack-fuzz.XXXXXX")"
findings="$build/fuzz-findings"
mkdir -p "$findings"
failed=()
for name in "${targets[@]}"; do
  binary="$build/fuzz/fuzz_$name"
  if [ ! -x "$binary" ]; then
    echo "fuzz: $binary is missing (configure with -DOCCTRACK_BUILD_FUZZERS=ON and build it)" >&2
    failed+=("$name")
    continue
  fi
  corpus="$work/$name"
  mkdir -p "$corpus" "$findings/$name"
  cp "$here/corpus/$name"/* "$corpus"/
  echo "== fuzz $name: ${seconds} s on $(ls "$corpus" | wc -l) seeds"
  # Findings land in $findings/NAME/ as crash-*, leak-*, timeout-*, oom-* (libFuzzer's names).
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    "$binary" "$corpus" -dict="$here/dict/$name.dict" -max_total_time="$seconds" -timeout=10 \
    -rss_limit_mb=2048 -malloc_limit_mb=2048 -detect_leaks=1 -print_final_stats=1 \
    -artifact_prefix="$findings/$name/" >"$work/$name.log" 2>&1
  status=$?
  grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$work/$name.log" | sed "s/^/fuzz $name: /"
  if [ $status -ne 0 ]; then
    failed+=("$name")
    tail -n 60 "$work/$name.log"
    echo "fuzz $name: FINDING (exit $status); inputs:" >&2
    grep -hoE "(Test unit written to|artifact_prefix=.*; Test unit written to) [^ ]+" "$work/$name.log" |
      sed 's/.*written to /  /' >&2
  fi
done
rm -rf "$work"
if [ ${#failed[@]} -ne 0 ]; then
  echo "fuzz: findings in: ${failed[*]} (inputs under $findings; see fuzz/README.md to turn one into a regression test)" >&2
  exit 1
fi
echo "fuzz: no findings"

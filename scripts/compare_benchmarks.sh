#!/usr/bin/env bash
# Times two builds of occtrack side by side in one run: the projection (float and double, with the literal
# reference in the same process) and the learned policy's cycle (B = 30 and B = 5), alternating between the
# two binaries round by round and pinned to one core, so that load on the machine falls on both alike.
# Prints one line per measurement: "round R base|new KIND {json}".
#
# Usage: scripts/compare_benchmarks.sh BASELINE_OCCTRACK NEW_OCCTRACK [ROUNDS] [CPU]
#   e.g. git worktree add /tmp/before <commit> && (build it) &&
#        scripts/compare_benchmarks.sh /tmp/before/build/occtrack build/occtrack 5 1
set -u
A=${1:?baseline occtrack binary}; B=${2:?new occtrack binary}; R=${3:-5}; CPU=${4:-1}
cd "$(dirname "$0")/.."
out=$(mktemp -d)
for r in $(seq 1 $R); do {
  for tag in base new; do
    bin=$A; [ $tag = new ] && bin=$B
    echo "round $r $tag float-literal $(taskset -c $CPU $bin bench projection --batch 30 --precision float --literal --literal-repeats 10 --repeats 500 --json | tr -d '\n')"
    echo "round $r $tag double-literal $(taskset -c $CPU $bin bench projection --batch 30 --precision double --literal --literal-repeats 10 --repeats 500 --json | tr -d '\n')"
    taskset -c $CPU $bin bench policy --variant cvae --batch 30 --repeats 2000 --json $out/p30.$tag.$r.json > /dev/null
    taskset -c $CPU $bin bench policy --variant cvae --batch 5 --repeats 2000 --json $out/p5.$tag.$r.json > /dev/null
    echo "round $r $tag policy30 $(tr -d '\n' < $out/p30.$tag.$r.json)"
    echo "round $r $tag policy5 $(tr -d '\n' < $out/p5.$tag.$r.json)"
  done
} | tee -a $out/log; done

# Medians over the rounds, and new / base.
python3 - $out/log <<'PY'
import json, re, statistics, sys
rows = {}
for line in open(sys.argv[1]):
    m = re.match(r"round (\d+) (\w+) (\S+) (.*)", line)
    if not m:
        continue
    _, tag, kind, text = m.groups()
    d = json.loads(text)
    if "literal" in kind:
        rows.setdefault((kind + " fast", tag), []).append(d["median_ms"])
        rows.setdefault((kind + " literal", tag), []).append(d["literal"]["median_ms"])
    else:
        rows.setdefault((kind, tag), []).append(d["median_ms"])
for kind in sorted({k for k, _ in rows}):
    a, b = statistics.median(rows[(kind, "base")]), statistics.median(rows[(kind, "new")])
    print(f"{kind:24s} base {a:9.3f} ms   new {b:9.3f} ms   new/base {b / a:.3f}")
PY

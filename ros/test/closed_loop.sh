#!/usr/bin/env bash
# The ROS 1 closed-loop test (ctest ros.closed_loop, label "ros"; docs/ros.md): a real roscore on a free port,
# the simulator on a short scenario, the occtrack node, and the checker, which judges cmd_vel, status and
# target_visible and then injects a NaN scan and a stale target (ros/test/check_node.cpp has the thresholds);
# last, the node's log must show each of those two stops once.
# Everything runs under a temporary ROS_HOME and is stopped on exit, pass or fail. No display needed.
#
#   closed_loop.sh NODE SIM CHECK SCENARIO
set -euo pipefail
node=$1 sim=$2 check=$3 scenario=$4

work=$(mktemp -d "${TMPDIR:-/tmp}/occtrack-ros.XXXXXX")
groups=()  # each process runs in its own session (setsid): its process group id is its pid
cleanup() {
  local status=$?
  for pgid in "${groups[@]}"; do kill -INT -- "-$pgid" 2>/dev/null || true; done
  for _ in $(seq 50); do  # up to 5 s for a clean shutdown, then force
    local alive=0
    for pgid in "${groups[@]}"; do kill -0 -- "-$pgid" 2>/dev/null && alive=1; done
    [[ $alive == 0 ]] && break
    sleep 0.1
  done
  for pgid in "${groups[@]}"; do kill -KILL -- "-$pgid" 2>/dev/null || true; done
  if [[ $status != 0 ]]; then
    for log in "$work"/*.log; do echo "--- $log (last lines)"; tail -n 20 "$log"; done
  fi
  rm -rf "$work"
  exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# start NAME COMMAND...: in the background, in its own process group, output to NAME.log. `timeout` is the
# backstop should this script itself be killed without its trap running (ctest's timeout is 120 s).
start() {
  local name=$1
  shift
  setsid timeout 150 "$@" >"$work/$name.log" 2>&1 &
  groups+=("$!")
}

# Nothing in the home directory; every node on the loopback interface (CI machines may not resolve their name).
export ROS_HOME=$work ROS_LOG_DIR=$work/log ROS_IP=127.0.0.1
unset ROS_HOSTNAME
port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI=http://127.0.0.1:$port

start roscore roscore -p "$port"
for _ in $(seq 150); do  # up to 15 s for the master to listen
  (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null && break
  sleep 0.1
done
(exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null || { echo "roscore did not start on port $port"; exit 1; }

# The robot turns slowly (yaw_rate) and starts rotated, so that wrong frame conversions would show.
start sim "$sim" __name:=occtrack_ros_sim _scenario:="$scenario" _yaw:=0.7 _yaw_rate:=0.2
start node "$node" __name:=occtrack_ros _rate:=20
timeout 110 "$check" __name:=occtrack_ros_check _rate:=20 _duration:=8 _sim:=/occtrack_ros_sim

# Each stop is logged once, not once a tick: the stale target's reason carries its age, which changes every
# tick (the node logs when a reason changes other than in its numbers).
for stop in "scan: only" "target: stale"; do
  lines=$(grep -c "occtrack: stopped: $stop" "$work/node.log" || true)
  echo "node log: $lines line(s) for \"stopped: $stop\""
  [[ $lines == 1 ]] || { echo "expected the stop \"$stop\" logged once"; exit 1; }
done

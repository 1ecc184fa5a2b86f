#!/usr/bin/env bash
# `make demo`: starts launch/demo.launch on a private ROS master, reports what the node loaded
# and which services it offers, then shuts everything down.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="/usr/bin:$PATH"
# catkin's setup scripts read unset variables.
set +u
# shellcheck disable=SC1091
source devel/setup.bash
set -u

# A master of our own on a free port, so the demo neither needs nor disturbs a running roscore.
port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI="http://127.0.0.1:$port"
log=$(mktemp /tmp/bvh_collision_demo.XXXXXX.log)
export ROSCONSOLE_STDOUT_LINE_BUFFERED=1
roslaunch --port "$port" bvh_collision demo.launch > "$log" 2>&1 &
launch_pid=$!
trap 'kill -INT $launch_pid 2>/dev/null; wait $launch_pid 2>/dev/null || true' EXIT

echo "demo: starting the collision checker on the demo robot (log: $log)"
for _ in $(seq 1 150); do
  rosparam get /collision_checker/robot/links > /dev/null 2>&1 && break
  kill -0 $launch_pid 2>/dev/null || { cat "$log"; echo "demo: roslaunch exited" >&2; exit 1; }
  sleep 0.2
done
rosparam get /collision_checker/robot/links > /dev/null 2>&1 || { cat "$log"; echo "demo: the node did not come up" >&2; exit 1; }

echo
echo "The node's start-up line:"
grep -o 'collision_checker: robot.*' "$log" | sed 's/\x1b\[[0-9;]*m//g' | head -1 || true
echo
echo "What it publishes about itself (private parameters):"
for p in robot/name robot/root_link robot/links robot/joints robot/collision_elements world_frame resolution; do
  printf '  ~%-26s %s\n' "$p" "$(rosparam get /collision_checker/$p)"
done
echo
echo "Services it offers:"
services=$(rosservice list 2>/dev/null | grep '^/collision_checker/' | grep -v -E '/(get_loggers|set_logger_level)$' || true)
if [[ -z "$services" ]]; then
  echo "  none yet: the queries of DESIGN.md section 4 are advertised as they are implemented"
else
  echo "$services" | sed 's/^/  /'
fi

#!/usr/bin/env bash
# The service benchmark (make bench): starts the node on panda (from ../shared/robots, or
# $BVH_COLLISION_ROBOTS) on a private ROS master, runs bench_node against it, and writes
# <dir>/bench_node.md and <dir>/tables/service.json. BENCH_QUICK=true: fewer calls (make test).
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="/usr/bin:$PATH"
out=${1:-build/bench}
mkdir -p "$out"
out=$(cd "$out" && pwd)
robots=${BVH_COLLISION_ROBOTS:-$(pwd)/../shared/robots}
set +u
# shellcheck disable=SC1091
source devel/setup.bash
set -u
export ROS_PACKAGE_PATH="$robots/panda:$ROS_PACKAGE_PATH"
port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI="http://127.0.0.1:$port"
log=$(mktemp /tmp/bvh_collision_bench.XXXXXX.log)
roslaunch --port "$port" bvh_collision collision_checker.launch \
  robot_description_file:="$robots/panda/robot.urdf" \
  robot_description_semantic_file:="$robots/panda/robot.srdf" proxy_levels:="[0.01]" > "$log" 2>&1 &
launch_pid=$!
trap 'kill -INT $launch_pid 2>/dev/null; wait $launch_pid 2>/dev/null || true' EXIT
devel/lib/bvh_collision/bench_node _urdf_file:="$robots/panda/robot.urdf" _output_dir:="$out" \
  _quick:="${BENCH_QUICK:-false}" \
  | tee "$out/bench_node.md"

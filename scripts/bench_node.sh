#!/usr/bin/env bash
# The service benchmarks (make bench), each against the node on a private ROS master:
#   - bench_node on panda (from ../shared/robots, or $BVH_COLLISION_ROBOTS): the round trip
#     against in-process (<dir>/bench_node.md, tables service and service_under_flood);
#   - bench_python (the in-process Python module) beside the C++ call and that node's rospy
#     services (<dir>/bench_python.md, table python);
#   - bench_node_live on the demo arm (its pillar) and on panda (a 640 x 480 depth camera):
#     certified motions while clouds arrive (<dir>/bench_node_live_<robot>.md, tables
#     live_world_service_<robot>).
# BENCH_QUICK=true: fewer calls, shorter series, a smaller image (make test).
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="/usr/bin:$PATH"
out=${1:-build/bench}
mkdir -p "$out"
out=$(cd "$out" && pwd)
robots=${BVH_COLLISION_ROBOTS:-$(pwd)/../shared/robots}
quick=${BENCH_QUICK:-false}
set +u
# shellcheck disable=SC1091
source devel/setup.bash
set -u
export ROS_PACKAGE_PATH="$robots/panda:$ROS_PACKAGE_PATH"
launch_pid=
stop_node() {
  [[ -n $launch_pid ]] || return 0
  kill -INT "$launch_pid" 2>/dev/null || true
  wait "$launch_pid" 2>/dev/null || true
  launch_pid=
}
trap stop_node EXIT
# start_node URDF SRDF PROXY_LEVELS: the node alone on a new private master.
start_node() {
  local port
  port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
  export ROS_MASTER_URI="http://127.0.0.1:$port"
  local log
  log=$(mktemp /tmp/bvh_collision_bench.XXXXXX.log)
  roslaunch --port "$port" bvh_collision collision_checker.launch robot_description_file:="$1" \
    robot_description_semantic_file:="$2" proxy_levels:="$3" > "$log" 2>&1 &
  launch_pid=$!
}

start_node "$robots/panda/robot.urdf" "$robots/panda/robot.srdf" "[0.01]"
devel/lib/bvh_collision/bench_node _urdf_file:="$robots/panda/robot.urdf" _output_dir:="$out" _quick:="$quick" \
  | tee "$out/bench_node.md"
# The Python module beside the C++ call and this node's rospy services (table python).
quick_flag=$([[ $quick == true ]] && echo --quick || true)
BVH_COLLISION_ROBOTS="$robots" python3 scripts/bench_python.py "$out" $quick_flag --node /collision_checker \
  | tee "$out/bench_python.md"
stop_node

start_node "$(pwd)/urdf/demo_arm.urdf" "" "[0.01]"
devel/lib/bvh_collision/bench_node_live _urdf_file:="$(pwd)/urdf/demo_arm.urdf" _robot:=demo_arm _scene:=pillar \
  _output_dir:="$out" _quick:="$quick" | tee "$out/bench_node_live_demo_arm.md"
stop_node

start_node "$robots/panda/robot.urdf" "$robots/panda/robot.srdf" "[0.01]"
devel/lib/bvh_collision/bench_node_live _urdf_file:="$robots/panda/robot.urdf" _robot:=panda _scene:=table \
  _output_dir:="$out" _quick:="$quick" | tee "$out/bench_node_live_panda.md"
stop_node

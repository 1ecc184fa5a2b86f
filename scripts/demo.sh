#!/usr/bin/env bash
# `make demo`: starts launch/demo.launch (the demo robot, robot_state_publisher, a scene publisher
# with a synthetic obstacle cloud, the checker) on a private ROS master, calls every service with
# demo_client and prints what it asked, what came back and the round-trip times, plans a motion
# around the obstacle with plan_demo (OMPL), then shuts down.
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
# RVIZ=true (make demo RVIZ=true, on a desktop): rviz too, and the planned path stays up a minute.
rviz=${RVIZ:-false}
roslaunch --port "$port" bvh_collision demo.launch rviz:="$rviz" > "$log" 2>&1 &
launch_pid=$!
trap 'kill -INT $launch_pid 2>/dev/null; wait $launch_pid 2>/dev/null || true' EXIT

echo "demo: starting the collision checker on the demo robot (log: $log)"
# ~ready: the robot summary is set and every service is served (60 s at most).
ready() { [[ "$(rosparam get /collision_checker/ready 2>/dev/null)" == "true" ]]; }
for _ in $(seq 1 300); do
  ready && break
  kill -0 $launch_pid 2>/dev/null || { cat "$log"; echo "demo: roslaunch exited" >&2; exit 1; }
  sleep 0.2
done
ready || { cat "$log"; echo "demo: the node did not become ready" >&2; exit 1; }

echo
echo "The node's start-up line:"
grep -o 'collision_checker: robot.*' "$log" | sed 's/\x1b\[[0-9;]*m//g' | head -1 || true
echo
echo "Scene: the demo arm upright at the origin of 'world'; a camera at (1.2, 0, 1.0) publishes"
echo "a cloud of a 0.12 x 0.12 x 0.8 m pillar at (0.45, 0.35, 0.4) in its own frame, twice a second."
echo "Times are round trips from this client (a new connection per call, as rosservice makes)."
devel/lib/bvh_collision/demo_client
echo
echo "Planning (OMPL's RRTConnect) from leaning forward on one side of the pillar to the other side,"
echo "with the checker in-process (on a copy of the node's octree) and through the node's services:"
# (only plan_demo's own lines: "plan_demo: ..." and its indented table)
hold=${PLAN_DEMO_HOLD:-$([[ "$rviz" == true ]] && echo 60 || echo 0)}
roslaunch bvh_collision plan_demo.launch hold:="$hold" 2>&1 | grep -E '^plan_demo: |^  [a-z]' || true
echo
[[ "$rviz" == true ]] || echo "With rviz: make demo RVIZ=true (the robot, the cloud, the voxels, the contacts and the planned path)"

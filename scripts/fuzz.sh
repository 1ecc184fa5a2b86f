#!/usr/bin/env bash
# The body of `make fuzz`: builds the libFuzzer targets with clang (./build-fuzz; the project's
# code under ASan + UBSan with coverage) and runs each for FUZZ_SECONDS (default 60), starting
# from its seed corpus in test/fuzz/corpus/<target>. New inputs go to build-fuzz/corpus/<target>
# (not kept); a crash or a violated invariant is written to test/fuzz/corpus/<target>/crash-<hash>
# so that `make test` replays it from then on (commit it with its fix). Prints executions per
# target; exits non-zero when any target found something.
set -uo pipefail
cd "$(dirname "$0")/.."
export PATH="/usr/bin:$PATH"
FUZZ_BUILD=${FUZZ_BUILD:-build-fuzz}
SECONDS_PER_TARGET=${FUZZ_SECONDS:-60}
JOBS=${JOBS:-2}
TARGETS=${FUZZ_TARGETS:-"robot_description mesh srdf octree_file scene_file point_cloud service_request"}

CC=clang CXX=clang++ cmake -S . -B "$FUZZ_BUILD" -DBVH_COLLISION_FUZZ=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCATKIN_ENABLE_TESTING=OFF > "$FUZZ_BUILD.configure.log" 2>&1 || { tail -20 "$FUZZ_BUILD.configure.log"; exit 1; }
make -C "$FUZZ_BUILD" -j"$JOBS" fuzz_targets || exit 1

# service_request runs a whole node, which advertises its services: a master of its own on a
# free port, for the length of the run.
MASTER_PID=""
stop_master() { [[ -n "$MASTER_PID" ]] && kill "$MASTER_PID" 2>/dev/null; wait 2>/dev/null; }
trap stop_master EXIT
if [[ " $TARGETS " == *" service_request "* ]]; then
  port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("", 0)); print(s.getsockname()[1])')
  rosmaster --core -p "$port" > "$FUZZ_BUILD.master.log" 2>&1 &
  MASTER_PID=$!
  export ROS_MASTER_URI="http://localhost:$port"
  for _ in $(seq 50); do rosnode list > /dev/null 2>&1 && break; sleep 0.2; done
fi

status=0
summary=()
for target in $TARGETS; do
  seeds="test/fuzz/corpus/$target"
  work="$FUZZ_BUILD/corpus/$target"
  mkdir -p "$work"
  binary=$(find "$FUZZ_BUILD" devel -name "fuzz_$target" -type f -perm -u+x 2>/dev/null | head -1)
  echo "== fuzz_$target for ${SECONDS_PER_TARGET} s"
  log="$FUZZ_BUILD/fuzz_$target.log"
  # A certified motion may check up to 20,000 states before it gives up: seconds in Release,
  # beyond 20 s under ASan and coverage, which is not a hang.
  timeout=20
  [[ $target == service_request ]] && timeout=120
  ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
    "$binary" -max_total_time="$SECONDS_PER_TARGET" -rss_limit_mb=2048 -timeout="$timeout" -max_len=65536 \
    -artifact_prefix="$seeds/" -print_final_stats=1 "$work" "$seeds" > "$log" 2>&1
  rc=$?
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  if [[ $rc != 0 ]]; then
    status=1
    grep -E "invariant violated|ERROR:|SUMMARY:|Test unit written" "$log" | head -5
  fi
  summary+=("fuzz_$target: ${runs:-?} executions in ${SECONDS_PER_TARGET} s, $( [[ $rc == 0 ]] && echo "nothing found" || echo "FOUND a failure (see $log)")")
done
printf '%s\n' "${summary[@]}"
exit $status

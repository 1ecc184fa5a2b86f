#!/usr/bin/env bash
# The body of `make soak`: node_soak.test (the node on panda for SOAK_SECONDS, default 600, under
# four clients, 10 Hz clouds and a moving arm) through rostest, its table written to
# <dir>/soak.md. Exits non-zero when a call failed, memory grew by 5 % or more after the first
# minute, or the last minute's p99 latency exceeded 1.5 times the first's.
set -uo pipefail
cd "$(dirname "$0")/.."
export PATH="/usr/bin:$PATH"
out=${1:-build/soak}
mkdir -p "$out"
set +u
# shellcheck disable=SC1091
source devel/setup.bash
set -u
log="$out/soak.log"
rostest --text bvh_collision node_soak.test duration:="${SOAK_SECONDS:-600}" > "$log" 2>&1
status=$?
# rostest --text exits 0 whatever the test said: the test's own verdict decides.
grep -a -q '\[  PASSED  \] 1 test' "$log" || status=1
{
  echo "# Soak: the node on panda, 4 clients, 10 Hz clouds, the arm moving ($(date -u +%F))"
  echo
  grep -a -E '^\| ' "$log"
} > "$out/soak.md"
cat "$out/soak.md"
grep -a -E "RESULT|FAILURE" "$log" | head -5
exit $status

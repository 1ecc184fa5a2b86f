#!/usr/bin/env bash
# make test-busy: the Release unit tests and the launch tests (no sanitizer pass) with two busy
# loops at normal priority beside them, as on a robot computer that runs drivers, a planner and
# perception beside the node. A test that fails here depends on the machine's speed: it must
# bound work or wait for events, not time (docs/testing.md). The last line is the same
# `N passed, N failed, N skipped` as make test's; the exit status is non-zero on any failure.
set -uo pipefail
cd "$(dirname "$0")/.."

loops=()
stop_loops() {
  for pid in "${loops[@]}"; do kill "$pid" 2>/dev/null; done
  for pid in "${loops[@]}"; do wait "$pid" 2>/dev/null; done
}
trap stop_loops EXIT
for _ in 1 2; do
  ( while :; do :; done ) &
  loops+=($!)
done
echo "== two busy loops at normal priority: pids ${loops[*]}"
CI= SANITIZE=0 bash scripts/run_tests.sh

#!/usr/bin/env bash
# The body of `make test`: the Release build (what `make build` builds), catkin_lint, then every
# unit and launch test of the Release build and the Python module's pytest suite
# (unless SANITIZE=1), and the unit tests under AddressSanitizer and UndefinedBehaviorSanitizer
# on the library of their own build folder (when SANITIZE=1 or CI=true; beside the launch tests
# and pytest, at the lowest priority, when both run). The last line is the combined count,
# `N passed, N failed, N skipped`; the exit status is non-zero when anything failed.
#
# Unit tests need no master and share nothing, so ctest runs JOBS of them at once (through
# catkin's run_tests.py, which writes each XML result, a failure one when a test crashes). Launch
# tests start masters and time services, so they run one at a time.
set -uo pipefail
cd "$(dirname "$0")/.."
export PATH="/usr/bin:$PATH"

BUILD=${BUILD:-build}
SAN_BUILD=${SAN_BUILD:-build-sanitize}
JOBS=${JOBS:-2}
BUILD_JOBS=${BUILD_JOBS:-3}
run_normal=1; run_sanitized=0
[[ "${SANITIZE:-0}" == "1" ]] && { run_normal=0; run_sanitized=1; }
[[ "${CI:-}" == "true" ]] && run_sanitized=1

# Every gtest of a build folder, JOBS at a time; a failure's output is printed in full.
unit_tests() {
  ctest --test-dir "$1" -j"$JOBS" -R '^_ctest_bvh_collision_gtest_' --output-on-failure
}

# The sanitized build: the project's libraries (-O1, ASan's advice: 28 % less compile time than
# -O2 for 20 % more test time, and the build is what the pass waits on; -g1: line tables for the
# sanitizers' reports, a third less compile time than -g) and the three tests that link a static project library. The
# tests themselves are not instrumented (CMakeLists.txt), so every other unit test runs again
# from the Release build on the sanitized library (scripts/run_preloaded_tests.py), as soon as
# the library is built (the file library_built marks it): the three tests are built after the
# library, beside that pass if it has started, and run after it.
own_tests=(test_check_tool test_fuzz_replay test_ros_conversions)
san_build_pid=""
# The build's exit status lands in $SAN_BUILD.build.status (the pass may run in a subshell, which
# cannot wait for a process it did not start).
start_sanitized_build() {
  rm -f "$SAN_BUILD/library_built" "$SAN_BUILD.build.status"
  ( { nice -n 19 cmake -S . -B "$SAN_BUILD" -DBVH_COLLISION_SANITIZE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo \
        -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" > "$SAN_BUILD.configure.log" 2>&1 \
      && nice -n 19 make -C "$SAN_BUILD" -j"$JOBS" bvh_collision_session bvh_collision_io \
      && touch "$SAN_BUILD/library_built" \
      && nice -n 19 make -C "$SAN_BUILD" -j"$JOBS" "${own_tests[@]}"; } > "$SAN_BUILD.build.log" 2>&1
    echo $? > "$SAN_BUILD.build.status" ) &
  san_build_pid=$!
}
# A failed build, as a failing test case.
sanitizer_build_failed() {
  tail -40 "$SAN_BUILD.configure.log" "$SAN_BUILD.build.log" 2>/dev/null
  echo "sanitizer build failed ($1)"
  mkdir -p "$SAN_BUILD/test_results"
  echo "<testsuite><testcase classname=\"sanitizer\" name=\"build $1\"><failure/></testcase></testsuite>" \
    > "$SAN_BUILD/test_results/build_failure_$1.xml"
}

# The unit tests under the sanitizers, once the sanitized library is built; non-zero on any
# failure. At the lowest priority, as the build: beside the launch tests (which wait on services
# and clocks, three quarters of one core over their 3.5 minutes) it takes the CPU they leave.
sanitized_pass() {
  local pass_status=0
  echo "== unit tests under ASan + UBSan ($SAN_BUILD) $(date +%T)"
  while [[ ! -e "$SAN_BUILD/library_built" && ! -e "$SAN_BUILD.build.status" ]]; do sleep 2; done
  if [[ ! -e "$SAN_BUILD/library_built" ]]; then
    sanitizer_build_failed library
    return 1
  fi
  echo "== sanitized library built $(date +%T)"
  rm -rf "$SAN_BUILD/test_results"
  export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}
  export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/scripts/lsan.supp:print_suppressions=0}
  export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}
  nice -n 19 python3 scripts/run_preloaded_tests.py "$BUILD" "$SAN_BUILD/devel/lib" "$SAN_BUILD/test_results/bvh_collision" "$JOBS" \
    "${own_tests[@]}" test_bench_report test_layers || pass_status=1  # (test_layers reads sources and symbols only)
  echo "== the sanitized build's own tests $(date +%T)"
  while [[ ! -e "$SAN_BUILD.build.status" ]]; do sleep 2; done
  if [[ "$(cat "$SAN_BUILD.build.status")" == 0 ]]; then
    nice -n 19 ctest --test-dir "$SAN_BUILD" -j"$JOBS" -R "^_ctest_bvh_collision_gtest_($(IFS='|'; echo "${own_tests[*]}"))\$" \
      --output-on-failure || pass_status=1
  else
    sanitizer_build_failed tests
    pass_status=1
  fi
  catkin_test_results "$SAN_BUILD/test_results" > /dev/null || pass_status=1
  echo "== sanitized pass done $(date +%T)"
  return $pass_status
}

# The sanitized build starts first, at the lowest priority: it takes the CPU the Release build
# and the tests leave (a build's serial steps and links; the tail of the unit tests; the launch
# tests, one at a time, mostly wait on services and clocks) and little else (nice 19 weighs 1.5 %
# of a nice-0 process).
[[ $run_sanitized == 1 ]] && start_sanitized_build

echo "== Release build ($BUILD) $(date +%T)"
if ! { cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=Release && make -C "$BUILD" -j"$BUILD_JOBS" all \
       && make -C "$BUILD" -j"$BUILD_JOBS" tests; }; then
  echo "Release build failed"
  [[ -n "$san_build_pid" ]] && { pkill -P "$san_build_pid"; kill "$san_build_pid"; } 2>/dev/null
  echo "0 passed, 1 failed, 0 skipped"
  exit 1
fi

# The robots' link proxies and clearance grids the tests share (test/robot_data.h: proxy_cache_dir),
# built afresh by each run: a cache left by other code is not what this code builds.
rm -rf "$BUILD/test_proxy_cache"

lint_dir="$BUILD/lint_results"
result_dirs=("$lint_dir")
status=0

# catkin_lint: one test case, failed on any error (warnings are printed, not fatal).
rm -rf "$lint_dir" && mkdir -p "$lint_dir"
echo "== catkin_lint"
if lint_out=$(catkin_lint -W1 . 2>&1); then lint_failure=""; else
  lint_failure="<failure message=\"catkin_lint reported errors\"/>"; status=1; fi
echo "$lint_out"
cat > "$lint_dir/catkin_lint.xml" <<XML
<testsuite name="catkin_lint" tests="1"><testcase classname="catkin_lint" name="package">${lint_failure}</testcase></testsuite>
XML

if [[ $run_normal == 1 ]]; then
  echo "== unit and launch tests ($BUILD) $(date +%T)"
  rm -rf "$BUILD/test_results"
  unit_tests "$BUILD" || status=1
  # The sanitized pass beside the launch tests and pytest, its output kept for the end.
  pass_pid=""
  if [[ $run_sanitized == 1 ]]; then
    rm -f "$SAN_BUILD.pass.status"
    ( sanitized_pass > "$SAN_BUILD.pass.log" 2>&1; echo $? > "$SAN_BUILD.pass.status" ) &
    pass_pid=$!
  fi
  echo "== launch tests ($BUILD) $(date +%T)"
  # The nodes' default cache ($ROS_HOME/bvh_collision/proxy_cache) in a fresh $ROS_HOME of the
  # build: proxies and grids another version of the code left in ~/.ros are not what this one builds.
  rm -rf "$BUILD/ros_home"
  ROS_HOME="$PWD/$BUILD/ros_home" ctest --test-dir "$BUILD" -R '^_ctest_bvh_collision_rostest_' --output-on-failure || status=1
  # The in-process Python module (docs/python.md) with pytest, its cases counted from its XML.
  echo "== Python module (pytest) $(date +%T)"
  ( set +u; source devel/setup.bash; set -u
    python3 -m pytest -q -p no:cacheprovider test/python --junitxml="$BUILD/test_results/bvh_collision/pytest-python.xml" ) \
    || status=1
  # catkin_test_results is the gate; its counts double gtest cases, so the summary counts XML.
  catkin_test_results "$BUILD/test_results" > /dev/null || status=1
  result_dirs+=("$BUILD/test_results")
fi

if [[ $run_sanitized == 1 ]]; then
  if [[ -n "${pass_pid:-}" ]]; then
    echo "== waiting on the sanitized pass $(date +%T)"
    wait "$pass_pid"
    cat "$SAN_BUILD.pass.log"
    [[ "$(cat "$SAN_BUILD.pass.status" 2>/dev/null)" == 0 ]] || status=1
  else
    [[ -z "$san_build_pid" ]] && start_sanitized_build
    sanitized_pass || status=1
  fi
  result_dirs+=("$SAN_BUILD/test_results")
fi

echo "== summary $(date +%T)"
[[ $run_normal == 1 ]] && python3 scripts/test_summary.py "release" "$BUILD/test_results" | tail -1
[[ $run_sanitized == 1 ]] && python3 scripts/test_summary.py "sanitized" "$SAN_BUILD/test_results" | tail -1
python3 scripts/test_summary.py "total" "${result_dirs[@]}" > "$BUILD/test_summary.txt" || status=1
grep '^FAILED' "$BUILD/test_summary.txt"
tail -1 "$BUILD/test_summary.txt" | sed 's/^total: //'
exit $status

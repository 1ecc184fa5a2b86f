#!/usr/bin/env python3
"""The sanitizer pass of `make test`, without a second build of the tests.

Usage: run_preloaded_tests.py RELEASE_BUILD SANITIZED_LIB_DIR RESULTS_DIR JOBS [SKIP ...]

The unit tests are not instrumented in either build (only the project's libraries are: see
CMakeLists.txt), so the Release build's test programs are run again, each with the sanitized
libbvh_collision_core.so found first (LD_LIBRARY_PATH beats their RUNPATH) and AddressSanitizer's
runtime preloaded (an uninstrumented program must load it first). Tests named in SKIP (those
linking a static project library, which the sanitized build runs itself) are left out, and so are
the cases in SANITIZER_FILTERS. Tests run
JOBS at a time, longest first (their ctest COST); each writes its gtest XML into RESULTS_DIR, and
one that dies before writing it (a sanitizer report aborts) gets a failure XML. Prints a ctest-like
line per test and the output of each failure; exits non-zero when any failed.
"""
import json
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from xml.sax.saxutils import escape

PREFIX = "_ctest_bvh_collision_gtest_"

# Cases the sanitizer pass leaves out: the same checks on the heaviest robots, whose load (hierarchies,
# clearance grids) takes minutes under ASan + UBSan; the Release pass runs them, and the sanitizers
# meet the same code on the robots kept (panda, abb_irb2400, panda_capsules, the demo arm).
SANITIZER_FILTERS = {
    "test_self_collision": "-Robots/SelfCollision.*/1:Robots/SelfCollision.*/2:Robots/SelfCollision.*/4",  # ur5e, pr2, solo
    "test_pair_clearance": "-Robots/PairClearanceOnRobot.*/1:Robots/PairClearanceOnRobot.*/2",  # ur5e, pr2
    # Contract sweeps over thousands of exact distance queries (55 s and 38 s under the
    # sanitizers): the code they drive runs sanitized in the same files' other cases and in
    # test_attached_objects, test_allowed_objects and test_ompl_validity; the Release pass keeps them.
    "test_tolerance_policy": "-TolerancePolicy.EachToleranceClassKeepsTheContractOnEveryKindPair",
    "test_scene_checker": "-SceneChecker.CertifiedMotionsHoldOnADenseSweep",
    # k-DOPs of 18 and 26 directions: the 14-direction one's code with other tables.
    "test_bvh": "-BvhOracle/4.*:BvhOracle/5.*",
}


def unit_tests(build, skip):
    shown = subprocess.run(["ctest", "--test-dir", build, "--show-only=json-v1"], check=True,
                           capture_output=True, text=True).stdout
    tests = []
    for t in json.loads(shown)["tests"]:
        name = t["name"]
        if not name.startswith(PREFIX) or name[len(PREFIX):] in skip:
            continue
        program = t["command"][-1].split()[0]  # run_tests.py's last argument: "<program> --gtest_output=..."
        cost = next((float(p["value"]) for p in t.get("properties", []) if p["name"] == "COST"), 0.0)
        tests.append((cost, name[len(PREFIX):], program))
    tests.sort(key=lambda t: -t[0])
    return [(name, program) for _, name, program in tests]


def main(argv):
    if len(argv) < 5:
        print(__doc__, file=sys.stderr)
        return 2
    build, lib_dir, results = os.path.abspath(argv[1]), os.path.abspath(argv[2]), os.path.abspath(argv[3])
    jobs, skip = int(argv[4]), set(argv[5:])
    os.makedirs(results, exist_ok=True)
    asan = subprocess.run(["gcc", "-print-file-name=libasan.so"], check=True, capture_output=True, text=True).stdout.strip()
    env = dict(os.environ, LD_PRELOAD=asan, LD_LIBRARY_PATH=lib_dir + os.pathsep + os.environ.get("LD_LIBRARY_PATH", ""))
    tests = unit_tests(build, skip)
    done = []

    def run(test):
        name, program = test
        xml = os.path.join(results, "gtest-%s.xml" % name)
        if os.path.exists(xml):
            os.remove(xml)
        start = time.time()
        args = [program, "--gtest_output=xml:" + xml]
        if name in SANITIZER_FILTERS:
            args.append("--gtest_filter=" + SANITIZER_FILTERS[name])
        p = subprocess.run(args, env=env, cwd=build, capture_output=True, text=True)
        seconds = time.time() - start
        failed = p.returncode != 0
        # A program that died before gtest wrote its report, or failed after it (a leak found at
        # exit), gets a failure of its own, so that the summary counts it.
        exit_xml = os.path.join(results, "gtest-%s-exit.xml" % name)
        if os.path.exists(exit_xml):
            os.remove(exit_xml)
        if failed and (not os.path.exists(xml) or 'failures="0"' in open(xml).read().split("<testsuite ", 1)[0]):
            with open(exit_xml if os.path.exists(xml) else xml, "w") as f:
                f.write('<testsuites><testsuite name="%s" tests="1" failures="1"><testcase classname="%s" name="run">'
                        '<failure message="%s"/></testcase></testsuite></testsuites>\n'
                        % (name, name, escape("exit status %d" % p.returncode, {'"': "&quot;"})))
        done.append(name)
        print("%2d/%d %-45s %s %8.2f sec" % (len(done), len(tests), name, "***Failed" if failed else "Passed", seconds),
              flush=True)
        if failed:
            print(p.stdout[-20000:] + p.stderr[-20000:], flush=True)
        return not failed

    with ThreadPoolExecutor(max_workers=jobs) as pool:
        passed = list(pool.map(run, tests))
    return 0 if all(passed) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))

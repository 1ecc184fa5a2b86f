#!/usr/bin/env python3
"""Counts test cases in gtest/rostest JUnit XML files and prints `N passed, N failed, N skipped`.

Debian's catkin_test_results counts a gtest file's <testsuites> and <testsuite> totals both, so
every gtest case is counted twice; this counts <testcase> elements instead. A rostest run writes
two files: rosunit-*.xml (the test node's own cases) and rostest-*.xml (one case: the launch ran
and the test node reported); both are counted.

Usage: test_summary.py LABEL DIR [DIR...]   exits 1 when a case failed or when there is none.
"""
import pathlib
import sys
import xml.etree.ElementTree as ET


def count(directory):
    passed, failed, skipped, failures = 0, 0, 0, []
    for path in sorted(pathlib.Path(directory).rglob("*.xml")):
        try:
            root = ET.parse(path).getroot()
        except ET.ParseError as error:
            failed += 1
            failures.append(f"{path}: unreadable result file ({error})")
            continue
        for case in root.iter("testcase"):
            name = f"{path.name}: {case.get('classname', '')}.{case.get('name', '')}"
            if case.find("failure") is not None or case.find("error") is not None:
                failed += 1
                failures.append(name)
            elif case.find("skipped") is not None or case.get("result") == "skipped":
                skipped += 1
            else:
                passed += 1
    return passed, failed, skipped, failures


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    label, totals = sys.argv[1], [0, 0, 0]
    for directory in sys.argv[2:]:
        passed, failed, skipped, failures = count(directory)
        for line in failures:
            print(f"FAILED {line}")
        totals = [totals[0] + passed, totals[1] + failed, totals[2] + skipped]
    print(f"{label}: {totals[0]} passed, {totals[1]} failed, {totals[2]} skipped")
    sys.exit(1 if totals[1] or not totals[0] else 0)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""The Python module's cost (make bench, table `python`; issue 59): per state and per certified
motion through bvh_collision.Checker for batches of 1, 100 and 10,000, beside the same C++ call in
the same process (timed inside C++: bvh_collision._core._cpp_seconds) and, with --node, beside the
node's check_states / check_motions through rospy on persistent connections.

Usage: bench_python.py OUTPUT_DIR [--quick] [--node /collision_checker]
Panda from ../shared/robots (or $BVH_COLLISION_ROBOTS) with its SRDF, the same wall of points the
service benchmark gives the node (bench/bench_node.cpp), so the two answer the same world.
Target: the module within 1.2x of the C++ call for batches of 100 and more.
"""
import json
import os
import platform
import statistics
import sys
import time

import numpy as np

import bvh_collision
from bvh_collision import _core

TARGET = 1.2


def machine():
    model, flags = "unknown CPU", ""
    with open("/proc/cpuinfo") as f:
        for line in f:
            if line.startswith("model name") and model == "unknown CPU":
                model = line.split(":", 1)[1].strip()
            if line.startswith("flags") and not flags:
                flags = line
    simd = next((s for s, flag in (("AVX-512F", " avx512f"), ("AVX2", " avx2"), ("SSE2", " sse2")) if flag in flags), "?")
    return f"{model} (widest SIMD: {simd}), {os.cpu_count()} cores, Python {platform.python_version()}"


def wall():
    i, j = np.meshgrid(np.arange(80), np.arange(60), indexing="ij")
    return np.stack([np.full(i.size, 0.6), -0.8 + 0.02 * i.ravel(), 0.02 * j.ravel()], axis=1).astype(np.float32)


def median_per_item(seconds, items):
    return 1e6 * statistics.median(seconds) / items


def timed_chunks(call, chunks):
    out = []
    for a, b in chunks:
        t0 = time.perf_counter()
        call(a, b)
        out.append(time.perf_counter() - t0)
    return out


class ServicePath:
    """The node's services through rospy (scripts/collision_client.py), or nothing without --node."""

    def __init__(self, node):
        self.client = None
        if node:
            sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
            import rospy
            from collision_client import CollisionClient
            rospy.init_node("bench_python", anonymous=True, disable_signals=True)
            self.client = CollisionClient(node)

    def states(self, names, q, _=None):
        return lambda: self.client.check_states(names, q.tolist())

    def motions(self, names, a, b):
        return lambda: self.client.check_motions(names, list(zip(a.tolist(), b.tolist())))


def rows_for(checker, service, kind, batches, quick):
    names, lo, hi = checker.joint_names, checker.limits[:, 0], checker.limits[:, 1]
    rng = np.random.default_rng(1)

    def draw(rows):  # random states, and motions of at most 0.3 rad a joint from them
        a = rng.uniform(lo, hi, size=(rows, checker.dof))
        return a, np.clip(a + rng.uniform(-0.3, 0.3, size=a.shape), lo, hi)

    out = []
    for n in batches:
        repeats = 3 if quick else (5 if n >= 10000 else 30 if n >= 100 else 300)
        # Each call its own rows (a motion asked again is answered from memory), and each path its own.
        chunks = [draw(n) for _ in range(repeats)]
        call = checker.check_states if kind == "states" else checker.check_motions
        module = timed_chunks(lambda a, b: call(a) if kind == "states" else call(a, b), chunks)
        a, b = draw(n * repeats)
        cpp = _core._cpp_seconds(checker, kind, a, b, n)
        ros_times = None
        if service.client:
            ros_call = service.states if kind == "states" else service.motions
            ros_times = timed_chunks(lambda a, b: ros_call(names, a, b)(), [draw(n) for _ in range(repeats)])
        ours, base = median_per_item(module, n), median_per_item(cpp, n)
        met = n < 100 or ours <= TARGET * base
        ros = median_per_item(ros_times, n) if ros_times else None
        out.append([f"check_{kind}", n, ours, base, ours / base, ros if ros else "-", ros / base if ros else "-",
                    "(latency)" if n < 100 else f"<= {TARGET}x", "yes" if met else "NO"])
    return out


def main(argv):
    if len(argv) < 2:
        sys.exit(__doc__)
    out_dir, quick = argv[1], "--quick" in argv[2:]
    node = argv[argv.index("--node") + 1] if "--node" in argv else ""
    robots = os.environ.get("BVH_COLLISION_ROBOTS", os.path.join(os.path.dirname(__file__), "..", "..", "shared", "robots"))
    panda = os.path.join(robots, "panda")
    # The node's proxy level too (scripts/bench_node.sh starts it so): proxies prove pairs apart in
    # exact checks and certified motions as well.
    checker = bvh_collision.Checker(os.path.join(panda, "robot.urdf"), os.path.join(panda, "robot.srdf"), package_paths=[panda],
                                    proxy_levels=[0.01])
    checker.insert_cloud(wall(), origin=[0.0, 0.0, 0.0], q=np.zeros(checker.dof), max_range=5.0)
    service = ServicePath(node)
    batches = [1, 100, 1000] if quick else [1, 100, 10000]
    rows = rows_for(checker, service, "states", batches, quick) + rows_for(checker, service, "motions", batches, quick)
    table = {
        "id": "python", "title": "Python in-process (bvh_collision.Checker) against the C++ call and the rospy service",
        "machine": machine(),
        "columns": ["query", "batch", "module us per item", "C++ us per item", "module / C++", "rospy us per item",
                    "rospy / C++", "target", "met"],
        "rows": rows,
        "notes": ["Panda with its SRDF, a 10 mm proxy level (as the node) and a wall of 4,800 points in a 2 cm octree (self and "
                  "environment, exact); "
                  "states drawn within the limits, motions of at most 0.3 rad a joint, certified. The C++ column times "
                  "the same call inside C++ with no Python between (bvh_collision._core._cpp_seconds); medians over "
                  "repeated calls. The rospy column calls the node (started by scripts/bench_node.sh on the same robot "
                  "and wall) on persistent connections" + ("" if node else ": not run here (no --node)") + "."],
    }
    os.makedirs(os.path.join(out_dir, "tables"), exist_ok=True)
    with open(os.path.join(out_dir, "tables", "python.json"), "w") as f:
        json.dump(table, f, indent=1)
    print(f"# {table['title']} ({table['machine']})\n")
    print("| " + " | ".join(table["columns"]) + " |")
    for r in rows:
        print("| " + " | ".join(f"{c:.4g}" if isinstance(c, float) else str(c) for c in r) + " |")
    missed = [r for r in rows if r[-1] == "NO"]
    print("\ntargets: " + ("all met" if not missed else "some MISSED (see above)"))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

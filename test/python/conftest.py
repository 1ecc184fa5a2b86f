"""Shared fixtures of the in-process module's tests (make test runs them with pytest): the shared
robots (../shared/robots, or $BVH_COLLISION_ROBOTS) and the C++ command-line tool, whose answers
the module's must equal."""
import os
import pathlib
import subprocess

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
ROBOTS = pathlib.Path(os.environ.get("BVH_COLLISION_ROBOTS", REPO.parent / "shared" / "robots"))
CHECK_TOOL = REPO / "devel" / "lib" / "bvh_collision" / "bvh_collision_check"


def robot_files(name):
    folder = ROBOTS / name
    if not (folder / "robot.urdf").exists():
        pytest.fail(f"the shared robot {name} is not at {folder} (set BVH_COLLISION_ROBOTS)")
    srdf = folder / "robot.srdf"
    return str(folder / "robot.urdf"), str(srdf) if srdf.exists() else "", [str(folder)]


@pytest.fixture(scope="session")
def bvh():
    import bvh_collision
    return bvh_collision


@pytest.fixture(scope="session")
def panda(bvh):
    urdf, srdf, paths = robot_files("panda")
    return bvh.Checker(urdf, srdf, package_paths=paths)


def random_states(checker, count, seed):
    limits = checker.limits
    rng = np.random.default_rng(seed)
    return rng.uniform(limits[:, 0], limits[:, 1], size=(count, checker.dof))


def cpp_answers(robot, checker, states, scene=None):
    """The C++ tool's answer for each state: (colliding pairs as a set of 'a:b', distance)."""
    urdf, srdf, paths = robot_files(robot)
    tmp = REPO / "build" / f"pytest_states_{os.getpid()}.txt"
    with open(tmp, "w") as f:
        f.write("joints: " + " ".join(checker.joint_names) + "\n")
        for q in states:
            f.write(" ".join(repr(float(v)) for v in q) + "\n")
    args = [str(CHECK_TOOL), "--urdf", urdf, "--package-path", ":".join(paths), "--states", str(tmp), "--distance"]
    if srdf:
        args += ["--srdf", srdf]
    if scene:
        args += ["--scene", scene]
    out = subprocess.run(args, capture_output=True, text=True, check=True).stdout
    tmp.unlink()
    answers = []
    for line in out.splitlines():
        words = line.split()
        pairs = set(words[2].split(",")) if words[1] == "collision" else set()
        distance = float(next(w for w in words if w.startswith("distance=")).split("=")[1])
        answers.append((pairs, distance))
    assert len(answers) == len(states), out
    return answers

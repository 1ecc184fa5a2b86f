"""The in-process module (python/module.cpp) against the C++ answers: the command-line tool
(bvh_collision_check, the same engine through C++ alone) for states, distances, pairs and scenes;
exact oracles for rays, clouds and octree files; bad inputs raising; the GIL released."""
import os
import threading

import numpy as np
import pytest

from conftest import REPO, cpp_answers, random_states, robot_files

SCENE = str(REPO / "test" / "data" / "start.scene")


def pair(a, b):
    return ":".join(sorted((a, b)))


def test_loads_a_shared_robot(panda):
    assert panda.dof == len(panda.joint_names) == 8  # 7 arm joints and a finger (the other mimics it)
    assert panda.joint_names[0] == "panda_joint1"
    assert panda.limits.shape == (8, 2) and np.all(panda.limits[:, 0] < panda.limits[:, 1])
    assert "panda_hand" in panda.link_names


@pytest.mark.parametrize("robot", ["panda", "ur5e", "pr2"])
def test_states_equal_the_cpp_answers(bvh, robot):
    urdf, srdf, paths = robot_files(robot)
    checker = bvh.Checker(urdf, srdf, package_paths=paths)
    states = random_states(checker, 300, seed=1)
    valid = checker.check_states(states)
    valid_d, distance, nearest = checker.check_states(states, distance=True)
    expected = cpp_answers(robot, checker, states)
    assert valid.dtype == np.bool_ and valid.shape == (300,)
    assert list(valid) == [not pairs for pairs, _ in expected]
    assert list(valid_d) == list(valid)
    for i, (pairs, d) in enumerate(expected):
        assert distance[i] == pytest.approx(d, rel=1e-7, abs=1e-9), i
        if valid[i]:
            assert nearest[i][0] in checker.link_names and nearest[i][1] in checker.link_names
    assert 0 < valid.sum() < 300, "both kinds of state in the sample"


def test_contacts_name_the_cpp_pairs(panda):
    states = random_states(panda, 200, seed=2)
    expected = cpp_answers("panda", panda, states)
    for q, (pairs, _) in zip(states, expected):
        found = {pair(c["a"], c["b"]) for c in panda.contacts(q) if c["self"]}
        assert found == pairs


def test_a_scene_file_equals_the_cpp_answers(bvh):
    urdf, srdf, paths = robot_files("panda")
    checker = bvh.Checker(urdf, srdf, package_paths=paths)
    assert checker.load_scene(SCENE) == []
    assert checker.object_ids == ["start_box"]
    states = random_states(checker, 300, seed=3)
    valid, distance, _ = checker.check_states(states, distance=True)
    expected = cpp_answers("panda", checker, states, scene=SCENE)
    assert list(valid) == [not pairs for pairs, _ in expected]
    for i, (_, d) in enumerate(expected):
        assert distance[i] == pytest.approx(d, rel=1e-7, abs=1e-9), i


def test_motions_are_certified(bvh):
    """A motion answered free has every state along it free (a 1/1000 sampling); one answered
    colliding is free up to its last valid fraction and meets a collision within a sampling step
    beyond (or starts or ends in one)."""
    urdf, srdf, paths = robot_files("panda")
    checker = bvh.Checker(urdf, srdf, package_paths=paths)
    checker.add_box("wall", [0.05, 1.0, 1.0], pose=[0.45, 0.0, 0.5, 0, 0, 0, 1])
    rng = np.random.default_rng(4)
    starts = random_states(checker, 60, seed=5)
    goals = starts + rng.uniform(-0.6, 0.6, size=starts.shape)
    goals = np.clip(goals, checker.limits[:, 0], checker.limits[:, 1])
    valid, fraction = checker.check_motions(starts, goals)
    assert valid.shape == fraction.shape == (60,)
    s = np.linspace(0.0, 1.0, 1001)
    for i in range(60):
        path = starts[i] + s[:, None] * (goals[i] - starts[i])
        free = checker.check_states(path)
        if valid[i]:
            assert fraction[i] == 1.0 and free.all(), i
        else:
            assert free[s < fraction[i] - 1e-12].all(), i
    assert valid.any() and not valid.all()
    one = checker.check_motions(starts[0], goals[0])
    assert (one[0][0], one[1][0]) == (valid[0], fraction[0]), "a single motion as a (dof,) row"


def test_a_ray_meets_a_box_where_it_is(bvh, panda):
    q = np.zeros(panda.dof)
    panda.add_box("target", [0.2, 0.2, 0.2], pose=np.array([[1, 0, 0, 2.0], [0, 1, 0, 0], [0, 0, 1, 1.5], [0, 0, 0, 1.0]]))
    try:
        hit = panda.cast_ray(q, np.array([0.0, 0.0, 1.5]), np.array([1.0, 0.0, 0.0]))
        assert hit["hit"] and hit["object"] == "target" and hit["link"] is None
        assert hit["distance"] == pytest.approx(1.9, abs=1e-9)
        assert hit["point"] == pytest.approx([1.9, 0.0, 1.5], abs=1e-9)
        miss = panda.cast_ray(q, [0.0, 0.0, 1.5], [-1.0, 0.0, 0.0], max_range=1.0)
        assert not miss["hit"]
    finally:
        assert panda.remove_object("target")


def test_a_cloud_fills_the_voxels_of_its_points_and_round_trips_through_a_file(bvh, tmp_path):
    urdf, srdf, paths = robot_files("panda")
    checker = bvh.Checker(urdf, srdf, package_paths=paths, octree_resolution=0.05)
    ys, zs = np.meshgrid(np.arange(-0.5, 0.5, 0.013), np.arange(0.0, 1.0, 0.013))
    points = np.stack([np.full(ys.size, 1.5), ys.ravel(), zs.ravel()], axis=1).astype(np.float32)
    stats = checker.insert_cloud(points, origin=[0.0, 0.0, 0.5])
    keys = {tuple(k) for k in np.floor(points.astype(np.float64) / 0.05).astype(int)}
    assert stats["points"] == len(points)
    assert checker.occupied_voxels == len(keys) == stats["occupied"]
    q = np.zeros(checker.dof)
    hit = checker.cast_ray(q, [0.5, 0.0, 0.5], [1.0, 0.0, 0.0])  # from beyond the arm, along +x
    assert hit["octree"] and hit["distance"] == pytest.approx(1.0, abs=0.051)
    path = str(tmp_path / "map.bt")
    checker.save_octree(path)
    other = bvh.Checker(urdf, srdf, package_paths=paths)
    other.load_octree(path)
    assert other.octree_resolution == 0.05 and other.occupied_voxels == len(keys)
    states = random_states(checker, 200, seed=6)
    assert list(other.check_states(states)) == list(checker.check_states(states))


def test_the_self_filter_keeps_the_robot_out_of_the_map(panda, bvh):
    urdf, srdf, paths = robot_files("panda")
    checker = bvh.Checker(urdf, srdf, package_paths=paths)
    q = np.zeros(checker.dof)
    near_base = np.array([[0.0, 0.0, 0.1]], dtype=np.float32)  # inside panda's base links
    checker.insert_cloud(near_base, origin=[1.0, 0.0, 1.0], q=q, self_filter_padding=0.05)
    assert checker.occupied_voxels == 0
    checker.insert_cloud(near_base, origin=[1.0, 0.0, 1.0])
    assert checker.occupied_voxels == 1


def test_attach_carries_an_object_and_detach_puts_it_back(bvh):
    urdf, srdf, paths = robot_files("panda")
    checker = bvh.Checker(urdf, srdf, package_paths=paths)
    q = np.zeros(checker.dof)
    checker.add_box("held", [0.04, 0.04, 0.04], pose=[0.088, 0.0, 0.80, 0, 0, 0, 1])
    states = random_states(checker, 300, seed=7)
    before = checker.check_states(states)
    checker.attach("held", "panda_hand", q, touch_links=["panda_leftfinger", "panda_rightfinger"])
    assert checker.object_ids == [] and checker.attached_ids == ["held"]
    carried = checker.check_states(states)
    assert not np.array_equal(carried, before), "the box moves with the hand"
    assert checker.detach("held", q) and checker.attached_ids == [] and checker.object_ids == ["held"]
    assert np.array_equal(checker.check_states(states), before)
    assert not checker.detach("held", q)


def test_meshes_from_arrays(panda):
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float) * 0.3
    triangles = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    panda.add_mesh("tetra", vertices, triangles, pose=[0.3, 0.0, 0.3, 0, 0, 0, 1])
    try:
        hit = panda.cast_ray(np.zeros(panda.dof), [0.35, 0.05, 2.0], [0.0, 0.0, -1.0])
        assert hit["object"] == "tetra"
    finally:
        panda.remove_object("tetra")


def test_a_tolerance_misses_no_collision(bvh):
    """docs/design.md: at tolerance t a state in collision is reported colliding, and one reported
    colliding is within t of a collision (checked against the exact distances)."""
    urdf, srdf, paths = robot_files("panda")
    checker = bvh.Checker(urdf, srdf, package_paths=paths, proxy_levels=[0.02])
    assert checker.proxy_levels == [0.02]
    states = random_states(checker, 2000, seed=8)
    exact, distance, _ = checker.check_states(states, distance=True)
    fast = checker.check_states(states, tolerance=0.02)
    assert not (fast & ~exact).any(), "a collision missed at the tolerance"
    assert (fast | (distance <= 0.02 + 1e-9)).all(), "a state reported colliding beyond the tolerance"
    assert (~exact).any()


def test_bad_inputs_raise_and_name_the_argument(panda, bvh):
    with pytest.raises(ValueError, match=r"q must have shape \(N, 8\)"):
        panda.check_states(np.zeros((3, 6)))
    nan = np.zeros((5, 8))
    nan[3, 2] = np.nan
    with pytest.raises(ValueError, match="state 3"):
        panda.check_states(nan)
    with pytest.raises(ValueError, match="tolerance"):
        panda.check_states(np.zeros((1, 8)), tolerance=-1.0)
    with pytest.raises(ValueError, match="same shape"):
        panda.check_motions(np.zeros((2, 8)), np.zeros((3, 8)))
    with pytest.raises(ValueError):
        panda.add_box("bad", [0.1, -0.1, 0.1])
    with pytest.raises(ValueError, match="quaternion"):
        panda.add_box("bad", [0.1, 0.1, 0.1], pose=[0, 0, 0, 0, 0, 0, 2])
    with pytest.raises(ValueError, match="vertex 7"):
        panda.add_mesh("bad", np.zeros((3, 3)), np.array([[0, 1, 7]]))
    with pytest.raises(ValueError, match=r"points must have shape \(N, 3\)"):
        panda.insert_cloud(np.zeros((4, 2)), origin=[0, 0, 0])
    with pytest.raises(ValueError, match="no link"):
        panda.attach("x", "no_such_link", np.zeros(8))
    with pytest.raises(RuntimeError):
        panda.load_octree("/nonexistent/map.bt")
    with pytest.raises(Exception, match="nonexistent"):
        panda.load_scene("/nonexistent/a.scene")
    with pytest.raises(Exception):
        bvh.Checker("<robot name='r'><link name='a'/></robot>")
    assert panda.object_ids == [], "nothing changed by a refused input"


def test_queries_release_the_gil(panda):
    """While one thread checks a large batch, another Python thread keeps running."""
    states = random_states(panda, 100000, seed=9)
    ticks, stop = [0], threading.Event()

    def count():
        while not stop.is_set():
            ticks[0] += 1

    counter = threading.Thread(target=count)
    counter.start()
    try:
        before = ticks[0]
        panda.check_states(states)
        during = ticks[0] - before
    finally:
        stop.set()
        counter.join()
    assert during > 1000


def test_urdf_and_srdf_given_as_text_answer_as_from_files(bvh, panda):
    urdf, srdf, paths = robot_files("panda")
    with open(urdf) as u, open(srdf) as s:
        from_text = bvh.Checker(u.read(), s.read(), package_paths=paths)
    assert from_text.joint_names == panda.joint_names
    states = random_states(panda, 300, seed=10)
    assert np.array_equal(from_text.check_states(states), panda.check_states(states))

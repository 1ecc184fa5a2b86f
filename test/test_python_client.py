#!/usr/bin/env python3
"""The rospy client (scripts/collision_client.py) on the demo scene, through the generated Python
messages: a free and a colliding state, a batch, a certified motion and a ray, each with the
answer the scene implies (the pillar at (0.45, 0.35, 0.4) that the camera's cloud shows)."""
import os
import sys
import time
import unittest

import rospy
import rostest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
from collision_client import BOTH, ENVIRONMENT, SELF, CheckerError, CollisionClient, pose  # noqa: E402
from shape_msgs.msg import SolidPrimitive  # noqa: E402

ARM = ["joint1", "joint2"]
HOME, LEAN = [0.0, 0.0], [0.66, 1.0]  # upright; leaning into the pillar


class PythonClient(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_python_client", anonymous=True)
        cls.client = CollisionClient("/collision_checker", timeout=60.0)
        # The pillar arrives with the camera's clouds (twice a second).
        deadline = time.time() + 30.0
        while time.time() < deadline and not cls.client.check_state(ARM, LEAN, checks=ENVIRONMENT).environment_collision:
            time.sleep(0.2)

    def test_free_and_colliding_states(self):
        free = self.client.check_state(ARM, HOME, distance=True)
        self.assertTrue(free.valid)
        self.assertGreater(free.min_distance, 0.0)
        hit = self.client.check_state(ARM, LEAN, max_contacts=1)
        self.assertFalse(hit.valid)
        self.assertTrue(hit.environment_collision)
        self.assertGreater(len(hit.contacts), 0)

    def test_batch(self):
        self.assertEqual(self.client.check_states(ARM, [HOME, LEAN, HOME]), [True, False, True])

    def test_motion(self):
        into = self.client.check_motion(ARM, HOME, LEAN)
        self.assertFalse(into.valid)
        self.assertGreater(into.last_valid_fraction, 0.0)
        self.assertLess(into.last_valid_fraction, 1.0)
        away = self.client.check_motion(ARM, HOME, [-1.0, 0.5])
        self.assertTrue(away.valid)
        self.assertEqual(away.last_valid_fraction, 1.0)
        both = self.client.check_motions(ARM, [(HOME, LEAN), (HOME, [-1.0, 0.5])])
        self.assertEqual([valid for valid, _ in both], [False, True])
        self.assertEqual(both[0][1], into.last_valid_fraction)

    def test_ray(self):
        ray = self.client.cast_ray((1.0, 0.35, 0.4), (-1.0, 0.0, 0.0))
        self.assertTrue(ray.hit)
        self.assertEqual(ray.body, "octree")
        self.assertAlmostEqual(ray.point.x, 0.51, delta=0.03)  # the pillar's near face, to a voxel

    def test_objects_and_errors(self):
        self.client.set_primitives("py_cone", [(SolidPrimitive.CONE, [0.4, 0.1], pose())], object_pose=pose((1.0, 0.0, 0.5)))
        ray = self.client.cast_ray((1.0, 0.5, 0.5), (0.0, -1.0, 0.0))
        self.assertEqual(ray.body, "py_cone")
        self.assertAlmostEqual(ray.distance, 0.45, places=9)  # the cone's radius at mid height: 0.05
        self.client.remove_object("py_cone")
        with self.assertRaises(CheckerError):
            self.client.remove_object("py_cone")
        with self.assertRaises(CheckerError):
            self.client.check_state(["no_such_joint"], [0.0], checks=SELF | ENVIRONMENT)
        self.assertEqual(BOTH, SELF | ENVIRONMENT)

    def test_scenes(self):
        # An object saved as a .scene file and loaded back (merged with what is there).
        self.client.set_primitives("py_box", [(SolidPrimitive.BOX, [0.1, 0.1, 0.1], pose())], object_pose=pose((1.0, -0.5, 0.5)))
        path = "/tmp/bvh_python_client_%d.scene" % os.getpid()
        self.client.save_scene(path, name="from python")
        self.client.remove_object("py_box")
        loaded = self.client.load_scene(path, merge=True)
        os.remove(path)
        self.assertEqual(loaded.name, "from python")
        self.assertGreaterEqual(loaded.objects, 1)
        self.assertEqual(self.client.cast_ray((1.0, 0.5, 0.5), (0.0, -1.0, 0.0)).body, "py_box")
        self.client.remove_object("py_box")
        with self.assertRaises(CheckerError):
            self.client.load_scene("/nonexistent/x.scene")

    def test_allowed_collisions(self):
        # A box around the arm at HOME collides; its default entry lets every link touch it, and
        # check_state names who does; removing the entry checks it again.
        self.client.set_primitives("py_wrap", [(SolidPrimitive.BOX, [0.3, 0.3, 0.3], pose())], object_pose=pose((0.0, 0.0, 0.6)))
        try:
            self.assertFalse(self.client.check_state(ARM, HOME, checks=ENVIRONMENT).valid)
            self.client.set_allowed_collisions(defaults=["py_wrap"])
            allowed = self.client.check_state(ARM, HOME, checks=ENVIRONMENT, report_allowed=True)
            self.assertTrue(allowed.valid)
            self.assertGreater(len(allowed.allowed_links), 0)
            self.assertEqual(set(allowed.allowed_objects), {"py_wrap"})
            with self.assertRaises(CheckerError):
                self.client.set_allowed_collisions(pairs=[("link1", "hand")])  # two links: the SRDF's
            self.client.set_allowed_collisions(defaults=["py_wrap"], remove=True)
            self.assertFalse(self.client.check_state(ARM, HOME, checks=ENVIRONMENT).valid)
        finally:
            self.client.remove_object("py_wrap")

    def test_attached_object(self):
        # A ball carried 0.3 m above the demo arm's hand (its frame at z = 1.25 m at HOME) is hit
        # by a ray from above as "py_ball"; put back into the world, it stays where it was carried.
        self.client.attach_object("py_ball", "hand", primitives=[(SolidPrimitive.SPHERE, [0.05], pose((0.0, 0.0, 0.3)))])
        try:
            ray = self.client.cast_ray((0.0, 0.0, 2.5), (0.0, 0.0, -1.0))
            self.assertEqual(ray.body, "py_ball")
            self.assertAlmostEqual(ray.point.z, 1.60, places=6)
            self.client.detach_object("py_ball")
            self.assertEqual(self.client.cast_ray((0.0, 0.0, 2.5), (0.0, 0.0, -1.0)).body, "py_ball")
            with self.assertRaises(CheckerError):
                self.client.detach_object("py_ball")  # no longer carried
        finally:
            self.client.remove_object("py_ball")


if __name__ == "__main__":
    rostest.rosrun("bvh_collision", "python_client", PythonClient)

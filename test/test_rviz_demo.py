#!/usr/bin/env python3
"""rviz, seen: demo.launch with rviz:=true under Xvfb (test/rviz_demo.test, started by xvfb-run).
Once the node's octree holds the camera's pillar, a colliding check_state has left its contacts and
plan_demo has published its planned path, the test takes a screenshot of the X display and checks
that each thing is drawn in the colours config/demo.rviz gives it: the cloud (magenta), the
occupied voxels (height colours, green at mid height), the planned path (yellow) and the contacts
(red spheres: red pixels that a screenshot taken before the colliding query did not have; the
voxels' top is red too), and that rviz logged no error (/rosout) and is still running. The screenshot goes to ~screenshot (README's docs/demo_rviz.png when
regenerated with BVH_COLLISION_SCREENSHOT)."""
import os
import subprocess
import sys
import time
import unittest

import rosnode
import rospy
import rostest
from PIL import Image
from rosgraph_msgs.msg import Log
from visualization_msgs.msg import Marker

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
from collision_client import ENVIRONMENT, CollisionClient  # noqa: E402

ARM = ["joint1", "joint2"]
LEAN = [0.66, 1.0]  # into the pillar


def count(pixels, test):
    return sum(1 for p in pixels if test(*p[:3]))


def screenshot(path):
    """The whole X display (xvfb-run's) as a PNG at `path`; its RGB pixels."""
    subprocess.run(["import", "-window", "root", path], check=True, timeout=30)
    return list(Image.open(path).convert("RGB").getdata())


class RvizDemo(unittest.TestCase):
    def test_rviz_shows_cloud_voxels_contacts_and_path(self):
        rospy.init_node("test_rviz_demo", anonymous=True)
        errors = []
        rospy.Subscriber("/rosout", Log, lambda m: errors.append("%s: %s" % (m.name, m.msg))
                         if m.level >= Log.ERROR and m.name.endswith("rviz") else None)
        paths = []
        rospy.Subscriber("/planned_path", Marker, paths.append)
        client = CollisionClient("/collision_checker", timeout=60.0)
        deadline = time.time() + 30.0
        while time.time() < deadline and not client.check_state(ARM, LEAN, checks=ENVIRONMENT).environment_collision:
            time.sleep(0.2)
        render = float(rospy.get_param("~render_seconds", 6.0))  # Xvfb renders in software
        time.sleep(render)
        red = lambda r, g, b: r > 150 and g < 60 and b < 60  # noqa: E731
        before = screenshot("/tmp/bvh_collision_rviz_before.png")
        contacts = client.check_state(ARM, LEAN, max_contacts=5).contacts
        self.assertGreater(len(contacts), 0, "the leaning arm touches the pillar")
        deadline = time.time() + 60.0
        while time.time() < deadline and not paths:
            time.sleep(0.5)
        self.assertTrue(paths, "plan_demo published no path")
        self.assertGreater(len(paths[-1].points), 10)
        time.sleep(render)
        shot = rospy.get_param("~screenshot", "/tmp/bvh_collision_rviz.png")
        pixels = screenshot(shot)
        magenta = count(pixels, lambda r, g, b: r > 180 and b > 180 and g < 80)
        yellow = count(pixels, lambda r, g, b: r > 200 and g > 200 and b < 60)
        green = count(pixels, lambda r, g, b: g > r + 60 and g > b + 60)
        new_red = count(pixels, red) - count(before, red)
        report = "magenta %d, yellow %d, green %d, new red %d of %d pixels (%s)" % (
            magenta, yellow, green, new_red, len(pixels), shot)
        rospy.loginfo(report)
        print(report)
        self.assertGreater(magenta, 200, "the obstacle cloud is not drawn: " + report)
        self.assertGreater(yellow, 100, "the planned path is not drawn: " + report)
        self.assertGreater(green, 200, "the voxels are not drawn: " + report)
        self.assertGreater(new_red, 30, "no contact is drawn: " + report)
        self.assertIn("/rviz", rosnode.get_node_names(), "rviz is not running")
        self.assertEqual(errors, [], "rviz reported errors")


if __name__ == "__main__":
    rostest.rosrun("bvh_collision", "rviz_demo", RvizDemo)

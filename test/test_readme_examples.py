#!/usr/bin/env python3
"""The README's first queries, run against the demo node as a new user would run them: each
`rosservice call` line of its sh block (with the answers its text promises), its Python block
(each printed value against the comment beside it), and its C++ block compared with the one
test_readme_example compiles and runs. So the guide cannot rot."""
import io
import os
import re
import subprocess
import sys
import time
import unittest
from contextlib import redirect_stdout

import rospy
import rostest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "scripts"))
from collision_client import ENVIRONMENT, CollisionClient  # noqa: E402

README = open(os.path.join(HERE, "..", "README.md")).read()
BLOCKS = re.findall(r"```(\w+)\n(.*?)```", README, re.S)


def blocks(kind):
    return [body for k, body in BLOCKS if k == kind]


def call(line):
    out = subprocess.run(["bash", "-c", line], capture_output=True, text=True, timeout=60)
    return out.returncode, out.stdout + out.stderr


class Readme(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_readme_examples", anonymous=True)
        client = CollisionClient("/collision_checker", timeout=60.0)
        # The pillar arrives with the camera's clouds (twice a second).
        deadline = time.time() + 60.0
        while time.time() < deadline and not client.check_state(["joint1", "joint2"], [0.66, 1.0], checks=ENVIRONMENT).environment_collision:
            time.sleep(0.2)

    def test_rosservice_calls(self):
        calls = [line for body in blocks("sh") for line in body.splitlines() if line.startswith("rosservice call")]
        self.assertEqual(len(calls), 3, "the README's first query has three rosservice calls")
        # What the README's text says each one answers.
        promised = {
            "check_state": ["valid: False", "environment_collision: True", 'body_a: "link3"', 'body_b: "octree"'],
            "check_motion": ["valid: False"],
            "cast_ray": ["hit: True", 'body: "octree"'],
        }
        for line in calls:
            service = line.split()[2].rsplit("/", 1)[1]
            code, out = call(line)
            self.assertEqual(code, 0, line + "\n" + out)
            for text in promised[service]:
                self.assertIn(text, out, line)
            if service == "check_motion":
                fraction = float(re.search(r"last_valid_fraction: ([0-9.eE+-]+)", out).group(1))
                self.assertAlmostEqual(fraction, 0.75, delta=0.05)
            if service == "cast_ray":
                distance = float(re.search(r"distance: ([0-9.eE+-]+)", out).group(1))
                self.assertAlmostEqual(distance, 0.48, delta=0.011)

    def test_python_block(self):
        (body,) = blocks("python")
        printed = io.StringIO()
        with redirect_stdout(printed):
            exec(compile(body, "README.md python block", "exec"), {})
        expected = [line.split("#", 1)[1].strip() for line in body.splitlines() if line.startswith("print(")]
        self.assertEqual(printed.getvalue().splitlines(), expected)

    def test_a_guide_of_at_most_10_kb_linking_every_docs_page(self):
        self.assertLessEqual(len(README.encode()), 10 * 1024)
        docs = os.path.join(HERE, "..", "docs")
        for page in sorted(os.listdir(docs)):
            if page.endswith(".md"):
                self.assertIn("(docs/%s)" % page, README, "docs/%s is not linked from the README" % page)
        for target in re.findall(r"\]\((docs/[^)#]+)", README):
            self.assertTrue(os.path.exists(os.path.join(HERE, "..", target)), target)

    def test_cpp_block_is_the_compiled_one(self):
        cpp = blocks("cpp")[0]
        source = open(os.path.join(HERE, "test_readme_example.cpp")).read()
        region = source.split("// README begin\n")[1].split("    // README end")[0]
        self.assertEqual(cpp, region, "the README's first C++ block differs from test/test_readme_example.cpp")


if __name__ == "__main__":
    rostest.rosrun("bvh_collision", "test_readme_examples", Readme)

#!/usr/bin/env python3
"""A rospy client of the collision checker node: every service, through the generated messages.

As a library (what a Python planner imports):

    from collision_client import CollisionClient   # scripts/ on the path, or copy the class
    client = CollisionClient("/collision_checker")
    client.check_state(["joint1", "joint2"], [0.66, 1.0]).valid

As a program, on a running node (make demo's demo.launch, or any robot):

    rosrun bvh_collision collision_client.py [--node /collision_checker] [--joints j1 j2 ...]

it calls each service once and prints what came back. Calls use persistent connections: a new
TCP connection per call costs more than most checks. A call whose answer carries an error raises
CheckerError with the node's message.
"""
import argparse
import sys
import time

import rospy
from bvh_collision.srv import (AttachObject, CastRay, CheckMotion, CheckMotions, CheckState, CheckStateRequest,
                               CheckStates, ClearBox, DetachObject, LoadScene, RemoveCollisionObject, SaveOctree,
                               SaveScene, SetAllowedCollisions, SetCollisionObject)
from geometry_msgs.msg import Point, Pose, Vector3
from sensor_msgs.msg import JointState
from shape_msgs.msg import SolidPrimitive
from std_srvs.srv import Empty

SELF = CheckStateRequest.SELF
ENVIRONMENT = CheckStateRequest.ENVIRONMENT
BOTH = SELF | ENVIRONMENT


class CheckerError(RuntimeError):
    """The node answered with an error (the request was refused; nothing changed)."""


def pose(position=(0.0, 0.0, 0.0), orientation=(0.0, 0.0, 0.0, 1.0)):
    p = Pose()
    p.position.x, p.position.y, p.position.z = position
    p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w = orientation
    return p


class CollisionClient:
    SERVICES = {"check_state": CheckState, "check_states": CheckStates, "check_motion": CheckMotion,
                "check_motions": CheckMotions,
                "cast_ray": CastRay, "clear_box": ClearBox, "set_collision_object": SetCollisionObject,
                "remove_collision_object": RemoveCollisionObject, "save_octree": SaveOctree,
                "load_scene": LoadScene, "save_scene": SaveScene, "clear_environment": Empty,
                "set_allowed_collisions": SetAllowedCollisions, "attach_object": AttachObject,
                "detach_object": DetachObject}

    def __init__(self, node="/collision_checker", timeout=30.0):
        """Waits up to `timeout` s for the node's ~ready (its robot summary ~robot is set and every
        service is served), then connects to each service."""
        self._proxies = {}
        deadline = time.time() + timeout
        while not rospy.get_param(node + "/ready", False):
            if time.time() > deadline or rospy.is_shutdown():
                raise CheckerError("%s did not become ready in %g s" % (node, timeout))
            time.sleep(0.05)
        self.robot = rospy.get_param(node + "/robot")
        for name, kind in self.SERVICES.items():
            rospy.wait_for_service(node + "/" + name, timeout=timeout)
            self._proxies[name] = rospy.ServiceProxy(node + "/" + name, kind, persistent=True)

    def _call(self, service, *args, **kwargs):
        response = self._proxies[service](*args, **kwargs)
        if getattr(response, "error", ""):
            raise CheckerError("%s: %s" % (service, response.error))
        return response

    def check_state(self, names, positions, checks=BOTH, distance=False, max_contacts=0, tolerance=0.0,
                    report_allowed=False):
        """One configuration: joints not named keep their current joint_states values. report_allowed:
        also the allowed (link, object) pairs that touch (allowed_links[i] with allowed_objects[i])."""
        return self._call("check_state", state=JointState(name=list(names), position=list(positions)), checks=checks,
                          max_contacts=max_contacts, distance=distance, tolerance=tolerance,
                          report_allowed=report_allowed)

    def check_states(self, names, rows, checks=BOTH, tolerance=0.0):
        """Many configurations (rows of len(names) values) in one call; returns the list of valid flags."""
        flat = [float(v) for row in rows for v in row]
        return list(self._call("check_states", joint_names=list(names), positions=flat, checks=checks,
                               tolerance=tolerance).valid)

    def check_motion(self, names, start, goal, checks=BOTH, resolution=0.0):
        """The straight motion; resolution 0 is certified (no collision between the states checked)."""
        return self._call("check_motion", joint_names=list(names), start=list(start), goal=list(goal), checks=checks,
                          resolution=resolution)

    def check_motions(self, names, motions, checks=BOTH):
        """Many certified motions [(start, goal), ...] in one call; returns [(valid, last_valid_fraction), ...]."""
        starts = [float(v) for start, _ in motions for v in start]
        goals = [float(v) for _, goal in motions for v in goal]
        r = self._call("check_motions", joint_names=list(names), starts=starts, goals=goals, checks=checks)
        return list(zip(r.valid, r.last_valid_fraction))

    def cast_ray(self, origin, direction, max_range=0.0):
        return self._call("cast_ray", origin=Point(*origin), direction=Vector3(*direction), max_range=max_range)

    def set_primitives(self, object_id, primitives, frame_id="", object_pose=None):
        """An object of shape_msgs primitives: [(SolidPrimitive.BOX, [x, y, z], pose), ...]."""
        shapes = [SolidPrimitive(type=t, dimensions=list(d)) for t, d, _ in primitives]
        return self._call("set_collision_object", id=object_id, frame_id=frame_id, pose=object_pose or pose(),
                          primitives=shapes, primitive_poses=[p for _, _, p in primitives])

    def remove_object(self, object_id):
        return self._call("remove_collision_object", id=object_id)

    def clear_box(self, lo, hi):
        return self._call("clear_box", min=Point(*lo), max=Point(*hi))

    def save_octree(self, path):
        return self._call("save_octree", path=path)

    def load_scene(self, path, merge=False):
        """A MoveIt .scene file's objects (merge: added to the others); the response has name, objects, shapes."""
        return self._call("load_scene", path=path, merge=merge)

    def save_scene(self, path, name=""):
        return self._call("save_scene", path=path, name=name)

    def set_allowed_collisions(self, pairs=(), defaults=(), allowed=True, remove=False):
        """MoveIt's allowed collisions with objects: pairs [(link or object, object), ...] and
        names whose default entry is set; allowed=False checks them, remove=True drops the entries."""
        return self._call("set_allowed_collisions", names_a=[a for a, _ in pairs], names_b=[b for _, b in pairs],
                          default_names=list(defaults), allowed=allowed, remove=remove)

    def attach_object(self, object_id, link, touch_links=(), primitives=None, frame_id="", object_pose=None):
        """Carry an object on `link` (touch_links may touch it): the world object `object_id` where
        it is, or, given primitives [(SolidPrimitive.BOX, [x, y, z], pose), ...], a new one posed in
        frame_id (empty: the link's frame)."""
        shapes = [SolidPrimitive(type=t, dimensions=list(d)) for t, d, _ in primitives or ()]
        return self._call("attach_object", id=object_id, link=link, touch_links=list(touch_links), frame_id=frame_id,
                          pose=object_pose or pose(), primitives=shapes,
                          primitive_poses=[p for _, _, p in primitives or ()])

    def detach_object(self, object_id, remove=False):
        """Put a carried object back into the world where its link holds it (remove=True: drop it)."""
        return self._call("detach_object", id=object_id, remove=remove)

    def clear_environment(self):
        return self._proxies["clear_environment"]()


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--node", default="/collision_checker")
    parser.add_argument("--joints", nargs="*", default=["joint1", "joint2"],
                        help="joints to move in the example calls (default: the demo arm's first two)")
    args = parser.parse_args(rospy.myargv(argv)[1:])
    rospy.init_node("collision_client", anonymous=True)
    client = CollisionClient(args.node)
    names = args.joints
    home, lean = [0.0] * len(names), ([0.66, 1.0] + [0.0] * len(names))[:len(names)]
    r = client.check_state(names, home, distance=True)
    print("check_state home: valid=%s min_distance=%.4f m closest=%s" % (r.valid, r.min_distance, list(r.closest_pair)))
    r = client.check_state(names, lean, max_contacts=1)
    print("check_state %s: valid=%s self=%s environment=%s contacts=%d"
          % (lean, r.valid, r.self_collision, r.environment_collision, len(r.contacts)))
    print("check_states [home, lean]:", client.check_states(names, [home, lean]))
    m = client.check_motion(names, home, lean)
    print("check_motion home -> lean (certified): valid=%s free up to %.3f of the way, %d states"
          % (m.valid, m.last_valid_fraction, m.states_checked))
    ray = client.cast_ray((1.0, 0.35, 0.4), (-1.0, 0.0, 0.0))
    print("cast_ray from (1, 0.35, 0.4) along -x: hit=%s body=%r distance=%.3f" % (ray.hit, ray.body, ray.distance))
    client.set_primitives("cone", [(SolidPrimitive.CONE, [0.3, 0.1], pose())], object_pose=pose((0.0, -0.6, 0.15)))
    print("set_collision_object 'cone': a 0.3 m cone (base radius 0.1) at (0, -0.6, 0.15)")
    client.remove_object("cone")
    print("remove_collision_object 'cone'")
    client.save_octree("/tmp/collision_client.bt")
    print("save_octree /tmp/collision_client.bt")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

"""The service-request seeds of the fuzz corpus (test/fuzz/service_target.cpp's encoding): one
byte picks the service, names and numbers come from small palettes. Used by make_loader_corpus.py."""
import struct

# ------------------------------------------------------------------ service requests (service_target.cpp)

NAMES = ["joint1", "joint2", "joint3", "joint4", "joint5", "joint6", "finger_joint_left", "base_link", "link3", "hand",
         "world", "box", "octree"]
PALETTE = {0.0: 0, 1.0: 1, -1.0: 2, 0.5: 3, 1e-300: 4, 1e300: 5, "nan": 6, "inf": 7, "-inf": 8, 1e-9: 9, 3.0: 10,
           -0.5: 11, 0.02: 12, 100.0: 13}


def num(v):
    if isinstance(v, str):
        return bytes([PALETTE[v]])
    if v in PALETTE:
        return bytes([PALETTE[v]])
    return bytes([20]) + struct.pack("<d", v)


def nums(values):
    return bytes([len(values)]) + b"".join(num(v) for v in values)


def name(n):
    if n == "":
        return bytes([255])
    if n in NAMES:
        return bytes([NAMES.index(n)])
    raw = n.encode()[:12]
    return bytes([200, len(raw)]) + raw


def names(ns):
    return bytes([len(ns)]) + b"".join(name(n) for n in ns)


def point(p):
    return b"".join(num(v) for v in p)


ARM = ["joint1", "joint2", "joint3", "joint4", "joint5", "joint6"]


def check_state(joints=ARM, positions=(0, 0.5, -0.5, 0, 1, 0), checks=3, contacts=2, distance=1, tolerance=0.0):
    return bytes([0]) + names(joints) + nums(positions) + bytes([checks, contacts, distance]) + num(tolerance)


def check_states(joints=ARM, positions=(0, 0.5, -0.5, 0, 1, 0) * 3, checks=3, tolerance=0.0):
    return bytes([1]) + names(joints) + nums(positions) + bytes([checks]) + num(tolerance)


def check_motion(joints=ARM, start=(0, 0, 0, 0, 0, 0), goal=(1, 0.5, 0, 0, 0, 0), checks=3, resolution=0.0):
    return bytes([2]) + names(joints[:5]) + nums(start[:5]) + nums(goal[:5]) + bytes([checks]) + num(resolution)


def check_motions(starts=(0, 0, 0, 0, 0, 1, 0.5, 0, 0, 0), goals=(1, 0.5, 0, 0, 0, 0, 0, 0, 0, 0), checks=3, joints=ARM):
    """check_motion's request, then bytes left: check_motions with the same joint names (rows of five)."""
    return check_motion(joints=joints) + nums(starts) + nums(goals) + bytes([checks])


def cast_ray(origin=(0.5, 0, 2), direction=(0, 0, -1), max_range=5.0):
    return bytes([3]) + point(origin) + point(direction) + num(max_range)


def clear_box(lo=(-0.1, -0.1, -0.1), hi=(0.1, 0.1, 0.1)):
    return bytes([5]) + point(lo) + point(hi)


POSE = ((0, 0, 0), (0, 0, 0, 1))
URIS = ["", "package://bvh_collision/test/fuzz/meshes/box.stl", "package://nothing/x.stl", "file:///nonexistent.stl",
        "/etc/hostname", "package://bvh_collision/test/fuzz/meshes/box.stl\0x"]


def pose(p=POSE):
    return point(p[0]) + point(p[1])


def set_object(ident="box", primitives=((1, (0.1, 0.2, 0.3)),), primitive_poses=None, meshes=(), mesh_poses=None,
               resources=(), scales=(), resource_poses=None, position=(0.5, 0, 0.2), orientation=(0, 0, 0, 1),
               frame="base_link"):
    """SetCollisionObject (service_target.cpp's shapes()): primitives as (type, dims), meshes as
    (vertices, triangles as index triples), resources as URIs; one identity pose per shape unless given."""
    out = bytes([6]) + name(ident) + pose((position, orientation)) + name(frame)
    out += bytes([len(primitives)]) + b"".join(bytes([kind]) + nums(dims) for kind, dims in primitives)
    poses = [POSE] * len(primitives) if primitive_poses is None else primitive_poses
    out += bytes([len(poses)]) + b"".join(pose(p) for p in poses)
    out += bytes([len(meshes)])
    for vertices, triangles in meshes:
        out += bytes([len(vertices)]) + b"".join(point(v) for v in vertices)
        out += bytes([len(triangles)]) + b"".join(b"".join(bytes([0, i]) for i in t) for t in triangles)
    poses = [POSE] * len(meshes) if mesh_poses is None else mesh_poses
    out += bytes([len(poses)]) + b"".join(pose(p) for p in poses)
    out += bytes([len(resources)]) + b"".join(bytes([URIS.index(u)]) for u in resources)
    out += bytes([len(scales)]) + b"".join(point(s) for s in scales)
    poses = [POSE] * len(resources) if resource_poses is None else resource_poses
    return out + bytes([len(poses)]) + b"".join(pose(p) for p in poses)


def service_cases():
    tri = ((0, 0, 0), (0.1, 0, 0), (0, 0.1, 0), (0, 0, 0.1))
    return [
        ("state", check_state()), ("state_self", check_state(checks=1)), ("state_env", check_state(checks=2)),
        ("state_nan", check_state(positions=(0, "nan", 0, 0, 0, 0))), ("state_inf_tolerance", check_state(tolerance="inf")),
        ("state_tolerance", check_state(tolerance=0.02)), ("state_unknown_joint", check_state(joints=["joint1", "nothing"], positions=(0, 0))),
        ("state_mismatch", check_state(positions=(0, 0))), ("state_huge", check_state(positions=(1e300, 0, 0, 0, 0, 0))),
        ("state_fixed_joint", check_state(joints=["hand", "joint1"], positions=(0, 0))), ("state_checks_255", check_state(checks=255)),
        ("state_duplicate", check_state(joints=["joint1", "joint1"], positions=(0, 1))), ("state_none", check_state(joints=[], positions=())),
        ("states", check_states()), ("states_ragged", check_states(positions=(0, 1, 2, 3, 4))), ("states_none", check_states(joints=[], positions=(0,))),
        ("states_nan", check_states(positions=("nan",) * 6)), ("states_tolerance", check_states(tolerance=0.02)),
        ("motion", check_motion()), ("motion_step", check_motion(resolution=0.02)), ("motion_tiny_step", check_motion(resolution=1e-300)),
        ("motion_nan", check_motion(goal=("nan", 0, 0, 0, 0))), ("motion_negative_step", check_motion(resolution=-1.0)),
        ("motion_inf_goal", check_motion(goal=("inf", 0, 0, 0, 0))), ("motion_mismatch", bytes([2]) + names(ARM[:2]) + nums((0,)) + nums((1, 1)) + bytes([3]) + num(0.0)),
        ("motions", check_motions()), ("motions_ragged", check_motions(starts=(0,) * 7, goals=(0,) * 7)),
        ("motions_unequal", check_motions(goals=(0,) * 5)), ("motions_nan", check_motions(goals=("nan",) + (0,) * 9)),
        ("motions_none", check_motions(starts=(), goals=())), ("motions_no_names", check_motions(joints=[])),
        ("motions_self", check_motions(checks=1)), ("motions_checks_9", check_motions(checks=9)),
        ("ray", cast_ray()), ("ray_zero_direction", cast_ray(direction=(0, 0, 0))), ("ray_nan", cast_ray(origin=("nan", 0, 0))),
        ("ray_huge_range", cast_ray(max_range=1e300)), ("ray_inf_range", cast_ray(max_range="inf")), ("ray_negative_range", cast_ray(max_range=-1.0)),
        ("clear_environment", bytes([4])), ("clear_box", clear_box()), ("clear_box_inverted", clear_box((1, 1, 1), (-1, -1, -1))),
        ("clear_box_nan", clear_box(("nan", 0, 0))), ("clear_box_huge", clear_box((-1e300,) * 3, (1e300,) * 3)),
        ("object_box", set_object()), ("object_sphere", set_object(primitives=((2, (0.1,)),))),
        ("object_cylinder", set_object(primitives=((3, (0.3, 0.05)),))), ("object_cone", set_object(primitives=((4, (0.3, 0.05)),))),
        ("object_cone_one_dimension", set_object(primitives=((4, (0.3,)),))),
        ("object_several", set_object(primitives=((1, (0.1, 0.2, 0.3)), (4, (0.3, 0.05))),
                                      primitive_poses=(POSE, ((0, 0, 0.3), (0, 0, 0, 1))))),
        ("object_poses_missing", set_object(primitives=((1, (0.1, 0.2, 0.3)), (2, (0.1,))), primitive_poses=(POSE,))),
        ("object_no_shape", set_object(primitives=())),
        ("object_mesh", set_object(primitives=(), resources=("package://bvh_collision/test/fuzz/meshes/box.stl",))),
        ("object_mesh_missing", set_object(primitives=(), resources=("package://nothing/x.stl",))),
        ("object_mesh_garbage", set_object(primitives=(), resources=("/etc/hostname",))),
        ("object_triangles", set_object(primitives=(), meshes=((tri, ((0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3))),))),
        ("object_triangles_out_of_range", set_object(primitives=(), meshes=((tri, ((0, 1, 9),)),))),
        ("object_triangles_no_pose", set_object(primitives=(), meshes=((tri, ((0, 1, 2),)),), mesh_poses=())),
        ("object_nan_size", set_object(primitives=((1, ("nan", 1, 1)),))), ("object_negative", set_object(primitives=((1, (-1, 1, 1)),))),
        ("object_huge", set_object(primitives=((1, (1e300, 1, 1)),))),
        ("object_zero_quaternion", set_object(orientation=(0, 0, 0, 0))), ("object_unknown_frame", set_object(frame="nothing")),
        ("object_shape_zero_quaternion", set_object(primitive_poses=(((0, 0, 0), (0, 0, 0, 0)),))),
        ("object_empty_id", set_object(ident="")), ("object_kind_0", set_object(primitives=((0, (1,)),))),
        ("object_kind_5", set_object(primitives=((5, (1,)),))),
        ("object_mesh_nul_in_uri", set_object(primitives=(), resources=(URIS[5],))),
        ("object_zero_scale", set_object(primitives=(), resources=("package://bvh_collision/test/fuzz/meshes/box.stl",), scales=((0, 1, 1),))),
        ("remove", bytes([7]) + name("box")), ("remove_unknown", bytes([7]) + name("nothing")), ("empty", b""),
    ]

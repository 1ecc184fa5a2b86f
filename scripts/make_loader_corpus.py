#!/usr/bin/env python3
"""Writes the seed corpora of the loader's fuzz targets (test/fuzz/corpus) and the mesh package
the robot target reads (test/fuzz/meshes): the mutation sweep of issue 21, a small
four-link robot (a box, a cylinder, a sphere, a mesh) with one thing changed per file, mesh files
in every format with one thing changed, and SRDFs. Deterministic; run it again after changing it
(`python3 scripts/make_loader_corpus.py`) and commit what changes. Files that `make fuzz` finds
are added beside these (named by their hash), never regenerated."""
import os
import random
import re
import shutil
import struct
import sys

from corpus_service_requests import service_cases

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "test", "fuzz")
CORPUS = os.path.join(ROOT, "corpus")

# ------------------------------------------------------------------ meshes (a closed box)

BOX_V = [(x, y, z) for x in (-0.05, 0.05) for y in (-0.04, 0.04) for z in (-0.03, 0.03)]
BOX_T = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
         (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]


def fmt(x):
    return repr(float(x))


def stl_binary(vertices=BOX_V, triangles=BOX_T, count=None):
    out = bytearray(b"fuzz box".ljust(80, b"\0"))
    out += struct.pack("<I", len(triangles) if count is None else count)
    for t in triangles:
        out += struct.pack("<3f", 0, 0, 0)
        for i in t:
            out += struct.pack("<3f", *vertices[i])
        out += b"\0\0"
    return bytes(out)


def stl_ascii(vertices=BOX_V, triangles=BOX_T):
    lines = ["solid box"]
    for t in triangles:
        lines += ["facet normal 0 0 0", "outer loop"]
        lines += ["vertex " + " ".join(str(c) for c in vertices[i]) for i in t]
        lines += ["endloop", "endfacet"]
    return ("\n".join(lines + ["endsolid box"]) + "\n").encode()


def obj(vertices=BOX_V, triangles=BOX_T):
    text = "".join("v %s %s %s\n" % tuple(str(c) for c in v) for v in vertices)
    text += "".join("f %d %d %d\n" % tuple(i + 1 for i in t) for t in triangles)
    return text.encode()


def collada(vertices=BOX_V, triangles=BOX_T):
    floats = " ".join(str(c) for v in vertices for c in v)
    p = " ".join(str(i) for t in triangles for i in t)
    return ("""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries><geometry id="box" name="box"><mesh>
    <source id="box-pos"><float_array id="box-pos-array" count="%d">%s</float_array>
      <technique_common><accessor source="#box-pos-array" count="%d" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="box-vtx"><input semantic="POSITION" source="#box-pos"/></vertices>
    <triangles count="%d"><input semantic="VERTEX" source="#box-vtx" offset="0"/><p>%s</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="scene">
    <node id="n"><instance_geometry url="#box"/></node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
""" % (3 * len(vertices), floats, len(vertices), len(triangles), p)).encode()


def with_vertex(value):
    return [tuple(value if (i == 5 and k == 0) else c for k, c in enumerate(v)) for i, v in enumerate(BOX_V)]


def mesh_cases():
    """(name, selector, bytes): the target's input is the selector byte then the file."""
    rng = random.Random(21)
    seeds = {"s": stl_binary(), "a": stl_ascii(), "o": obj(), "d": collada()}
    selector = {"s": b"s", "a": b"s", "o": b"o", "d": b"d"}
    cases = [("seed_" + k, selector[k], v) for k, v in seeds.items()]
    for k, data in seeds.items():
        for f in (0.0, 0.1, 0.25, 0.5, 0.75, 0.9, 0.99):
            cases.append(("truncated_%s_%d" % (k, int(f * 100)), selector[k], data[: int(len(data) * f)]))
        for n in range(4):  # a few random byte changes
            b = bytearray(data)
            for _ in range(1 + n * 3):
                b[rng.randrange(len(b))] = rng.randrange(256)
            cases.append(("flipped_%s_%d" % (k, n), selector[k], bytes(b)))
        cases.append(("random_bytes_%s" % k, selector[k], bytes(rng.randrange(256) for _ in range(3000))))
    poisons = {"nan": float("nan"), "inf": float("inf"), "big": 1e30, "huge": 1e308}
    for name, value in poisons.items():
        vs = with_vertex(value)
        if name != "huge":  # a float cannot hold 1e308
            cases.append(("vertex_%s_binary" % name, b"s", stl_binary(vs)))
        cases.append(("vertex_%s_ascii" % name, b"s", stl_ascii(vs)))
        cases.append(("vertex_%s_obj" % name, b"o", obj(vs)))
        cases.append(("vertex_%s_dae" % name, b"d", collada(vs)))
    all_nan = [(float("nan"),) * 3] * 8
    cases += [("all_nan_binary", b"s", stl_binary(all_nan)), ("all_nan_obj", b"o", obj(all_nan))]
    flat = [(x, y, 0.0) for x, y, _ in BOX_V]
    cases += [("flat_binary", b"s", stl_binary(flat)), ("flat_obj", b"o", obj(flat)),
              ("flat_dae", b"d", collada(flat))]
    cases += [("binary_count_too_large", b"s", stl_binary(count=1000)),
              ("binary_count_zero", b"s", stl_binary(count=0)),
              ("binary_count_2e9", b"s", stl_binary(count=2000000000)),
              ("binary_no_triangles", b"s", stl_binary(triangles=[]))]
    ascii_text = stl_ascii().decode()
    for name, (old, new) in {
        "four_vertices": ("vertex -0.05 -0.04 0.03\nendloop", "vertex -0.05 -0.04 0.03\nvertex 0 0 0\nendloop"),
        "two_vertices": ("outer loop\nvertex -0.05 -0.04 -0.03\n", "outer loop\n"),
        "no_endloop": ("endloop\nendfacet", "endfacet"),
        "no_endfacet": ("endloop\nendfacet\nfacet", "endloop\nfacet"),
        "no_endsolid": ("endsolid box\n", ""),
        "exponent": ("vertex -0.05 -0.04 -0.03", "vertex -0.05 -0.04 -3e99999999999999999999"),
        "word_for_number": ("vertex -0.05 -0.04 -0.03", "vertex -0.05 minus 0.03"),
        "hex_number": ("vertex -0.05 -0.04 -0.03", "vertex 0x10 -0.04 -0.03"),
        "two_coordinates": ("vertex -0.05 -0.04 -0.03", "vertex -0.05 -0.04"),
        "nested_solid": ("facet normal", "solid inner\nfacet normal"),
        "endsolid_first": ("solid box", "endsolid box\nsolid box"),
    }.items():
        cases.append(("ascii_" + name, b"s", ascii_text.replace(old, new, 1).encode()))
    obj_text = obj().decode()
    for name, (old, new) in {
        "index_zero": ("f 1 2 4", "f 0 2 4"), "index_beyond": ("f 1 2 4", "f 1 2 99"),
        "index_negative": ("f 1 2 4", "f -1 -2 -3"), "index_too_negative": ("f 1 2 4", "f -100 2 4"),
        "two_indices": ("f 1 2 4", "f 1 2"), "slashes": ("f 1 2 4", "f 1/1/1 2/2/2 4/4/4"),
        "two_coordinates": ("v -0.05 -0.04 -0.03", "v -0.05 -0.04"), "overflow": ("v -0.05 -0.04 -0.03", "v 1e400 0 0"),
        "word": ("v -0.05 -0.04 -0.03", "v a b c"), "huge_index": ("f 1 2 4", "f 1 2 4294967297"),
        "polygon": ("f 1 2 4", "f 1 2 4 3"), "no_faces": (obj_text, obj_text.split("f ")[0]),
    }.items():
        cases.append(("obj_" + name, b"o", obj_text.replace(old, new, 1).encode()))
    dae_text = collada().decode()
    p_list = " ".join(str(i) for t in BOX_T for i in t)
    for name, (old, new) in {
        "stride_million": ('stride="3"', 'stride="1000000"'), "stride_zero": ('stride="3"', 'stride="0"'),
        "stride_negative": ('stride="3"', 'stride="-3"'), "stride_word": ('stride="3"', 'stride="three"'),
        "index_minus_one": ("<p>0 1 3", "<p>-1 1 3"), "index_2_31": ("<p>0 1 3", "<p>2147483648 1 3"),
        "index_2_32": ("<p>0 1 3", "<p>4294967295 1 3"), "index_beyond": ("<p>0 1 3", "<p>8 1 3"),
        "p_word": ("<p>0 1 3", "<p>0 x 3"), "p_fraction": ("<p>0 1 3", "<p>0 1.5 3"),
        "p_short": ("<p>" + p_list, "<p>" + p_list.rsplit(" ", 1)[0]), "p_empty": ("<p>" + p_list, "<p>"),
        "count_beyond": ('accessor source="#box-pos-array" count="8"', 'accessor source="#box-pos-array" count="80"'),
        "count_negative": ('accessor source="#box-pos-array" count="8"', 'accessor source="#box-pos-array" count="-8"'),
        "array_count_wrong": ('count="24"', 'count="240"'), "offset_negative": ('offset="0"', 'offset="-1"'),
        "offset_large": ('offset="0"', 'offset="7"'), "triangles_count_wrong": ('<triangles count="12"', '<triangles count="1200"'),
        "float_word": ("count=\"24\">-0.05", "count=\"24\">abc"), "no_source": ('source="#box-pos"', 'source="#nothing"'),
        "self_instance": ('<instance_geometry url="#box"/>', '<instance_geometry url="#box"/><instance_node url="#n"/>'),
        "no_scene": ('<scene><instance_visual_scene url="#scene"/></scene>', ""),
        "not_xml": (dae_text, dae_text[: len(dae_text) // 3] + "<<<"),
    }.items():
        cases.append(("dae_" + name, b"d", dae_text.replace(old, new, 1).encode()))
    return seeds, cases


# ------------------------------------------------------------------ robot descriptions

def small_robot(changes=None):
    v = {
        "BOX": '<box size="0.1 0.2 0.3"/>',
        "CYLINDER": '<cylinder radius="0.05" length="0.4"/>',
        "SPHERE": '<sphere radius="0.07"/>',
        "MESH": '<mesh filename="package://fuzz_meshes/meshes/box.stl" scale="1 1 1"/>',
        "ORIGIN": '<origin xyz="0 0 0.1" rpy="0 0 0"/>',
        "J1_ORIGIN": '<origin xyz="0 0 0.5" rpy="0 0 0"/>', "J1_AXIS": '<axis xyz="0 0 1"/>',
        "J1_LIMIT": '<limit lower="-1" upper="1" effort="1" velocity="1"/>',
        "J2_TYPE": "revolute", "J2_CHILD": "link2", "J2_AXIS": "1 0 0", "J3_PARENT": "link2",
        "J3": '<joint name="j3" type="fixed"><parent link="{J3_PARENT}"/><child link="link3"/></joint>',
        "EXTRA": "", "LINK3": '<link name="link3"><collision><geometry>{MESH}</geometry></collision></link>',
    }
    v.update(changes or {})
    text = ('<robot name="small">'
            '<link name="base"><collision>{ORIGIN}<geometry>{BOX}</geometry></collision></link>'
            '<link name="link1"><collision><geometry>{CYLINDER}</geometry></collision></link>'
            '<link name="link2"><collision><geometry>{SPHERE}</geometry></collision></link>'
            '{LINK3}'
            '<joint name="j1" type="revolute"><parent link="base"/><child link="link1"/>{J1_ORIGIN}{J1_AXIS}{J1_LIMIT}</joint>'
            '<joint name="j2" type="{J2_TYPE}"><parent link="link1"/><child link="{J2_CHILD}"/>'
            '<axis xyz="{J2_AXIS}"/><limit lower="0" upper="1" effort="1" velocity="1"/></joint>'
            '{J3}{EXTRA}</robot>')
    for _ in range(3):  # placeholders inside replacements
        text = text.replace("{LINK3}", v["LINK3"]).replace("{J3}", v["J3"])
        text = re.sub(r"\{([A-Z0-9_]+)\}", lambda m: v[m.group(1)], text)
    return text


SCALARS = ["nan", "inf", "-inf", "abc", "", " ", "1e300", "1e308", "-1", "0", "1e-300", "0x10", "1,5",
           "1 2", "1e99999999999999999999"]
VECTORS = ["nan 1 1", "1 inf 1", "a b c", "1 1", "1 1 1 1", "1e308 1 1", "1e300 1 1", "", "0 0 0",
           "-1 1 1", "1e-300 1 1", "1,1,1", "1 1 1e99999999999999999999"]


def robot_cases():
    cases = [("seed", small_robot())]
    scalar_slots = {
        "cylinder_radius": ("CYLINDER", '<cylinder radius="%s" length="0.4"/>'),
        "cylinder_length": ("CYLINDER", '<cylinder radius="0.05" length="%s"/>'),
        "sphere_radius": ("SPHERE", '<sphere radius="%s"/>'),
        "limit_lower": ("J1_LIMIT", '<limit lower="%s" upper="1" effort="1" velocity="1"/>'),
        "limit_upper": ("J1_LIMIT", '<limit lower="-1" upper="%s" effort="1" velocity="1"/>'),
        "limit_effort": ("J1_LIMIT", '<limit lower="-1" upper="1" effort="%s" velocity="1"/>'),
        "limit_velocity": ("J1_LIMIT", '<limit lower="-1" upper="1" effort="1" velocity="%s"/>'),
    }
    vector_slots = {
        "box_size": ("BOX", '<box size="%s"/>'),
        "mesh_scale": ("MESH", '<mesh filename="package://fuzz_meshes/meshes/box.stl" scale="%s"/>'),
        "origin_xyz": ("ORIGIN", '<origin xyz="%s"/>'), "origin_rpy": ("ORIGIN", '<origin rpy="%s"/>'),
        "joint_xyz": ("J1_ORIGIN", '<origin xyz="%s"/>'), "joint_rpy": ("J1_ORIGIN", '<origin rpy="%s"/>'),
        "joint_axis": ("J1_AXIS", '<axis xyz="%s"/>'),
    }
    for slot, (key, pattern) in scalar_slots.items():
        for i, value in enumerate(SCALARS):
            cases.append(("%s_%d" % (slot, i), small_robot({key: pattern % value})))
    for slot, (key, pattern) in vector_slots.items():
        for i, value in enumerate(VECTORS):
            cases.append(("%s_%d" % (slot, i), small_robot({key: pattern % value})))
    mesh = '<mesh filename="%s"/>'
    for name, uri in {
        "stl_ascii": "package://fuzz_meshes/meshes/box_ascii.stl", "obj": "package://fuzz_meshes/meshes/box.obj",
        "dae": "package://fuzz_meshes/meshes/box.dae", "missing": "package://fuzz_meshes/meshes/none.stl",
        "directory": "package://fuzz_meshes/meshes", "dev_zero": "file:///dev/zero", "dev_null": "/dev/null",
        "http": "http://example.com/box.stl", "no_package": "package://no_such_package/box.stl",
        # issue 31: a control character in the name, as a character reference (a NUL cut the
        # name short and box.stl loaded) or written
        "nul_reference": "package://fuzz_meshes/meshes/box.stl&#0;x", "nul_hex_reference": "package://fuzz_meshes/meshes/box.stl&#x0;",
        "tab_reference": "package://fuzz_meshes/meshes/box.stl&#9;", "escape_reference": "package://fuzz_meshes/meshes/box.stl&#x1b;",
        "control_written": "package://fuzz_meshes/meshes/box.stl\x01",
        "empty_uri": "", "package_only": "package://", "relative": "meshes/box.stl", "upper_case": "package://fuzz_meshes/meshes/BOX.STL",
    }.items():
        cases.append(("mesh_uri_" + name, small_robot({"MESH": mesh % uri})))
    structure = {
        "empty_geometry": {"MESH": ""}, "mesh_no_filename": {"MESH": "<mesh/>"},
        "capsule": {"MESH": '<capsule radius="0.1" length="0.2"/>'}, "cone": {"MESH": '<cone radius="0.1" length="0.2"/>'},
        "two_shapes": {"MESH": '<box size="1 1 1"/><sphere radius="1"/>'},
        "no_geometry": {"LINK3": '<link name="link3"><collision></collision></link>'},
        "two_collisions": {"LINK3": '<link name="link3"><collision><geometry><box size="1 1 1"/></geometry></collision>'
                                    '<collision><geometry><sphere radius="0.1"/></geometry></collision></link>'},
        "no_collision": {"LINK3": '<link name="link3"/>'},
        "link_no_name": {"LINK3": '<link><collision><geometry><box size="1 1 1"/></geometry></collision></link>'},
        "joint_two_parents": {"J3_PARENT": 'base"/><child link="link2'},
        "joint_self_parent": {"J2_CHILD": "link1"},
        "cycle": {"EXTRA": '<joint name="j4" type="fixed"><parent link="link3"/><child link="base"/></joint>'},
        "two_roots": {"EXTRA": '<link name="lonely"/>'},
        "missing_child": {"J3": '<joint name="j3" type="fixed"><parent link="link2"/><child link="nowhere"/></joint>'},
        "missing_parent": {"J3_PARENT": "nowhere"},
        "duplicate_link": {"EXTRA": '<link name="link1"/>'},
        "duplicate_joint": {"EXTRA": '<joint name="j1" type="fixed"><parent link="link3"/><child link="extra"/></joint><link name="extra"/>'},
        "unknown_joint_type": {"J2_TYPE": "hinge"}, "continuous": {"J2_TYPE": "continuous"},
        "prismatic": {"J2_TYPE": "prismatic"}, "floating": {"J2_TYPE": "floating"}, "planar": {"J2_TYPE": "planar"},
        "fixed_zero_axis": {"J2_TYPE": "fixed", "J2_AXIS": "0 0 0"}, "zero_axis": {"J2_AXIS": "0 0 0"},
        "mimic_unknown": {"J3": '<joint name="j3" type="revolute"><parent link="link2"/><child link="link3"/><axis xyz="0 0 1"/>'
                                '<limit lower="-1" upper="1" effort="1" velocity="1"/><mimic joint="nothing"/></joint>'},
        "mimic_nan": {"J3": '<joint name="j3" type="revolute"><parent link="link2"/><child link="link3"/><axis xyz="0 0 1"/>'
                            '<limit lower="-1" upper="1" effort="1" velocity="1"/><mimic joint="j1" multiplier="nan"/></joint>'},
        "mimic_huge": {"J3": '<joint name="j3" type="prismatic"><parent link="link2"/><child link="link3"/><axis xyz="0 0 1"/>'
                             '<limit lower="-1" upper="1" effort="1" velocity="1"/><mimic joint="j1" multiplier="1e300" offset="1e300"/></joint>'},
        "mimic_self": {"J3": '<joint name="j3" type="revolute"><parent link="link2"/><child link="link3"/><axis xyz="0 0 1"/>'
                             '<limit lower="-1" upper="1" effort="1" velocity="1"/><mimic joint="j3"/></joint>'},
        "prismatic_far": {"J3": '<joint name="j3" type="prismatic"><parent link="link2"/><child link="link3"/><axis xyz="0 0 1"/>'
                                '<limit lower="0" upper="1e300" effort="1" velocity="1"/></joint>'},
        "revolute_no_limit": {"J1_LIMIT": ""},
    }
    for name, change in structure.items():
        cases.append((name, small_robot(change)))
    # issue 31: links and moving joints but no collision geometry (the CLI answered "0 free")
    cases.append(("no_collision_geometry", re.sub(r"<collision>.*?</collision>", "", small_robot())))
    seed = small_robot()
    for f in (0.0, 0.1, 0.3, 0.5, 0.7, 0.9, 0.99):
        cases.append(("truncated_%d" % int(f * 100), seed[: int(len(seed) * f)]))
    cases += [("not_xml", "this is not a robot"), ("no_robot_root", "<model name='x'/>"),
              ("nested_robot", '<robot name="a"><robot name="b"/></robot>'), ("no_name", "<robot/>"),
              ("empty_robot", '<robot name="e"/>'), ("entity", '<!DOCTYPE r [<!ENTITY a "aaaa">]><robot name="&a;"/>'),
              ("deep_nesting", '<robot name="d">' + "<x>" * 2000 + "</x>" * 2000 + "</robot>")]
    return cases


# ------------------------------------------------------------------ SRDF

VIRTUAL = '<virtual_joint name="root_joint" type="floating" parent_frame="world" child_link="a"/>'


def srdf_cases():
    body = ('<robot name="r"><disable_collisions link1="a" link2="b" reason="Adjacent"/>'
            '<disable_default_collisions link="d"/><enable_collisions link1="a" link2="d"/>'
            '<group name="g"><joint name="j1"/></group>'
            '<group_state name="home" group="g"><joint name="j1" value="0.5"/></group_state></robot>')
    cases = [("seed", body)]
    for name, (old, new) in {
        "self_pair": ('link1="a" link2="b"', 'link1="a" link2="a"'), "unknown_link": ('link1="a" link2="b"', 'link1="a" link2="zz"'),
        "missing_link2": ('link1="a" link2="b"', 'link1="a"'), "empty_names": ('link1="a" link2="b"', 'link1="" link2=""'),
        "enable_self": ('<enable_collisions link1="a" link2="d"/>', '<enable_collisions link1="d" link2="d"/>'),
        "disable_default_unknown": ('link="d"', 'link="nothing"'), "disable_default_empty": ('link="d"', ""),
        "state_nan": ('value="0.5"', 'value="nan"'), "state_word": ('value="0.5"', 'value="abc"'),
        "state_inf": ('value="0.5"', 'value="inf"'), "state_huge": ('value="0.5"', 'value="1e400"'),
        "state_unknown_joint": ('<joint name="j1" value', '<joint name="jx" value'),
        "state_no_value": (' value="0.5"', ""), "state_unknown_group": ('group="g"', 'group="nothing"'),
        "wrong_root": ("<robot name=\"r\">", "<srdf name=\"r\">"), "truncated": (body, body[: len(body) // 2]),
        "not_xml": (body, "nothing at all"), "empty": (body, ""),
        # issue 31: multi-DOF joints take a list (floating: x y z qx qy qz qw; planar: x y theta)
        "state_floating": ("<group ", VIRTUAL + '<group_state name="half_sitting" group="g"><joint name="root_joint" '
                           'value="0. 0. 1.01927 0. 0. 0. 1."/></group_state><group '),
        "state_floating_not_unit": ("<group ", VIRTUAL + '<group_state name="s" group="g"><joint name="root_joint" '
                                    'value="1 2 3 0 0 0 2"/></group_state><group '),
        "state_floating_six": ("<group ", VIRTUAL + '<group_state name="s" group="g"><joint name="root_joint" '
                               'value="0 0 1 0 0 1"/></group_state><group '),
        "state_floating_zero_quaternion": ("<group ", VIRTUAL + '<group_state name="s" group="g"><joint name="root_joint" '
                                           'value="0 0 1 0 0 0 0"/></group_state><group '),
        "state_planar": ('<joint name="j1" value="0.5"/>', '<joint name="j1" value="0.5"/><joint name="j4" value="0.5 -0.25 1."/>'),
        "state_planar_two": ('<joint name="j1" value="0.5"/>', '<joint name="j1" value="0.5"/><joint name="j4" value="1 2"/>'),
        "state_revolute_two": ('value="0.5"', 'value="0.5 0.25"'),
        "state_fixed_value": ('<joint name="j1" value="0.5"/>', '<joint name="j1" value="0.5"/><joint name="j2" value="0"/>'),
        "virtual_unknown_type": ("<group ", VIRTUAL.replace("floating", "hinge") + "<group "),
        "duplicate_state": ('</group_state>', '</group_state><group_state name="home" group="g"><joint name="j1" value="0"/></group_state>'),
    }.items():
        cases.append((name, body.replace(old, new, 1)))
    return cases


# ------------------------------------------------------------------ OctoMap files (.bt, .ot)

def octree_path(depth=16, child=0):
    """One voxel: a chain of nodes from the root, child `child` at each level."""
    return depth, child


def bt_data(depth=16, child=0, leaf_bits=0b01):
    # Per inner node two bytes, two bits per child (children 0-3, then 4-7): 11 inner, 01
    # occupied leaf, 10 free leaf (OcTreeBase::writeBinaryNode).
    out = bytearray()
    for level in range(depth):
        bits = 0b11 if level < depth - 1 else leaf_bits
        pair = [0, 0]
        pair[child // 4] = bits << (2 * (child % 4))
        out += bytes(pair)
    return bytes(out)


def ot_data(depth=16, child=0, value=2.0, leaf_mask=0):
    # Per node its float log-odds and a byte with a bit per existing child (writeData).
    out = bytearray()
    for level in range(depth + 1):
        mask = (1 << child) if level < depth else leaf_mask
        out += struct.pack("<f", value) + bytes([mask])
    return bytes(out)


def octree_header(binary, res="0.05", size="17", ident="OcTree"):
    kind = "binary file" if binary else "file"
    return ("# Octomap OcTree %s\nid %s\nsize %s\nres %s\ndata\n" % (kind, ident, size, res)).encode()


def octree_cases():
    cases = [("bt", b"\0" + octree_header(True) + bt_data()), ("ot", b"\1" + octree_header(False) + ot_data())]
    for res in ("0", "-1", "nan", "inf", "1e-300", "1e300", "abc", ""):
        cases.append(("bt_res_" + (res or "empty"), b"\0" + octree_header(True, res=res) + bt_data()))
        cases.append(("ot_res_" + (res or "empty"), b"\1" + octree_header(False, res=res) + ot_data()))
    for size in ("0", "4294967296", "-5", "x"):
        cases.append(("ot_size_" + size, b"\1" + octree_header(False, size=size) + ot_data()))
    for ident in ("ColorOcTree", "OcTreeStamped", "CountingOcTree", "nothing"):
        cases.append(("ot_id_" + ident, b"\1" + octree_header(False, ident=ident) + ot_data()))
    good_ot, good_bt = ot_data(), bt_data()
    for cut in (1, 5, 40, len(good_ot) - 1):
        cases.append(("ot_truncated_%d" % cut, b"\1" + octree_header(False) + good_ot[:cut]))
    for cut in (1, 7, len(good_bt) - 1):
        cases.append(("bt_truncated_%d" % cut, b"\0" + octree_header(True) + good_bt[:cut]))
    for value, name in ((float("nan"), "nan"), (float("inf"), "inf"), (-1e30, "huge")):
        cases.append(("ot_value_" + name, b"\1" + octree_header(False) + ot_data(value=value)))
    # Deeper than 16 levels: a leaf with children below it.
    cases.append(("ot_too_deep", b"\1" + octree_header(False) + ot_data(depth=16, leaf_mask=1) + ot_data(depth=3)))
    cases.append(("ot_deep_chain", b"\1" + octree_header(False) + ot_data(depth=40)))
    cases.append(("bt_too_deep", b"\0" + octree_header(True) + bt_data(depth=20)))
    cases.append(("ot_all_children", b"\1" + octree_header(False, size="9") + struct.pack("<f", 1.0) + b"\xff" + ot_data(depth=0) * 8))
    cases.append(("bt_no_header", b"\0" + bt_data()))
    cases.append(("ot_no_data_line", b"\1" + octree_header(False).replace(b"data\n", b"") + ot_data()))
    cases.append(("empty_bt", b"\0"))
    cases.append(("empty_ot", b"\1"))
    return cases


# ------------------------------------------------------------------ point clouds (cloud_target.cpp)

def cloud(points=((0.1, 0.2, 0.3), (1, 1, 1), (-0.5, 0.25, 2), (0, 0, 0)), fields=(("x", 0, 7), ("y", 4, 7), ("z", 8, 7)),
          height=1, width=None, point_step=12, row_step=None, bigendian=False, data=None, fmt="<3f"):
    """The byte layout ByteReader reads: height, width, fields (name, offset, datatype, count),
    endianness, point_step, row_step, then the data."""
    width = len(points) // height if width is None else width
    names = {"x": 0, "y": 1, "z": 2, "rgb": 3, "intensity": 4}
    out = bytearray()
    out += bytes([0, height]) if height <= 4 else bytes([255]) + struct.pack("<I", height)
    out += bytes([0, width]) if width <= 64 else bytes([255]) + struct.pack("<I", width)
    out += bytes([len(fields)])
    for name, offset, datatype in fields:
        out += bytes([names[name]]) + (bytes([0, offset]) if offset <= 40 else bytes([255]) + struct.pack("<I", offset))
        out += bytes([datatype, 1])
    out += bytes([255 if bigendian else 0])
    out += bytes([0, point_step]) if point_step <= 48 else bytes([255]) + struct.pack("<I", point_step)
    out += bytes([0]) if row_step is None else bytes([255]) + struct.pack("<I", row_step)
    if data is None:
        data = b"".join(struct.pack(fmt, *p) for p in points)
    return bytes(out + data)


def cloud_cases():
    nan, inf = float("nan"), float("inf")
    doubles = (("x", 0, 8), ("y", 8, 8), ("z", 16, 8))
    return [
        ("plain", cloud()), ("doubles", cloud(fields=doubles, point_step=24, fmt="<3d")),
        ("organized", cloud(height=2)), ("nan_inf", cloud(points=((nan, 0, 0), (inf, 1, 1), (0, -inf, 0), (1, 2, 3)))),
        ("far", cloud(points=((1e30, 0, 0), (5000, 0, 0), (0, 0, 4.99), (0, 0, 5.01)))),
        ("no_z", cloud(fields=(("x", 0, 7), ("y", 4, 7)))), ("int_field", cloud(fields=(("x", 0, 3), ("y", 4, 7), ("z", 8, 7)))),
        ("offset_beyond", cloud(fields=(("x", 0, 7), ("y", 4, 7), ("z", 10, 7)))),
        ("point_step_0", cloud(point_step=0)), ("point_step_4", cloud(point_step=4)),
        ("row_step_short", cloud(row_step=4)), ("row_step_huge", cloud(row_step=0xFFFFFFFF)),
        ("width_huge", cloud(width=0xFFFFFFFF)), ("height_huge", cloud(height=0xFFFFFFFF, width=1)),
        ("width_huge_step_0", cloud(width=0xFFFFFFFF, point_step=0, row_step=0)),
        ("data_short", cloud(data=b"\0" * 20)), ("data_empty", cloud(data=b"")), ("bigendian", cloud(bigendian=True)),
        ("duplicate_x", cloud(fields=(("x", 0, 7), ("x", 4, 7), ("y", 4, 7), ("z", 8, 7)))),
        ("width_0", cloud(points=(), width=0)), ("rgb_beside", cloud(fields=(("x", 0, 7), ("y", 4, 7), ("z", 8, 7), ("rgb", 12, 7)),
                                                                    point_step=16, fmt="<4f",
                                                                    points=((0.1, 0.2, 0.3, 0), (1, 1, 1, 0)))),
        ("empty", b""),
    ]


def write(folder, name, data):
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def main():
    # Only the generated seeds are replaced; files found by the fuzzer (crash-*, found-*) stay.
    for target in ("robot_description", "mesh", "srdf", "octree_file", "point_cloud", "service_request"):
        folder = os.path.join(CORPUS, target)
        if os.path.isdir(folder):
            for f in os.listdir(folder):
                if f.startswith("seed-"):
                    os.remove(os.path.join(folder, f))
    seeds, mesh = mesh_cases()
    # No package.xml here (catkin would take it for a package of the workspace): the robot
    # target makes a scratch package of these files at run time.
    meshes = os.path.join(ROOT, "meshes")
    shutil.rmtree(meshes, ignore_errors=True)
    for name, key in (("box.stl", "s"), ("box_ascii.stl", "a"), ("box.obj", "o"), ("box.dae", "d")):
        write(meshes, name, seeds[key])
    count = 0
    for name, sel, data in mesh:
        write(os.path.join(CORPUS, "mesh"), "seed-" + name, sel + data)
        count += 1
    for name, text in robot_cases():
        write(os.path.join(CORPUS, "robot_description"), "seed-" + name + ".urdf", text)
        count += 1
    for name, text in srdf_cases():
        write(os.path.join(CORPUS, "srdf"), "seed-" + name + ".srdf", text)
        count += 1
    for target, cases in (("octree_file", octree_cases()), ("point_cloud", cloud_cases()), ("service_request", service_cases())):
        for name_, data in cases:
            write(os.path.join(CORPUS, target), "seed-" + name_, data)
            count += 1
    print("wrote %d seed inputs to %s" % (count, os.path.relpath(CORPUS)))


if __name__ == "__main__":
    sys.exit(main())

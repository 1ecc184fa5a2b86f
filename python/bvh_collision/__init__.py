"""bvh_collision in Python: the robot's collision checker in-process, on numpy arrays.

    import numpy as np
    import bvh_collision

    checker = bvh_collision.Checker("robot.urdf", "robot.srdf")
    valid = checker.check_states(np.zeros((10, checker.dof)))  # True: collision-free

docs/python.md has the whole interface. The node's messages and services stay where rospy looks
for them: bvh_collision.msg and bvh_collision.srv (they import without the in-process module).
"""
try:
    from bvh_collision._core import Checker  # noqa: F401  (the C++ module, python/module.cpp)
except ImportError as _error:  # a build without the module: the messages must still import
    _MISSING = str(_error)

    def __getattr__(name):
        if name == "Checker":
            raise ImportError("bvh_collision's in-process module is not built here (" + _MISSING + "): "
                              "`make build` builds it into devel/, `pip install .` into a Python environment")
        raise AttributeError(name)

"""The Python package bvh_collision (docs/python.md).

Under catkin (CMakeLists.txt's catkin_python_setup) this only names the package: the C++ module
is built by CMake into the devel space. `pip install .` builds that module with CMake too (the
Debian packages `make deps` installs are needed: the build is the package's own CMakeLists.txt)
and installs it with the libraries it links, found beside it ($ORIGIN).
"""
import glob
import os
import re
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = os.path.dirname(os.path.abspath(__file__))


def version():
    with open(os.path.join(HERE, "package.xml")) as f:
        return re.search(r"<version>([^<]+)</version>", f.read()).group(1)


class CMakeModule(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    """Configures the package with CMake in the build folder and builds the module alone."""

    def build_extension(self, ext):
        out = os.path.abspath(os.path.dirname(self.get_ext_fullpath(ext.name)))
        build = os.path.abspath(os.path.join(self.build_temp, "cmake"))
        env = dict(os.environ, PATH="/usr/bin:" + os.environ.get("PATH", ""))  # catkin needs Debian's python3
        subprocess.check_call(["cmake", "-S", HERE, "-B", build, "-DCMAKE_BUILD_TYPE=Release",
                               "-DBVH_COLLISION_PYTHON_OUTPUT_DIR=" + out, "-DCMAKE_INSTALL_RPATH=$ORIGIN",
                               "-DCMAKE_BUILD_WITH_INSTALL_RPATH=ON", "-DPYTHON_EXECUTABLE=" + sys.executable],
                              env=env)
        subprocess.check_call(["cmake", "--build", build, "--target", "bvh_collision_python", "-j",
                               str(os.cpu_count() or 2)], env=env)
        for lib in glob.glob(os.path.join(build, "devel", "lib", "libbvh_collision_*.so")):
            shutil.copy(lib, out)


setup(
    name="bvh_collision",
    version=version(),
    description="A robot's collision checker in-process, on numpy arrays (BVHs, an octree, certified motions)",
    packages=["bvh_collision"],
    package_dir={"": "python"},
    ext_modules=[CMakeModule("bvh_collision._core")],
    cmdclass={"build_ext": CMakeBuild},
    install_requires=["numpy"],
)

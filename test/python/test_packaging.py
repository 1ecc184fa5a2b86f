"""The package as users get it: the module and the node's generated messages from one
`import bvh_collision` (the devel space), and setup.py (pip install .) naming the package and the
version package.xml gives. (pip install itself builds the whole library: checked by hand, see
docs/python.md.)"""
import re
import subprocess
import sys

from conftest import REPO


def test_the_module_and_the_messages_import_together():
    import bvh_collision
    from bvh_collision.srv import CheckStates

    assert bvh_collision.Checker.__module__ == "bvh_collision._core"
    assert CheckStates._type == "bvh_collision/CheckStates"


def test_setup_py_names_the_package_at_package_xmls_version():
    out = subprocess.run([sys.executable, "setup.py", "--name", "--version"], cwd=REPO, capture_output=True, text=True,
                         check=True).stdout.split()
    version = re.search(r"<version>([^<]+)</version>", (REPO / "package.xml").read_text()).group(1)
    assert out[-2:] == ["bvh_collision", version]

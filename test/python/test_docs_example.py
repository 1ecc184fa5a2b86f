"""docs/python.md's in-process example runs as written (so it cannot rot): it prints the free
fraction and writes its plot."""
import os
import re
import subprocess
import sys

from conftest import REPO, ROBOTS


def test_the_docs_example_runs_and_writes_its_plot(tmp_path):
    text = (REPO / "docs" / "python.md").read_text()
    block = re.search(r"<!-- example: in-process -->\n```python\n(.*?)```", text, re.S)
    assert block, "docs/python.md has lost its example"
    script = tmp_path / "example.py"
    script.write_text(block.group(1))
    env = dict(os.environ, BVH_COLLISION_ROBOTS=str(ROBOTS))
    out = subprocess.run([sys.executable, str(script)], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    free = float(re.search(r"free: ([0-9.]+)", out.stdout).group(1))
    assert 0.0 < free < 1.0
    png = tmp_path / "free_fraction.png"
    assert png.exists() and png.stat().st_size > 10000 and png.read_bytes()[1:4] == b"PNG"

"""Examples run; the core never imports matplotlib; public API is explicit."""

import runpy
import subprocess
import sys
from pathlib import Path

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

import bwim

ROOT = Path(__file__).resolve().parents[2]


def test_examples_run(capsys):
    for script in sorted((ROOT / "examples").glob("*.py")):
        runpy.run_path(str(script), run_name="__main__")
    assert "frequencies" in capsys.readouterr().out


def test_core_does_not_import_matplotlib():
    code = "import sys, bwim, bwim.paper, bwim.cli; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"


def test_public_api_listed():
    for name in bwim.__all__:
        assert hasattr(bwim, name), name
    for path in (ROOT / "src").rglob("*.py"):
        assert "import *" not in path.read_text(), path


@given(
    length=st.floats(1.0, 100.0),
    fractions=st.lists(st.floats(0.01, 0.99), max_size=4),
    extra=st.integers(0, 10),
)
def test_grid_lines_pass_through_required_points(length, fractions, extra):
    through = sorted({round(f * length, 6) for f in fractions})
    n = len(through) + 1 + extra
    lines = bwim.grid_lines(length, n, through=through)
    assert lines.size == n + 1
    assert lines[0] == 0.0 and np.isclose(lines[-1], length)
    assert np.all(np.diff(lines) > 0)
    for t in through:
        assert np.min(np.abs(lines - t)) < 1e-9 * length

"""Every script in examples/ runs as a user runs it (a fresh interpreter) and says something sensible."""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _run(name, *args):
    p = subprocess.run([sys.executable, str(EXAMPLES / f"{name}.py"), *args], capture_output=True, text=True,
                       timeout=600)
    assert p.returncode == 0, p.stderr
    return p.stdout


def test_custom_law_runs_in_sampled_mode():
    """The Python-only tanh law runs in the python engine at 1 kHz and tracks within 0.1 rad over 1 s."""
    out = _run("custom_law", "1.0")
    line = next(ln for ln in out.splitlines() if "tanh-robust" in ln)
    assert "python engine" in line and "sampled 1000 Hz" in line and ": ok," in line
    err = float(re.search(r"max\|e\| = ([0-9.e+-]+) rad", line).group(1))
    assert err < 0.1

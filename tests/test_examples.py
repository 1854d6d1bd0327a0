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


def test_ur5_payload_robust_beats_fbl_on_the_same_plant():
    """examples/ur5_payload.py (2 s): both laws finish, and the robust law with exact payload bounds
    has a smaller max|e| than FBL on the UR5 carrying 5 kg."""
    out = _run("ur5_payload", "2.0")
    errs = {law: float(re.search(rf"{law} on .*max\|e\| = ([0-9.e+-]+) rad", out).group(1)) for law in ("fbl", "robust")}
    assert ": ok;" in out and out.count(": ok;") == 2
    assert errs["robust"] < errs["fbl"]


def test_ur5_gains_in_the_config_are_the_scripts():
    """The K of examples/ur5_payload.toml is what `--gains` computes (50 x diag M(q_d(0)))."""
    from rc3r.io import read_toml

    printed = _run("ur5_payload", "--gains")
    k = [float(x) for x in re.search(r"K = \[(.*)\]", printed).group(1).split(",")]
    cfg = read_toml(EXAMPLES / "ur5_payload.toml", "config")
    assert cfg["gains"]["robust"]["K"] == k


def test_montecarlo_example_robust_beats_fbl_and_resumes(tmp_path):
    """examples/montecarlo.py (4 plants, 1 s): robust median max|e| < FBL's / 10; a second run resumes (0 new)."""
    out = _run("montecarlo", "4", "1.0", f"--out={tmp_path / 'mc'}")
    med = {law: float(re.search(rf"{law}: .*median max\|e\| = ([0-9.e+-]+) rad", out).group(1))
           for law in ("fbl", "robust")}
    assert med["robust"] < 0.1 * med["fbl"]
    again = _run("montecarlo", "4", "1.0", f"--out={tmp_path / 'mc'}")
    assert "(0 new)" in again and (tmp_path / "mc" / "error_vs_distance.png").stat().st_size > 0

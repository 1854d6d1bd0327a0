"""numba's disk cache is keyed on the package's content: an edit of a module a compiled kernel
calls is seen by the next process (numba alone stamps a kernel with its own file only)."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from rc3r import _numba_cache

SRC = Path(__file__).resolve().parents[1] / "src"


def test_hash_changes_with_any_numba_module_and_ignores_others(tmp_path):
    """package_hash covers every module that uses numba (not only the one defining a kernel)."""
    pkg = tmp_path / "rc3r"
    shutil.copytree(SRC / "rc3r", pkg, ignore=shutil.ignore_patterns("__pycache__"))
    h0 = _numba_cache.package_hash(str(pkg))
    status = pkg / "simulate" / "status.py"
    status.write_text(status.read_text().replace("abs(x[i]) > lim[0]", "abs(x[i]) > 0.5 * lim[0]"))
    h1 = _numba_cache.package_hash(str(pkg))
    assert h1 != h0
    (pkg / "cli" / "bounds.py").write_text((pkg / "cli" / "bounds.py").read_text() + "\n# a comment\n")
    assert _numba_cache.package_hash(str(pkg)) == h1  # a module without numba code does not count


def test_every_module_the_compiled_template_imports_counts_in_the_hash():
    """Each rc3r module that engines/compiled.py imports from (kernels, status codes, the Rosenbrock tables'
    plain constants, which numba freezes into the machine code) mentions numba, so package_hash covers
    it: an edited table is recompiled, never served from a stale cache. (Found by a mutation run: a
    RODAS coefficient edited in engines/_tableaux.py, a file that did not mention numba, left every
    simulation bit-identical.)"""
    import re

    template = (SRC / "rc3r" / "simulate" / "engines" / "compiled.py").read_text()
    mods = set(re.findall(r"^from (rc3r(?:\.\w+)+) import", template, flags=re.M))
    assert "rc3r.simulate.engines._tableaux" in mods and len(mods) >= 5
    for mod in sorted(mods):
        path = SRC / Path(*mod.split("."))
        path = path / "__init__.py" if path.is_dir() else path.with_suffix(".py")
        assert b"numba" in path.read_bytes(), f"{mod} does not count in package_hash"


def test_rc3r_kernels_use_the_package_stamp():
    """Every cached rc3r kernel's locator is one of ours, and its source stamp carries the hash."""
    from rc3r.simulate import status
    from rc3r.trajectory import reference_into

    for fn in (status.check, reference_into):
        locator = fn._cache._impl._locator
        assert type(locator) in _numba_cache._INSTALLED
        assert locator.get_source_stamp()[1] == _numba_cache.package_hash()


_PROBE = r"""
import numpy as np
import rc3r
from rc3r.simulate import SimOptions, simulate
spec = rc3r.build_run(controller="fbl", duration=0.01, rate=1000.0)
x0 = np.array([0.8, 0.0, 0.0, 0.0, 0.0, 0.0])   # |q1| = 0.8 rad, inside q_max = 1
res = simulate(spec.true_rigid, spec.law, spec.trajectory, SimOptions(duration=0.002, rate=1000.0, q_max=1.0,
                                                                 engine="fast"), x0=x0)
print("STATUS", 0 if res.ok else 2 if "|q|" in res.message else res.message)
"""


@pytest.mark.slow
def test_an_edit_of_a_called_module_reaches_the_compiled_engine(tmp_path):
    """The compiled engine's integrators call status.check from another file. Edit check so |q| = 0.8 rad
    passes a bound of 1 rad only unedited; the next process must see the edit (status 2, QBOUND) although
    the engine's source is unchanged and its cache was written before the edit."""
    shutil.copytree(SRC / "rc3r", tmp_path / "rc3r", ignore=shutil.ignore_patterns("__pycache__"))
    env = dict(os.environ, PYTHONPATH=str(tmp_path))
    env.pop("NUMBA_CACHE_DIR", None)
    env.pop("NUMBA_DISABLE_JIT", None)

    def probe() -> str:
        out = subprocess.run([sys.executable, "-c", _PROBE], env=env, capture_output=True, text=True,
                             timeout=300, cwd=tmp_path)
        assert out.returncode == 0, out.stderr
        return [ln for ln in out.stdout.splitlines() if ln.startswith("STATUS")][0]

    assert probe() == "STATUS 0"  # compiles and caches
    assert probe() == "STATUS 0"  # from the cache
    status = tmp_path / "rc3r" / "simulate" / "status.py"
    status.write_text(status.read_text().replace("abs(x[i]) > lim[0]", "abs(x[i]) > 0.5 * lim[0]"))
    assert probe() == "STATUS 2"  # the edit is seen: QBOUND

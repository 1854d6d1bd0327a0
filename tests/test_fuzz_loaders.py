"""Hypothesis fuzzing of the file loaders: random mutations of valid files get only clean refusals.

Each mutation of the committed URDF, of the parameter and box TOML files, and of a run
configuration is loaded the way the command line loads it. The property: the loader
returns a robot / a box / a run specification, or raises :class:`rc3r.errors.Rc3rError`
(the one-line ``rc3r: error:`` of the command line); never any other exception (a
traceback for a user), and nothing is printed meanwhile (no C++ line on file descriptor 2,
no Python warning). Examples are derandomized, so a failure reproduces.
"""
from __future__ import annotations

import os
import sys
import tempfile
import warnings
from contextlib import contextmanager
from pathlib import Path

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from rc3r.errors import Rc3rError
from rc3r.io import read_toml, tomllib
from rc3r.robots import load_urdf_robot, robot_class
from rc3r.runspec import build_run
from rc3r.uncertainty import load_box

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "src" / "rc3r" / "robots" / "rr3" / "data"
URDF = (ROOT / "urdf" / "rr3.urdf").read_text()
PARAMS = (DATA / "rr3.toml").read_text()
BOX = (DATA / "paper_box.toml").read_text()
CONFIG = """seed = 3
perturbed = true
[controller]
kind = "robust"
K = [100.0, 100.0, 100.0]
Lambda = 50.0
eps = 0.5
[model]
theta = "paper"
rho = "certified"
[simulation]
duration = 0.2
rate = 1000.0
jac_reuse = 5
[trajectory]
kind = "paper"
"""

FUZZ = settings(max_examples=60, deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])

# pieces a mutation inserts: markup, numbers that break physics or parsing, TOML syntax
PIECES = st.sampled_from(['<', '>', '"', '/>', '</link>', '<inertia/>', '=', ' ', '\n', 'nan', 'inf', '-1',
                          '1e308', '-0', '0', '1e-320', 'true', '[', ']', '[[link]]', '{', '"x"', '#', "'",
                          '= [1, 0]', 'mass', 'ixx="-1"', 'type="prismatic"', '\x00', 'é'])


@st.composite
def mutated(draw, text: str):
    """``text`` with 1-3 edits: delete a slice, insert a piece, duplicate a slice, replace a number."""
    for _ in range(draw(st.integers(1, 3))):
        n = len(text)
        i = draw(st.integers(0, max(n - 1, 0)))
        j = min(n, i + draw(st.integers(0, 40)))
        kind = draw(st.sampled_from(["delete", "insert", "duplicate", "replace"]))
        if kind == "delete":
            text = text[:i] + text[j:]
        elif kind == "insert":
            text = text[:i] + draw(PIECES) + text[i:]
        elif kind == "duplicate":
            text = text[:j] + text[i:j] + text[j:]
        else:
            text = text[:i] + draw(PIECES) + text[j:]
    return text


#: Warnings Python does not show by default (outside __main__): never printed to a user.
_HIDDEN = (DeprecationWarning, PendingDeprecationWarning, ImportWarning)


@contextmanager
def _fd2():
    """Everything written on file descriptor 2 meanwhile, C++ included: a trap of the test's own
    (fd 2 duplicated onto a temporary file), independent of rc3r.io.native_stderr."""
    sys.stderr.flush()
    saved, caught = os.dup(2), []
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 2)
        try:
            yield caught
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            caught.append(sink.read().decode(errors="replace"))


def _clean(load) -> None:
    """The loader returns or raises Rc3rError, and prints nothing meanwhile: no C++ line on fd 2
    (urdfdom's "Error: ..."), no Python warning (numpy's RuntimeWarning: overflow)."""
    with _fd2() as err, warnings.catch_warnings(record=True) as shown:
        warnings.simplefilter("always")
        try:
            load()
        except Rc3rError as exc:
            event(f"refused: {type(exc).__name__}")  # a clean refusal
        else:
            event("loaded")
    assert err == [""], err
    assert not [f"{w.category.__name__}: {w.message}" for w in shown if not issubclass(w.category, _HIDDEN)]


@FUZZ
@given(text=mutated(URDF))
def test_mutated_urdf_is_loaded_or_refused_cleanly_by_the_closed_form_loader(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("u") / "arm.urdf"
    path.write_text(text, errors="surrogatepass")
    _clean(lambda: robot_class().from_urdf(path))


@FUZZ
@given(text=mutated(URDF))
def test_mutated_urdf_is_loaded_or_refused_cleanly_by_the_generic_loader(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("g") / "arm.urdf"
    path.write_text(text, errors="surrogatepass")
    _clean(lambda: load_urdf_robot(path))


@FUZZ
@given(text=mutated(PARAMS))
def test_mutated_parameter_file_is_loaded_or_refused_cleanly(tmp_path_factory, text):
    d = tmp_path_factory.mktemp("p")
    (d / "p.toml").write_text(text, errors="surrogatepass")
    _clean(lambda: robot_class().make_urdf(d / "p.toml", d / "out.urdf"))


@FUZZ
@given(text=mutated(BOX))
def test_mutated_box_file_is_loaded_or_refused_cleanly(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("b") / "box.toml"
    path.write_text(text, errors="surrogatepass")
    names = robot_class().nominal().standard_parameter_names
    _clean(lambda: load_box(path, names))


@FUZZ
@given(text=mutated(CONFIG))
def test_mutated_run_config_is_built_or_refused_cleanly(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("c") / "run.toml"
    path.write_text(text, errors="surrogatepass")
    _clean(lambda: build_run(config=read_toml(path, "config file")))


def test_the_unmutated_files_load():
    """The fuzzers start from files that load: a refusal above is the mutation's doing."""
    assert robot_class().from_urdf(ROOT / "urdf" / "rr3.urdf").n == 3
    assert build_run(config=tomllib.loads(CONFIG)).options.rate == 1000.0


@pytest.mark.parametrize("text", ["", "\x00", "<robot>", '<robot name="x"/>', "<?xml version='1.0'?>"])
def test_degenerate_urdfs(tmp_path, text):
    path = tmp_path / "x.urdf"
    path.write_text(text)
    with pytest.raises(Rc3rError):
        robot_class().from_urdf(path)
    with pytest.raises(Rc3rError):
        load_urdf_robot(path)


def _npz_log() -> bytes:
    """A valid NPZ log (t, q, tau of the 3R: 200 samples at 1 kHz) as bytes."""
    import io

    import numpy as np

    t = np.arange(200) * 1e-3
    q = np.column_stack([np.sin(2 * np.pi * f * t) for f in (1.0, 2.0, 3.0)])
    buf = io.BytesIO()
    np.savez(buf, t=t, q=q, tau=np.cos(q))
    return buf.getvalue()


NPZ_LOG = _npz_log()


@FUZZ
@given(edits=st.lists(st.tuples(st.integers(0, len(NPZ_LOG) - 1), st.integers(1, 255)), min_size=1, max_size=4),
       cut=st.one_of(st.none(), st.integers(0, len(NPZ_LOG))))
def test_corrupted_npz_log_is_loaded_or_refused_cleanly(tmp_path_factory, edits, cut):
    """Property: an NPZ log with 1-4 bytes flipped (in the zip headers, the .npy headers, the data or the
    CRCs) and possibly truncated is read or refused with one Rc3rError -- never zipfile's BadZipFile, a
    zlib error or numpy's ValueError (exit 70 on main: "BadZipFile: Bad CRC-32 for file 'q.npy'")."""
    from rc3r.identify.log import load_log

    data = bytearray(NPZ_LOG)
    for at, flip in edits:
        data[at] ^= flip
    path = tmp_path_factory.mktemp("npz") / "log.npz"
    path.write_bytes(bytes(data[:cut]) if cut is not None else bytes(data))
    _clean(lambda: load_log(path, n=3))


def test_the_unmutated_npz_log_loads(tmp_path):
    from rc3r.identify.log import load_log

    (tmp_path / "log.npz").write_bytes(NPZ_LOG)
    assert load_log(tmp_path / "log.npz", n=3).samples == 200

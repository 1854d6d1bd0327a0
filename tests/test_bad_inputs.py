"""The bad-input battery: every command, every kind of mistake, one clean refusal each.

For each case: exit 2, stderr exactly one line, ``rc3r: error: ...``, naming the problem (the
expected words) -- captured at the file-descriptor level, so a C++ library's ``Error:`` line
counts -- no Python warning (numpy's ``RuntimeWarning: overflow`` would be printed), no
traceback, and an earlier result in ``--out`` left as it was. Every case runs with the working
directory in a temporary directory, so a command that defaults to ``out/...`` cannot touch the
checkout. (More cases with their own assertions live beside the modules they exercise:
``test_study.py``, ``test_output.py``, ``test_rr3_urdf.py``, ``test_paper.py``,
``test_campaign.py``.)
"""
from __future__ import annotations

import os
import re
import shlex
import stat
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from rc3r.cli import main
from rc3r.errors import ConfigError

ROOT = Path(__file__).resolve().parents[1]
URDF = (ROOT / "urdf" / "rr3.urdf").read_text()
PARAMS = (ROOT / "src" / "rc3r" / "robots" / "rr3" / "data" / "rr3.toml").read_text()

#: A regular file that no one may read, root included: procfs refuses reads of a write-only
#: sysctl (mode 0200) whatever the caller's capabilities (a chmod 000 file does not stop root).
UNREADABLE = "/proc/sys/vm/drop_caches"

#: A file name over the system's limit (NAME_MAX = 255 bytes): ENAMETOOLONG.
LONG = "n" * 300


def _urdf(old: str, new: str) -> str:
    assert old in URDF, old
    return URDF.replace(old, new, 1)


def _loop(parent: str, child: str) -> str:
    return URDF.replace("</robot>", f'  <joint name="loop" type="fixed">\n    <parent link="{parent}" />\n'
                                    f'    <child link="{child}" />\n  </joint>\n</robot>')

FILES = {
    "empty.urdf": "",
    "notxml.urdf": "<robot name='x'><link",
    "notrobot.urdf": "<model/>",
    "negmass.urdf": re.sub(r'<mass value="[^"]*"', '<mass value="-1"', URDF, count=1),
    "zeromass.urdf": re.sub(r'<mass value="[^"]*"', '<mass value="0"', URDF, count=1),
    "nanmass.urdf": re.sub(r'<mass value="[^"]*"', '<mass value="nan"', URDF, count=1),
    "textmass.urdf": re.sub(r'<mass value="[^"]*"', '<mass value="heavy"', URDF, count=1),
    "noiyz.urdf": re.sub(r' iyz="[^"]*"', "", URDF, count=1),
    "negixx.urdf": re.sub(r'ixx="[^"]*"', 'ixx="-5"', URDF, count=1),
    "infxyz.urdf": re.sub(r'xyz="[^"]*"', 'xyz="0 inf 0"', URDF, count=1),
    "prismatic.urdf": URDF.replace('type="revolute"', 'type="prismatic"', 1),
    "bad.toml": "[controller\nK = 1",
    "kpp.toml": "[controller]\nkind = \"fbl\"\nKpp = 5\n",
    "duration_str.toml": "[simulation]\nduration = \"abc\"\n",
    "seed_neg.toml": "seed = -1\n",
    "seed_float.toml": "seed = 1e400\n",
    "controller_int.toml": "controller = 5\n",
    "engine.toml": "[simulation]\nengine = \"warp\"\n",
    "jac0.toml": "[simulation]\njac_reuse = 0\n",
    "jacfloat.toml": "[simulation]\njac_reuse = 1.5\n",
    "rho_str.toml": "perturbed = true\n[model]\nrho = \"huge\"\n",
    "theta_len.toml": "[model]\ntheta = [1.0, 2.0]\n",
    "perturbed_str.toml": "perturbed = \"yes\"\n",
    "simulaton.toml": "[simulaton]\nduration = 1\n",
    "gain_neg.toml": "[controller]\nkind = \"robust\"\nK = [100, -1, 100]\n",
    "gain_bool.toml": "[controller]\nkind = \"robust\"\nK = true\n",
    "output_rate.toml": "[simulation]\noutput_rate = 1e12\n",
    "box_key.toml": "[delta]\nmas = [0, 1]\n",
    "box_empty.toml": "[delta]\nmass = [1, 0]\n",
    "box_nan.toml": "[delta]\nmass = [0, nan]\n",
    "box_str.toml": "[delta]\nmass = \"lots\"\n",
    "box_link.toml": "[[link]]\nindex = 9\nm = [0, 1]\n",
    "params_key.toml": "[link1]\nmasss = 1\n",
    # urdfdom's errors (it writes "Error: ..." lines on fd 2 beside rc3r's own line)
    "dangling.urdf": _urdf('<parent link="link2" />', '<parent link="nolink" />'),
    "duplink.urdf": _urdf('<link name="tool" />', '<link name="tool" />\n  <link name="tool" />'),
    "tworoots.urdf": _urdf('<child link="tool" />', '<child link="link1" />'),
    "cycle.urdf": _loop("tool", "base_link"),  # base_link -> ... -> tool -> base_link: no root
    # numbers that overflow the arithmetic (numpy's RuntimeWarning lines, then exit 70 on main)
    "bigorigin.urdf": re.sub(r'(<joint name="joint2".*?<origin xyz=")[^"]*"', r'\g<1>1e300 0 0"', URDF, count=1,
                             flags=re.S),
    "bigmass.urdf": re.sub(r'<mass value="[^"]*"', '<mass value="1e300"', URDF, count=1),
    "edgemass.urdf": re.sub(r'<mass value="[^"]*"', '<mass value="1e12"', URDF, count=1),  # at the bound
    "box_big.toml": "[delta]\nmass = [0, 1e300]\n",
    "params_big.toml": PARAMS.replace("mass = 10.0", "mass = 1e300", 1),
    # parameter files with a key rc3r would ignore
    "params_top.toml": "colour = \"red\"\n" + PARAMS,
    "params_link.toml": PARAMS.replace("mass = 10.0", "mass = 10.0\nmas = 1.0", 1),
    "params_inertia.toml": PARAMS.replace("ixx = 0.5,", "ixx = 0.5, ixq = 1.0,", 1),
}

# (id, argv with {d} = the files' directory, {out} = an earlier result directory, {t} = a directory of
# files that must not be replaced (_targets), expected words)
CASES = [
    # verify-model
    ("vm-missing", "verify-model --urdf {d}/nope.urdf", "not found"),
    ("vm-empty", "verify-model --urdf {d}/empty.urdf", "malformed URDF"),
    ("vm-notxml", "verify-model --urdf {d}/notxml.urdf", "malformed URDF"),
    ("vm-notrobot", "verify-model --urdf {d}/notrobot.urdf", "not <robot>"),
    ("vm-negmass", "verify-model --urdf {d}/negmass.urdf", "not a physical robot"),
    ("vm-zeromass", "verify-model --urdf {d}/zeromass.urdf", "not a physical robot"),
    ("vm-nanmass", "verify-model --urdf {d}/nanmass.urdf", "not a finite number"),
    ("vm-textmass", "verify-model --urdf {d}/textmass.urdf", "not a finite number"),
    ("vm-noiyz", "verify-model --urdf {d}/noiyz.urdf", "has no iyz"),
    ("vm-negixx", "verify-model --urdf {d}/negixx.urdf", "not positive definite"),
    ("vm-infxyz", "verify-model --urdf {d}/infxyz.urdf", "not a finite number"),
    ("vm-prismatic", "verify-model --urdf {d}/prismatic.urdf", "prismatic"),
    ("vm-dir", "verify-model --urdf {d}", "not a file"),
    ("vm-devzero", "verify-model --urdf /dev/zero", "not a file"),
    ("vm-samples0", "verify-model --samples 0", "--samples"),
    ("vm-samples-neg", "verify-model --samples -5", "--samples"),
    ("vm-samples-text", "verify-model --samples many", "--samples"),
    ("vm-seed-neg", "verify-model --seed -1", "--seed"),
    ("vm-robot", "verify-model --robot nosuch", "nosuch"),
    ("vm-generic", "verify-model --generic", "--generic needs --urdf"),
    # make-urdf
    ("mu-missing", "make-urdf --params {d}/nope.toml --out {t}/x.urdf", "not found"),
    ("mu-malformed", "make-urdf --params {d}/bad.toml --out {t}/x.urdf", "malformed TOML"),
    ("mu-binary", "make-urdf --params {d}/binary.toml --out {t}/x.urdf", "not a text file"),
    ("mu-devzero", "make-urdf --params /dev/zero --out {t}/x.urdf", "not a regular file"),
    # URDFs urdfdom refuses (its stderr caught and folded into the one line), on every load path
    ("vm-dangling", "verify-model --urdf {d}/dangling.urdf", "parent link [nolink] of joint [joint3] not found"),
    ("vm-generic-dangling", "verify-model --generic --urdf {d}/dangling.urdf", "parent link [nolink]"),
    ("bd-urdf-dangling", "bounds --urdf {d}/dangling.urdf", "parent link [nolink]"),
    ("run-plant-dangling", "run --plant {d}/dangling.urdf --out {out}", "parent link [nolink]"),
    ("vm-duplink", "verify-model --urdf {d}/duplink.urdf", "link 'tool' is not unique"),
    ("vm-generic-duplink", "verify-model --generic --urdf {d}/duplink.urdf", "link 'tool' is not unique"),
    ("vm-tworoots", "verify-model --urdf {d}/tworoots.urdf", "Two root links"),
    ("vm-cycle", "verify-model --urdf {d}/cycle.urdf", "No root link"),
    ("vm-generic-cycle", "verify-model --generic --urdf {d}/cycle.urdf", "No root link"),
    # magnitudes beyond MAX_MAGNITUDE (1e12): refused at the edge, no overflow warning
    ("vm-bigorigin", "verify-model --urdf {d}/bigorigin.urdf", "beyond 1e+12"),
    ("vm-generic-bigorigin", "verify-model --generic --urdf {d}/bigorigin.urdf", "magnitude <= 1e+12"),
    ("vm-bigmass", "verify-model --urdf {d}/bigmass.urdf", "beyond 1e+12"),
    ("vm-generic-bigmass", "verify-model --generic --urdf {d}/bigmass.urdf", "magnitude <= 1e+12"),
    ("bd-urdf-bigmass", "bounds --urdf {d}/bigmass.urdf", "beyond 1e+12"),
    ("bd-urdf-edgemass", "bounds --urdf {d}/edgemass.urdf", "cannot be computed in double precision"),
    ("bd-box-big", "bounds --box {d}/box_big.toml", "beyond 1e+12"),
    ("bd-box-big-json", "bounds --box {d}/box_big.toml --json", "beyond 1e+12"),
    ("run-box-big", "run --perturbed --box {d}/box_big.toml --out {out}", "beyond 1e+12"),
    ("mu-big", "make-urdf --params {d}/params_big.toml --out {t}/x.urdf", "link 1 mass 1e+300 is beyond"),
    # files that cannot be read or named (exit 70 on main)
    ("vm-unreadable", f"verify-model --urdf {UNREADABLE}", "Permission denied"),
    ("vm-generic-unreadable", f"verify-model --generic --urdf {UNREADABLE}", "Permission denied"),
    ("bd-unreadable", f"bounds --urdf {UNREADABLE}", "Permission denied"),
    ("vm-generic-dir", "verify-model --generic --urdf {d}", "not a file"),
    ("vm-longname", f"verify-model --urdf {{d}}/{LONG}.urdf", "File name too long"),
    ("vm-generic-longname", f"verify-model --generic --urdf {{d}}/{LONG}.urdf", "File name too long"),
    ("bd-longname", f"bounds --urdf {{d}}/{LONG}.urdf", "File name too long"),
    ("vm-samples-huge", "verify-model --samples 100000000000", "more than 100000"),
    # make-urdf: unknown keys, and --out that is not a file rc3r may replace
    ("mu-key-top", "make-urdf --params {d}/params_top.toml --out {t}/x.urdf", "unknown key 'colour' in the top level"),
    ("mu-key-link", "make-urdf --params {d}/params_link.toml --out {t}/x.urdf", "unknown key 'mas' in link 1"),
    ("mu-key-inertia", "make-urdf --params {d}/params_inertia.toml --out {t}/x.urdf",
     "unknown key 'ixq' in link 1 inertia"),
    ("mu-key-old", "make-urdf --params {d}/params_key.toml --out {t}/x.urdf", "unknown key 'link1'"),
    ("mu-out-dir", "make-urdf --out {d}/dir.toml", "is a directory"),
    ("mu-out-empty", "make-urdf --out ''", "is empty"),
    ("mu-out-root", "make-urdf --out /", "is a directory"),
    ("mu-out-longname", f"make-urdf --out {{d}}/{LONG}.urdf", "File name too long"),
    ("mu-out-longtmp", f"make-urdf --out {{d}}/{LONG[:250]}.urdf", "File name too long"),  # .<name>.XXXXXXXX.urdf
    ("mu-out-symlink", "make-urdf --out {t}/link.urdf", "symbolic link"),
    ("mu-out-fifo", "make-urdf --out {t}/fifo.urdf", "not a regular file"),
    ("mu-out-chardev", "make-urdf --out {t}/chardev.urdf", "not a regular file"),
    ("mu-out-proc", "make-urdf --out /proc/rc3r.urdf", "cannot write"),
    # run --out that cannot be written, found before any work (progress lines would be a 2nd line)
    ("out-proc", "run --duration 0.1 --out /proc/rc3r-out", "cannot write in /proc"),
    ("out-under-file", "run --duration 0.1 --out {d}/afile/run", "Not a directory"),
    ("out-longname", f"run --duration 0.1 --out {{d}}/{LONG}", "File name too long"),
    ("out-longlock", f"run --duration 0.1 --out {{d}}/{LONG[:250]}", "File name too long"),
    # bounds
    ("bd-missing", "bounds --box {d}/nope.toml", "not found"),
    ("bd-malformed", "bounds --box {d}/bad.toml", "malformed TOML"),
    ("bd-key", "bounds --box {d}/box_key.toml", "mas"),
    ("bd-str", "bounds --box {d}/box_str.toml", "mass"),
    ("bd-link", "bounds --box {d}/box_link.toml", "index"),
    ("bd-dir", "bounds --box {d}/dir.toml", "directory"),
    ("bd-devzero", "bounds --box /dev/zero", "not a regular file"),
    ("bd-urdf", "bounds --urdf {d}/nope.urdf", "not found"),
    # run: options
    ("run-eps0", "run --eps 0 --out {out}", "--eps"),
    ("run-eps-neg", "run --eps -1 --out {out}", "--eps"),
    ("run-eps-nan", "run --eps nan --out {out}", "--eps"),
    ("run-eps-inf", "run --eps inf --out {out}", "--eps"),
    ("run-rate0", "run --rate 0 --out {out}", "--rate"),
    ("run-rate-huge", "run --rate 1e12 --out {out}", "controller samples"),
    ("run-duration0", "run --duration 0 --out {out}", "--duration"),
    ("run-duration-huge", "run --duration 1e9 --out {out}", "rows"),
    ("run-rate-slow", "run --rate 0.01 --duration 1 --out {out}", "slower than the duration"),
    ("run-controller", "run --controller nosuch --out {out}", "nosuch"),
    ("run-plant", "run --plant garbage --out {out}", "garbage"),
    ("run-plant-seed", "run --plant random:abc --out {out}", "random:"),
    ("run-plant-corner", "run --plant corner:01 --out {out}", "corner:"),
    ("run-plant-urdf", "run --plant {d}/nope.urdf --out {out}", "not found"),
    ("run-robot", "run --robot nosuch --out {out}", "nosuch"),
    ("run-payload-text", "run --robot ur5 --payload heavy --out {out}", "LO:HI"),
    ("run-payload-com", "run --robot ur5 --payload 0:1 --payload-com 1,2 --out {out}", "X,Y,Z"),
    ("run-com-alone", "run --robot ur5 --payload-com 0,0,0.1 --out {out}", "without a payload"),
    ("run-ur5-nobox", "run --robot ur5 --perturbed --out {out}", "no default box"),
    ("run-engine", "run --engine warp --out {out}", "--engine"),
    ("run-box-missing", "run --perturbed --box {d}/nope.toml --out {out}", "not found"),
    ("run-box-key", "run --perturbed --box {d}/box_key.toml --out {out}", "mas"),
    # run: config files
    ("cfg-missing", "run --config {d}/nope.toml --out {out}", "not found"),
    ("cfg-malformed", "run --config {d}/bad.toml --out {out}", "malformed TOML"),
    ("cfg-devzero", "run --config /dev/zero --out {out}", "not a regular file"),
    ("cfg-dir", "run --config {d}/dir.toml --out {out}", "directory"),
    ("cfg-binary", "run --config {d}/binary.toml --out {out}", "not a text file"),
    ("cfg-kpp", "run --config {d}/kpp.toml --out {out}", "Kpp"),
    ("cfg-duration", "run --config {d}/duration_str.toml --out {out}", "duration"),
    ("cfg-seed-neg", "run --config {d}/seed_neg.toml --out {out}", "seed"),
    ("cfg-seed-float", "run --config {d}/seed_float.toml --out {out}", "seed"),
    ("cfg-controller", "run --config {d}/controller_int.toml --out {out}", "controller"),
    ("cfg-engine", "run --config {d}/engine.toml --out {out}", "engine"),
    ("cfg-jac0", "run --config {d}/jac0.toml --out {out}", "jac_reuse"),
    ("cfg-jacfloat", "run --config {d}/jacfloat.toml --out {out}", "jac_reuse"),
    ("cfg-rho", "run --config {d}/rho_str.toml --out {out}", "rho"),
    ("cfg-theta", "run --config {d}/theta_len.toml --out {out}", "theta"),
    ("cfg-perturbed", "run --config {d}/perturbed_str.toml --out {out}", "perturbed"),
    ("cfg-table", "run --config {d}/simulaton.toml --out {out}", "simulaton"),
    ("cfg-gain", "run --config {d}/gain_neg.toml --out {out}", "K"),
    ("cfg-gain-bool", "run --config {d}/gain_bool.toml --out {out}", "K must be numbers"),
    ("bd-empty", "bounds --box {d}/box_empty.toml", "is empty"),
    ("bd-nan", "bounds --box {d}/box_nan.toml", "not finite"),
    ("cfg-output-rate", "run --config {d}/output_rate.toml --out {out}", "rows"),
    # run: where to write
    ("out-file", "run --duration 0.1 --out {d}/afile", "is a file"),
    ("out-device", "run --duration 0.1 --out /dev/null", "not a directory"),
    ("out-root", "run --duration 0.1 --out /", "filesystem root"),
    ("out-empty", "run --duration 0.1 --out ''", "--out is empty"),
    ("out-dot", "run --duration 0.1 --out .", "--out is empty"),
    ("out-parent", "run --duration 0.1 --out ..", "contains it"),
    ("out-foreign", "run --duration 0.1 --out {d}/foreign", "rc3r did not write"),
    ("paper-out-file", "paper --out {d}/afile", "is a file"),
    ("paper-out-foreign", "paper --out {d}/foreign", "rc3r did not write"),
    # montecarlo
    ("mc-n0", "montecarlo --n 0 --out {out}", "--n"),
    ("mc-n-neg", "montecarlo --n -3 --out {out}", "--n"),
    ("mc-n-text", "montecarlo --n many --out {out}", "--n"),
    ("mc-controllers", "montecarlo --controllers fbl,nosuch --out {out}", "nosuch"),
    ("mc-controllers-empty", "montecarlo --controllers , --out {out}", "controller"),
    ("mc-workers0", "montecarlo --workers 0 --out {out}", "--workers"),
    ("mc-eps0", "montecarlo --eps 0 --out {out}", "--eps"),
    ("mc-rate-neg", "montecarlo --rate -1 --out {out}", "--rate"),
    ("mc-box", "montecarlo --n 1 --box {d}/nope.toml --out {d}/mcbox", "not found"),
    ("mc-both", "montecarlo --n 1 --workers 2 --scheduler tcp://127.0.0.1:1 --out {d}/mcboth", "not both"),
    ("mc-out-file", "montecarlo --n 1 --out {d}/afile", "is a file"),
    ("mc-out-foreign", "montecarlo --n 1 --out {d}/foreign", "rc3r did not write"),
    ("mc-config", "montecarlo --n 1 --config {d}/kpp.toml --out {d}/mccfg", "Kpp"),
    ("mc-orphan", "montecarlo --n 1 --resume --out {d}/campaign", "no campaign.json"),
    ("mc-robot", "montecarlo --robot ur5 --n 1 --out {d}/mcur5", "no default box"),
    # sweep
    ("sw-none", "sweep", "required: what"),
    ("run-payload-order", "run --robot ur5 --payload 5:1 --out {out}", "LO <= HI"),
    ("bd-devnull", "bounds --box /dev/null", "not a regular file"),
    ("sw-what", "sweep foo", "foo"),
    ("sw-eps0", "sweep eps --eps 0 --out {out}", "--eps"),
    ("sw-eps-neg", "sweep eps --eps -1 --out {out}", "--eps"),
    ("sw-rates0", "sweep rate --rates 0 --out {out}", "--rates"),
    ("sw-K0", "sweep rate --K 0 --out {out}", "--K"),
    ("sw-K-neg", "sweep rate --K -5 --out {out}", "--K"),
    ("sw-n-neg", "sweep rate --n -1 --out {out}", "--n"),
    # hostile plant options, a bounds file of another robot, a design rate no run can reach (issue 33, item 8)
    ("run-friction-huge", "run --friction 1e300:0 --duration 0.1 --out {out}", "friction viscous [1e+300"),
    ("run-friction-coulomb", "run --friction 0:1e6 --duration 0.1 --out {out}", "beyond 100000 (N m)"),
    ("run-noise-huge", "run --noise 1e300:0 --rate 1000 --duration 0.1 --out {out}", "noise_q [1e+300"),
    ("run-noise-qd", "run --noise 0:1e3 --rate 1000 --duration 0.1 --out {out}", "noise_qd [1000"),
    ("run-bounds-robot", "run --bounds {d}/ur5_named.toml --duration 0.1 --out {out}",
     "identified on robot 'ur5', the run's robot is 'rr3'"),
    ("design-bounds-robot", "design --bounds {d}/ur5_named.toml --rate 1000 --out {d}/design-out",
     "identified on robot 'ur5', the run's robot is 'rr3'"),
    ("design-rate-huge", "design --rate 1e9 --duration 1 --out {d}/design-out", "controller samples per verification"),
    ("design-rate-duration", "design --rate 2e5 --duration 10 --out {d}/design-out", "2e+06 controller samples"),
    # the parser
    ("no-command", "", "command"),
    ("unknown-command", "fly", "fly"),
    ("unknown-flag", "run --fast-please --out {out}", "--fast-please"),
    ("bench-flag", "bench --nope", "--nope"),
]


def test_the_battery_has_at_least_80_cases():
    assert len(CASES) >= 80 and len({c[0] for c in CASES}) == len(CASES)


#: Warnings Python does not show by default (outside __main__): not printed to a user.
_HIDDEN = (DeprecationWarning, PendingDeprecationWarning, ImportWarning)


@pytest.fixture(scope="module")
def bad_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("bad")
    for name, text in FILES.items():
        (d / name).write_text(text)
    (d / "binary.toml").write_bytes(b"\xff\xfe\x00binary")
    (d / "afile").write_text("not a directory")
    (d / "dir.toml").mkdir()
    (d / "foreign").mkdir()
    (d / "foreign" / "thesis.tex").write_text("not rc3r's")
    (d / "campaign").mkdir()
    (d / "campaign" / "runs.csv").write_text("job\n")
    _named_bounds(d / "ur5_named.toml", "ur5")
    return d


def _named_bounds(path: Path, name: str) -> Path:
    """A valid bounds.toml of the 3R (its n, p and coefficient names) whose ``robot`` key says ``name``."""
    import numpy as np

    import rc3r
    from rc3r.identify.bounds_file import write_bounds

    arm = rc3r.load_robot("rr3")
    b = {"theta0": arm.theta, "P": np.eye(arm.p), "rho": 1.0, "rho_i": np.ones(arm.p), "confidence": 0.95,
         "chi2": 25.0}
    return write_bounds(path, b, arm, robot_name=name)


def _targets(t: Path) -> Path:
    """Files make-urdf must never replace ({t} of a case): a symbolic link, a FIFO, a character device;
    a refused make-urdf --out {t}/x.urdf must not write x.urdf there either."""
    t.mkdir()
    (t / "target.urdf").write_text("a file a symbolic link points to")
    (t / "link.urdf").symlink_to(t / "target.urdf")
    os.mkfifo(t / "fifo.urdf")
    try:  # a character device like /dev/null (mknod needs CAP_MKNOD; a FIFO stands in otherwise)
        os.mknod(t / "chardev.urdf", 0o644 | stat.S_IFCHR, os.makedev(1, 3))
    except OSError:
        os.mkfifo(t / "chardev.urdf")
    return t


def _untouched(d: Path, t: Path) -> None:
    """The targets that must never be replaced are as they were, and make-urdf wrote nothing."""
    assert (t / "link.urdf").is_symlink() and (t / "target.urdf").read_text() == "a file a symbolic link points to"
    assert stat.S_ISFIFO(os.lstat(t / "fifo.urdf").st_mode)
    assert not stat.S_ISREG(os.lstat(t / "chardev.urdf").st_mode)
    assert sorted(p.name for p in t.iterdir()) == ["chardev.urdf", "fifo.urdf", "link.urdf", "target.urdf"]
    assert (d / "dir.toml").is_dir() and list((d / "dir.toml").iterdir()) == []


@pytest.mark.parametrize("case, argv, words", CASES, ids=[c[0] for c in CASES])
def test_bad_input_is_one_clean_line(case, argv, words, bad_files, tmp_path, monkeypatch, capfd):
    if "/proc/" in argv and not os.path.isdir("/proc/sys"):
        pytest.skip("needs Linux procfs")
    work = tmp_path / "cwd"
    work.mkdir()
    monkeypatch.chdir(work)
    out = tmp_path / "earlier"
    out.mkdir()
    (out / "metrics.json").write_text('{"earlier": true}')
    t = _targets(tmp_path / "targets")
    args = [a.format(d=bad_files, out=out, t=t) for a in shlex.split(argv)]
    capfd.readouterr()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code = main(args)
    err = capfd.readouterr().err
    shown = [f"{w.category.__name__}: {w.message}" for w in caught if not issubclass(w.category, _HIDDEN)]
    assert code == 2, (case, code, err)
    assert err.count("\n") == 1 and err.startswith("rc3r: error: ") and words in err, (case, err)
    assert not shown, (case, shown)
    assert "Traceback" not in err and "internal error" not in err
    assert (out / "metrics.json").read_text() == '{"earlier": true}'
    assert sorted(p.name for p in out.iterdir()) == ["metrics.json"]
    assert (bad_files / "foreign" / "thesis.tex").read_text() == "not rc3r's"
    assert list(work.iterdir()) == []
    _untouched(bad_files, t)
    assert not (bad_files / "design-out").exists()


def test_bounds_never_prints_a_non_finite_number(monkeypatch, capsys):
    """Whatever overflows inside the bounds (here the certified radius of the paper's theta0, made
    infinite) is refused in one line; stdout stays empty: no ``Infinity`` in the JSON, which is not
    JSON. On main this printed ``"rho": Infinity`` and exited 0."""
    import rc3r.cli.bounds as cli_bounds

    real = cli_bounds.certified_radius
    monkeypatch.setattr(cli_bounds, "certified_radius", lambda b, t: (float("inf"), real(b, t)[1]))
    for extra in ([], ["--json"]):
        assert main(["bounds", *extra]) == 2
        cap = capsys.readouterr()
        assert cap.out == "" and cap.err.count("\n") == 1, cap
        assert "paper_theta0_certified.rho is not finite" in cap.err


def test_urdfdom_lines_never_reach_the_terminal():
    """End to end in a fresh process (the real file descriptor 2, no pytest capture): a URDF with a
    dangling parent gives rc3r's one line only, with urdfdom's reason folded in. On main urdfdom's
    two lines ("Error: Failed to build tree ...", "at line 262 in .../model.cpp") came first."""
    path = Path(os.environ.get("TMPDIR", "/tmp")) / f"rc3r-dangling-{os.getpid()}.urdf"
    path.write_text(FILES["dangling.urdf"])
    try:
        p = subprocess.run([sys.executable, "-c", "import sys; from rc3r.cli import main; sys.exit(main(sys.argv[1:]))",
                            "verify-model", "--generic", "--urdf", str(path)], capture_output=True, text=True,
                           timeout=120)
    finally:
        path.unlink()
    assert p.returncode == 2 and p.stdout == "", p
    assert p.stderr.count("\n") == 1 and p.stderr.startswith("rc3r: error: Pinocchio cannot read URDF"), p.stderr
    assert "parent link [nolink] of joint [joint3] not found" in p.stderr and "model.cpp" not in p.stderr


# --- rc3r identify on hostile logs (issue 33, item 8) ---------------------------------------------

def _log_table(n: int = 2000, dt: float = 1e-3):
    """A plausible 3-joint log (t, q, tau) of ``n`` samples every ``dt`` s: enough to pass load_log."""
    import numpy as np

    t = np.arange(n) * dt
    q = np.column_stack([np.sin(2 * np.pi * f * t) for f in (0.5, 0.7, 1.1)])
    tau = np.column_stack([np.cos(2 * np.pi * f * t) for f in (0.5, 0.7, 1.1)])
    return t, q, tau


def _hostile_log(kind: str, d: Path) -> Path:
    import numpy as np

    from rc3r.identify.log import Log, save_log

    t, q, tau = _log_table()
    if kind == "tau-1e300":
        tau[700, 1] = 1e300
    elif kind == "t-last-1e300":
        t[-1] = 1e300
    elif kind == "t-last-1e9":
        t[-1] = 1e9
    elif kind == "gap-1e6":
        t[1000:] += 1e6
    elif kind == "gap-1s":
        t[1000:] += 1.0
    elif kind == "gaps-everywhere":  # every 10th step 60 median steps (each bridged): a grid of 6.9 x the samples
        t = np.concatenate([[0.0], np.cumsum(np.where(np.arange(1, t.size) % 10, 1e-3, 60e-3))])
    if kind == "header-only":
        path = d / "header.csv"
        path.write_text("t,q1,q2,q3,tau1,tau2,tau3\n")
        return path
    if kind.startswith("npz"):
        path = d / f"{kind}.npz"
        save_log(Log(t, q, tau), path)
        data = path.read_bytes()
        if kind == "npz-crc":  # a flipped byte inside an array: the zip's CRC-32 check fails
            k = data.index(b"q.npy") + 400
            data = data[:k] + bytes([data[k] ^ 0xFF]) + data[k + 1:]
        else:  # truncated halfway
            data = data[:len(data) // 2]
        path.write_bytes(data)
        return path
    path = d / f"{kind}.csv"
    save_log(Log(t, q, tau), path)
    return path


HOSTILE_LOGS = [
    ("tau-1e300", "tau2 is 1e+300 at sample 701, beyond 1e+12"),     # main: LinAlgError, exit 70
    ("t-last-1e300", "t is 1e+300 at sample 2000, beyond 1e+12"),    # main: "Maximum allowed size exceeded"
    ("t-last-1e9", "more than 1e+06 s"),                             # a grid of 1e12 points
    ("gap-1e6", "more than 1e+06 s"),                                # main: MemoryError, 7.4 GiB
    ("gap-1s", "a gap of 1.001 s between samples 1000 and 1001"),
    ("gaps-everywhere", "gaps fill most of it"),
    ("npz-crc", "not a readable NPZ file: BadZipFile"),               # main: BadZipFile, exit 70
    ("npz-truncated", "not a readable NPZ file"),
    ("header-only", "has a header and no rows"),                      # main: numpy's UserWarning too
]


@pytest.mark.parametrize("kind, words", HOSTILE_LOGS, ids=[c[0] for c in HOSTILE_LOGS])
def test_identify_refuses_hostile_logs_in_one_line(kind, words, tmp_path, monkeypatch, capfd):
    """Property: a log whose numbers would overflow (a torque of 1e300), whose time span or gaps would make
    the resampling grid enormous, a corrupt NPZ, or a CSV with only its header is refused by ``rc3r
    identify`` with exit 2, exactly one ``rc3r: error:`` line naming the problem, no Python warning, no
    traceback, and no --out written (limits: rc3r.identify.log's docstring, docs/errors.md)."""
    monkeypatch.chdir(tmp_path)
    path = _hostile_log(kind, tmp_path)
    out = tmp_path / "id"
    capfd.readouterr()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code = main(["identify", str(path), "--robot", "rr3", "--out", str(out)])
    err = capfd.readouterr().err
    shown = [f"{w.category.__name__}: {w.message}" for w in caught if not issubclass(w.category, _HIDDEN)]
    assert code == 2, (kind, code, err)
    assert err.count("\n") == 1 and err.startswith("rc3r: error: ") and words in err, (kind, err)
    assert not shown and "Traceback" not in err, (kind, shown, err)
    assert not out.exists()


def test_npz_log_too_large_unpacked_is_refused_unread(tmp_path, monkeypatch):
    """Property: an NPZ whose arrays would unpack to more than MAX_NPZ_BYTES (a zip bomb) is refused from
    its zip directory, before numpy reads (allocates) any array."""
    import numpy as np

    import rc3r.identify.log as L

    t, q, tau = _log_table()
    path = tmp_path / "log.npz"
    L.save_log(L.Log(t, q, tau), path)
    assert L.load_log(path).samples == t.size
    monkeypatch.setattr(L, "MAX_NPZ_BYTES", 1000)
    monkeypatch.setattr(np, "load", lambda *a, **k: pytest.fail("np.load called on an oversized NPZ"))
    with pytest.raises(ConfigError, match="GiB unpacked, more than"):
        L.load_log(path)


# --- rc3r excite: length bounds and files it would overwrite (issue 33, item 8) -------------------

EXCITE = ["excite", "--robot", "rr3", "--harmonics", "2"]


EXCITE_CASES = [
    ("duration-huge", ["--duration", "1e9", "--out", "t.csv"], {}, "an exciting trajectory lasts 1 to 3600 s"),
    ("duration-tiny", ["--duration", "1e-4", "--out", "t.csv"], {}, "an exciting trajectory lasts 1 to 3600 s"),
    ("rate-huge", ["--duration", "10", "--rate", "1e9", "--out", "t.csv"], {}, "is 1e+10 samples"),
    ("rate-tiny", ["--duration", "10", "--rate", "1", "--out", "t.csv"], {}, "is 11 samples"),
    ("out-exists", ["--duration", "1", "--out", "t.csv"], {"t.csv": "mine"}, "--out t.csv exists; give --force"),
    ("json-exists", ["--duration", "1", "--out", "t.csv"], {"t.json": "mine"}, "t.json exists; give --force"),
    ("log-exists", ["--duration", "1", "--out", "t.csv", "--synthetic-log", "l.npz"], {"l.npz": "mine"},
     "--synthetic-log l.npz exists"),
    ("truth-exists", ["--duration", "1", "--out", "t.csv", "--synthetic-log", "l.csv"], {"l.truth.json": "mine"},
     "l.truth.json exists; give --force"),
    ("log-is-out", ["--duration", "1", "--out", "t.csv", "--synthetic-log", "t.csv", "--force"], {},
     "--synthetic-log t.csv is the same file as --out t.csv"),
    ("log-is-out-dotted", ["--duration", "1", "--out", "t.csv", "--synthetic-log", "./t.csv"], {}, "the same file"),
]


@pytest.mark.parametrize("case, extra, existing, words", EXCITE_CASES, ids=[c[0] for c in EXCITE_CASES])
def test_excite_refuses_before_any_work(case, extra, existing, words, tmp_path, monkeypatch, capfd):
    """Property: ``rc3r excite`` with a duration or sample count out of bounds, an existing trajectory,
    .json, synthetic log or .truth.json without --force, or --synthetic-log naming --out (even with
    --force) exits 2 with one ``rc3r: error:`` line (no progress line: nothing ran), and every file in
    the directory is left byte for byte (on main: MemoryError of 7.3 TiB, a 1-sample trajectory,
    silent overwrites)."""
    monkeypatch.chdir(tmp_path)
    for name, text in existing.items():
        (tmp_path / name).write_text(text)
    capfd.readouterr()
    code = main(EXCITE + extra)
    err = capfd.readouterr().err
    assert code == 2 and err.count("\n") == 1 and err.startswith("rc3r: error: ") and words in err, (case, err)
    assert {p.name: p.read_text() for p in tmp_path.iterdir()} == existing


def test_excite_force_replaces_its_own_files(tmp_path, monkeypatch, capfd):
    """Property: with --force the refused rerun goes through and replaces the trajectory and its .json."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.csv").write_text("old")
    (tmp_path / "t.json").write_text("old")
    assert main(EXCITE + ["--duration", "1", "--out", "t.csv", "--force"]) == 0
    assert (tmp_path / "t.csv").read_text().startswith("t,q1,q2,q3,qd1") and (tmp_path / "t.json").read_text() != "old"


@pytest.mark.parametrize("tol", [-1.0, 0.0, float("nan"), float("inf"), "0.01", True])
def test_build_run_refuses_a_tolerance_that_is_not_positive(tol):
    """Property: rc3r.build_run(tolerance=...) (and a config's tolerance) must be a finite number > 0 [rad];
    anything else is a ParameterError naming it (on main build_run(tolerance=-1.0) returned a spec)."""
    import rc3r
    from rc3r.errors import ParameterError

    with pytest.raises(ParameterError, match="tolerance"):
        rc3r.build_run(duration=0.1, tolerance=tol)
    with pytest.raises(ParameterError, match="tolerance"):
        rc3r.build_run(duration=0.1, config={"tolerance": tol})
    assert rc3r.build_run(duration=0.1, tolerance=0.02).tolerance == 0.02


def test_bounds_file_of_the_same_robot_is_accepted(tmp_path):
    """Property: the robot-name check refuses only another robot: the 3R's own file (robot = "rr3") builds."""
    import rc3r

    path = _named_bounds(tmp_path / "b.toml", "rr3")
    spec = rc3r.build_run(duration=0.1, bounds=str(path))
    assert spec.model["bounds_file"] == str(path)


# --- a diverged run prints its one error line, no informational engine note (issue 33, item 8) ------

@pytest.mark.parametrize("eps, code", [("0.01", 3), (None, 0)])
def test_engine_note_is_not_printed_beside_a_divergence(eps, code, tmp_path, monkeypatch, capfd):
    """Property: when ``auto`` passes the compiled engine over (forced here, whatever numba's cache holds),
    a run that diverges prints on stderr only its announcement and its one ``rc3r: error:`` line -- not the
    informational "python engine: the compiled one is passed over ..." line (main printed it first); a run
    that finishes still says it (after the run)."""
    import importlib

    sim = importlib.import_module("rc3r.simulate")  # the package (rc3r.simulate is also a function's name)
    monkeypatch.setattr(sim, "planned_engine", lambda plant, law, options: ("python", "a test forces the note"))
    argv = ["run", "--controller", "robust", "--perturbed", "--rate", "1000", "--duration", "0.3", "--engine",
            "python", "--out", str(tmp_path / "run")] + ([] if eps is None else ["--eps", eps])
    capfd.readouterr()
    assert main(argv) == code
    lines = capfd.readouterr().err.splitlines()
    if code == 3:
        assert [ln for ln in lines if not ln.startswith("rc3r run: ")] == [ln for ln in lines if
                                                                          ln.startswith("rc3r: error: diverged")]
        assert len(lines) == 2, lines
    else:
        assert any("python engine: the compiled one is passed over, a test forces the note" in ln for ln in lines)

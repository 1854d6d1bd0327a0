"""The bad-input battery: every command, every kind of mistake, one clean refusal each.

For each case: exit 2, exactly one ``rc3r: error: ...`` line on stderr naming the problem
(the expected words), no traceback, and an earlier result in ``--out`` left as it was.
Every case runs with the working directory in a temporary directory, so a command that
defaults to ``out/...`` cannot touch the checkout. (More cases with their own assertions
live beside the modules they exercise: ``test_study.py``, ``test_output.py``,
``test_rr3_urdf.py``, ``test_paper.py``, ``test_campaign.py``.)
"""
from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from rc3r.cli import main

ROOT = Path(__file__).resolve().parents[1]
URDF = (ROOT / "urdf" / "rr3.urdf").read_text()

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
}

# (id, argv with {d} = the files' directory and {out} = an earlier result directory, expected words)
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
    ("mu-missing", "make-urdf --params {d}/nope.toml --out {d}/x.urdf", "not found"),
    ("mu-malformed", "make-urdf --params {d}/bad.toml --out {d}/x.urdf", "malformed TOML"),
    ("mu-binary", "make-urdf --params {d}/binary.toml --out {d}/x.urdf", "not a text file"),
    ("mu-devzero", "make-urdf --params /dev/zero --out {d}/x.urdf", "not a regular file"),
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
    # the parser
    ("no-command", "", "command"),
    ("unknown-command", "fly", "fly"),
    ("unknown-flag", "run --fast-please --out {out}", "--fast-please"),
    ("bench-flag", "bench --nope", "--nope"),
]


def test_the_battery_has_at_least_80_cases():
    assert len(CASES) >= 80 and len({c[0] for c in CASES}) == len(CASES)


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
    return d


@pytest.mark.parametrize("case, argv, words", CASES, ids=[c[0] for c in CASES])
def test_bad_input_is_one_clean_line(case, argv, words, bad_files, tmp_path, monkeypatch, capsys):
    work = tmp_path / "cwd"
    work.mkdir()
    monkeypatch.chdir(work)
    out = tmp_path / "earlier"
    out.mkdir()
    (out / "metrics.json").write_text('{"earlier": true}')
    args = [a.format(d=bad_files, out=out) for a in shlex.split(argv)]
    code = main(args)
    err = capsys.readouterr().err
    errors = [ln for ln in err.splitlines() if ln.startswith("rc3r: error:")]
    assert code == 2, (case, code, err)
    assert len(errors) == 1 and words in errors[0], (case, err)
    assert "Traceback" not in err and "internal error" not in err
    assert (out / "metrics.json").read_text() == '{"earlier": true}'
    assert sorted(p.name for p in out.iterdir()) == ["metrics.json"]
    assert (bad_files / "foreign" / "thesis.tex").read_text() == "not rc3r's"
    assert list(work.iterdir()) == []

"""The documentation's structure (no Sphinx needed; CI builds the HTML with -W in .ci/run).

* the API reference lists every public name of ``rc3r`` and documents the main modules;
* every ``docs/*.md`` page is in the table of contents (a glob catches new ones);
* the notebook is stored without outputs (they come from executing it at build time) and
  never selects a matplotlib backend other than the notebook's inline one;
* the docs never point at ``../shared``;
* a newcomer finds the path from the paper to their own arm (issue 33 item 7): the README starts
  with its two commands, then the path, then the reference; the first page's "Where next" and the
  index lead to generic, identification, design and export before the method's pages.
"""
from __future__ import annotations

import importlib
import importlib.util
import json
import re
from pathlib import Path

import pytest

import rc3r

DOCS = Path(__file__).resolve().parents[1] / "docs"

#: Modules of the module map that the API reference must document (automodule with members).
MAIN_MODULES = ("rc3r.robots", "rc3r.robots.base", "rc3r.controllers", "rc3r.trajectory", "rc3r.uncertainty.box",
                "rc3r.uncertainty.bounds", "rc3r.simulate", "rc3r.runspec", "rc3r.campaign.jobs",
                "rc3r.campaign.runner", "rc3r.plotting", "rc3r.verify", "rc3r.io", "rc3r.errors")


def _resolve(dotted: str):
    """The object named ``dotted`` (module path, then attributes)."""
    parts = dotted.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        for attr in parts[k:]:
            obj = getattr(obj, attr)
        return obj
    raise ImportError(dotted)


def test_api_index_lists_every_public_name():
    text = (DOCS / "api" / "index.rst").read_text()
    assert ".. currentmodule:: rc3r" in text
    entries = re.findall(r"^\s+~([\w.]+)\s*$", text, flags=re.M)
    listed = {}
    for entry in entries:
        obj = _resolve("rc3r." + entry)
        listed[entry.rsplit(".", 1)[-1]] = obj
    public = [n for n in rc3r.__all__ if n != "__version__"]
    missing = sorted(n for n in public if n not in listed)
    assert not missing, f"docs/api/index.rst does not list {missing}"
    for name in public:  # each entry is the object rc3r exports, at its defining module
        assert listed[name] is getattr(rc3r, name), name


def test_api_pages_document_the_main_modules():
    pages = "\n".join(p.read_text() for p in (DOCS / "api").glob("*.rst"))
    documented = re.findall(r"^\.\. automodule:: ([\w.]+)\s*$", pages, flags=re.M)
    for mod in documented:
        importlib.import_module(mod)
    missing = sorted(set(MAIN_MODULES) - set(documented))
    assert not missing, f"no API page documents {missing}"


def test_every_markdown_page_is_in_the_toctree():
    index = (DOCS / "index.md").read_text()
    block = re.search(r"```\{toctree\}\n(.*?)```", index, flags=re.S)
    assert block, "docs/index.md has no toctree"
    lines = [ln.strip() for ln in block.group(1).splitlines()]
    options = {ln for ln in lines if ln.startswith(":")}
    entries = [ln for ln in lines if ln and not ln.startswith(":")]
    for entry in entries:
        if entry != "*":
            assert any((DOCS / f"{entry}{ext}").is_file() for ext in (".md", ".rst", ".ipynb")), entry
    if ":glob:" in options and "*" in entries:
        return  # every top-level page, present or future
    pages = {p.stem for p in DOCS.glob("*.md")} - {"index"}
    assert not pages - set(entries), f"not in the toctree: {sorted(pages - set(entries))}"


def test_notebooks_are_stored_without_outputs():
    notebooks = sorted((DOCS / "notebooks").glob("*.ipynb"))
    assert notebooks
    for path in notebooks:
        nb = json.loads(path.read_text())
        for cell in nb["cells"]:
            if cell["cell_type"] != "code":
                continue
            source = "".join(cell["source"])
            assert not cell.get("outputs") and cell.get("execution_count") is None, f"{path.name}: outputs stored"
            assert "matplotlib.use(" not in source and "MPLBACKEND" not in source, f"{path.name} forces a backend"


def test_docs_do_not_point_at_shared():
    for path in DOCS.rglob("*"):
        if path.is_file() and "_build" not in path.parts and path.suffix in (".md", ".rst", ".py", ".ipynb"):
            assert "../shared" not in path.read_text(), path


#: The path of a new user from the paper to their arm at their rate (README "The path", in order).
PATH = ("rc3r paper", "rc3r verify-model", "rc3r identify", "rc3r bounds", "rc3r design", "rc3r montecarlo",
        "rc3r export")


def _sections(text: str) -> list[tuple[str, str]]:
    """``(heading, body)`` of every ``## `` section of a Markdown text, in order (the preamble first)."""
    parts = re.split(r"^## (.*)$", text, flags=re.M)
    return [("", parts[0])] + list(zip(parts[1::2], parts[2::2]))


def test_readme_starts_with_its_two_commands_then_the_path_then_the_reference():
    """The README's first two code blocks are the set-up-and-run commands (the paper's, then the
    tests'); its first section after them is the path, naming every step in order; the command
    table comes after the path, and lists the path's commands first in the same order."""
    readme = (DOCS.parent / "README.md").read_text()
    blocks = re.findall(r"```bash\n(.*?)```", readme, flags=re.S)
    assert "pip install -e ." in blocks[0] and "rc3r paper" in blocks[0], blocks[0]
    assert "pip install" in blocks[1] and "pytest" in blocks[1], blocks[1]
    sections = _sections(readme)
    assert blocks[0] in sections[0][1] and blocks[1] in sections[0][1]
    heading, body = sections[1]
    assert heading.lower().startswith("the path"), heading
    places = [body.find(f"`{cmd}") for cmd in PATH]
    assert -1 not in places and places == sorted(places), dict(zip(PATH, places))
    assert sections[2][0].lower().startswith("reference"), sections[2][0]
    rows = [ln.split("`")[1].split()[1] for ln in sections[2][1].splitlines() if ln.startswith("| `rc3r")]
    assert rows[:len(PATH) - 2] == ["paper", "verify-model", "excite", "identify", "bounds"], rows
    in_path = [r for r in rows if f"rc3r {r}" in PATH]
    assert in_path == [c.split()[1] for c in PATH], in_path


def test_where_next_and_the_index_lead_to_the_pages_of_your_arm():
    """docs/first-10-minutes.md "Where next" links generic, identification, design and export before any
    page of the method; docs/index.md's table of contents puts them right after the first two pages."""
    first = dict(_sections((DOCS / "first-10-minutes.md").read_text()))
    where = next(body for heading, body in first.items() if "Where next" in heading)
    links = re.findall(r"\]\(([\w-]+)\.md\)", where)
    mine = ["generic", "identification", "design", "export"]
    assert all(page in links for page in mine), links
    assert max(links.index(p) for p in mine) < links.index("conventions"), links
    index = (DOCS / "index.md").read_text()
    entries = [ln.strip() for ln in re.search(r"```\{toctree\}\n(.*?)```", index, flags=re.S).group(1).splitlines()
               if ln.strip() and not ln.strip().startswith(":")]
    assert entries[:6] == ["first-10-minutes", "notebooks/quickstart", *mine], entries


# ---- console transcripts checked against the real output (issue 33 item 4) ------------------------

#: A console block whose output is checked: the comment ``<!-- transcript: SCRIPT ... -->`` right before
#: its fence. SCRIPT runs exactly the block's ``$ rc3r ...`` commands, in the page's order.
TRANSCRIPT = re.compile(r"<!-- transcript: (\S+)[^>]*-->\n```console\n(.*?)```", flags=re.S)

#: What depends on the machine's load, masked on both sides: wall times, runs per minute.
TIMING = (re.compile(r"wall [\d.]+ s"), re.compile(r"[\d.]+ s \([\d.]+ runs/min\)"))


def transcripts() -> dict:
    """SCRIPT -> [(page, command, expected stdout lines)] of every marked block, in page order."""
    out: dict = {}
    for page in sorted(DOCS.glob("*.md")):
        for script, body in TRANSCRIPT.findall(page.read_text()):
            for chunk in re.split(r"^\$ ", body, flags=re.M)[1:]:
                command, *lines = chunk.rstrip("\n").split("\n")
                out.setdefault(script, []).append((page.name, command, lines))
    return out


def script_commands(script: str) -> list[str]:
    """The rc3r command lines of an example script (``$RC3R`` read as ``rc3r``)."""
    text = (DOCS.parent / script).read_text()
    return ["rc3r " + ln.split(None, 1)[1] for ln in text.splitlines() if ln.startswith("$RC3R ")]


def _mask(line: str, cwd) -> str:
    line = line.replace(f"{cwd}/", "")
    for rx in TIMING:
        line = rx.sub(lambda m: re.sub(r"[\d.]+", "#", m.group(0)), line)
    return line


#: A printed number (the text between numbers is compared exactly, the numbers within NUMBER_RTOL).
NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")

#: How far a printed number may move between the supported environments (Python 3.10 with NumPy 2.2 /
#: SciPy 1.15 against 3.12 with NumPy 2.4 / SciPy 1.17; other BLAS builds): SLSQP's excitation design
#: stops at a slightly different optimum (condition number 3.850 against 3.854, 0.1 %), and every
#: figure computed downstream of that trajectory moves with it. The transcripts document what the
#: commands print (every word, verdict and layout exactly); the numbers themselves are pinned by the
#: tests of the modules that compute them. 5 % leaves room for that drift and still fails on a changed
#: default (a cut-off, a rate, a run count) or a figure off by a factor.
NUMBER_RTOL = 0.05


def same_line(got: str, want: str) -> bool:
    """Whether a printed line matches the transcript's: the same words, every number within NUMBER_RTOL
    of the transcript's (or within one unit of its last printed digit, for rounded small values)."""
    if NUMBER.sub("#", got) != NUMBER.sub("#", want):
        return False
    for a, b in zip(NUMBER.findall(got), NUMBER.findall(want)):
        mantissa = b.lower().split("e")[0]
        ulp = 10.0 ** -len(mantissa.split(".")[1]) if "." in mantissa else 1.0
        if abs(float(a) - float(b)) > max(NUMBER_RTOL * abs(float(b)), ulp):
            return False
    return True


def run_commands(commands, cwd) -> list[list[str]]:
    """Each command's stdout lines (run in-process in ``cwd``, working directory prefix removed)."""
    import contextlib
    import io
    import os
    import shlex

    from rc3r.cli import main

    old, outputs = os.getcwd(), []
    os.chdir(cwd)
    try:
        for command in commands:
            with contextlib.redirect_stdout(io.StringIO()) as buf:
                code = main(shlex.split(command)[1:])
            text = buf.getvalue()
            assert code == 0, (command, code, text)
            outputs.append([ln.replace(f"{cwd}/", "") for ln in text.rstrip("\n").split("\n")])
    finally:
        os.chdir(old)
    return outputs


@pytest.mark.slow
@pytest.mark.skipif(importlib.util.find_spec("cvxpy") is None,
                    reason="the transcripts were recorded with the test extra's cvxpy (Python >= 3.11): identify "
                           "prints the consistency SDP's line only with it")
def test_every_console_transcript_marked_as_checked_is_what_its_commands_print(tmp_path):
    """The marked console blocks of docs/*.md (docs/identification.md's worked example) hold exactly the
    commands of their example script, in its order, and each command's stdout line for line (wall times
    and runs per minute masked; progress lines go to stderr and are not in the transcripts). Rewrite them
    after a change of output with ``python tests/test_docs.py --update``."""
    found = transcripts()
    assert "examples/identified_design.sh" in found, "docs/identification.md lost its checked transcript"
    for script, blocks in found.items():
        assert [cmd for _, cmd, _ in blocks] == script_commands(script), script
        work = tmp_path / Path(script).stem
        work.mkdir()
        got = run_commands([cmd for _, cmd, _ in blocks], work)
        for (page, cmd, want), lines in zip(blocks, got):
            have, need = [_mask(ln, work) for ln in lines], [_mask(ln, work) for ln in want]
            bad = [f"  got:  {a}\n  want: {b}" for a, b in zip(have, need) if not same_line(a, b)]
            assert len(have) == len(need) and not bad, \
                f"{page}: $ {cmd} ({len(have)} lines printed, {len(need)} in the transcript)\n" + "\n".join(bad)


def test_a_transcript_line_matches_on_its_words_and_numbers_within_tolerance():
    """same_line: words exact; 3.854 printed where the transcript says 3.85 passes (0.1 %), 4.1 where it
    says 3.85 fails (6.5 %), a changed word fails, 0.004 against 0.003 passes (one unit of the last digit)."""
    assert same_line("condition number: 3.854 (6.14x worse)", "condition number: 3.85 (6.15x worse)")
    assert not same_line("condition number: 4.1 (6.14x worse)", "condition number: 3.85 (6.15x worse)")
    assert not same_line("verdict: chattering 3.85", "verdict: clean 3.85")
    assert same_line("rms 0.004 N m", "rms 0.003 N m")
    assert not same_line("rms 0.005 N m", "rms 0.003 N m")
    assert not same_line("20001 samples", "10001 samples")


def _update() -> None:
    """Rewrite every marked transcript with its commands' real output (run in a temporary directory)."""
    import tempfile

    for script, blocks in transcripts().items():
        with tempfile.TemporaryDirectory() as tmp:
            got = run_commands([cmd for _, cmd, _ in blocks], Path(tmp).resolve())
        outputs = {cmd: lines for (_, cmd, _), lines in zip(blocks, got)}

        def body(match):
            cmds = [c.split("\n", 1)[0] for c in re.split(r"^\$ ", match.group(2), flags=re.M)[1:]]
            new = "".join(f"$ {c}\n" + "".join(f"{ln}\n" for ln in outputs[c]) for c in cmds)
            return match.group(0).replace(match.group(2), new)

        for page in sorted({p for p, _, _ in blocks}):
            path = DOCS / page
            path.write_text(TRANSCRIPT.sub(lambda m: body(m) if m.group(1) == script else m.group(0),
                                           path.read_text()))
            print(f"updated {path}")


if __name__ == "__main__":
    import sys

    if sys.argv[1:] != ["--update"]:
        sys.exit("usage: python tests/test_docs.py --update  (rewrite the checked console transcripts)")
    _update()


def test_the_compiled_effect_example_of_architecture_md_is_one_registered_file():
    """docs/architecture.md, "Adding a compiled plant effect", names its worked example's file: it exists, it
    registers a compiled effect with a layout, both kernels, a config key and a CLI option, and the package
    names it nowhere else but in the import that registers it (one file)."""
    from rc3r.plants import EFFECTS

    text = (DOCS / "architecture.md").read_text()
    section = text.split("## Adding a compiled plant effect", 1)[1].split("\n## ", 1)[0]
    path = re.search(r"`(src/rc3r/plants/\w+\.py)`", section).group(1)
    file = DOCS.parent / path
    assert file.is_file(), path
    module = "rc3r.plants." + file.stem
    cls = next(c for c in EFFECTS.values() if c.__module__ == module)
    assert cls.compiled and cls.LAYOUT and cls.value_kernel and cls.slope_kernel and cls.config_keys and cls.cli
    src = DOCS.parent / "src" / "rc3r"
    named = [p for p in src.rglob("*.py") if p != file and re.search(rf"\b{file.stem}\b", p.read_text())]
    assert {p.relative_to(src).as_posix() for p in named} <= {"plants/__init__.py", "__init__.py"}, named

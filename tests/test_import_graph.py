"""The package's import graph has no circle and no import that runs back up the declared layers.

Read from the source with ``ast``, not by importing: every ``import`` and ``from ... import`` of
``src/rc3r``, at module level and inside functions alike (a deferred import is still a dependency,
it only hides the circle until run time). ``from pkg import name`` counts as an import of the
module ``pkg.name`` where that module exists, else of ``pkg``. A module's import of a package that
contains it (``from . import Law`` in ``rc3r/controllers/ellipsoid.py``) is no edge: Python runs that
package's ``__init__.py`` before the module anyway, so the import adds no dependency, and a package
that gathers its modules in its face stays allowed. The top package ``rc3r`` is the exception: its
face is a layer of its own, high up, and the library below it must not import it.

Properties checked:

* no two modules of the package import each other, directly or around a longer loop;
* every import goes to the importer's own layer or one below it (:data:`LAYERS`);
* every module of the package has a layer.

To see the graph yourself: ``python tests/test_import_graph.py`` prints every import that breaks a
rule (nothing when the graph is clean).
"""
from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "rc3r"

#: The layers of the package, lowest first: a module may import its own layer and the layers below,
#: never one above. A module belongs to the layer of the longest prefix that names it. Written
#: once, here; docs/architecture.md ("Layers") reads the same.
LAYERS = (
    # foundations: errors, shared orders and names, URDF files by name, file formats, the numba cache, compiled trigonometry
    ("rc3r.errors", "rc3r.conventions", "rc3r.urdf_names", "rc3r.io", "rc3r._numba_cache", "rc3r._trig"),
    # plain numerics every layer above may use
    ("rc3r.trajectory", "rc3r.plotting"),
    # identification from logs knows no robot class: it works on regressors and arrays
    ("rc3r.identify",),
    # boxes, bounds and ellipsoids on standard parameters (a robot's contract returns them)
    ("rc3r.uncertainty",),
    # the laws and the plant's effects, both generic over n and p
    ("rc3r.controllers", "rc3r.plants"),
    # the robots: their models and the kernels they declare for the compiled engine
    ("rc3r.robots",),
    # the simulator: builds its compiled engine from a robot's declared kernels
    ("rc3r.simulate",),
    # the sampled-data rule: a calculation on a law and a model that study asks for default gains
    ("rc3r.design.rule",),
    # runs as data (rc3r.study: the former name of rc3r.runspec) and the model checks
    ("rc3r.runspec", "rc3r.study", "rc3r.plant_sets", "rc3r.verify"),
    # many runs; a run's controller as C
    ("rc3r.campaign", "rc3r.export"),
    # rc3r design: the rule verified over the bounds on the campaign runner
    ("rc3r.design",),
    # the public face and the provenance it reports
    ("rc3r", "rc3r.provenance"),
    # above the library: the paper's experiment and the benchmarks; the library never imports them
    ("rc3r.experiments",),
    # the command line, on top of everything
    ("rc3r.cli",),
)


def modules(src: Path = SRC) -> dict[str, Path]:
    """Dotted name -> file of every module of the package under ``src``."""
    out = {}
    for p in sorted(src.rglob("*.py")):
        parts = p.relative_to(src.parent).with_suffix("").parts
        out[".".join(parts[:-1]) if parts[-1] == "__init__" else ".".join(parts)] = p
    return out


def imports(src: Path = SRC) -> dict[str, dict[str, int]]:
    """``{importer: {imported: line}}`` over the package's own modules, every import of every scope."""
    mods = modules(src)
    top = src.name

    def resolve(name: str) -> str | None:
        while name and name not in mods:
            name = name.rpartition(".")[0]
        return name or None

    graph: dict[str, dict[str, int]] = {}
    for name, path in mods.items():
        here = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            targets = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = here.split(".")
                    base = base[:len(base) - node.level + 1]
                    mod = ".".join(base + ([node.module] if node.module else []))
                else:
                    mod = node.module or ""
                targets = [f"{mod}.{a.name}" if f"{mod}.{a.name}" in mods else mod for a in node.names]
            for target in targets:
                if target.split(".")[0] != top:
                    continue
                hit = resolve(target)
                if hit and hit != name and not (hit != top and name.startswith(hit + ".")):
                    graph.setdefault(name, {}).setdefault(hit, node.lineno)
    return graph


def layer(module: str) -> int | None:
    """Index in :data:`LAYERS` of the longest prefix naming ``module`` (None if none does)."""
    best, found = -1, None
    for i, names in enumerate(LAYERS):
        for prefix in names:
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > best:
                best, found = len(prefix), i
    return found


def circles(graph: dict[str, dict[str, int]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, {}):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(set(graph) | {w for ws in graph.values() for w in ws}):
        if v not in index:
            visit(v)
    return sorted(out)


def upward(graph: dict[str, dict[str, int]]) -> list[str]:
    """``"a -> b (line)"`` for every import of a module ``a`` from a higher layer's module ``b``."""
    return [f"{a} -> {b} (line {line})" for a, targets in sorted(graph.items())
            for b, line in sorted(targets.items()) if layer(b) > layer(a)]


def test_every_module_has_a_layer():
    assert not [m for m in modules() if layer(m) is None]


def test_no_circles():
    """No module reaches itself through imports: every circle is listed with the lines that tie it."""
    graph = imports()
    found = circles(graph)
    detail = [", ".join(f"{a} -> {b} (line {graph[a][b]})" for a in c for b in c if b in graph.get(a, {}))
              for c in found]
    assert not found, "import circles:\n" + "\n".join(detail)


def test_no_import_runs_back_up():
    """Every import goes to the importer's layer or below (LAYERS, lowest first)."""
    bad = upward(imports())
    assert not bad, "imports that run back up the layers:\n" + "\n".join(bad)


def test_the_checks_see_a_planted_circle_and_a_planted_upward_import(tmp_path):
    """The graph reader itself: a deferred import that closes a loop, and one from a low layer to a
    high one, are both found (so a clean answer on the package means something)."""
    pkg = tmp_path / "rc3r"
    (pkg / "robots").mkdir(parents=True)
    (pkg / "cli").mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "errors.py").write_text("")
    (pkg / "cli" / "__init__.py").write_text("")
    (pkg / "robots" / "__init__.py").write_text("from .a import x\n")
    (pkg / "robots" / "a.py").write_text("def f():\n    from .b import y\n")
    (pkg / "robots" / "b.py").write_text("from . import a\nfrom ..cli import main\n")
    graph = imports(pkg)
    assert circles(graph) == [["rc3r.robots.a", "rc3r.robots.b"]]
    assert upward(graph) == ["rc3r.robots.b -> rc3r.cli (line 2)"]


if __name__ == "__main__":
    g = imports()
    for c in circles(g):
        print("circle:", " <-> ".join(c))
    for u in upward(g):
        print("up:", u)

"""Where the benchmarks' progress messages go: :func:`rc3r.experiments.bench3r.run_bench` sets the sink
(the command line prints them), every benchmark module reports through :func:`_progress`."""
from __future__ import annotations

#: The sink of progress messages, one callable in a list so that setting it reaches every importer.
_REPORT = [lambda msg: None]


def _progress(msg: str) -> None:
    _REPORT[0](msg)

"""Where a first (cold) compile spends its time: numba's compile events of one ``rc3r`` command, per function.

Runs ``rc3r ARGS...`` in this interpreter with a listener on numba's ``numba:compile`` events and prints the
40 functions with the largest exclusive compile time [s, wall] (the time of their own compile, their callees'
compiles subtracted), each with the function whose compile asked for it, and the sum. Give it an empty
``NUMBA_CACHE_DIR`` (and ``RC3R_COLD_START=compile``) to see a cold start::

    NUMBA_CACHE_DIR=$(mktemp -d) RC3R_COLD_START=compile python benchmarks/compile_profile.py paper --out /tmp/p
"""
from __future__ import annotations

import sys
import time

from numba.core import event as ev


class _Events(ev.Listener):
    """Every start and end of a numba compile, with its time."""

    def __init__(self):
        self.buf = []

    def on_start(self, event):
        self.buf.append((time.perf_counter(), True, event))

    def on_end(self, event):
        self.buf.append((time.perf_counter(), False, event))


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    rec = _Events()
    ev.register("numba:compile", rec)
    from rc3r.cli import main as rc3r_main

    t0 = time.perf_counter()
    rc = rc3r_main(argv)
    total = time.perf_counter() - t0
    stack, excl, parent = [], {}, {}
    for ts, start, event in rec.buf:
        fn = event.data["dispatcher"].py_func
        key = f"{fn.__qualname__}@{fn.__module__}"
        if start:
            if stack:
                parent.setdefault(key, stack[-1][0])
            stack.append([key, ts, 0.0])
        else:
            k, t1, child = stack.pop()
            excl[k] = excl.get(k, 0.0) + (ts - t1) - child
            if stack:
                stack[-1][2] += ts - t1
    for d, k in sorted(((v, k) for k, v in excl.items()), reverse=True)[:40]:
        print(f"{d:7.2f} s  {k}  <- {parent.get(k)}", file=sys.stderr)
    print(f"compile (sum of exclusive times) {sum(excl.values()):.1f} s, command {total:.1f} s (exit {rc})",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

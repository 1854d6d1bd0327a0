#!/usr/bin/env python
"""Run the rc3r benchmark: ``python benchmarks/run.py [--json] [--quick]``.

The same as ``rc3r bench``; everything lives in :mod:`rc3r.bench` (see benchmarks/README.md).
"""
import sys

from rc3r.cli import main

if __name__ == "__main__":
    sys.exit(main(["bench", *sys.argv[1:]]))

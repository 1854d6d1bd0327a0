"""Experiments above the library: studies of particular robots (they name them openly) and the
benchmarks. The library never imports this package; the command line does.

* :mod:`.paper3r` -- the paper's section 4 on its 3R arm (``rc3r paper``);
* :mod:`.bench3r` -- ``rc3r bench``'s closed form against Pinocchio and the simulation timings.
"""

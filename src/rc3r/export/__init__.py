"""``rc3r export``: the controller of a run as self-contained C99, with a harness that checks it.

* :mod:`.c` -- ``rc3r_controller.h`` / ``.c``: trajectory, regressor, law, state, hold, delay line;
* :mod:`.chain` -- the generic serial chain's regressor in C (port of
  :mod:`rc3r.robots.pinocchio_kernel`); a robot class may supply its own
  (``c_regressor_source()``);
* :mod:`.harness` -- recorded states, rc3r's torques, ``check.c`` and the ``Makefile``.

``docs/export.md`` has the contract of ``rc3r_control`` and the measured agreement and cost.
"""
from .c import controller_sources
from .harness import write_export

__all__ = ["controller_sources", "write_export"]

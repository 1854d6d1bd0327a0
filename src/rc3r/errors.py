"""Exception types of rc3r.

Every error a user can cause derives from :class:`Rc3rError`; the command line
prints ``rc3r: error: <message>`` (one line) and exits non-zero for these, never a
traceback.
"""


class Rc3rError(Exception):
    """Base class of the user-facing errors (exit code 2 on the command line)."""

    exit_code = 2


class ParameterError(Rc3rError, ValueError):
    """Link parameters, gains or bounds that are not finite or not physical."""


class UrdfError(Rc3rError):
    """A URDF that is missing, malformed, or not the 3R arm of the paper."""


class ConfigError(Rc3rError, ValueError):
    """A configuration (TOML) file or command-line option that cannot be used."""


class WorkerLostError(Rc3rError):
    """A campaign lost its workers: a local pool process was killed (out of memory, ``kill``),
    or a Dask cluster has had no workers for longer than the grace period. An environment
    fault, not a bug: the finished rows are kept and ``--resume`` runs the rest
    (exit code 75, ``EX_TEMPFAIL`` of sysexits.h: try again)."""

    exit_code = 75


class DivergenceError(Rc3rError):
    """A simulation that left its state/torque bounds; raised only on request."""

    exit_code = 3

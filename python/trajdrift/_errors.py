"""The exceptions trajdrift raises: one base class, three kinds, each with the command line's one-line
message (what ``trajdrift`` prints after ``error:``) and its exit code."""

from __future__ import annotations

__all__ = ["Error", "UsageError", "InputError", "MetricError"]


class Error(Exception):
    """A trajdrift failure. ``str(e)`` is the command line's one-line message: it names the file, the
    topic or the parameter, and what to do."""

    #: The exit code the command line ends with for this error.
    exit_code: int = 1


class UsageError(Error, ValueError, TypeError):
    """A bad parameter value or argument (the command line's exit code 2), e.g. ``grid=1e-9``: the
    message names the parameter as its flag (``--grid``), the value and the range. Also a
    ``ValueError`` and a ``TypeError`` (an unknown keyword, an argument of the wrong type)."""

    exit_code = 2


class InputError(Error):
    """An input that cannot be read: a missing or damaged file, an unknown topic, a text file in
    another format, a TF chain without a transform."""


class MetricError(Error):
    """The data do not allow the computation: too few samples, no overlap in time, no pose pair within
    ``t_max_diff``, a degenerate alignment, orientations a pose relation needs and the data lack."""


# Tracebacks and reprs name them as the package exports them: ``trajdrift.UsageError``.
for _cls in (Error, UsageError, InputError, MetricError):
    _cls.__module__ = "trajdrift"
del _cls

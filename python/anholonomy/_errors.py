"""The exceptions of the harness, raised by the native module."""

from __future__ import annotations

from typing import Optional


class AnholonomyError(Exception):
    """Base class of the harness's own exceptions."""


class InputError(AnholonomyError, ValueError):
    """Bad input: the scenario (or a file it names, or an argument) is
    unusable, as the CLI's exit status 2.

    ``str(error)`` is the CLI's one-line message without ``error:``:
    ``FILE:LINE: key `KEY`: what is wrong``.
    """

    #: The file at fault (a scenario, URDF, ...), when there is one.
    file: Optional[str]
    #: 1-based line in ``file``, when known.
    line: Optional[int]
    #: The scenario key (or argument) at fault, e.g. ``sim.friction``.
    key: Optional[str]

    def __init__(
        self,
        message: str,
        file: Optional[str] = None,
        line: Optional[int] = None,
        key: Optional[str] = None,
    ) -> None:
        super().__init__(message)
        self.file = file
        self.line = line
        self.key = key

    def __reduce__(self):  # keeps file, line and key through pickling
        return (type(self), (str(self), self.file, self.line, self.key))


class RuntimeFailure(AnholonomyError, RuntimeError):
    """A run failed (exit status 3 in the CLI): the physics diverged, logs
    could not be written, or a feedback law returned something that is not
    an input (wrong arity, not numbers, not finite)."""

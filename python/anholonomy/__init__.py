"""anholonomy: does the plan survive physics?

The harness plans a nonholonomic motion, integrates it on the ideal
kinematic model, replays the same commands on a rigid-body model in Rapier
(from a URDF, with contact and friction), compares the two against the
scenario's thresholds and can log everything (MCAP, Rerun, summary.json).
This package runs the harness's Rust core in process::

    import anholonomy

    s = anholonomy.load("scenarios/disk_paper.toml")
    r = anholonomy.run(s.replace({"sim.friction": 0.5}))
    r.passed, r.metrics["sim_goal_position"], r.sim.q[-1]

    # a feedback law u = law(t, q), sampled every `period` s and held
    r = anholonomy.run(s, law=lambda t, q: [0.1, 0.0], period=0.02)

Errors are exceptions: :class:`InputError` for bad input (with the file,
line and key the CLI names), :class:`RuntimeFailure` for runs that fail;
an exception raised inside a law propagates unchanged.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import (
    Any,
    Callable,
    Dict,
    Iterable,
    List,
    Mapping,
    Optional,
    Sequence,
    Tuple,
    Union,
)

import numpy as np
from numpy.typing import NDArray

from ._errors import AnholonomyError, InputError, RuntimeFailure
from . import _native
from ._native import Scenario

__version__: str = _native.__version__

__all__ = [
    "AnholonomyError",
    "DEFAULT_MAX_STEPS",
    "InputError",
    "Law",
    "Plan",
    "Result",
    "RuntimeFailure",
    "Scenario",
    "ScenarioLike",
    "Series",
    "Trajectory",
    "load",
    "run",
    "run_many",
]

#: The CLI's default step budget (``--max-steps``): the most steps of
#: ``sim.dt`` one run may take.
DEFAULT_MAX_STEPS: int = _native.DEFAULT_MAX_STEPS

#: What :func:`load` and :func:`run` accept: a :class:`Scenario`, a path, TOML
#: text or a dict of the scenario's tables.
ScenarioLike = Union[Scenario, str, "os.PathLike[str]", Mapping[str, Any]]

#: A feedback law: ``u = law(t, q)`` with ``t`` in s (float) and ``q`` the
#: state (numpy float64 array, SI units, angles in radians); returns the
#: inputs (a sequence or array of floats, in ``Scenario.input_names`` order).
Law = Callable[[float, NDArray[np.float64]], Any]

FloatArray = NDArray[np.float64]


def _is_toml_text(s: str) -> bool:
    return "\n" in s or "=" in s


def load(
    source: ScenarioLike,
    *,
    path: Union[str, "os.PathLike[str]", None] = None,
    max_steps: int = DEFAULT_MAX_STEPS,
) -> Scenario:
    """Read and validate a scenario, as the CLI does before it runs anything.

    ``source`` is a path to a scenario file, TOML text (a ``str`` that
    contains a newline or ``=``), or a dict of the file's tables
    (``{"start": [...], "model": {"kind": ...}, ...}``). Text and dicts are
    read as if from the file ``path`` (default ``./scenario.toml``): paths
    inside (``model.urdf``) resolve against its directory and the name
    defaults to its stem. Angles in ``start`` and ``goal`` are in degrees, as
    in files.

    Validation covers the keys and their ranges, the URDF against the model,
    the plan (a goal the planner cannot reach) and the physics at the start
    pose; ``max_steps`` is the step budget (the CLI's ``--max-steps``).

    Raises :class:`InputError` with the file, line and key at fault.
    """
    if isinstance(source, Scenario):
        return source
    as_file = Path(path) if path is not None else Path("scenario.toml")
    if isinstance(source, Mapping):
        return _native.load_table(dict(source), str(as_file.absolute()), max_steps)
    if isinstance(source, str) and _is_toml_text(source):
        return _native.load_text(source, str(as_file.absolute()), max_steps)
    if isinstance(source, (str, os.PathLike)):
        return _native.load_file(os.fspath(source), max_steps)
    raise TypeError(
        f"load() takes a path, TOML text or a dict, not {type(source).__name__}"
    )


@dataclass(frozen=True)
class Trajectory:
    """One run sampled at every step: ``t`` (N,), states ``q`` (N, n) with
    column names ``names``, the inputs ``u`` (N, m) applied from ``t[k]`` on
    (named ``input_names``) and ``label[k]``, the index into ``labels`` of the
    plan segment (or the law's label) in force. SI units, angles in radians.
    """

    t: FloatArray
    q: FloatArray
    names: Tuple[str, ...]
    u: FloatArray
    input_names: Tuple[str, ...]
    label: NDArray[np.int64]
    labels: Tuple[str, ...]

    def __len__(self) -> int:
        return len(self.t)

    def __getitem__(self, name: str) -> FloatArray:
        """The column of a state coordinate (or of an input) by name."""
        if name in self.names:
            return self.q[:, self.names.index(name)]
        if name in self.input_names:
            return self.u[:, self.input_names.index(name)]
        raise KeyError(f"{name!r}: not one of {self.names + self.input_names}")

    @property
    def final(self) -> Dict[str, float]:
        """The last state by coordinate name."""
        return {n: float(x) for n, x in zip(self.names, self.q[-1])}


@dataclass(frozen=True)
class Plan:
    """What was commanded: the inputs of the ideal run at its samples (``t``
    (N,), ``q`` (N, m), the same array as ``u``, named ``names``: the model's
    inputs), with the plan's ``duration`` (s; a feedback law's horizon), its
    timed ``segments`` ``(label, start, end)``, the planner's ``details`` and
    a feedback law's ``hold_period`` (s; ``None`` for open-loop u(t))."""

    t: FloatArray
    q: FloatArray
    names: Tuple[str, ...]
    label: NDArray[np.int64]
    labels: Tuple[str, ...]
    duration: float
    segments: Tuple[Tuple[str, float, float], ...]
    details: Any
    hold_period: Optional[float]

    @property
    def u(self) -> FloatArray:
        """The commands (same array as ``q``)."""
        return self.q

    def __len__(self) -> int:
        return len(self.t)


@dataclass(frozen=True)
class Series:
    """A series the system computed from both runs, on its own time grid."""

    t: FloatArray
    values: FloatArray


@dataclass(frozen=True)
class Result:
    """The outcome of one scenario run.

    ``metrics`` are the CLI's metrics (the same numbers ``summary.json``
    holds), ``passed``/``failures`` its threshold verdict, ``summary`` the
    ``summary.json`` object (also when no logs were written). For a scenario
    with a ``[sweep]`` table (``kind == "sweep"``) the metrics are the
    sweep's, ``ideal``/``sim``/``plan`` are ``None`` and ``summary`` is
    ``sweep.json`` when logs were written.
    """

    name: str
    planner: str
    kind: str
    passed: bool
    failures: Tuple[str, ...]
    metrics: Dict[str, float]
    ideal: Optional[Trajectory]
    sim: Optional[Trajectory]
    plan: Optional[Plan]
    #: The physics system's extra channels (slip, momentum, ...) on ``sim.t``.
    channels: Dict[str, FloatArray]
    #: Series the system computed after the runs (e.g. ``V/ideal``).
    series: Dict[str, Series]
    summary: Optional[Dict[str, Any]]
    log_dir: Optional[Path]
    steps: int
    #: Wall time of each stage, s (plan, ideal, physics, analysis, logs, total).
    timings: Dict[str, float]
    state_names: Tuple[str, ...]
    input_names: Tuple[str, ...]
    #: A sweep's results table, as the CLI prints it.
    table: str = ""
    #: How often a Python law was called (both runs); its calls' wall time
    #: is ``timings["law"]``, s.
    law_calls: int = 0
    #: ``PASS``, ``FAIL``, ``XFAIL`` or ``XPASS``: ``passed`` against the
    #: scenario's ``expect = "fails"`` (as the CLI's table prints it).
    verdict: str = "PASS"

    def __repr__(self) -> str:
        verdict = "passed" if self.passed else f"failed: {'; '.join(self.failures)}"
        return f"<Result {self.name!r} ({self.planner}, {self.steps} steps): {verdict}>"

    @classmethod
    def _from_native(cls, d: Dict[str, Any]) -> "Result":
        names = tuple(d["state_names"])
        inputs = tuple(d["input_names"])
        ideal = sim = plan = None
        if d["kind"] == "run":
            labels = tuple(d["labels"])

            def traj(x: Dict[str, Any]) -> Trajectory:
                return Trajectory(
                    t=x["t"],
                    q=x["q"],
                    names=names,
                    u=x["u"],
                    input_names=inputs,
                    label=x["label"],
                    labels=labels,
                )

            ideal, sim = traj(d["ideal"]), traj(d["sim"])
            p = d["plan"]
            plan = Plan(
                t=ideal.t,
                q=ideal.u,
                names=inputs,
                label=ideal.label,
                labels=labels,
                duration=p["duration"],
                segments=tuple(tuple(s) for s in p["segments"]),
                details=p["details"],
                hold_period=p["hold_period"],
            )
        series = {k: Series(t=t, values=v) for k, (t, v) in d.get("series", {}).items()}
        return cls(
            name=d["name"],
            planner=d["planner"],
            kind=d["kind"],
            passed=d["passed"],
            failures=tuple(d["failures"]),
            metrics=d["metrics"],
            ideal=ideal,
            sim=sim,
            plan=plan,
            channels=d.get("channels", {}),
            series=series,
            summary=d["summary"],
            log_dir=Path(d["log_dir"]) if d["log_dir"] is not None else None,
            steps=d["steps"],
            timings=d["timings"],
            state_names=names,
            input_names=inputs,
            table=d.get("table", ""),
            law_calls=d.get("law_calls", 0),
            verdict=d["verdict"],
        )


def _logs(logs: Union[str, "os.PathLike[str]", None]) -> Optional[str]:
    return None if logs is None else os.fspath(logs)


def run(
    scenario: ScenarioLike,
    logs: Union[str, "os.PathLike[str]", None] = None,
    *,
    law: Optional[Law] = None,
    period: Optional[float] = None,
    horizon: Optional[float] = None,
    pose_rate: float = 100.0,
) -> Result:
    """Run one scenario end to end: ideal run, physics replay, comparison,
    thresholds, and logs in ``logs/<name>/`` when ``logs`` is given (the
    CLI's ``run.mcap``, ``run.rrd``, ``series.json``, ``summary.json``, link
    poses at ``pose_rate`` per simulated second, 0 = every sample). A
    scenario with a ``[sweep]`` table runs its variants.

    With ``law``, the scenario's planner is replaced by the feedback law
    ``u = law(t, q)``, sampled every ``period`` s on the ideal and on the
    simulated state and held in between, for at most ``horizon`` s (default:
    the scenario's plan duration); the rest (model, physics, start, goal,
    thresholds, settling) is the scenario's. The law is called on the ideal
    run first, then on the physics run (each from ``t = 0``), with exactly
    the samples an external law (``[planner] kind = "external"``) is sent.

    The physics runs without the GIL (other Python threads keep running; a
    law re-acquires it for each sample) and Ctrl-C stops a run at its next
    step (``KeyboardInterrupt``). Raises :class:`InputError`,
    :class:`RuntimeFailure`, or the exception a law raised.
    """
    s = load(scenario)
    d = _native.run(
        s,
        _logs(logs),
        law=law,
        period=period,
        horizon=horizon,
        pose_rate=pose_rate,
    )
    return Result._from_native(d)


def run_many(
    scenarios: Iterable[ScenarioLike],
    logs: Union[str, "os.PathLike[str]", None] = None,
    *,
    pose_rate: float = 100.0,
    return_exceptions: bool = False,
) -> List[Union[Result, BaseException]]:
    """Run several scenarios in parallel, like the CLI: every scenario is
    validated first, then they run on a thread pool (``RAYON_NUM_THREADS``
    sets its size), longest first; results come back in input order and are
    the same on any number of threads. When a run fails, the others still
    run (and log); then the first failure is raised, or with
    ``return_exceptions`` each failed scenario's exception takes its place
    in the list.
    """
    loaded = [load(s) for s in scenarios]
    out = _native.run_many(
        loaded,
        _logs(logs),
        pose_rate=pose_rate,
        return_exceptions=return_exceptions,
    )
    return [x if isinstance(x, BaseException) else Result._from_native(x) for x in out]

"""Stubs of the native module (Rust, pyo3). The public API is
``anholonomy``; ``Scenario`` is re-exported from here."""

from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np
from numpy.typing import NDArray

__version__: str
DEFAULT_MAX_STEPS: int

class Scenario:
    """A validated scenario: parsed and checked like the CLI does before it
    runs anything (keys, ranges, URDF, the plan, the physics at the start
    pose). Make one with ``anholonomy.load``; ``replace`` gives variants."""

    def replace(self, changes: Mapping[str, Any]) -> "Scenario":
        """A variant: values written over this scenario's keys, given by the
        dotted key paths sweeps use (``"sim.friction"``, ``"goal"``,
        ``"start[2]"``, ``"planner.k1"``), then validated like a file. Angles
        in ``start``/``goal`` are in degrees, as in the file. Raises
        ``InputError`` (with the key and the line where the file writes it)."""
    @property
    def name(self) -> str:
        """The scenario's name (its log directory)."""
    @property
    def file(self) -> Any:
        """The file it was read from (``pathlib.Path``; for text and dicts,
        the path they were read as)."""
    @property
    def description(self) -> str: ...
    @property
    def model(self) -> str:
        """The model kind (``model.kind``)."""
    @property
    def planner(self) -> str:
        """The planner kind (``planner.kind``)."""
    @property
    def state_names(self) -> List[str]:
        """Names of the state coordinates (columns of ``Result.ideal.q``)."""
    @property
    def input_names(self) -> List[str]:
        """Names of the inputs (what a feedback law returns, in this order)."""
    @property
    def start(self) -> NDArray[np.float64]:
        """Start state in model coordinates, SI units (angles in radians)."""
    @property
    def goal(self) -> NDArray[np.float64]:
        """Goal state in model coordinates, SI units (angles in radians)."""
    @property
    def dt(self) -> float:
        """Physics and integration step ``sim.dt``, s."""
    @property
    def duration(self) -> float:
        """Duration of the validated plan, s (a feedback law's default horizon)."""
    @property
    def text(self) -> str:
        """The scenario's TOML text as read (without ``replace``'s changes)."""
    @property
    def is_sweep(self) -> bool:
        """Whether the scenario has a ``[sweep]`` table."""
    def to_dict(self) -> Dict[str, Any]:
        """The resolved scenario (defaults filled in, SI units) as a dict."""

def load_file(path: str, max_steps: int) -> Scenario: ...
def load_text(text: str, path: str, max_steps: int) -> Scenario: ...
def load_table(table: Dict[str, Any], path: str, max_steps: int) -> Scenario: ...
def run(
    scenario: Scenario,
    logs: Optional[str] = None,
    law: Optional[Callable[[float, NDArray[np.float64]], Any]] = None,
    period: Optional[float] = None,
    horizon: Optional[float] = None,
    pose_rate: float = 100.0,
) -> Dict[str, Any]: ...
def run_many(
    scenarios: Sequence[Scenario],
    logs: Optional[str] = None,
    pose_rate: float = 100.0,
    return_exceptions: bool = False,
) -> List[Any]: ...

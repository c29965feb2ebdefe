"""Type stubs for skyplan (the extension module skyplan._skyplan and its Python half)."""

import os
from typing import (
    Any,
    Callable,
    Dict,
    List,
    Optional,
    Sequence,
    Tuple,
    TypedDict,
    TypeVar,
    Union,
    final,
    overload,
)

import numpy as np
import numpy.typing as npt

from ._errors import AirspaceUnavailable as AirspaceUnavailable
from ._errors import BadInput as BadInput
from ._errors import Conflict as Conflict
from ._errors import InvalidGoal as InvalidGoal
from ._errors import InvalidStart as InvalidStart
from ._errors import NoPath as NoPath
from ._errors import PlanError as PlanError
from ._errors import Timeout as Timeout
from ._heuristic import Heuristic as Heuristic

__version__: str
__all__ = [
    "Airspace",
    "AirspaceUnavailable",
    "BadInput",
    "Conflict",
    "Heuristic",
    "InvalidGoal",
    "InvalidStart",
    "NoPath",
    "Plan",
    "PlanError",
    "Planner",
    "Timeout",
    "__version__",
    "a_star",
    "astar_path",
    "bresenham_prune",
    "create_grid",
    "planners",
    "prune_path",
]

_Cell = Tuple[int, int]
_CellLike = Union[Tuple[int, int], Sequence[int], npt.NDArray[np.integer[Any]]]
_Point = TypeVar("_Point")
_PathLike = Union[str, "os.PathLike[str]"]

def create_grid(
    data: npt.ArrayLike, drone_altitude: float, safety_distance: float
) -> Tuple[npt.NDArray[np.float64], int, int]:
    """FCND's ``create_grid``, bit for bit: ``(grid, north_offset, east_offset)``.

    ``data``: the (n, 6) colliders array (north, east, alt, d_north, d_east, d_alt).
    ``grid``: float64, 1.0 = blocked, row = north - north_offset, column = east - east_offset.
    """

@overload
def a_star(
    grid: npt.ArrayLike,
    start: _CellLike,
    goal: _CellLike,
    *,
    diagonal: bool = True,
    corner_cutting: bool = True,
) -> Tuple[List[_Cell], float]: ...
@overload
def a_star(
    grid: npt.ArrayLike,
    heuristic: Callable[..., float],
    start: _CellLike,
    goal: _CellLike,
    *,
    diagonal: bool = True,
    corner_cutting: bool = True,
) -> Tuple[List[_Cell], float]:
    """Exactly optimal grid path ``(path, cost)`` with FCND's move model by default.

    FCND's ``heuristic`` argument is accepted and ignored. ``path``: ``(row, col)`` tuples from
    start to goal; ``cost`` in cells. Raises NoPath, InvalidStart, InvalidGoal, BadInput.
    """

def prune_path(path: Sequence[_Point], epsilon: float = 1e-6) -> List[_Point]:
    """FCND's collinearity pruning: drops the middle of three collinear points."""

def bresenham_prune(grid: npt.ArrayLike, path: Sequence[_Point]) -> List[_Point]:
    """Line-of-sight pruning along Bresenham lines (nonzero = blocked)."""

def astar_path(
    weights: Union[npt.NDArray[np.float32], npt.NDArray[np.float64]],
    start: _CellLike,
    goal: _CellLike,
    allow_diagonal: bool = False,
    heuristic_override: Optional[int] = None,
) -> Optional[npt.NDArray[np.int32]]:
    """pyastar2d's ``astar_path``: (N, 2) int32 path over weights >= 1 (``inf`` walls), or None.

    The same paths as pyastar2d's, ties included. ``heuristic_override``: a :class:`Heuristic`
    (pyastar2d's ``Heuristic`` or its number work too); None is ``Heuristic.DEFAULT``.
    Deliberately more than pyastar2d: float64 weights are accepted (costs summed in float64;
    pyastar2d asserts float32); refused with BadInput (a ValueError) where pyastar2d crashes or
    lets them through: NaN weights, an unknown heuristic number.
    """

class _PlannerRow(TypedDict):
    name: str
    label: str
    dims: int
    optimality: str
    maps: str
    summary: str
    exact: bool
    grid_path: bool
    needs_obstacles: bool

def planners() -> List[_PlannerRow]:
    """Every planner, from the planning API's registry, in its order.

    ``name`` (the ``planner=`` value), ``label``, ``dims`` (2 or 3), ``optimality``, ``maps``
    (``any_grid`` or ``obstacles``), ``summary``; predicates: ``exact`` (shortest grid
    path: Dijkstra's cost), ``grid_path`` (a path through grid cells: takes ``connectivity``,
    ``corner_cutting``, ``prune``, ``epsilon``, ``shortcut``), ``needs_obstacles`` (a map of obstacles, not a fixed grid).
    """

@final
class Plan:
    """A planned route, every segment re-checked against the map."""

    @property
    def waypoints(self) -> npt.NDArray[np.float64]:
        """(n, 4) ``[north_m, east_m, alt_m, heading_rad]`` (FCND's layout)."""
    @property
    def lla(self) -> Optional[npt.NDArray[np.float64]]:
        """(n, 2) ``[lat_deg, lon_deg]``, None on maps without a geodetic home."""
    @property
    def trajectory(self) -> Optional[npt.NDArray[np.float64]]:
        """(n, 11) samples ``[t_s, north_m, east_m, alt_m, v_north, v_east, v_up, a_north,
        a_east, a_up, yaw_deg]`` of the trajectory (``trajectory=True``), or None."""
    @property
    def cost_m(self) -> float:
        """Route length of the planner, metres."""
    @property
    def planner(self) -> str:
        """The planner's CLI name."""
    @property
    def stats(self) -> Dict[str, Any]:
        """The CLI's ``--json`` fields besides the waypoints."""
    def to_json(self) -> str:
        """The whole plan as JSON text."""
    def to_file(self, path: _PathLike, format: Optional[str] = None) -> None:
        """Writes the waypoints (.json .csv .h5 .geojson .plan, or ``format=``)."""
    def __len__(self) -> int: ...

@final
class Planner:
    """A map loaded once, and every skyplan planner on it (:func:`planners` lists them); safe to
    share between threads."""

    def __new__(
        cls,
        map: Union[None, _PathLike, npt.ArrayLike] = None,
        *,
        home: Optional[Tuple[float, float]] = None,
        resolution_m: Optional[float] = None,
        unknown_free: bool = False,
        origin_ne: Optional[Tuple[float, float]] = None,
        cell_m: Optional[float] = None,
        terrain: Optional[_PathLike] = None,
    ) -> "Planner": ...
    @property
    def name(self) -> str: ...
    @property
    def kind(self) -> str: ...
    @property
    def bounds_ne(self) -> Tuple[float, float, float, float]:
        """``(north_min_m, north_max_m, east_min_m, east_max_m)``."""
    def plan(
        self,
        start: Optional[Tuple[float, float]] = None,
        goal: Optional[Tuple[float, float]] = None,
        *,
        planner: Optional[str] = None,
        alt_m: Optional[float] = None,
        alt_agl_m: Optional[float] = None,
        safety_m: Optional[float] = None,
        cell_m: Optional[float] = None,
        start_ne: Optional[Tuple[float, float]] = None,
        goal_ne: Optional[Tuple[float, float]] = None,
        start_lla: Optional[Tuple[float, float]] = None,
        goal_lla: Optional[Tuple[float, float]] = None,
        start_alt_m: Optional[float] = None,
        goal_alt_m: Optional[float] = None,
        time_limit_ms: Optional[int] = None,
        seed: Optional[int] = None,
        no_fly: Optional[str] = None,
        departure: Optional[str] = None,
        **options: Any,
    ) -> Plan:
        """Plans a route from ``start`` to ``goal`` ((north_m, east_m)); options as the CLI's.

        ``planner``: a ``name`` from :func:`planners` (every planner of the registry).
        ``no_fly``: the text of a no-fly zone file (GeoJSON or a QGroundControl ``.plan``), e.g.
        ``open("data/no-fly-sample.geojson").read()``; the 2D planners go around the zones.
        ``departure``: when the flight leaves (RFC 3339, ``"2026-12-03T17:00:00Z"``); a zone
        with a time window then applies only if it is active between the departure and the
        latest arrival (without it every timed zone applies).
        """

@final
class Airspace:
    """A shared airspace store of operational intents: ``"sqlite:FILE"``, ``"sqlite::memory:"``
    or ``"postgres://USER@HOST:PORT/DATABASE"`` (TLS with ``?sslmode=verify-full&sslrootcert=CA.pem``,
    a client certificate with ``&sslcert=…&sslkey=…``)."""

    def __new__(cls, url: str) -> "Airspace": ...
    @property
    def url(self) -> str: ...
    def reserve(
        self,
        planner: Planner,
        departure: Union[str, Tuple[str, str], Dict[str, str]],
        *,
        priority: int = 0,
        owner: str = "python",
        search: str = "departure",
        deadline_ms: Optional[int] = None,
        start: Optional[Tuple[float, float]] = None,
        goal: Optional[Tuple[float, float]] = None,
        **options: Any,
    ) -> Dict[str, Any]:
        """Plans with ``planner`` and reserves the flight as a new intent (``search``:
        ``"departure"`` or ``"space_time"``, the latter within ``deadline_ms`` if given, proving
        the earliest arrival over half the time left and then heading for the goal, else
        :class:`Timeout`); raises :class:`Conflict` when no way is free."""
    def intents(self) -> List[Dict[str, Any]]: ...
    def get(self, id: str) -> Optional[Dict[str, Any]]: ...
    def delete(self, id: str) -> Optional[Dict[str, Any]]: ...
    def conflicts(self) -> List[Tuple[str, str]]: ...
    def fleet(
        self,
        planner: Planner,
        missions: Sequence[Dict[str, Any]],
        *,
        mode: str = "shift",
        start: Optional[str] = None,
        deadline_ms: Optional[int] = None,
    ) -> Dict[str, Any]:
        """Plans and reserves ``missions`` in order (``mode``: ``"shift"``, ``"space_time"`` or
        ``"reject_on_conflict"``; ``deadline_ms``: with ``"space_time"``, when a flight's answer
        is due: its search proves the earliest arrival over half the time left, then heads for
        the goal, and gives up at four-fifths, the flight ``timed_out``); the report as
        ``skyplan fleet --json`` writes it."""

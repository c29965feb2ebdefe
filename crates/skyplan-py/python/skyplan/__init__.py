"""skyplan: drone motion planning in Rust, for Python.

FCND drop-ins (replace ``from planning_utils import ...`` by ``from skyplan import ...``):

* :func:`create_grid` -- FCND's grid, bit for bit, with its offsets;
* :func:`a_star` -- exactly optimal, FCND's move model, FCND's call ``a_star(grid, h, start, goal)``;
* :func:`prune_path` and :func:`bresenham_prune`.

pyastar2d drop-in (``import skyplan as pyastar2d``): :func:`astar_path` (float32 weights >= 1,
``np.inf`` walls; pyastar2d's paths, ties included) and :class:`Heuristic`
(``heuristic_override=``). skyplan also takes float64 weights, which pyastar2d refuses.

The whole planner: :class:`Planner` loads a map once (the bundled FCND city, a colliders.csv,
an occupancy image, a MovingAI map or a numpy grid) and plans with any skyplan planner:
:func:`planners` lists them all, from the planning API's registry (name, dims, optimality,
maps, summary, and the predicates ``exact``, ``grid_path``, ``needs_obstacles``); :class:`Plan`
holds the waypoints as numpy arrays.

The shared airspace: :class:`Airspace` (a SQLite file, memory or PostgreSQL store) reserves
flights planned by a :class:`Planner` as operational intents -- the departure shifted, or the
route re-planned around the others in space and time -- one by one (``reserve``) or as a fleet
(``fleet``); :class:`Conflict` when no way is free.

Failures raise :class:`PlanError` subclasses: :class:`InvalidStart`, :class:`InvalidGoal`,
:class:`NoPath`, :class:`Timeout`, :class:`BadInput`. The GIL is released while planning.
"""

from ._errors import (
    AirspaceUnavailable,
    BadInput,
    Conflict,
    InvalidGoal,
    InvalidStart,
    NoPath,
    PlanError,
    Timeout,
)
from ._heuristic import Heuristic
from ._skyplan import (
    Airspace,
    Plan,
    Planner,
    __version__,
    a_star,
    astar_path,
    bresenham_prune,
    create_grid,
    planners,
    prune_path,
)

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

"""pyastar2d's ``Heuristic`` for :func:`skyplan.astar_path` (``heuristic_override=``)."""

from enum import IntEnum


class Heuristic(IntEnum):
    """The heuristics of :func:`skyplan.astar_path`, with pyastar2d's names and numbers.

    ``DEFAULT``: L-infinity distance with diagonal moves, L1 without (optimal paths).
    ``ORTHOGONAL_X``: straight along the rows first, then along the columns.
    ``ORTHOGONAL_Y``: straight along the columns first, then along the rows.
    The two orthogonal heuristics are pyastar2d's experimental "pretty lines": their paths
    are not always the cheapest. pyastar2d's own ``Heuristic`` members work as well.
    """

    DEFAULT = 0
    ORTHOGONAL_X = 1
    ORTHOGONAL_Y = 2

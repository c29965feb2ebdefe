"""``import pyastar2d`` resolved to skyplan, for running pyastar2d's own test suite against it.

Only on the PYTHONPATH of that run (ci.sh); pyastar2d's package exports exactly these two.
"""

from skyplan import Heuristic, astar_path

__all__ = ["astar_path", "Heuristic"]

"""astar_path with pyastar2d's contract, against pyastar2d and an independent Dijkstra."""

import math

import numpy as np
import pytest

import skyplan
from conftest import dijkstra


def weighted_dijkstra(weights, start, goal, diagonal):
    """Textbook Dijkstra: entering a cell costs its weight (pyastar2d's model, diagonals too)."""
    rows, cols = weights.shape
    steps = [(-1, 0), (1, 0), (0, -1), (0, 1)]
    if diagonal:
        steps += [(-1, -1), (-1, 1), (1, -1), (1, 1)]

    def neighbours(r, c):
        for dr, dc in steps:
            nr, nc = r + dr, c + dc
            if 0 <= nr < rows and 0 <= nc < cols and math.isfinite(weights[nr, nc]):
                yield nr, nc, float(weights[nr, nc])

    return dijkstra(start, goal, neighbours)


def walked_cost(weights, path, diagonal):
    """The cost of a returned path, checking it moves one (or one diagonal) cell at a time."""
    total = 0.0
    for (r0, c0), (r1, c1) in zip(path[:-1], path[1:]):
        step = (abs(int(r1) - int(r0)), abs(int(c1) - int(c0)))
        assert step in ([(0, 1), (1, 0), (1, 1)] if diagonal else [(0, 1), (1, 0)]), step
        w = float(weights[r1, c1])
        assert math.isfinite(w), "path enters a wall"
        total += w
    return total


def random_weights(rng, rows, cols):
    w = rng.integers(1, 10, (rows, cols)).astype(np.float32)
    w[rng.random((rows, cols)) < 0.25] = np.inf
    return w


@pytest.mark.parametrize("diagonal", [False, True])
def test_costs_equal_dijkstra(diagonal):
    rng = np.random.default_rng(5 + diagonal)
    found = missing = 0
    for _ in range(80):
        w = random_weights(rng, int(rng.integers(1, 25)), int(rng.integers(1, 25)))
        start = (int(rng.integers(w.shape[0])), int(rng.integers(w.shape[1])))
        goal = (int(rng.integers(w.shape[0])), int(rng.integers(w.shape[1])))
        want = weighted_dijkstra(w, start, goal, diagonal)
        path = skyplan.astar_path(w, start, goal, allow_diagonal=diagonal)
        if want is None:
            assert path is None
            missing += 1
            continue
        assert path.dtype == np.int32 and path.ndim == 2 and path.shape[1] == 2
        assert tuple(path[0]) == start and tuple(path[-1]) == goal
        assert walked_cost(w, path, diagonal) == want
        found += 1
    assert found >= 30 and missing >= 5


@pytest.mark.parametrize("diagonal", [False, True])
def test_costs_equal_pyastar2d(diagonal):
    pyastar2d = pytest.importorskip("pyastar2d")
    rng = np.random.default_rng(17 + diagonal)
    compared = 0
    for _ in range(80):
        w = random_weights(rng, int(rng.integers(2, 40)), int(rng.integers(2, 40)))
        start = (int(rng.integers(w.shape[0])), int(rng.integers(w.shape[1])))
        goal = (int(rng.integers(w.shape[0])), int(rng.integers(w.shape[1])))
        theirs = pyastar2d.astar_path(w, start, goal, allow_diagonal=diagonal)
        ours = skyplan.astar_path(w, start, goal, allow_diagonal=diagonal)
        assert (theirs is None) == (ours is None)
        if ours is None:
            continue
        # Small integer weights: float32 sums are exact, so both optimal costs are equal.
        assert walked_cost(w, ours, diagonal) == walked_cost(w, theirs, diagonal)
        assert ours.dtype == theirs.dtype
        compared += 1
    assert compared >= 30


def test_default_is_four_connected_as_pyastar2d():
    w = np.ones((5, 5), dtype=np.float32)
    path = skyplan.astar_path(w, (0, 0), (4, 4))
    assert len(path) == 9  # 8 orthogonal moves
    assert len(skyplan.astar_path(w, (0, 0), (4, 4), allow_diagonal=True)) == 5


def test_contract_errors_are_value_errors():
    w = np.ones((4, 4), dtype=np.float32)
    with pytest.raises(ValueError, match="float32"):
        skyplan.astar_path(w.astype(np.float64), (0, 0), (3, 3))
    low = w.copy()
    low[1, 1] = 0.5
    with pytest.raises(ValueError, match="minimum cost"):
        skyplan.astar_path(low, (0, 0), (3, 3))
    with pytest.raises(ValueError, match="outside"):
        skyplan.astar_path(w, (4, 0), (3, 3))
    with pytest.raises(ValueError, match="outside"):
        skyplan.astar_path(w, (0, 0), (0, -1))
    nan = w.copy()
    nan[2, 2] = np.nan
    with pytest.raises(skyplan.BadInput):
        skyplan.astar_path(nan, (0, 0), (3, 3))

"""astar_path with pyastar2d's contract, against pyastar2d and an independent Dijkstra.

pyastar2d's own test suite runs against skyplan too (ci.sh, tests/pyastar2d_suite).
"""

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


def real_pyastar2d():
    """pyastar2d itself (skipped when it is not installed), never the shim that is skyplan."""
    pyastar2d = pytest.importorskip("pyastar2d")
    assert pyastar2d.astar_path is not skyplan.astar_path
    return pyastar2d


HEURISTICS = list(skyplan.Heuristic)


def test_heuristic_is_pyastar2ds():
    theirs = real_pyastar2d().Heuristic
    assert [(h.name, h.value) for h in skyplan.Heuristic] == [(h.name, h.value) for h in theirs]


@pytest.mark.parametrize("heuristic", HEURISTICS, ids=lambda h: h.name)
@pytest.mark.parametrize("diagonal", [False, True])
def test_paths_equal_pyastar2d(diagonal, heuristic):
    """The same path, cell for cell, ties included: uniform grids (every shortest path ties),
    small integer weights (many ties), and the orthogonal heuristics' non-optimal paths."""
    pyastar2d = real_pyastar2d()
    rng = np.random.default_rng(31 + 2 * diagonal + 4 * int(heuristic))
    compared = 0
    for k in range(120):
        rows, cols = int(rng.integers(1, 30)), int(rng.integers(1, 30))
        if k % 3 == 0:
            w = np.ones((rows, cols), dtype=np.float32)
        else:
            w = rng.integers(1, 4, (rows, cols)).astype(np.float32)
        w[rng.random((rows, cols)) < 0.2 * (k % 2)] = np.inf
        start = (int(rng.integers(rows)), int(rng.integers(cols)))
        goal = (int(rng.integers(rows)), int(rng.integers(cols)))
        w[start] = w[goal] = 1.0
        theirs = pyastar2d.astar_path(
            w, start, goal, allow_diagonal=diagonal, heuristic_override=pyastar2d.Heuristic(heuristic)
        )
        ours = skyplan.astar_path(w, start, goal, allow_diagonal=diagonal, heuristic_override=heuristic)
        if theirs is None:
            assert ours is None
            continue
        assert ours is not None and ours.dtype == theirs.dtype
        assert ours.tolist() == theirs.tolist(), (start, goal)
        compared += 1
    assert compared >= 50


def test_orthogonal_heuristics_walk_straight():
    """pyastar2d's documented shapes on an open grid: ORTHOGONAL_X moves along the rows first
    (down to half the rows' distance), ORTHOGONAL_Y along the columns first."""
    w = np.ones((9, 9), dtype=np.float32)
    x = skyplan.astar_path(w, (0, 0), (8, 8), heuristic_override=skyplan.Heuristic.ORTHOGONAL_X)
    y = skyplan.astar_path(w, (0, 0), (8, 8), heuristic_override=skyplan.Heuristic.ORTHOGONAL_Y)
    for path, along in ((x, 0), (y, 1)):
        assert walked_cost(w, path, False) == 16  # still a shortest path here
        # The first moves all change the same coordinate, until half way.
        firsts = path[1:5, along] - path[:4, along]
        assert firsts.tolist() == [1, 1, 1, 1]
        assert path[:5, 1 - along].tolist() == [0] * 5
    assert x.tolist() != y.tolist()
    default = skyplan.astar_path(w, (0, 0), (8, 8))
    assert default.tolist() == skyplan.astar_path(
        w, (0, 0), (8, 8), heuristic_override=skyplan.Heuristic.DEFAULT
    ).tolist()
    # pyastar2d's own Heuristic members and plain numbers work as well.
    assert skyplan.astar_path(w, (0, 0), (8, 8), heuristic_override=1).tolist() == x.tolist()


@pytest.mark.parametrize("heuristic", HEURISTICS, ids=lambda h: h.name)
def test_every_heuristic_finds_a_legal_path_or_none(heuristic):
    """Orthogonal heuristics are not admissible: their paths are legal, never cheaper than
    Dijkstra's, and found exactly when one exists; the default's are Dijkstra's cost."""
    rng = np.random.default_rng(47 + int(heuristic))
    for _ in range(60):
        w = random_weights(rng, int(rng.integers(1, 20)), int(rng.integers(1, 20)))
        start = (int(rng.integers(w.shape[0])), int(rng.integers(w.shape[1])))
        goal = (int(rng.integers(w.shape[0])), int(rng.integers(w.shape[1])))
        for diagonal in (False, True):
            want = weighted_dijkstra(w, start, goal, diagonal)
            path = skyplan.astar_path(w, start, goal, diagonal, heuristic)
            if want is None:
                assert path is None
                continue
            assert tuple(path[0]) == start and tuple(path[-1]) == goal
            cost = walked_cost(w, path, diagonal)
            if heuristic == skyplan.Heuristic.DEFAULT:
                assert cost == want
            else:
                assert cost >= want


def test_float64_weights_are_summed_in_float64():
    """skyplan takes float64 weights (pyastar2d asserts float32) and searches them in float64:
    optimal to float64's precision, and able to tell costs apart that float32 cannot."""
    rng = np.random.default_rng(3)
    for _ in range(40):
        w = 1.0 + 4.0 * rng.random((15, 15))
        w[rng.random(w.shape) < 0.2] = np.inf
        start, goal = (0, 0), (14, 14)
        w[start] = w[goal] = 1.0
        for diagonal in (False, True):
            want = weighted_dijkstra(w, start, goal, diagonal)
            path = skyplan.astar_path(w, start, goal, allow_diagonal=diagonal)
            if want is None:
                assert path is None
            else:
                assert walked_cost(w, path, diagonal) == pytest.approx(want, rel=1e-12)
    # Around a wall, over the top row or along the bottom one; one of them 1e-9 dearer, which
    # float32 rounds away (1 + 1e-9 is 1.0 there): float64 takes the cheaper side both times.
    chosen = {}
    for dearer in (0, 2):
        w = np.ones((3, 3))
        w[1, 1] = np.inf
        w[dearer, 1] = 1 + 1e-9
        chosen[dearer] = skyplan.astar_path(w, (1, 0), (1, 2))[2].tolist()
        rounded = skyplan.astar_path(w.astype(np.float32), (1, 0), (1, 2))[2].tolist()
        chosen[dearer, "float32"] = rounded
    assert chosen[0] == [2, 1] and chosen[2] == [0, 1]
    assert chosen[0, "float32"] == chosen[2, "float32"]  # a tie in float32


def test_contract_errors_are_value_errors():
    w = np.ones((4, 4), dtype=np.float32)
    for dtype in (np.int64, np.float16, np.uint8):
        with pytest.raises(ValueError, match="float32"):
            skyplan.astar_path(w.astype(dtype), (0, 0), (3, 3))
    with pytest.raises(ValueError, match="float32"):
        skyplan.astar_path(w.tolist(), (0, 0), (3, 3))
    for bad in (3, -1, "ORTHOGONAL_X", 1.0):
        with pytest.raises(skyplan.BadInput, match="heuristic_override"):
            skyplan.astar_path(w, (0, 0), (3, 3), heuristic_override=bad)
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

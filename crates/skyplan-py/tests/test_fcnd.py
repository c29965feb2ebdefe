"""FCND drop-ins against FCND's own algorithms and an independent Dijkstra."""

import math

import numpy as np
import pytest
from conftest import dijkstra_cost, fcnd_create_grid, path_cost_checked, random_grid
from fcnd_reference import fcnd_a_star

import skyplan


@pytest.mark.parametrize("altitude", [0, 3, 5, 10, 20.5, 50, 120, 300])
@pytest.mark.parametrize("margin", [0, 1, 3, 5, 7.5])
def test_create_grid_is_fcnds_on_the_real_map(colliders, altitude, margin):
    want, want_north, want_east = fcnd_create_grid(colliders, altitude, margin)
    got, north, east = skyplan.create_grid(colliders, altitude, margin)
    assert got.dtype == np.float64 and want.dtype == np.float64
    assert got.shape == want.shape
    assert np.array_equal(got, want)
    assert (north, east) == (want_north, want_east)
    assert type(north) is int and type(east) is int


def test_create_grid_real_map_offsets_and_size(colliders):
    grid, north, east = skyplan.create_grid(colliders, 5, 5)
    # FCND's city: the grid's corner is 316 m south and 445 m west of the home.
    assert (north, east) == (-316, -445)
    assert grid.shape == (921, 921)
    assert 0 < grid.sum() < grid.size


def test_create_grid_fractional_boxes_and_clipping():
    rng = np.random.default_rng(7)
    for _ in range(30):
        n = int(rng.integers(1, 40))
        data = np.column_stack(
            [
                rng.uniform(-80, 80, n),
                rng.uniform(-60, 90, n),
                rng.uniform(0, 30, n),
                rng.uniform(0.1, 12, n),
                rng.uniform(0.1, 12, n),
                rng.uniform(0.1, 30, n),
            ]
        )
        altitude, margin = float(rng.uniform(0, 40)), float(rng.uniform(-2, 9))
        want = fcnd_create_grid(data, altitude, margin)
        got = skyplan.create_grid(data, altitude, margin)
        assert np.array_equal(got[0], want[0])
        assert got[1:] == want[1:]


def test_create_grid_accepts_integer_data():
    data = np.array([[10, 10, 5, 2, 3, 5], [-4, 7, 1, 1, 1, 1]])
    want = fcnd_create_grid(data.astype(np.float64), 4, 1)
    got = skyplan.create_grid(data, 4, 1)
    assert np.array_equal(got[0], want[0]) and got[1:] == want[1:]


@pytest.mark.parametrize(
    "diagonal,corner_cutting", [(True, True), (True, False), (False, True)]
)
def test_a_star_costs_equal_dijkstra_on_random_grids(diagonal, corner_cutting):
    rng = np.random.default_rng(42 + diagonal * 2 + corner_cutting)
    checked = unreachable = 0
    for _ in range(60):
        rows, cols = int(rng.integers(2, 30)), int(rng.integers(2, 30))
        grid = random_grid(rng, rows, cols, float(rng.uniform(0.0, 0.45)))
        free = np.argwhere(grid == 0)
        if len(free) < 2:
            continue
        a, b = free[rng.choice(len(free), 2, replace=False)]
        start, goal = (int(a[0]), int(a[1])), (int(b[0]), int(b[1]))
        want = dijkstra_cost(grid, start, goal, diagonal, corner_cutting)
        if want is None:
            with pytest.raises(skyplan.NoPath):
                skyplan.a_star(grid, start, goal, diagonal=diagonal, corner_cutting=corner_cutting)
            unreachable += 1
            continue
        path, cost = skyplan.a_star(
            grid, start, goal, diagonal=diagonal, corner_cutting=corner_cutting
        )
        assert path[0] == start and path[-1] == goal
        assert all(type(p) is tuple and len(p) == 2 for p in path)
        walked = path_cost_checked(grid, path, diagonal, corner_cutting)
        assert math.isclose(walked, cost, rel_tol=0, abs_tol=1e-9)
        assert math.isclose(cost, want, rel_tol=0, abs_tol=1e-9), (start, goal)
        checked += 1
    assert checked >= 30 and unreachable >= 1


def euclid(a, b):
    return float(np.linalg.norm(np.array(a) - np.array(b)))


def test_a_star_on_the_city_as_fcnd_calls_it(colliders):
    grid, north_offset, east_offset = skyplan.create_grid(colliders, 5, 5)
    grid_start = (-north_offset, -east_offset)
    grid_goal = (grid_start[0] + 100, grid_start[1] + 100)
    path, cost = skyplan.a_star(grid, euclid, grid_start, grid_goal)
    assert path == skyplan.a_star(grid, grid_start, grid_goal)[0]
    assert path[0] == grid_start and path[-1] == grid_goal
    want = dijkstra_cost(grid, grid_start, grid_goal)
    assert math.isclose(cost, want, abs_tol=1e-9)
    fcnd_path, fcnd_cost = fcnd_a_star(grid, euclid, grid_start, grid_goal)
    assert fcnd_path, "FCND's a_star found no path"
    assert cost <= fcnd_cost + 1e-9
    assert math.isclose(path_cost_checked(grid, path), cost, abs_tol=1e-9)


def test_a_star_same_cell_and_numpy_indices():
    grid = np.zeros((3, 4))
    assert skyplan.a_star(grid, (1, 1), (1, 1)) == ([(1, 1)], 0.0)
    path, cost = skyplan.a_star(grid.astype(bool), np.array([0, 0]), (np.int64(2), np.int32(3)))
    assert math.isclose(cost, 1 + 2 * math.sqrt(2))
    assert path[0] == (0, 0) and path[-1] == (2, 3)


def fcnd_prune_path(path, epsilon=1e-6):
    """FCND's prune_path with its numpy determinant."""

    def point(p):
        return np.array([p[0], p[1], 1.0]).reshape(1, -1)

    pruned = list(path)
    i = 0
    while i < len(pruned) - 2:
        m = np.concatenate((point(pruned[i]), point(pruned[i + 1]), point(pruned[i + 2])), 0)
        if abs(np.linalg.det(m)) < epsilon:
            del pruned[i + 1]
        else:
            i += 1
    return pruned


def test_prune_path_is_fcnds(colliders):
    grid, north_offset, east_offset = skyplan.create_grid(colliders, 5, 5)
    start = (-north_offset, -east_offset)
    for goal in [(start[0] + 420, start[1] + 390), (start[0] - 150, start[1] + 300)]:
        path, _ = skyplan.a_star(grid, start, goal)
        pruned = skyplan.prune_path(path)
        assert pruned == fcnd_prune_path(path)
        assert len(pruned) < len(path) and pruned[0] == start and pruned[-1] == goal
    rng = np.random.default_rng(3)
    for _ in range(50):
        pts = [tuple(p) for p in rng.integers(0, 6, (int(rng.integers(0, 12)), 2)).tolist()]
        assert skyplan.prune_path(pts) == fcnd_prune_path(pts)
        # Generic floats (numpy's LU determinant and the direct formula differ by rounding,
        # which matters only for a determinant within rounding of epsilon), then points on
        # lines with half-metre steps.
        floats = [tuple(p) for p in rng.uniform(0, 4, (8, 2)).tolist()]
        steps = np.cumsum(rng.choice([0.5, 0.0], (10, 2)), axis=0)
        floats += [tuple(p) for p in (steps + floats[-1]).tolist()]
        for eps in (1e-6, 0.05, 0.3):  # the steps give determinants in multiples of 0.25
            assert skyplan.prune_path(floats, eps) == fcnd_prune_path(floats, eps)


def bresenham_cells(x0, y0, x1, y1):
    """The `bresenham` package's line (the FCND lessons'): integer cells, both ends included."""
    dx, dy = x1 - x0, y1 - y0
    xsign = 1 if dx > 0 else -1
    ysign = 1 if dy > 0 else -1
    dx, dy = abs(dx), abs(dy)
    if dx > dy:
        xx, xy, yx, yy = xsign, 0, 0, ysign
    else:
        dx, dy = dy, dx
        xx, xy, yx, yy = 0, ysign, xsign, 0
    d = 2 * dy - dx
    y = 0
    for x in range(dx + 1):
        yield x0 + x * xx + y * yx, y0 + x * xy + y * yy
        if d >= 0:
            y += 1
            d -= 2 * dx
        d += 2 * dy


def reference_bresenham_prune(grid, path):
    def clear(a, b):
        return all(
            0 <= r < grid.shape[0] and 0 <= c < grid.shape[1] and grid[r, c] == 0
            for r, c in bresenham_cells(a[0], a[1], b[0], b[1])
        )

    if len(path) < 3:
        return list(path)
    kept, anchor = [path[0]], 0
    for j in range(2, len(path)):
        if not clear(path[anchor], path[j]):
            anchor = j - 1
            kept.append(path[anchor])
    kept.append(path[-1])
    return kept


def test_bresenham_prune_against_a_reference(colliders):
    grid, north_offset, east_offset = skyplan.create_grid(colliders, 5, 5)
    start = (-north_offset, -east_offset)
    for goal in [(start[0] - 150, start[1] + 300), (start[0] + 420, start[1] + 390)]:
        path, _ = skyplan.a_star(grid, start, goal)
        pruned = skyplan.bresenham_prune(grid, path)
        assert pruned == reference_bresenham_prune(grid, path)
        assert 2 <= len(pruned) < len(skyplan.prune_path(path))
    rng = np.random.default_rng(11)
    for _ in range(40):
        g = random_grid(rng, 20, 20, 0.25)
        free = np.argwhere(g == 0)
        a, b = free[rng.choice(len(free), 2, replace=False)]
        try:
            path, _ = skyplan.a_star(g, tuple(a.tolist()), tuple(b.tolist()))
        except skyplan.NoPath:
            continue
        assert skyplan.bresenham_prune(g, path) == reference_bresenham_prune(g, path)

"""Bad input raises the right exception, never crashes the interpreter."""

import numpy as np
import pytest

import skyplan


def test_exception_classes():
    for cls in (skyplan.InvalidStart, skyplan.InvalidGoal, skyplan.NoPath, skyplan.Timeout,
                skyplan.BadInput):
        assert issubclass(cls, skyplan.PlanError)
    for cls in (skyplan.InvalidStart, skyplan.InvalidGoal, skyplan.BadInput):
        assert issubclass(cls, ValueError)
    assert skyplan.NoPath.kind == "no_path" and skyplan.BadInput.kind == "bad_request"
    assert isinstance(skyplan.__version__, str) and skyplan.__version__.count(".") == 2


@pytest.mark.parametrize(
    "data",
    [
        np.array([["a", "b", "c", "d", "e", "f"]]),
        np.ones((3, 6), dtype=complex),
        np.array([[object()] * 6], dtype=object),
        np.ones(6),
        np.ones((2, 3, 6)),
        np.ones((4, 5)),
        np.ones((0, 6)),
        np.array([[1.0, 2.0, np.nan, 1.0, 1.0, 1.0]]),
        np.array([[1.0, 2.0, 3.0, np.inf, 1.0, 1.0]]),
        "colliders.csv",
    ],
    ids=["str", "complex", "object", "1-D", "3-D", "5 columns", "empty", "NaN", "inf", "path"],
)
def test_create_grid_bad_data(data):
    with pytest.raises(skyplan.BadInput):
        skyplan.create_grid(data, 5, 5)


def test_create_grid_bad_numbers():
    data = np.array([[0.0, 0.0, 5.0, 2.0, 2.0, 5.0]])
    for alt, margin in [(np.nan, 5), (5, float("inf")), ("5", 5), (None, 5)]:
        with pytest.raises(skyplan.BadInput):
            skyplan.create_grid(data, alt, margin)


GRID = np.zeros((5, 6))
GRID[2, 1:5] = 1


@pytest.mark.parametrize(
    "grid",
    [np.zeros((2, 3, 4)), np.zeros(5), np.array([["0", "1"]]), np.zeros((3, 3), dtype=complex),
     np.array([[0.0, np.nan], [0.0, 0.0]])],
    ids=["3-D", "1-D", "str", "complex", "NaN"],
)
def test_a_star_bad_grid(grid):
    with pytest.raises(skyplan.BadInput):
        skyplan.a_star(grid, (0, 0), (1, 1))


def test_a_star_bad_cells():
    with pytest.raises(skyplan.InvalidStart, match="off the 5 × 6 grid"):
        skyplan.a_star(GRID, (-1, 0), (4, 4))
    with pytest.raises(skyplan.InvalidStart):
        skyplan.a_star(GRID, (5, 0), (4, 4))
    with pytest.raises(skyplan.InvalidGoal):
        skyplan.a_star(GRID, (0, 0), (4, 6))
    with pytest.raises(skyplan.InvalidStart, match="blocked"):
        skyplan.a_star(GRID, (2, 2), (4, 4))
    with pytest.raises(skyplan.InvalidGoal, match="blocked"):
        skyplan.a_star(GRID, (0, 0), (2, 3))
    for bad in [(1.5, 2), (np.nan, 0), (0,), (0, 1, 2), "ab", None, (np.float32(1), 1)]:
        with pytest.raises(skyplan.BadInput):
            skyplan.a_star(GRID, bad, (4, 4))
    with pytest.raises(skyplan.BadInput, match="positional"):
        skyplan.a_star(GRID, (0, 0))
    walled = GRID.copy()
    walled[2, :] = 1
    with pytest.raises(skyplan.NoPath):
        skyplan.a_star(walled, (0, 0), (4, 4))


def test_prune_bad_points():
    with pytest.raises(skyplan.BadInput):
        skyplan.prune_path([(0, 0), (1, float("nan")), (2, 2)])
    with pytest.raises(skyplan.BadInput):
        skyplan.prune_path(5)
    with pytest.raises(skyplan.BadInput):
        skyplan.bresenham_prune(GRID, [(0, 0), (0.5, 1), (0, 2)])


@pytest.fixture(scope="module")
def city():
    return skyplan.Planner()


def test_planner_bad_requests(city):
    with pytest.raises(skyplan.BadInput, match="finite"):
        city.plan((np.nan, 0.0))
    with pytest.raises(skyplan.InvalidStart):
        city.plan((5000.0, 0.0))
    with pytest.raises(skyplan.InvalidGoal):
        city.plan(goal=(0.0, 5000.0))
    with pytest.raises(skyplan.BadInput, match="unknown field `safty_m`"):
        city.plan(safty_m=3)
    with pytest.raises(skyplan.BadInput, match="unknown planner"):
        city.plan(planner="nope")
    with pytest.raises(skyplan.BadInput, match="alt_m -5"):
        city.plan(alt_m=-5)
    with pytest.raises(skyplan.BadInput, match="goal_alt_m is not used by planner jps"):
        city.plan(goal_alt_m=30)
    with pytest.raises(skyplan.BadInput, match="given twice"):
        city.plan((0.0, 0.0), start_ne=(1.0, 1.0))
    with pytest.raises(skyplan.BadInput):
        city.plan(start_lla=(37.79, -122.39), start_ne=(0.0, 0.0))
    with pytest.raises(skyplan.BadInput):
        city.plan((1.0, 2.0, 3.0))
    with pytest.raises(skyplan.BadInput):
        city.plan(alt_m=float("nan"))
    with pytest.raises(skyplan.BadInput):
        city.plan(alt_m=object())


def test_planner_start_inside_a_building(city):
    # The home is free; a building's footprint a few metres away is not.
    with pytest.raises((skyplan.InvalidStart,)) as info:
        city.plan((-10.0, 85.0), alt_m=5, safety_m=5, planner="astar")
    assert "start" in str(info.value)


def test_planner_timeout(city):
    with pytest.raises(skyplan.Timeout):
        city.plan(planner="rrt-connect", goal_ne=(420.0, 390.0), time_limit_ms=1,
                  start_alt_m=5, goal_alt_m=5, max_alt_m=6)


def test_planner_bad_maps(tmp_path):
    with pytest.raises(FileNotFoundError):
        skyplan.Planner(str(tmp_path / "missing.csv"))
    with pytest.raises(skyplan.BadInput, match="unknown map type"):
        skyplan.Planner(tmp_path / "map.txt")
    (tmp_path / "broken.csv").write_text("lat0 x, lon0 y\nnope\n")
    with pytest.raises(skyplan.BadInput):
        skyplan.Planner(tmp_path / "broken.csv")
    with pytest.raises(skyplan.BadInput):
        skyplan.Planner(np.zeros((3, 3, 3)))
    with pytest.raises(skyplan.BadInput):
        skyplan.Planner(np.array([[0.0, np.nan]]))
    with pytest.raises(skyplan.BadInput):
        skyplan.Planner(np.zeros((3, 3)), cell_m=0)
    with pytest.raises(skyplan.BadInput, match="origin_ne"):
        skyplan.Planner(origin_ne=(1, 2))
    with pytest.raises(skyplan.BadInput, match="own home"):
        skyplan.Planner(home=(37.0, -122.0))
    grid_planner = skyplan.Planner(np.zeros((4, 4)))
    with pytest.raises(skyplan.BadInput, match="missing start"):
        grid_planner.plan()
    # Planners that need a colliders map refuse a grid: test_planner.py checks every one.

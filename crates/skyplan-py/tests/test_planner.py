"""Planner.plan against the CLI (`skyplan plan --json`), every planner, files, maps."""

import json

import numpy as np
import pytest
from conftest import COLLIDERS, MOVINGAI, run_cli

import skyplan


@pytest.fixture(scope="module")
def city():
    return skyplan.Planner()


def cli_plan(cli, tmp_path, *args):
    out = tmp_path / "cli.json"
    text = run_cli(cli, "plan", "--json", "--out", str(out), *args, cwd=tmp_path)
    return json.loads(text), out


REQUESTS = [
    ({}, []),
    ({"planner": "astar", "goal_ne": (-191.5, 319.5), "alt_m": 10, "safety_m": 3},
     ["--planner", "astar", "--goal-ne=-191.5,319.5", "--alt-m", "10", "--safety-m", "3"]),
    ({"planner": "theta", "start_ne": (12.5, -40.0), "goal_ne": (298.5, -160.5)},
     ["--planner", "theta", "--start-ne=12.5,-40", "--goal-ne", "298.5,-160.5"]),
    ({"planner": "jps-plus", "connectivity": 4}, ["--planner", "jps-plus", "--connectivity", "4"]),
    ({"planner": "rrt-connect", "goal_alt_m": 30, "seed": 7},
     ["--planner", "rrt-connect", "--goal-alt-m", "30", "--seed", "7"]),
    ({"planner": "voronoi", "goal_lla": (37.79518, -122.39925)},
     ["--planner", "voronoi", "--goal-lla", "37.79518,-122.39925"]),
    ({"planner": "wavefront", "cell_m": 2}, ["--planner", "wavefront", "--cell-m", "2"]),
]


@pytest.mark.parametrize("options,args", REQUESTS, ids=lambda v: str(v)[:40])
def test_plan_equals_the_cli(city, cli, tmp_path, options, args):
    want, out = cli_plan(cli, tmp_path, *args)
    plan = city.plan(**options)
    assert np.array_equal(plan.waypoints, np.array(want["waypoints"], dtype=np.float64))
    assert np.array_equal(plan.lla, np.array(want["waypoints_lla"]))
    assert plan.cost_m == want["cost_m"]
    assert plan.planner == want["planner"]
    stats = plan.stats
    for key in ("map", "start", "goal", "expansions", "mission_length_m", "grid", "path_cells"):
        assert stats.get(key) == want.get(key), key
    # The waypoint file is the CLI's, byte for byte.
    mine = tmp_path / "mine.json"
    plan.to_file(mine)
    assert mine.read_bytes() == out.read_bytes()


def test_positional_start_goal_are_north_east(city, cli, tmp_path):
    want, _ = cli_plan(cli, tmp_path, "--start-ne=-101.5,21.5", "--goal-ne", "250,-300")
    plan = city.plan((-101.5, 21.5), (250, -300))
    assert np.array_equal(plan.waypoints, np.array(want["waypoints"]))


def test_plan_object(city, tmp_path):
    plan = city.plan()
    w = plan.waypoints
    assert w.dtype == np.float64 and w.ndim == 2 and w.shape[1] == 4 and len(plan) == len(w)
    assert tuple(w[0, :2]) == (0.0, 0.0) and tuple(w[-1, :2]) == (420.0, 390.0)
    assert np.all(w[:, 2] == 5.0)
    assert plan.lla.shape == (len(w), 2)
    assert "waypoints" not in plan.stats and plan.stats["status"] == "ok"
    assert json.loads(plan.to_json())["waypoints"] == w.tolist()
    for ext in ("json", "csv", "h5", "geojson", "plan"):
        path = tmp_path / f"route.{ext}"
        plan.to_file(path)
        assert path.stat().st_size > 0
    lines = (tmp_path / "route.csv").read_text().splitlines()
    assert lines[0] == "north_m,east_m,alt_m,heading_rad,lat_deg,lon_deg"
    assert len(lines) == len(w) + 1
    plan.to_file(str(tmp_path / "route.txt"), format="geojson")
    assert json.loads((tmp_path / "route.txt").read_text())["type"] == "FeatureCollection"
    with pytest.raises(skyplan.BadInput, match="extension"):
        plan.to_file(tmp_path / "route.kml")
    assert "cost_m=" in repr(plan)


def test_every_planner_is_reachable(city):
    names = [p["name"] for p in skyplan.planners()]
    assert sorted(names) == sorted([
        "jps", "jps-plus", "ch", "astar", "dijkstra", "theta", "any-angle", "wavefront", "costmap",
        "voronoi", "prm", "lazy-prm", "rrt-connect", "rrt-star", "voxel",
    ])
    for name in names:
        options = {"planner": name, "goal_ne": (60.0, 40.0)}
        if name in ("prm", "lazy-prm", "rrt-connect", "rrt-star", "voxel"):
            options["time_limit_ms"] = 2000
        plan = city.plan(**options)
        assert plan.planner == name
        assert tuple(plan.waypoints[-1, :2]) == (60.0, 40.0)
        assert plan.cost_m >= np.hypot(60.0, 40.0) - 1e-9


def test_movingai_map_equals_the_cli(cli, tmp_path):
    path = MOVINGAI / "den312d.map"
    planner = skyplan.Planner(str(path))
    assert planner.kind == "moving_ai"
    text = run_cli(
        cli, "plan", "--map", str(path), "--start-ne", "10.5,20.5", "--goal-ne", "61.5,58.5",
        "--json", cwd=tmp_path,
    )
    want = json.loads(text)
    plan = planner.plan((10.5, 20.5), (61.5, 58.5))
    assert np.array_equal(plan.waypoints, np.array(want["waypoints"]))
    assert plan.lla is None
    with pytest.raises(skyplan.BadInput, match="geodetic home"):
        plan.to_file(tmp_path / "x.json")
    homed = skyplan.Planner(path, home=(37.79, -122.39)).plan((10.5, 20.5), (61.5, 58.5))
    assert homed.lla.shape == (len(homed), 2)


def test_colliders_file_and_numpy_grid(colliders):
    from_file = skyplan.Planner(COLLIDERS)
    assert from_file.kind == "colliders"
    # The same boxes as the bundled map; a file has no default goal.
    assert np.array_equal(
        from_file.plan(goal=(420.0, 390.0)).waypoints, skyplan.Planner().plan().waypoints
    )
    # A numpy grid placed as FCND's grid: row = north - north_offset.
    grid, north_offset, east_offset = skyplan.create_grid(colliders, 5, 5)
    planner = skyplan.Planner(grid, origin_ne=(north_offset, east_offset))
    assert planner.kind == "grid"
    assert planner.bounds_ne == (north_offset, north_offset + 921, east_offset, east_offset + 921)
    plan = planner.plan((0.5, 0.5), (100.5, 100.5), planner="astar")
    path, cost = skyplan.a_star(grid, (-north_offset, -east_offset),
                                (-north_offset + 100, -east_offset + 100), corner_cutting=False)
    assert plan.cost_m == pytest.approx(cost, abs=1e-9)
    for n, e in plan.waypoints[:, :2]:
        assert grid[int(np.floor(n - north_offset)), int(np.floor(e - east_offset))] == 0


def test_small_grid_known_answer():
    grid = np.array([[0, 0, 0, 0, 0], [0, 1, 1, 1, 0], [0, 0, 0, 0, 0]], dtype=bool)
    planner = skyplan.Planner(grid)
    # Row 0 is the southern edge. Without corner cutting: along row 0, six straight moves.
    assert planner.plan((1.5, 0.5), (1.5, 4.5), planner="dijkstra").cost_m == 6.0
    # With it: two diagonals past the wall's ends and two straight moves.
    cut = planner.plan((1.5, 0.5), (1.5, 4.5), planner="dijkstra", corner_cutting=True)
    assert cut.cost_m == pytest.approx(2 + 2 * np.sqrt(2))


def test_jps_plus_table_is_kept_between_calls(city):
    """The session keeps the JPS+ table: only the first call on a grid builds it."""
    first = city.plan(planner="jps-plus", goal_ne=(60.0, 40.0))
    second = city.plan(planner="jps-plus")
    jps = city.plan(planner="jps")
    assert first.stats["jps_plus_table"] in ("built", "reused")
    assert second.stats["jps_plus_table"] == "reused"
    assert second.cost_m == jps.cost_m

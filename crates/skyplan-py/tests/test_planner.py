"""Planner.plan against the CLI (`skyplan plan --json`), every planner, files, maps.

Planners are taken from the registry (`skyplan.planners()`) and chosen by its predicates, never
from a list typed here: a new planner is tested without editing this file.
"""

import json
import re

import numpy as np
import pytest
from conftest import COLLIDERS, MOVINGAI, REPO, dijkstra_cost, run_cli

import skyplan

PLANNERS = skyplan.planners()


def by_name(row):
    return row["name"]


def first(**where):
    """The first registry row whose fields equal `where` (e.g. a deterministic 3D planner)."""
    return next(p for p in PLANNERS if all(p[k] == v for k, v in where.items()))


@pytest.fixture(scope="module")
def city():
    return skyplan.Planner()


def cli_plan(cli, tmp_path, *args):
    out = tmp_path / "cli.json"
    text = run_cli(cli, "plan", "--json", "--out", str(out), *args, cwd=tmp_path)
    return json.loads(text), out


# Option spellings (the planner is the default unless the options need a 3D one); every
# planner is compared with the CLI in test_every_planner_equals_the_cli.
THREE_D = first(dims=3, optimality="feasible")["name"]
REQUESTS = [
    ({}, []),
    ({"goal_ne": (-191.5, 319.5), "alt_m": 10, "safety_m": 3},
     ["--goal-ne=-191.5,319.5", "--alt-m", "10", "--safety-m", "3"]),
    ({"start_ne": (12.5, -40.0), "goal_ne": (298.5, -160.5)},
     ["--start-ne=12.5,-40", "--goal-ne", "298.5,-160.5"]),
    ({"connectivity": 4}, ["--connectivity", "4"]),
    ({"planner": THREE_D, "goal_alt_m": 30, "seed": 7},
     ["--planner", THREE_D, "--goal-alt-m", "30", "--seed", "7"]),
    ({"goal_lla": (37.79518, -122.39925)}, ["--goal-lla", "37.79518,-122.39925"]),
    ({"cell_m": 2}, ["--cell-m", "2"]),
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


def test_trajectory_samples_are_the_clis_csv(city, cli, tmp_path):
    """trajectory=True gives the samples as an (n, 11) array, equal to the CLI's --samples CSV."""
    assert city.plan().trajectory is None
    out = tmp_path / "traj.csv"
    # A route that turns (on one straight leg, stopping at its ends is the faster trajectory).
    run_cli(cli, "plan", "--trajectory", "--goal-ne=120,-61", "--samples", str(out),
            "--out", str(tmp_path / "w.json"), cwd=tmp_path)
    want = np.loadtxt(out, delimiter=",", skiprows=1)
    plan = city.plan(goal_ne=(120, -61), trajectory=True, max_speed_m_s=10.0)
    got = plan.trajectory
    assert got.dtype == np.float64 and got.shape == want.shape and got.shape[1] == 11
    np.testing.assert_allclose(got[:, 1:10], want[:, 1:10], rtol=0, atol=1e-9)
    assert np.all(np.linalg.norm(got[:, 4:7], axis=1) <= 10.0 + 1e-9)
    stats = plan.stats["trajectory"]
    assert stats["method"] == "minimum_jerk" and "samples" not in stats
    assert stats["bounds"]["speed_m_s"] <= 10.0 + 1e-9
    with pytest.raises(skyplan.BadInput, match="max_speed_m_s is used only with a trajectory"):
        city.plan(max_speed_m_s=3.0)


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


def test_planners_are_the_clis(cli, tmp_path):
    """skyplan.planners() is the registry the CLI offers: its `plan --planner` values, in order,
    with the same summaries; names are unique and every row carries its predicates."""
    text = run_cli(cli, "plan", "--help", cwd=tmp_path)
    values = text.split("--planner <PLANNER>", 1)[1].split("Possible values:", 1)[1]
    offered = []
    for line in values.splitlines()[1:]:
        found = re.match(r"\s+- ([a-z0-9-]+):\s+(.*)$", line)
        if not found:
            break
        offered.append((found[1], found[2].strip()))
    assert offered == [(p["name"], p["summary"]) for p in PLANNERS]
    assert len({p["name"] for p in PLANNERS}) == len(PLANNERS)
    for p in PLANNERS:
        assert list(p) == [
            "name", "label", "dims", "optimality", "maps", "summary",
            "exact", "grid_path", "needs_obstacles",
        ]
        assert p["dims"] in (2, 3) and p["label"]
        assert p["exact"] == (p["optimality"] == "exact")
        assert p["needs_obstacles"] == (p["maps"] == "obstacles")
        assert isinstance(p["grid_path"], bool)


@pytest.fixture(scope="module")
def den312d():
    return skyplan.Planner(MOVINGAI / "den312d.map")


@pytest.mark.parametrize("row", PLANNERS, ids=by_name)
def test_every_planner_equals_the_cli(city, den312d, cli, tmp_path, row):
    """Each planner on a map it takes: the bundled city for those that need obstacles, a MovingAI
    map (small: planners that preprocess the grid stay quick) for the others."""
    name = row["name"]
    if row["needs_obstacles"]:
        planner, start, goal, map_args = city, (0.0, 0.0), (60.0, 40.0), []
    else:
        path = MOVINGAI / "den312d.map"
        planner, start, goal, map_args = den312d, (10.5, 20.5), (61.5, 58.5), ["--map", str(path)]
    options = {"planner": name, "start_ne": start, "goal_ne": goal}
    args = [*map_args, "--planner", name, "--start-ne=%r,%r" % start, "--goal-ne=%r,%r" % goal]
    if row["dims"] == 3:
        options["time_limit_ms"] = 2000
        args += ["--time-limit-ms", "2000"]
    text = run_cli(cli, "plan", "--json", *args, cwd=tmp_path)
    want = json.loads(text)
    plan = planner.plan(**options)
    straight = np.hypot(goal[0] - start[0], goal[1] - start[1])
    assert plan.planner == want["planner"] == name
    assert tuple(plan.waypoints[0, :2]) == start and tuple(plan.waypoints[-1, :2]) == goal
    assert plan.cost_m >= straight - 1e-9
    if row["optimality"] == "asymptotically_optimal":
        # It improves its route until the time limit: the clock decides where it stops.
        assert want["cost_m"] >= straight - 1e-9
    else:
        assert np.array_equal(plan.waypoints, np.array(want["waypoints"]))
        assert plan.cost_m == want["cost_m"]


@pytest.fixture(scope="module")
def maze():
    """A random 40 x 50 occupancy grid, two far free cells, and Dijkstra's cost between them
    (8-connected, no corner cutting: the planners' default move model on a numpy grid)."""
    rng = np.random.default_rng(11)
    grid = (rng.random((40, 50)) < 0.25).astype(np.float64)
    start, goal = (1, 1), (38, 47)
    grid[start] = grid[goal] = 0
    want = dijkstra_cost(grid, start, goal, diagonal=True, corner_cutting=False)
    assert want is not None and want > 40
    return grid, start, goal, want


def test_registry_predicates_hold_on_a_grid(maze):
    """What each row's predicates promise, checked on a numpy grid against Dijkstra: `exact`
    planners find its cost; `grid_path` ones take the grid-path options (and, unless any-angle,
    never beat Dijkstra); exact any-angle ones are the shortest of all; `needs_obstacles` ones
    refuse the grid."""
    grid, start, goal, want = maze
    planner = skyplan.Planner(grid)
    ends = [(start[0] + 0.5, start[1] + 0.5), (goal[0] + 0.5, goal[1] + 0.5)]
    straight = np.hypot(goal[0] - start[0], goal[1] - start[1])
    costs = {}
    for row in PLANNERS:
        name = row["name"]
        if row["needs_obstacles"]:
            with pytest.raises(skyplan.BadInput, match="map of obstacles"):
                planner.plan(*ends, planner=name)
            continue
        plan = planner.plan(*ends, planner=name)
        costs[name] = plan.cost_m
        for n, e in plan.waypoints[:, :2]:
            assert grid[int(np.floor(n)), int(np.floor(e))] == 0, name
        assert plan.cost_m >= straight - 1e-9, name
        if row["exact"]:
            assert plan.cost_m == pytest.approx(want, abs=1e-9), name
        any_angle = row["optimality"] in ("any_angle", "exact_any_angle")
        if row["grid_path"]:
            four = planner.plan(*ends, planner=name, connectivity=4)
            if not any_angle:  # a path of grid moves: never shorter than Dijkstra's
                assert plan.cost_m >= want - 1e-9, name
                assert four.cost_m >= plan.cost_m - 1e-9, name
        else:
            with pytest.raises(skyplan.BadInput, match=f"connectivity is not used by planner {name}"):
                planner.plan(*ends, planner=name, connectivity=4)
    assert costs, "no planner takes a numpy grid"
    for row in PLANNERS:
        if row["optimality"] == "exact_any_angle":
            assert costs[row["name"]] <= min(costs.values()) + 1e-9
            assert costs[row["name"]] <= want + 1e-9


@pytest.mark.parametrize("row", PLANNERS, ids=by_name)
def test_altitude_options_are_for_3d_planners(city, row):
    """`dims`: only 3D planners take a goal altitude; 2D ones refuse it by name."""
    if row["dims"] == 3:
        plan = city.plan(planner=row["name"], goal_ne=(60.0, 40.0), goal_alt_m=20, time_limit_ms=2000)
        assert plan.waypoints[-1, 2] == 20.0
    else:
        with pytest.raises(skyplan.BadInput, match=f"goal_alt_m is not used by planner {row['name']}"):
            city.plan(planner=row["name"], goal_alt_m=20)


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


@pytest.mark.parametrize("row", [p for p in PLANNERS if p["exact"]], ids=by_name)
def test_small_grid_known_answer(row):
    grid = np.array([[0, 0, 0, 0, 0], [0, 1, 1, 1, 0], [0, 0, 0, 0, 0]], dtype=bool)
    planner = skyplan.Planner(grid)
    name = row["name"]
    # Row 0 is the southern edge. Without corner cutting: along row 0, six straight moves.
    assert planner.plan((1.5, 0.5), (1.5, 4.5), planner=name).cost_m == 6.0
    # With it: two diagonals past the wall's ends and two straight moves.
    cut = planner.plan((1.5, 0.5), (1.5, 4.5), planner=name, corner_cutting=True)
    assert cut.cost_m == pytest.approx(2 + 2 * np.sqrt(2))


def test_jps_plus_table_is_kept_between_calls(city):
    """The session keeps the JPS+ table: only the first call on a grid builds it."""
    first = city.plan(planner="jps-plus", goal_ne=(60.0, 40.0))
    second = city.plan(planner="jps-plus")
    jps = city.plan(planner="jps")
    assert first.stats["jps_plus_table"] in ("built", "reused")
    assert second.stats["jps_plus_table"] == "reused"
    assert second.cost_m == jps.cost_m


def test_terrain_equals_the_cli(cli, tmp_path):
    """A numpy grid on the bundled DEM: the route keeps 30 m above the ground like the CLI's
    (the CLI's own test checks the clearance against rasterio), lla gains heights above sea
    level, and alt_agl_m without terrain is refused."""
    dem = REPO / "data" / "terrain" / "jacksboro.tif"
    grid = np.zeros((300, 300), dtype=np.uint8)
    grid[100:200, 140:160] = 1
    planner = skyplan.Planner(grid, home=(36.56, -84.28), terrain=dem)
    plan = planner.plan((10.5, 10.5), (290.5, 280.5), alt_agl_m=30)
    assert plan.lla.shape == (len(plan), 3)
    np.save(tmp_path / "grid.npy", grid)
    img = tmp_path / "grid.pgm"
    # The same grid as an image for the CLI: row 0 of an image is its northern edge.
    pixels = np.where(grid[::-1] > 0, 0, 254).astype(np.uint8)
    img.write_bytes(b"P5\n300 300\n255\n" + pixels.tobytes())
    text = run_cli(
        cli, "plan", "--map", str(img), "--resolution", "1", "--home", "36.56,-84.28",
        "--terrain", str(dem), "--alt-agl-m", "30", "--start-ne", "10.5,10.5",
        "--goal-ne", "290.5,280.5", "--json", cwd=tmp_path,
    )
    want = json.loads(text)
    assert np.allclose(plan.waypoints, np.array(want["waypoints"]), atol=1e-9)
    assert np.allclose(plan.lla, np.array(want["waypoints_lla"]), atol=1e-9)
    assert want["terrain"]["alt_agl_m"] == 30
    with pytest.raises(skyplan.BadInput, match="alt_agl_m"):
        skyplan.Planner(grid, home=(36.56, -84.28)).plan((10.5, 10.5), (290.5, 280.5), alt_agl_m=30)
    with pytest.raises(skyplan.BadInput, match="does not cover"):
        skyplan.Planner(grid, home=(37.79, -122.39), terrain=dem)
    # A file too big for any DEM it can hold is refused from its size (a sparse file).
    big = tmp_path / "big.tif"
    with open(big, "wb") as f:
        f.truncate(800_000_001)
    with pytest.raises(skyplan.BadInput, match="more than a DEM"):
        skyplan.Planner(grid, home=(36.56, -84.28), terrain=big)


def test_departure_applies_timed_zones_as_the_cli(city, cli, tmp_path):
    """no_fly and departure as keywords give the CLI's route and its no_fly details: departing
    before the sample helipad closes, it is inactive and flown over; without a departure it
    applies."""
    zones = REPO / "data" / "no-fly-sample.geojson"
    early = "2026-12-03T07:00:00Z"
    want, _ = cli_plan(cli, tmp_path, "--no-fly", str(zones), "--departure", early)
    plan = city.plan(no_fly=zones.read_text(), departure=early)
    assert np.array_equal(plan.waypoints, np.array(want["waypoints"], dtype=np.float64))
    got = json.loads(plan.to_json())["no_fly"]
    assert got == want["no_fly"] and got["outside_window"] == [1]
    always = json.loads(city.plan(no_fly=zones.read_text()).to_json())["no_fly"]
    assert always["outside_window"] == [] and always["timed_always"] == [1]
    with pytest.raises(skyplan.BadInput, match="departure"):
        city.plan(no_fly=zones.read_text(), departure="tomorrow")

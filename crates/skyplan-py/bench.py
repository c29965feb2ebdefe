"""Per-query times on the FCND city: skyplan from Python, the CLI, and FCND's own A*.

    python crates/skyplan-py/bench.py [--runs 20] [--fcnd-runs 3] [--cli target/release/skyplan]
        [--planners jps,astar]

Planner.plan is timed with every exact grid planner of the registry (skyplan.planners() rows
with `exact` and `grid_path`), or the ones --planners names.

The query is FCND's: the home cell to the city's default goal (420 m north, 390 m east) at 5 m
altitude with a 5 m margin. FCND's create_grid and a_star are reproduced in
tests/fcnd_reference.py from FCND's planning_utils.py (A* with diagonal moves and the Euclidean
heuristic), in plain Python.
"""

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import skyplan

REPO = Path(__file__).resolve().parents[2]
# FCND's create_grid and a_star: the same reproduction the tests compare skyplan with.
sys.path.insert(0, str(Path(__file__).resolve().parent / "tests"))
from fcnd_reference import fcnd_a_star, fcnd_create_grid  # noqa: E402


def heuristic(position, goal_position):
    return np.linalg.norm(np.array(position) - np.array(goal_position))


def median_ms(fn, runs):
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        fn()
        times.append((time.perf_counter() - t0) * 1000)
    return statistics.median(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--fcnd-runs", type=int, default=3)
    ap.add_argument("--cli", default=str(REPO / "target" / "release" / "skyplan"))
    ap.add_argument(
        "--planners",
        help="comma-separated planner names [default: every exact grid planner of skyplan.planners()]",
    )
    args = ap.parse_args()

    data = np.loadtxt(REPO / "data" / "colliders.csv", delimiter=",", dtype="float64", skiprows=2)
    grid, n0, e0 = skyplan.create_grid(data, 5, 5)
    start = (-n0, -e0)
    goal = (start[0] + 420, start[1] + 390)
    rows = []

    rows.append(("create_grid, skyplan", median_ms(lambda: skyplan.create_grid(data, 5, 5), args.runs), ""))
    rows.append(("create_grid, FCND (numpy)", median_ms(lambda: fcnd_create_grid(data, 5, 5), 3), ""))

    _, cost = skyplan.a_star(grid, heuristic, start, goal)
    rows.append((
        "skyplan.a_star (FCND API, grid → path)",
        median_ms(lambda: skyplan.a_star(grid, heuristic, start, goal), args.runs),
        f"cost {cost:.3f}",
    ))
    planner = skyplan.Planner()
    if args.planners:
        names = args.planners.split(",")
    else:
        names = [p["name"] for p in skyplan.planners() if p["exact"] and p["grid_path"]]
    for name in names:
        planner.plan(planner=name)  # the session's grid and tables, built once
        plan = planner.plan(planner=name)
        rows.append((
            f"Planner.plan(planner={name!r})",
            median_ms(lambda: planner.plan(planner=name), args.runs),
            f"cost {plan.cost_m:.3f} m, search {plan.stats['search_time_us'] / 1000:.2f} ms",
        ))

    cli = Path(args.cli)
    if cli.exists():
        with tempfile.TemporaryDirectory() as tmp:
            def run_cli():
                out = subprocess.run(
                    [str(cli), "plan", "--json", "--out", f"{tmp}/w.json"],
                    capture_output=True, text=True, check=True,
                )
                return json.loads(out.stdout)

            report = run_cli()
            rows.append((
                "CLI `skyplan plan --json` (process)",
                median_ms(run_cli, max(3, args.runs // 2)),
                f"cost {report['cost_m']:.3f} m, in-process total {report['timings_us']['total_us'] / 1000:.2f} ms",
            ))
    else:
        rows.append(("CLI", float("nan"), f"{cli} missing: cargo build --release"))

    fcnd = []
    for _ in range(args.fcnd_runs):
        t0 = time.perf_counter()
        _, fcnd_cost = fcnd_a_star(grid, heuristic, start, goal)
        fcnd.append((time.perf_counter() - t0) * 1000)
    rows.append((
        "FCND a_star (plain Python)",
        statistics.median(fcnd),
        f"cost {fcnd_cost:.3f} ({(fcnd_cost / cost - 1) * 100:+.1f} % vs optimal)",
    ))

    print(f"FCND city, home cell {start} → {goal}, 5 m altitude, 5 m margin (median ms per query)")
    for what, ms, note in rows:
        print(f"  {what:42s} {ms:10.2f} ms  {note}")


if __name__ == "__main__":
    main()

"""The GIL is released while planning: other Python threads run during a plan, and threads
planning at once get the same answers."""

import threading
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

import skyplan

# A CPU-bound query: A* (not JPS) across the city.
REQUEST = {"planner": "astar", "goal_ne": (420.0, 390.0)}
THREADS = 4


def test_threads_planning_at_once_get_the_same_routes():
    planner = skyplan.Planner()
    reference = planner.plan(**REQUEST).waypoints
    with ThreadPoolExecutor(THREADS) as pool:
        outs = list(pool.map(lambda _: planner.plan(**REQUEST).waypoints, range(2 * THREADS)))
    for out in outs:
        assert np.array_equal(out, reference)


def test_other_threads_run_while_a_plan_computes():
    # An anytime planner (the registry's asymptotically optimal one, RRT*) spends its whole
    # time limit (1 s). While it does, this thread keeps looping: the
    # longest gap between two of its iterations stays far below the plan's time. Were the GIL
    # held by the plan, this thread would stall for the whole second. (No speed is measured:
    # the margin is the plan's own length, whatever the machine's load.)
    planner = skyplan.Planner()
    anytime = next(p for p in skyplan.planners() if p["optimality"] == "asymptotically_optimal")
    request = {"planner": anytime["name"], "time_limit_ms": 1000}
    planned_s = []

    def plan():
        t0 = time.perf_counter()
        planner.plan(**request)
        planned_s.append(time.perf_counter() - t0)

    worker = threading.Thread(target=plan)
    longest_gap_s, last = 0.0, time.perf_counter()
    worker.start()
    while worker.is_alive():
        now = time.perf_counter()
        longest_gap_s, last = max(longest_gap_s, now - last), now
    worker.join()
    assert planned_s and planned_s[0] >= 0.9, planned_s
    assert longest_gap_s < 0.5 * planned_s[0], (longest_gap_s, planned_s)


def test_a_star_releases_the_gil_too(colliders):
    grid, n0, e0 = skyplan.create_grid(colliders, 5, 5)
    start, goal = (-n0, -e0), (-n0 + 400, -e0 + 380)
    want = skyplan.a_star(grid, start, goal, diagonal=False)
    with ThreadPoolExecutor(THREADS) as pool:
        outs = list(pool.map(lambda _: skyplan.a_star(grid, start, goal, diagonal=False), range(8)))
    assert all(o == want for o in outs)

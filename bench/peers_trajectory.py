"""Trajectory peers for `skyplan bench --trajectory`: TOPP-RA and ruckig on the same routes.

Usage: python peers_trajectory.py ROUTES.json VMAX AMAX JMAX
ROUTES.json: [[[north_m, east_m, alt_m], ...], ...]. Prints one JSON object per peer and route:
{"peer", "route", "duration_s", "compute_s"} or {"peer", "note"} when a peer is missing.

Both peers take per-axis limits; they get the norm limits divided by sqrt(axes) so that their
speed and acceleration norms stay within the limits (as skyplan's must):
- toppra: time-optimal parametrisation of a cubic spline through the waypoints (chord-length
  parameter), velocity and acceleration limits (no jerk limit; the spline is not checked
  against obstacles);
- ruckig: jerk-limited point-to-point legs from rest to rest, one per route segment (the
  stop-at-each-waypoint profile, along the segments).
"""

import json
import math
import sys
import time


def toppra_duration(points, v, a):
    import numpy as np
    import toppra as ta
    import toppra.algorithm as algo
    import toppra.constraint as constraint

    ta.setup_logging("WARNING")
    pts = np.asarray(points, dtype=float)
    dims = pts.shape[1]
    chords = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    ss = np.concatenate([[0.0], np.cumsum(chords)])
    path = ta.SplineInterpolator(ss, pts)
    vlim = np.tile([-v, v], (dims, 1))
    alim = np.tile([-a, a], (dims, 1))
    instance = algo.TOPPRA(
        [constraint.JointVelocityConstraint(vlim), constraint.JointAccelerationConstraint(alim)],
        path,
        parametrizer="ParametrizeConstAccel",
        gridpt_min_nb_points=max(100, 4 * len(pts)),
    )
    traj = instance.compute_trajectory()
    if traj is None:
        raise RuntimeError("toppra found no parametrisation")
    return float(traj.duration)


def ruckig_duration(points, v, a, j):
    from ruckig import InputParameter, Result, Ruckig, Trajectory

    dims = len(points[0])
    otg = Ruckig(dims)
    total = 0.0
    for p, q in zip(points, points[1:]):
        inp = InputParameter(dims)
        inp.current_position = list(p)
        inp.target_position = list(q)
        inp.max_velocity = [v] * dims
        inp.max_acceleration = [a] * dims
        inp.max_jerk = [j] * dims
        traj = Trajectory(dims)
        if otg.calculate(inp, traj) not in (Result.Working, Result.Finished):
            raise RuntimeError("ruckig refused a leg")
        total += traj.duration
    return total


def main():
    routes_path, vmax, amax, jmax = sys.argv[1], *map(float, sys.argv[2:5])
    with open(routes_path) as f:
        routes = json.load(f)
    for peer, run in (
        ("toppra", lambda pts, s: toppra_duration(pts, vmax / s, amax / s)),
        ("ruckig", lambda pts, s: ruckig_duration(pts, vmax / s, amax / s, jmax / s)),
    ):
        try:
            __import__(peer)
        except ImportError as e:
            print(json.dumps({"peer": peer, "note": f"{peer} is not installed ({e})"}))
            continue
        for k, pts in enumerate(routes):
            planar = all(abs(p[2] - pts[0][2]) < 1e-9 for p in pts)
            pts2 = [p[:2] for p in pts] if planar else pts
            scale = math.sqrt(len(pts2[0]))
            t0 = time.perf_counter()
            try:
                d = run(pts2, scale)
            except Exception as e:  # a peer's failure is a row, not the end of the bench
                print(json.dumps({"peer": peer, "route": k, "note": str(e)}))
                continue
            dt = time.perf_counter() - t0
            print(json.dumps({"peer": peer, "route": k, "duration_s": d, "compute_s": dt}))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""OMPL peers of `skyplan bench --3d`: RRTConnect, PRM and RRT* in R^3 (OMPL 2.x Python wheels).

Usage: peers3d.py PROBLEM.json BUDGET_S
PROBLEM.json: {"boxes": [[minN, minE, minAlt, maxN, maxE, maxAlt], ...] (already grown by the
margin), "bounds": [minN, minE, minAlt, maxN, maxE, maxAlt], "queries": [[sN, sE, sA, gN, gE, gA], ...]}.
Validity is exact point-in-closed-box (touching a grown box is a collision), at OMPL's default
motion resolution. Prints one JSON line per (peer, query): time to first solution (RRT*: the whole
budget), simplified length, and whether every simplified segment passes an exact continuous
segment-box (slab) re-check.
"""
import json
import os
import sys
import time

import numpy as np


def main():
    problem = json.load(open(sys.argv[1]))
    budget_s = float(sys.argv[2])
    try:
        from ompl import base as ob, geometric as og, util as ou
    except Exception as e:  # noqa: BLE001
        for peer in ("ompl-rrtconnect", "ompl-prm", "ompl-rrtstar"):
            print(json.dumps({"peer": peer, "unavailable": f"import ompl: {e}"}), flush=True)
        return
    ou.setLogLevel(ou.LOG_NONE)
    boxes = np.array(problem["boxes"], dtype=float).reshape(-1, 6)
    lo, hi = boxes[:, :3], boxes[:, 3:]
    bmin, bmax = np.array(problem["bounds"][:3]), np.array(problem["bounds"][3:])

    def valid_point(p):
        if np.any(p < bmin) or np.any(p > bmax):
            return False
        return not np.any(np.all((p >= lo) & (p <= hi), axis=1))

    def segment_free(a, b):
        if not (valid_point(a) and valid_point(b)):
            return False
        d = b - a
        with np.errstate(divide="ignore", invalid="ignore"):
            t1 = (lo - a) / d
            t2 = (hi - a) / d
        tmin = np.where(d != 0, np.minimum(t1, t2), -np.inf)
        tmax = np.where(d != 0, np.maximum(t1, t2), np.inf)
        inside = np.all((d != 0) | ((a >= lo) & (a <= hi)), axis=1)
        enter = np.max(np.maximum(tmin, 0.0), axis=1)
        leave = np.min(np.minimum(tmax, 1.0), axis=1)
        return not np.any(inside & (enter <= leave))

    space = ob.RealVectorStateSpace(3)
    rb = ob.RealVectorBounds(3)
    for i in range(3):
        rb.setLow(i, float(bmin[i]))
        rb.setHigh(i, float(bmax[i]))
    space.setBounds(rb)
    peers = [("ompl-rrtconnect", og.RRTConnect), ("ompl-prm", og.PRM), ("ompl-rrtstar", og.RRTstar)]
    for name, cls in peers:
        for k, q in enumerate(problem["queries"]):
            ss = og.SimpleSetup(space)
            ss.setStateValidityChecker(lambda s: bool(valid_point(np.array([s[0], s[1], s[2]]))))
            st, gl = space.allocState(), space.allocState()
            for i in range(3):
                st[i], gl[i] = q[i], q[3 + i]
            ss.setStartAndGoalStates(st, gl)
            ss.setPlanner(cls(ss.getSpaceInformation()))
            t = time.perf_counter()
            solved = ss.solve(budget_s)
            dt = time.perf_counter() - t
            exact = bool(solved) and ss.haveExactSolutionPath()
            rec = {"peer": name, "query": k, "time_s": dt, "solved": exact}
            if exact:
                ss.simplifySolution()
                path = ss.getSolutionPath()
                pts = np.array([[path.getState(i)[j] for j in range(3)] for i in range(path.getStateCount())])
                rec["length_m"] = float(np.sum(np.linalg.norm(np.diff(pts, axis=0), axis=1)))
                rec["recheck_ok"] = all(segment_free(pts[i], pts[i + 1]) for i in range(len(pts) - 1))
            print(json.dumps(rec), flush=True)


if __name__ == "__main__":
    main()
    sys.stdout.flush()
    os._exit(0)  # skip nanobind's leak report at interpreter exit

"""Shared fixtures: the real FCND map, the release CLI, and independent reference algorithms.

The references here are written from FCND's and textbook definitions, in plain Python/numpy,
with no code from skyplan: the tests compare skyplan against them.
"""

import heapq
import math
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
from fcnd_reference import fcnd_create_grid  # noqa: F401 (the tests import it from here)

REPO = Path(__file__).resolve().parents[3]
COLLIDERS = REPO / "data" / "colliders.csv"
MOVINGAI = REPO / "data" / "movingai"


@pytest.fixture(scope="session")
def colliders():
    """The real FCND map as FCND loads it."""
    return np.loadtxt(COLLIDERS, delimiter=",", dtype="float64", skiprows=2)


SQRT2 = math.sqrt(2.0)


def moves(diagonal, corner_cutting):
    """The move set: (d_row, d_col, cost, needs both side cells free)."""
    out = [(-1, 0, 1.0, False), (1, 0, 1.0, False), (0, -1, 1.0, False), (0, 1, 1.0, False)]
    if diagonal:
        for dr in (-1, 1):
            for dc in (-1, 1):
                out.append((dr, dc, SQRT2, not corner_cutting))
    return out


def dijkstra(start, goal, neighbours):
    """Textbook Dijkstra (heapq): `neighbours(r, c)` yields `(nr, nc, cost)`; the cost of the
    cheapest path, None when the goal is unreachable."""
    dist = {start: 0.0}
    heap = [(0.0, start)]
    while heap:
        d, (r, c) = heapq.heappop(heap)
        if (r, c) == goal:
            return d
        if d > dist[(r, c)]:
            continue
        for nr, nc, cost in neighbours(r, c):
            nd = d + cost
            if nd < dist.get((nr, nc), math.inf):
                dist[(nr, nc)] = nd
                heapq.heappush(heap, (nd, (nr, nc)))
    return None


def dijkstra_cost(grid, start, goal, diagonal=True, corner_cutting=True):
    """Textbook Dijkstra (heapq) over free cells (grid == 0); None when unreachable."""
    rows, cols = grid.shape
    blocked = grid != 0

    def free(r, c):
        return 0 <= r < rows and 0 <= c < cols and not blocked[r, c]

    if not free(*start) or not free(*goal):
        return None
    steps = moves(diagonal, corner_cutting)

    def neighbours(r, c):
        for dr, dc, cost, sides in steps:
            nr, nc = r + dr, c + dc
            if not free(nr, nc):
                continue
            if sides and not (free(r + dr, c) and free(r, c + dc)):
                continue
            yield nr, nc, cost

    return dijkstra(start, goal, neighbours)


def path_cost_checked(grid, path, diagonal=True, corner_cutting=True):
    """The length of a cell path, asserting every cell free and every step a legal move."""
    rows, cols = grid.shape
    allowed = {(dr, dc): (cost, sides) for dr, dc, cost, sides in moves(diagonal, corner_cutting)}
    total = 0.0
    for r, c in path:
        assert 0 <= r < rows and 0 <= c < cols and grid[r, c] == 0, (r, c)
    for (r0, c0), (r1, c1) in zip(path, path[1:]):
        step = (r1 - r0, c1 - c0)
        assert step in allowed, f"illegal move {step}"
        cost, sides = allowed[step]
        if sides:
            assert grid[r0 + step[0], c0] == 0 and grid[r0, c0 + step[1]] == 0, "cut corner"
        total += cost
    return total


def random_grid(rng, rows, cols, density):
    return (rng.random((rows, cols)) < density).astype(np.float64)


@pytest.fixture(scope="session")
def cli():
    """The release CLI (built by ci.sh, or `cargo build --release` in the repository)."""
    path = Path(os.environ.get("SKYPLAN_CLI", REPO / "target" / "release" / "skyplan"))
    if not path.exists():
        pytest.fail(f"{path} is missing: build it with `cargo build --release` (ci.sh does)")
    return path


def run_cli(cli, *args, cwd):
    out = subprocess.run(
        [str(cli), *args], cwd=cwd, capture_output=True, text=True, timeout=300, check=False
    )
    assert out.returncode == 0, out.stderr
    return out.stdout

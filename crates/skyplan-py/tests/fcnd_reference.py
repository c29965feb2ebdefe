"""FCND's own create_grid and a_star, reproduced from FCND's planning_utils.py in plain
Python/numpy with no code from skyplan: the tests compare skyplan against them, and bench.py
times them."""

import math
from queue import PriorityQueue

import numpy as np


def fcnd_create_grid(data, drone_altitude, safety_distance):
    """FCND's create_grid, in plain numpy, as planning_utils.py defines it."""
    north_min = np.floor(np.min(data[:, 0] - data[:, 3]))
    north_max = np.ceil(np.max(data[:, 0] + data[:, 3]))
    east_min = np.floor(np.min(data[:, 1] - data[:, 4]))
    east_max = np.ceil(np.max(data[:, 1] + data[:, 4]))
    north_size = int(np.ceil(north_max - north_min))
    east_size = int(np.ceil(east_max - east_min))
    grid = np.zeros((north_size, east_size))
    for i in range(data.shape[0]):
        north, east, alt, d_north, d_east, d_alt = data[i, :]
        if alt + d_alt + safety_distance > drone_altitude:
            rows = (
                int(np.clip(north - d_north - safety_distance - north_min, 0, north_size - 1)),
                int(np.clip(north + d_north + safety_distance - north_min, 0, north_size - 1)),
            )
            cols = (
                int(np.clip(east - d_east - safety_distance - east_min, 0, east_size - 1)),
                int(np.clip(east + d_east + safety_distance - east_min, 0, east_size - 1)),
            )
            grid[rows[0] : rows[1] + 1, cols[0] : cols[1] + 1] = 1
    return grid, int(north_min), int(east_min)


# FCND's Action order: WEST, EAST, NORTH, SOUTH, then the diagonals.
FCND_ACTIONS = [(0, -1, 1), (0, 1, 1), (-1, 0, 1), (1, 0, 1)] + [
    (dr, dc, math.sqrt(2)) for dr in (-1, 1) for dc in (-1, 1)
]


def fcnd_a_star(grid, h, start, goal):
    """FCND's a_star (planning_utils.py, diagonal version: target on the grid and not 1):
    visited on push, so not optimal. Returns (path, cost), or ([], 0) when the goal is not found."""
    n, m = grid.shape[0] - 1, grid.shape[1] - 1
    queue = PriorityQueue()
    queue.put((0, start))
    visited = {start}
    branch = {}
    found = False
    while not queue.empty():
        current = queue.get()[1]
        current_cost = 0.0 if current == start else branch[current][0]
        if current == goal:
            found = True
            break
        for dr, dc, cost in FCND_ACTIONS:
            x, y = current[0] + dr, current[1] + dc
            if x < 0 or x > n or y < 0 or y > m or grid[x, y] == 1:
                continue
            nxt = (x, y)
            branch_cost = current_cost + cost
            if nxt not in visited:
                visited.add(nxt)
                branch[nxt] = (branch_cost, current)
                queue.put((branch_cost + h(nxt, goal), nxt))
    if not found:
        return [], 0
    path, node = [goal], goal
    while branch[node][1] != start:
        node = branch[node][1]
        path.append(node)
    path.append(start)
    return path[::-1], branch[goal][0]

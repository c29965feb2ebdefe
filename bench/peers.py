"""Python peers for `skyplan bench --peers`: the grid planners people use instead of skyplan.

Usage: python peers.py GRID.bin ROWS COLS QUERIES.json MODEL BUDGET_S
  GRID.bin      rows*cols bytes, row-major, 1 = blocked
  QUERIES.json  [[start_row, start_col, goal_row, goal_col], ...]
  MODEL         "octile" (no corner cutting) or "octile-cc" (corner cutting)
  BUDGET_S      wall-clock budget per peer; a peer stops after the query that exceeds it

Prints one JSON object per line: {"peer", "query", "time_s", "cost"} or {"peer", "unavailable"}.
Costs are octile lengths (orthogonal 1, diagonal sqrt 2) of the returned cell paths, so every
peer is measured with the same ruler, whatever it optimises internally. Set up with
bench/setup-peers.sh (numpy, pyastar2d, pathfinding in bench/.venv).
"""

import heapq
import json
import math
import sys
import time
from queue import PriorityQueue

SQRT2 = math.sqrt(2.0)
MOVES = [(1, 0, 1.0), (-1, 0, 1.0), (0, 1, 1.0), (0, -1, 1.0),
         (1, 1, SQRT2), (1, -1, SQRT2), (-1, 1, SQRT2), (-1, -1, SQRT2)]


def octile_length(path):
    total = 0.0
    for (r0, c0), (r1, c1) in zip(path, path[1:]):
        total += SQRT2 if (r0 != r1 and c0 != c1) else 1.0
    return total


def make_free(blocked, rows, cols):
    def free(r, c):
        return 0 <= r < rows and 0 <= c < cols and not blocked[r * cols + c]
    return free


def moves_from(free, r, c, corner_cutting):
    for dr, dc, cost in MOVES:
        nr, nc = r + dr, c + dc
        if not free(nr, nc):
            continue
        if dr and dc and not corner_cutting and not (free(r + dr, c) and free(r, c + dc)):
            continue
        yield nr, nc, cost


def octile_h(r, c, gr, gc):
    dr, dc = abs(r - gr), abs(c - gc)
    return (max(dr, dc) - min(dr, dc)) + SQRT2 * min(dr, dc)


def textbook_astar(blocked, rows, cols, start, goal, corner_cutting):
    """Textbook A* with heapq, a g-score dict and a closed set (optimal)."""
    free = make_free(blocked, rows, cols)
    gr, gc = goal
    g = {start: 0.0}
    parent = {start: None}
    closed = set()
    heap = [(octile_h(*start, gr, gc), 0.0, start)]
    while heap:
        _, gcur, cur = heapq.heappop(heap)
        if cur in closed:
            continue
        if cur == goal:
            path = []
            while cur is not None:
                path.append(cur)
                cur = parent[cur]
            return path[::-1]
        closed.add(cur)
        for nr, nc, cost in moves_from(free, cur[0], cur[1], corner_cutting):
            nxt = (nr, nc)
            ng = gcur + cost
            if nxt not in closed and ng < g.get(nxt, math.inf):
                g[nxt] = ng
                parent[nxt] = cur
                heapq.heappush(heap, (ng + octile_h(nr, nc, gr, gc), ng, nxt))
    return None


def fcnd_astar(blocked, rows, cols, start, goal, corner_cutting):
    """The FCND starter code's A*: PriorityQueue, nodes marked visited when pushed (so the first,
    not the best, route to a node wins), Euclidean heuristic."""
    free = make_free(blocked, rows, cols)
    queue = PriorityQueue()
    queue.put((0.0, start))
    visited = {start}
    branch = {}
    found = False
    while not queue.empty():
        item = queue.get()
        current_node = item[1]
        current_cost = 0.0 if current_node == start else branch[current_node][0]
        if current_node == goal:
            found = True
            break
        for nr, nc, cost in moves_from(free, current_node[0], current_node[1], corner_cutting):
            next_node = (nr, nc)
            branch_cost = current_cost + cost
            queue_cost = branch_cost + math.hypot(nr - goal[0], nc - goal[1])
            if next_node not in visited:
                visited.add(next_node)
                branch[next_node] = (branch_cost, current_node)
                queue.put((queue_cost, next_node))
    if not found:
        return None
    path = [goal]
    n = goal
    while branch[n][1] != start:
        n = branch[n][1]
        path.append(n)
    path.append(start)
    return path[::-1]


def pyastar2d_peer(weights, start, goal, corner_cutting):
    import pyastar2d
    path = pyastar2d.astar_path(weights, start, goal, allow_diagonal=True)
    return None if path is None else [tuple(int(x) for x in p) for p in path]


def pathfinding_peer(matrix, start, goal, corner_cutting):
    from pathfinding.core.diagonal_movement import DiagonalMovement
    from pathfinding.core.grid import Grid
    from pathfinding.finder.a_star import AStarFinder
    grid = Grid(matrix=matrix)
    mode = DiagonalMovement.always if corner_cutting else DiagonalMovement.only_when_no_obstacle
    finder = AStarFinder(diagonal_movement=mode)
    # The package indexes nodes (x = column, y = row).
    path, _ = finder.find_path(grid.node(start[1], start[0]), grid.node(goal[1], goal[0]), grid)
    return [(node.y, node.x) for node in path] if path else None


def main():
    grid_path, rows, cols, queries_path, model, budget_s = sys.argv[1:7]
    rows, cols, budget_s = int(rows), int(cols), float(budget_s)
    corner_cutting = model == "octile-cc"
    with open(grid_path, "rb") as f:
        blocked = f.read()
    with open(queries_path) as f:
        queries = json.load(f)

    peers = [
        ("python-heapq-astar", lambda s, g: textbook_astar(blocked, rows, cols, s, g, corner_cutting)),
        ("fcnd-astar", lambda s, g: fcnd_astar(blocked, rows, cols, s, g, corner_cutting)),
    ]
    try:
        import numpy as np
        blocked_arr = np.frombuffer(blocked, dtype=np.uint8).reshape(rows, cols).astype(bool)
        try:
            import pyastar2d  # noqa: F401
            # The weight array is built once per grid, outside the timed call (skyplan's grid is
            # not timed either): both sides are timed around the search call only.
            weights = np.where(blocked_arr, np.inf, 1.0).astype(np.float32)
            peers.append(("pyastar2d", lambda s, g: pyastar2d_peer(weights, s, g, corner_cutting)))
        except ImportError as e:
            print(json.dumps({"peer": "pyastar2d", "unavailable": str(e)}), flush=True)
        try:
            import pathfinding  # noqa: F401
            matrix = (~blocked_arr).astype(int).tolist()
            peers.append(("python-pathfinding", lambda s, g: pathfinding_peer(matrix, s, g, corner_cutting)))
        except ImportError as e:
            print(json.dumps({"peer": "python-pathfinding", "unavailable": str(e)}), flush=True)
    except ImportError as e:
        for name in ("pyastar2d", "python-pathfinding"):
            print(json.dumps({"peer": name, "unavailable": f"numpy: {e}"}), flush=True)

    for name, solve in peers:
        spent = 0.0
        for i, (sr, sc, gr, gc) in enumerate(queries):
            if spent > budget_s:
                break
            t = time.perf_counter()
            path = solve((sr, sc), (gr, gc))
            dt = time.perf_counter() - t
            spent += dt
            cost = octile_length(path) if path else None
            print(json.dumps({"peer": name, "query": i, "time_s": dt, "cost": cost}), flush=True)


if __name__ == "__main__":
    main()

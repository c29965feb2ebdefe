//! Seeded perfect mazes in the shape of MovingAI's `maze512-C-k` maps, and scenarios for them
//! whose optimal lengths come from an exact Dijkstra search.
//!
//! The layout follows the published maps: corridors `C` cells wide separated by walls one cell
//! thick, on a pitch of `C + 1`; wall lines at every multiple of the pitch (so row 0 and column 0
//! are walls); the bottom and right edges of the map close the last row and column of maze
//! cells, which are cut short when `W − 1` or `H − 1` is not a multiple of the pitch (as in
//! `maze512-32-9`, whose last corridor is 16 cells wide). The maze is *perfect* (one way between
//! any two cells): a recursive backtracker on the coarse grid of maze cells, opening one wall
//! segment (`C` cells) between neighbours; the crossings of wall lines always stay blocked.
//!
//! [`generate_rooms`] makes maps in the shape of MovingAI's *room* maps (`8room_000` …
//! `64room_009`): square rooms `R` cells wide on the same pitch, joined by *doors* — gaps of `D`
//! cells at a seeded place in the wall between two neighbouring rooms. The rooms of a spanning
//! tree (the same backtracker) always get a door, so every room is reachable; every other pair of
//! neighbours gets one with probability ½, so there are many ways between two rooms, as in the
//! published maps.
//!
//! Scenario lengths use the move model of `skyplan scen`: 8-connected, diagonals cost √2 and need
//! both orthogonally adjacent cells free (no corner cutting).
//!
//! ```
//! use skyplan_map::maze::{MazeSpec, generate, scenarios};
//! let spec = MazeSpec { width: 9, height: 9, corridor_cells: 3, seed: 7 };
//! let map = generate(&spec)?;
//! assert_eq!(map.passable.iter().filter(|&&p| p).count(), 4 * 9 + 3 * 3);
//! let scen = scenarios(&map, "m.map", 5, 1)?;
//! assert_eq!(scen.len(), 5);
//! assert!(scen.iter().all(|s| s.optimal_length > 0.0));
//! # Ok::<(), skyplan_map::maze::MazeError>(())
//! ```

use crate::movingai::{MovingAiMap, Scenario};
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// The widest corridor [`generate`] makes, cells.
pub const MAX_CORRIDOR_CELLS: usize = 64;

/// The largest side [`generate`] makes, cells (MovingAI's parser takes up to 32 768).
pub const MAX_SIDE: usize = 1 << 15;

/// What maze to make.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MazeSpec {
    /// Columns of the map.
    pub width: usize,
    /// Rows of the map.
    pub height: usize,
    /// Corridor width, cells (walls are one cell thick).
    pub corridor_cells: usize,
    /// Seed of the generator: the same spec gives the same maze on every machine.
    pub seed: u64,
}

/// Why a maze or its scenarios cannot be made.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MazeError {
    /// The corridor width is out of range.
    #[error("corridor width {0}: expected 1 to {MAX_CORRIDOR_CELLS} cells")]
    CorridorWidth(usize),
    /// A side is too small to hold one corridor or too large for a MovingAI map.
    #[error(
        "{what} {value}: expected {min} to {MAX_SIDE} cells (a wall and a corridor or room of {corridor} cells)"
    )]
    Side {
        /// `width` or `height`.
        what: &'static str,
        /// The value asked for.
        value: usize,
        /// The least that holds one corridor.
        min: usize,
        /// The corridor width asked for.
        corridor: usize,
    },
    /// The room width is out of range.
    #[error("room width {0}: expected 1 to {MAX_CORRIDOR_CELLS} cells")]
    RoomWidth(usize),
    /// The door width is out of range.
    #[error("door width {door}: expected 1 to the room width, {room} cells")]
    DoorWidth {
        /// The door width asked for.
        door: usize,
        /// The room width.
        room: usize,
    },
    /// The map has fewer than two free cells connected to each other.
    #[error("the map has no two connected free cells to draw scenarios from")]
    NoScenarios,
}

/// A small, fast, seeded generator (SplitMix64): the same numbers on every machine.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A number in `0..n` (`n > 0`), without modulo bias worth noticing (`n` ≪ 2⁶⁴).
    fn below(&mut self, n: usize) -> usize {
        ((u128::from(self.next()) * n as u128) >> 64) as usize
    }
}

/// The maze of `spec` as a MovingAI map.
///
/// Errors: a corridor width outside 1..=[`MAX_CORRIDOR_CELLS`], or a side shorter than
/// `corridor_cells + 1` (one wall and one corridor) or longer than [`MAX_SIDE`].
pub fn generate(spec: &MazeSpec) -> Result<MovingAiMap, MazeError> {
    layout(spec, None)
}

/// What room map to make ([`generate_rooms`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RoomsSpec {
    /// Columns of the map.
    pub width: usize,
    /// Rows of the map.
    pub height: usize,
    /// Room width, cells (walls are one cell thick).
    pub room_cells: usize,
    /// Door width, cells (1 ..= `room_cells`; a door in a wall cut short by the map's edge is
    /// at most as wide as that wall).
    pub door_cells: usize,
    /// Seed of the generator.
    pub seed: u64,
}

/// The room map of `spec` (module docs).
///
/// ```
/// use skyplan_map::maze::{RoomsSpec, generate_rooms};
/// let spec = RoomsSpec { width: 25, height: 25, room_cells: 7, door_cells: 2, seed: 1 };
/// let map = generate_rooms(&spec)?;
/// let free = map.passable.iter().filter(|&&p| p).count();
/// // 9 rooms of 7 × 7, and a door of 2 cells in at least the 8 walls of a spanning tree.
/// assert!(free >= 9 * 49 + 8 * 2 && free <= 9 * 49 + 12 * 2);
/// # Ok::<(), skyplan_map::maze::MazeError>(())
/// ```
///
/// Errors: a room width outside 1..=[`MAX_CORRIDOR_CELLS`], a door width outside
/// 1..=`room_cells`, and sides as [`generate`]'s.
pub fn generate_rooms(spec: &RoomsSpec) -> Result<MovingAiMap, MazeError> {
    if !(1..=MAX_CORRIDOR_CELLS).contains(&spec.room_cells) {
        return Err(MazeError::RoomWidth(spec.room_cells));
    }
    if spec.door_cells == 0 || spec.door_cells > spec.room_cells {
        return Err(MazeError::DoorWidth {
            door: spec.door_cells,
            room: spec.room_cells,
        });
    }
    let maze = MazeSpec {
        width: spec.width,
        height: spec.height,
        corridor_cells: spec.room_cells,
        seed: spec.seed,
    };
    layout(&maze, Some(spec.door_cells))
}

/// Cells of width `c` on a pitch of `c + 1`, joined along a seeded spanning tree: by whole wall
/// segments (a maze, `door` = `None`), or by doors of `door` cells, with every other
/// neighbouring pair joined with probability ½ (rooms).
fn layout(spec: &MazeSpec, door: Option<usize>) -> Result<MovingAiMap, MazeError> {
    let c = spec.corridor_cells;
    if !(1..=MAX_CORRIDOR_CELLS).contains(&c) {
        return Err(MazeError::CorridorWidth(c));
    }
    for (what, value) in [("width", spec.width), ("height", spec.height)] {
        if value < c + 1 || value > MAX_SIDE {
            return Err(MazeError::Side {
                what,
                value,
                min: c + 1,
                corridor: c,
            });
        }
    }
    let (w, h, pitch) = (spec.width, spec.height, c + 1);
    // Maze cells per axis: every started pitch after the first wall line.
    let (cols, rows) = ((w - 1).div_ceil(pitch), (h - 1).div_ceil(pitch));
    let mut passable = vec![false; w * h];
    let mut carve = |x0: usize, y0: usize, x1: usize, y1: usize| {
        for y in y0..y1.min(h) {
            passable[y * w + x0..y * w + x1.min(w)].fill(true);
        }
    };
    for j in 0..rows {
        for i in 0..cols {
            carve(
                i * pitch + 1,
                j * pitch + 1,
                (i + 1) * pitch,
                (j + 1) * pitch,
            );
        }
    }
    let mut rng = SplitMix64(spec.seed);
    // Opens the wall between cell `a` and its neighbour to the right (`right`) or below: the
    // wall line x = (i + 1) · pitch or y = (j + 1) · pitch, over the cells' span (cut by the
    // map's edge), whole or a door of `door` cells at a seeded place.
    let mut open = |a: usize, right: bool, rng: &mut SplitMix64| {
        let (i, j) = (a % cols, a / cols);
        let (lo, hi) = if right {
            (j * pitch + 1, ((j + 1) * pitch).min(h))
        } else {
            (i * pitch + 1, ((i + 1) * pitch).min(w))
        };
        let (from, to) = match door {
            None => (lo, hi),
            Some(d) => {
                let d = d.min(hi - lo);
                let at = lo + rng.below(hi - lo - d + 1);
                (at, at + d)
            }
        };
        if right {
            let x = (i + 1) * pitch;
            carve(x, from, x + 1, to);
        } else {
            let y = (j + 1) * pitch;
            carve(from, y, to, y + 1);
        }
    };
    // Recursive backtracker (iterative) from a seeded cell.
    let mut seen = vec![false; cols * rows];
    let mut joined = vec![[false; 2]; cols * rows]; // per cell: to its right, below
    let first = rng.below(cols * rows);
    seen[first] = true;
    let mut stack = vec![first];
    let mut options = Vec::with_capacity(4);
    while let Some(&here) = stack.last() {
        let (i, j) = (here % cols, here / cols);
        options.clear();
        if i > 0 && !seen[here - 1] {
            options.push(here - 1);
        }
        if i + 1 < cols && !seen[here + 1] {
            options.push(here + 1);
        }
        if j > 0 && !seen[here - cols] {
            options.push(here - cols);
        }
        if j + 1 < rows && !seen[here + cols] {
            options.push(here + cols);
        }
        if options.is_empty() {
            stack.pop();
            continue;
        }
        let next = options[rng.below(options.len())];
        let right = next % cols != i;
        let a = here.min(next);
        open(a, right, &mut rng);
        joined[a][usize::from(!right)] = true;
        seen[next] = true;
        stack.push(next);
    }
    if door.is_some() {
        for (a, sides) in joined.iter().enumerate() {
            let (i, j) = (a % cols, a / cols);
            for (k, exists) in [(0, i + 1 < cols), (1, j + 1 < rows)] {
                if exists && !sides[k] && rng.next() & 1 == 1 {
                    open(a, k == 0, &mut rng);
                }
            }
        }
    }
    Ok(MovingAiMap {
        width: w,
        height: h,
        passable,
    })
}

/// The 8 moves (dx, dy) and whether they are diagonal.
const MOVES: [(isize, isize); 8] = [
    (1, 0),
    (-1, 0),
    (0, 1),
    (0, -1),
    (1, 1),
    (1, -1),
    (-1, 1),
    (-1, -1),
];

/// Exact octile distances (no corner cutting) from `start` (an index `y · width + x`) to every
/// cell: `f64::INFINITY` where unreachable or blocked. Dijkstra's algorithm; each distance is
/// the sum of the path's unit and √2 steps, as MovingAI's published lengths are.
///
/// ```
/// let map = skyplan_map::movingai::parse_map("type octile\nheight 2\nwidth 3\nmap\n...\n.@.\n")?;
/// let d = skyplan_map::maze::distances(&map, 0);
/// assert_eq!(d[2], 2.0);
/// assert_eq!(d[3], 1.0);
/// assert_eq!(d[5], 2.0 + 1.0); // no diagonal past the blocked corner
/// assert!(d[4].is_infinite());
/// # Ok::<(), skyplan_map::ParseError>(())
/// ```
pub fn distances(map: &MovingAiMap, start: usize) -> Vec<f64> {
    let (w, h) = (map.width as isize, map.height as isize);
    let mut dist = vec![f64::INFINITY; map.passable.len()];
    if !map.passable.get(start).copied().unwrap_or(false) {
        return dist;
    }
    let free = |x: isize, y: isize| {
        x >= 0 && y >= 0 && x < w && y < h && map.passable[(y * w + x) as usize]
    };
    let mut heap = BinaryHeap::new();
    dist[start] = 0.0;
    heap.push(Entry(0.0, start));
    while let Some(Entry(d, here)) = heap.pop() {
        if d > dist[here] {
            continue;
        }
        let (x, y) = ((here % map.width) as isize, (here / map.width) as isize);
        for (dx, dy) in MOVES {
            let (nx, ny) = (x + dx, y + dy);
            if !free(nx, ny) {
                continue;
            }
            let diagonal = dx != 0 && dy != 0;
            if diagonal && !(free(x + dx, y) && free(x, y + dy)) {
                continue;
            }
            let nd = d + if diagonal {
                std::f64::consts::SQRT_2
            } else {
                1.0
            };
            let next = (ny * w + nx) as usize;
            if nd < dist[next] {
                dist[next] = nd;
                heap.push(Entry(nd, next));
            }
        }
    }
    dist
}

/// A heap entry ordered by smallest distance first.
#[derive(PartialEq)]
struct Entry(f64, usize);

impl Eq for Entry {}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        other.0.total_cmp(&self.0).then(other.1.cmp(&self.1))
    }
}

/// `count` seeded scenarios on `map` (named `map_name` in each row), sorted by bucket as
/// MovingAI's files are. Each draws a free start, runs [`distances`] from it, picks a bucket
/// (`⌊length / 4⌋`, MovingAI's) uniformly among those the start reaches, then a goal in it: the
/// lengths spread over short and long queries alike. Start and goal always differ.
///
/// Errors: [`MazeError::NoScenarios`] when no free cell has a free neighbour it can reach.
pub fn scenarios(
    map: &MovingAiMap,
    map_name: &str,
    count: usize,
    seed: u64,
) -> Result<Vec<Scenario>, MazeError> {
    let free: Vec<usize> = (0..map.passable.len())
        .filter(|&i| map.passable[i])
        .collect();
    let mut rng = SplitMix64(seed ^ 0x5ce7_a710);
    let mut out = Vec::with_capacity(count);
    let mut by_bucket: Vec<Vec<usize>> = Vec::new();
    let mut isolated = 0usize;
    while out.len() < count {
        if free.is_empty() || isolated > 64 + 4 * free.len() {
            return Err(MazeError::NoScenarios);
        }
        let start = free[rng.below(free.len())];
        let dist = distances(map, start);
        by_bucket.iter_mut().for_each(Vec::clear);
        for (i, &d) in dist.iter().enumerate() {
            if d.is_finite() && i != start {
                let b = (d / 4.0) as usize;
                if by_bucket.len() <= b {
                    by_bucket.resize_with(b + 1, Vec::new);
                }
                by_bucket[b].push(i);
            }
        }
        let reached: Vec<usize> = (0..by_bucket.len())
            .filter(|&b| !by_bucket[b].is_empty())
            .collect();
        if reached.is_empty() {
            isolated += 1;
            continue;
        }
        let bucket = reached[rng.below(reached.len())];
        let goal = by_bucket[bucket][rng.below(by_bucket[bucket].len())];
        out.push(Scenario {
            line: 0,
            bucket: u32::try_from(bucket).unwrap_or(u32::MAX),
            map: map_name.to_string(),
            start_x: start % map.width,
            start_y: start / map.width,
            goal_x: goal % map.width,
            goal_y: goal / map.width,
            optimal_length: dist[goal],
        });
    }
    out.sort_by_key(|s| s.bucket);
    for (k, s) in out.iter_mut().enumerate() {
        s.line = k + 2;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::VecDeque;

    fn spec(width: usize, height: usize, corridor_cells: usize, seed: u64) -> MazeSpec {
        MazeSpec {
            width,
            height,
            corridor_cells,
            seed,
        }
    }

    fn free(m: &MovingAiMap, x: usize, y: usize) -> bool {
        m.passable[y * m.width + x]
    }

    /// Free cells reached from the first free cell by 4-connected steps, and all free cells.
    fn reached_and_free(m: &MovingAiMap) -> (usize, usize) {
        let all = m.passable.iter().filter(|&&p| p).count();
        let Some(first) = m.passable.iter().position(|&p| p) else {
            return (0, 0);
        };
        let mut seen = vec![false; m.passable.len()];
        let mut queue = VecDeque::from([first]);
        seen[first] = true;
        let mut n = 0;
        while let Some(i) = queue.pop_front() {
            n += 1;
            let (x, y) = (i % m.width, i / m.width);
            let mut step = |nx: usize, ny: usize| {
                let j = ny * m.width + nx;
                if m.passable[j] && !seen[j] {
                    seen[j] = true;
                    queue.push_back(j);
                }
            };
            if x > 0 {
                step(x - 1, y)
            }
            if y > 0 {
                step(x, y - 1)
            }
            if x + 1 < m.width {
                step(x + 1, y)
            }
            if y + 1 < m.height {
                step(x, y + 1)
            }
        }
        (n, all)
    }

    /// Whether the k × k square with top-left (x, y) is all free.
    fn free_square(m: &MovingAiMap, x: usize, y: usize, k: usize) -> bool {
        x + k <= m.width
            && y + k <= m.height
            && (y..y + k).all(|r| (x..x + k).all(|c| free(m, c, r)))
    }

    #[test]
    fn every_maze_is_connected_and_its_corridors_are_as_wide_as_asked() {
        for c in 1..=8 {
            for seed in [1, 2] {
                // Sides that fit whole corridors: 1 + k · (c + 1).
                let (w, h) = (1 + 7 * (c + 1), 1 + 5 * (c + 1));
                let m = generate(&spec(w, h, c, seed)).unwrap();
                let (reached, all) = reached_and_free(&m);
                assert_eq!(reached, all, "c {c} seed {seed}: not connected");
                // At least c wide: every free cell lies in a free c × c square.
                for y in 0..h {
                    for x in 0..w {
                        if !free(&m, x, y) {
                            continue;
                        }
                        let inside = (y.saturating_sub(c - 1)..=y).any(|y0| {
                            (x.saturating_sub(c - 1)..=x).any(|x0| free_square(&m, x0, y0, c))
                        });
                        assert!(
                            inside,
                            "c {c} seed {seed}: ({x}, {y}) in a narrower passage"
                        );
                    }
                }
                // At most c wide: no free (c + 1) × (c + 1) square anywhere.
                for y in 0..h {
                    for x in 0..w {
                        assert!(!free_square(&m, x, y, c + 1), "c {c}: room at ({x}, {y})");
                    }
                }
                // Walls one cell thick on the top and left borders.
                assert!((0..w).all(|x| !free(&m, x, 0)) && (0..h).all(|y| !free(&m, 0, y)));
            }
        }
    }

    #[test]
    fn a_maze_is_perfect_one_opening_fewer_than_its_cells() {
        for c in [1, 3, 8] {
            let (cols, rows) = (9, 6);
            let (w, h) = (1 + cols * (c + 1), 1 + rows * (c + 1));
            let m = generate(&spec(w, h, c, 11)).unwrap();
            // An opening is a free cell on a wall line (one per opened segment: count the first
            // cell of each segment).
            let mut openings = 0;
            for y in 0..h {
                for x in 0..w {
                    let on_x_line = x % (c + 1) == 0;
                    let on_y_line = y % (c + 1) == 0;
                    if free(&m, x, y) && (on_x_line != on_y_line) {
                        let first = if on_x_line {
                            y % (c + 1) == 1
                        } else {
                            x % (c + 1) == 1
                        };
                        openings += usize::from(first);
                    }
                }
            }
            assert_eq!(openings, cols * rows - 1, "c {c}");
            assert_eq!(reached_and_free(&m).0, reached_and_free(&m).1);
        }
    }

    #[test]
    fn sides_that_cut_the_last_corridor_short_stay_connected() {
        for (w, h, c) in [(512, 512, 8), (512, 300, 32), (40, 23, 4), (3, 2, 1)] {
            let m = generate(&spec(w, h, c, 5)).unwrap();
            assert_eq!((m.width, m.height), (w, h));
            let (reached, all) = reached_and_free(&m);
            assert_eq!(reached, all, "{w} × {h}, c {c}");
        }
    }

    /// FNV-1a of bytes: a fixed hash, the same in every Rust version.
    fn fnv(b: &[u8]) -> u64 {
        b.iter().fold(0xcbf2_9ce4_8422_2325, |h, &x| {
            (h ^ u64::from(x)).wrapping_mul(0x100_0000_01b3)
        })
    }

    /// The mazes written before rooms shared their layout (values taken from that build), so
    /// the seeds in the docs still make the same mazes.
    #[test]
    fn mazes_are_the_ones_earlier_versions_made() {
        for (w, h, c, seed, hash) in [
            (64, 50, 3, 7, 0x3c7f_b520_5732_61cf_u64),
            (101, 77, 1, 2, 0x7375_30c5_7d66_3020),
            (512, 512, 8, 1, 0xb26c_c056_f018_9ad0),
        ] {
            let m = generate(&spec(w, h, c, seed)).unwrap();
            let text = crate::movingai::to_map_text(&m);
            assert_eq!(fnv(text.as_bytes()), hash, "{w} × {h}, c {c}, seed {seed}");
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_maze_and_another_seed_another() {
        let a = generate(&spec(64, 64, 2, 42)).unwrap();
        assert_eq!(a, generate(&spec(64, 64, 2, 42)).unwrap());
        assert_ne!(a, generate(&spec(64, 64, 2, 43)).unwrap());
        let s = scenarios(&a, "a.map", 20, 9).unwrap();
        assert_eq!(s, scenarios(&a, "a.map", 20, 9).unwrap());
    }

    #[test]
    fn bad_specs_are_refused_with_the_value_and_the_range() {
        let e = generate(&spec(64, 64, 0, 1)).unwrap_err();
        assert_eq!(e.to_string(), "corridor width 0: expected 1 to 64 cells");
        assert!(generate(&spec(64, 64, 65, 1)).is_err());
        let e = generate(&spec(4, 64, 4, 1)).unwrap_err();
        assert_eq!(
            e.to_string(),
            "width 4: expected 5 to 32768 cells (a wall and a corridor or room of 4 cells)"
        );
        assert!(generate(&spec(64, MAX_SIDE + 1, 1, 1)).is_err());
        let walls = MovingAiMap {
            width: 2,
            height: 2,
            passable: vec![true, false, false, false],
        };
        assert_eq!(
            scenarios(&walls, "w.map", 1, 1).unwrap_err(),
            MazeError::NoScenarios
        );
    }

    /// The oracle: exact distances by repeated relaxation of every edge until nothing changes
    /// (Bellman–Ford; no heap, no ordering).
    fn bellman_ford(m: &MovingAiMap, start: usize) -> Vec<f64> {
        let (w, h) = (m.width as isize, m.height as isize);
        let ok = |x: isize, y: isize| {
            x >= 0 && y >= 0 && x < w && y < h && free(m, x as usize, y as usize)
        };
        let mut d = vec![f64::INFINITY; m.passable.len()];
        d[start] = 0.0;
        loop {
            let mut changed = false;
            for y in 0..h {
                for x in 0..w {
                    let i = (y * w + x) as usize;
                    if !ok(x, y) || d[i].is_infinite() {
                        continue;
                    }
                    for dy in -1..=1isize {
                        for dx in -1..=1isize {
                            if (dx, dy) == (0, 0) || !ok(x + dx, y + dy) {
                                continue;
                            }
                            if dx != 0 && dy != 0 && !(ok(x + dx, y) && ok(x, y + dy)) {
                                continue;
                            }
                            let step = if dx != 0 && dy != 0 { 2f64.sqrt() } else { 1.0 };
                            let j = ((y + dy) * w + x + dx) as usize;
                            if d[i] + step < d[j] - 1e-12 {
                                d[j] = d[i] + step;
                                changed = true;
                            }
                        }
                    }
                }
            }
            if !changed {
                return d;
            }
        }
    }

    fn rooms(w: usize, h: usize, room: usize, door: usize, seed: u64) -> MovingAiMap {
        generate_rooms(&RoomsSpec {
            width: w,
            height: h,
            room_cells: room,
            door_cells: door,
            seed,
        })
        .unwrap()
    }

    /// Every room is whole and reachable; every opening in a wall is one door of exactly the
    /// asked width (or the whole of a wall cut shorter by the map's edge); the spanning tree's
    /// walls and about half of the others have one; scenario lengths are an independent
    /// relaxation's.
    #[test]
    fn room_maps_are_connected_rooms_joined_by_doors_of_the_asked_width() {
        for (w, h, r, d, seed) in [
            (1 + 9 * 9, 1 + 7 * 9, 8, 2, 1),
            (100, 61, 16, 4, 2),
            (1 + 6 * 33, 1 + 4 * 33, 32, 8, 3),
            (3, 40, 1, 1, 4),
        ] {
            let m = rooms(w, h, r, d, seed);
            let (reached, all) = reached_and_free(&m);
            assert_eq!(reached, all, "{w} × {h}, r {r}: not connected");
            let pitch = r + 1;
            let (cols, rows) = ((w - 1).div_ceil(pitch), (h - 1).div_ceil(pitch));
            for j in 0..rows {
                for i in 0..cols {
                    let (x0, y0) = (i * pitch + 1, j * pitch + 1);
                    let (x1, y1) = (((i + 1) * pitch).min(w), ((j + 1) * pitch).min(h));
                    assert!(
                        (y0..y1).all(|y| (x0..x1).all(|x| free(&m, x, y))),
                        "room {i},{j}"
                    );
                }
            }
            // Doors: runs of free cells on wall lines, away from the crossings.
            let mut doors = 0;
            for j in 0..rows {
                for i in 0..cols {
                    let walls = [
                        (i + 1 < cols).then(|| {
                            let x = (i + 1) * pitch;
                            let y1 = ((j + 1) * pitch).min(h);
                            (j * pitch + 1..y1)
                                .map(|y| free(&m, x, y))
                                .collect::<Vec<_>>()
                        }),
                        (j + 1 < rows).then(|| {
                            let y = (j + 1) * pitch;
                            let x1 = ((i + 1) * pitch).min(w);
                            (i * pitch + 1..x1)
                                .map(|x| free(&m, x, y))
                                .collect::<Vec<_>>()
                        }),
                    ];
                    for wall in walls.into_iter().flatten() {
                        let open = wall.iter().filter(|&&f| f).count();
                        if open == 0 {
                            continue;
                        }
                        doors += 1;
                        assert_eq!(open, d.min(wall.len()), "{w} × {h}: door width");
                        let first = wall.iter().position(|&f| f).unwrap();
                        assert!(wall[first..first + open].iter().all(|&f| f), "one gap");
                    }
                }
            }
            let neighbours = (cols - 1) * rows + cols * (rows - 1);
            let tree = cols * rows - 1;
            assert!(doors >= tree && doors <= neighbours, "{doors} doors");
            if neighbours - tree >= 20 {
                let extra = (doors - tree) as f64 / (neighbours - tree) as f64;
                assert!(
                    (0.25..0.75).contains(&extra),
                    "{extra}: about half the others"
                );
            }
            for s in scenarios(&m, "r.map", 6, seed).unwrap() {
                let truth = bellman_ford(&m, s.start_y * m.width + s.start_x);
                let t = truth[s.goal_y * m.width + s.goal_x];
                assert!((s.optimal_length - t).abs() < 1e-9, "{s:?} vs {t}");
            }
        }
        let e = generate_rooms(&RoomsSpec {
            width: 64,
            height: 64,
            room_cells: 8,
            door_cells: 9,
            seed: 1,
        })
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "door width 9: expected 1 to the room width, 8 cells"
        );
    }

    #[test]
    fn scenario_lengths_equal_an_independent_relaxation() {
        for c in [1, 2, 4, 8] {
            let m = generate(&spec(40, 31, c, c as u64)).unwrap();
            let list = scenarios(&m, "t.map", 12, 3).unwrap();
            assert_eq!(list.len(), 12);
            assert!(list.windows(2).all(|p| p[0].bucket <= p[1].bucket));
            for s in &list {
                let truth = bellman_ford(&m, s.start_y * m.width + s.start_x);
                let t = truth[s.goal_y * m.width + s.goal_x];
                assert!((s.optimal_length - t).abs() < 1e-9, "c {c}: {s:?} vs {t}");
                assert_eq!(s.bucket, (t / 4.0) as u32);
                assert!((s.start_x, s.start_y) != (s.goal_x, s.goal_y));
                assert!(free(&m, s.start_x, s.start_y) && free(&m, s.goal_x, s.goal_y));
            }
        }
    }
}

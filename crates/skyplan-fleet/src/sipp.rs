//! Safe-interval path planning (SIPP; Phillips & Likhachev, "SIPP: Safe Interval Path Planning
//! for Dynamic Environments", ICRA 2011) on an occupancy grid: the earliest arrival at the goal
//! when cells are unsafe at known times, waiting (hovering) allowed anywhere and a later
//! departure allowed within a window.
//!
//! Each cell's timeline is cut into its *safe intervals*, the maximal stretches of time it is
//! not blocked. A search state is a cell and one of its safe intervals, reached at the earliest
//! time the search has found; a move from cell `c` to a neighbour `n` takes `τ` (its length over
//! the speed) and is allowed at a departure `t` when both cells are safe over all of
//! `[t, t + τ]`. Since arriving earlier in an interval never hurts (one can wait), keeping the
//! earliest arrival per state makes the search exact: with an admissible heuristic (the
//! shortest distance to the goal over the grid's free cells at full speed, blind to the blocked
//! times, from a backward search resumed as needed) the first goal state taken from the queue
//! is the earliest arrival over all routes on the grid's moves and all waits. A search given
//! [`SippQuery::exact_until`] may stop proving that part way and head for the goal instead; its
//! answer then says how much sooner a route could arrive at most.

use skyplan_cspace::{Cell, Grid2};
use std::cmp::Reverse;
use std::collections::BinaryHeap;
// foldhash: the states and cells are looked up for every move the search tries; SipHash made
// the lookups a tenth of a crowded fleet's time.
use foldhash::{HashMap, HashMapExt};

/// Safe intervals start this long after a blocked one ends and end this long before the next
/// begins, seconds: blocked intervals are closed, safe ones closed too, and never touch.
pub const GAP_S: f64 = 1e-3;

/// How far past the horizon a state's lower bound on its arrival at the goal may lie before the
/// search drops it, seconds: rounding in the sums of move times, never a real arrival.
const HORIZON_TOLERANCE_S: f64 = 1e-6;

/// A closed interval of time, seconds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    /// Start, seconds.
    pub start_s: f64,
    /// End, seconds.
    pub end_s: f64,
}

/// Sorts and merges closed intervals (those that overlap or touch become one).
///
/// ```
/// use skyplan_fleet::sipp::{Interval, merge_intervals};
/// let iv = |start_s, end_s| Interval { start_s, end_s };
/// let merged = merge_intervals(vec![iv(5.0, 8.0), iv(0.0, 2.0), iv(1.0, 3.0)]);
/// assert_eq!(merged, vec![iv(0.0, 3.0), iv(5.0, 8.0)]);
/// ```
pub fn merge_intervals(mut blocked: Vec<Interval>) -> Vec<Interval> {
    merge_in_place(&mut blocked);
    blocked
}

/// Sorts and merges `blocked` in place, as [`merge_intervals`] does, without allocating.
fn merge_in_place(blocked: &mut Vec<Interval>) {
    blocked.retain(|b| b.start_s <= b.end_s);
    blocked.sort_unstable_by(|a, b| a.start_s.total_cmp(&b.start_s));
    let mut kept = 0;
    for k in 0..blocked.len() {
        let b = blocked[k];
        if kept > 0 && b.start_s <= blocked[kept - 1].end_s {
            blocked[kept - 1].end_s = blocked[kept - 1].end_s.max(b.end_s);
        } else {
            blocked[kept] = b;
            kept += 1;
        }
    }
    blocked.truncate(kept);
}

/// The safe intervals between merged blocked ones, from −∞ to +∞.
#[cfg(test)]
fn safe_intervals(blocked: &[Interval]) -> Vec<Interval> {
    let mut out = Vec::with_capacity(blocked.len() + 1);
    push_safe_intervals(blocked, &mut out);
    out
}

/// Appends the safe intervals between merged blocked ones, from −∞ to +∞, to `out`.
fn push_safe_intervals(blocked: &[Interval], out: &mut Vec<Interval>) {
    let mut from = f64::NEG_INFINITY;
    for b in blocked {
        let end = b.start_s - GAP_S;
        if end >= from {
            out.push(Interval {
                start_s: from,
                end_s: end,
            });
        }
        from = b.end_s + GAP_S;
    }
    out.push(Interval {
        start_s: from,
        end_s: f64::INFINITY,
    });
}

/// Where and when each cell is blocked, asked once per cell the search reaches.
pub trait Timeline {
    /// The times `cell` is blocked (any order; they are merged).
    fn blocked(&mut self, cell: Cell) -> Vec<Interval>;

    /// Appends the times `cell` is blocked to `out` (any order): what the search calls, so
    /// that a timeline can fill one buffer the search reuses. By default, [`Self::blocked`].
    fn blocked_into(&mut self, cell: Cell, out: &mut Vec<Interval>) {
        out.extend(self.blocked(cell));
    }
}

impl<F: FnMut(Cell) -> Vec<Interval>> Timeline for F {
    fn blocked(&mut self, cell: Cell) -> Vec<Interval> {
        self(cell)
    }
}

/// A space-time search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SippQuery {
    /// The start cell.
    pub start: Cell,
    /// The goal cell.
    pub goal: Cell,
    /// Seconds to cross one cell north, south, east or west (a diagonal takes √2 times as long).
    pub cell_s: f64,
    /// The latest departure, seconds (the earliest is 0).
    pub latest_departure_s: f64,
    /// No arrival later than this, seconds.
    pub horizon_s: f64,
    /// Diagonal moves (never between two blocked orthogonal neighbours: no corner cutting).
    pub diagonals: bool,
    /// Most states taken from the queue before giving up.
    pub max_expansions: usize,
    /// When to give up, if ever ([`SippError::Deadline`]): the clock is read at the first state
    /// and then every [`DEADLINE_EVERY`] states (also with only `exact_until` set).
    pub deadline: Option<std::time::Instant>,
    /// Until when the search proves the earliest arrival, if not to the end: past this
    /// instant it heads for the goal, its open states ordered by the arrival plus
    /// [`HEADLONG_WEIGHT`] times the bound on the time left, and the route found may arrive
    /// later than the earliest ([`SippPath::earliest_bound_s`] says by how much at most).
    pub exact_until: Option<std::time::Instant>,
}

/// How much the search weighs the time left against the time spent once it stops proving
/// the earliest arrival ([`SippQuery::exact_until`]).
pub const HEADLONG_WEIGHT: f64 = 10.0;

/// How many states the search takes between two looks at the clock (a look costs about as
/// much as a state); the first look is at the first state.
pub const DEADLINE_EVERY: usize = 256;

/// A cell of the route and when the flight is in it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimedCell {
    /// The cell.
    pub cell: Cell,
    /// Arrival (for the start: the departure), seconds.
    pub arrive_s: f64,
    /// Departure to the next cell (for the goal: its arrival), seconds.
    pub leave_s: f64,
}

/// The route found and what the search did.
#[derive(Debug, Clone, PartialEq)]
pub struct SippPath {
    /// The cells in order, with times.
    pub cells: Vec<TimedCell>,
    /// States taken from the queue.
    pub expansions: usize,
    /// No route arrives before this, seconds: the arrival itself when the search proved it
    /// the earliest, else what was proven when it stopped proving
    /// ([`SippQuery::exact_until`]).
    pub earliest_bound_s: f64,
}

impl SippPath {
    /// Whether the arrival is proven the earliest.
    pub fn proven_earliest(&self) -> bool {
        self.arrival_s() <= self.earliest_bound_s + HORIZON_TOLERANCE_S
    }

    /// The departure, seconds.
    pub fn departure_s(&self) -> f64 {
        self.cells.first().map_or(0.0, |c| c.arrive_s)
    }

    /// The arrival at the goal, seconds.
    pub fn arrival_s(&self) -> f64 {
        self.cells.last().map_or(0.0, |c| c.arrive_s)
    }

    /// Seconds spent waiting after departure (hovering).
    pub fn hover_s(&self) -> f64 {
        self.cells.iter().map(|c| c.leave_s - c.arrive_s).sum()
    }
}

/// Why no route was found.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SippError {
    /// The start or goal is blocked or off the grid.
    #[error("the {which} cell (row {}, col {}) is blocked or off the grid", .cell.row, .cell.col)]
    Endpoint {
        /// "start" or "goal".
        which: &'static str,
        /// The cell.
        cell: Cell,
    },
    /// Every route and wait within the window and horizon meets a blocked time.
    #[error(
        "no route reaches the goal by {horizon_s:.0} s leaving within {latest_departure_s:.0} s ({expansions} states searched)"
    )]
    NoRoute {
        /// The latest departure searched, seconds.
        latest_departure_s: f64,
        /// The horizon, seconds.
        horizon_s: f64,
        /// States taken from the queue.
        expansions: usize,
    },
    /// The search stopped at its budget of states.
    #[error("stopped after {0} states without reaching the goal")]
    Budget(usize),
    /// The search stopped at its deadline.
    #[error("stopped at its deadline after {0} states without reaching the goal")]
    Deadline(usize),
}

struct Node {
    cell: Cell,
    interval: u32,
    arrive_s: f64,
    /// Departure from the parent.
    left_parent_s: f64,
    parent: u32,
    /// Superseded by an earlier arrival at the same state.
    stale: bool,
}

const NONE: u32 = u32::MAX;

/// An open list's entry in the order of [`skyplan_search::OpenEntry`] — smallest `f` first,
/// then the later arrival (deeper), then the older state — as integers (in a
/// [`Reverse`]): each time as [`f64::total_cmp`] orders it, the arrival's complemented.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
struct Queued {
    f: u64,
    later_first: u64,
    node: u32,
}

impl Queued {
    fn new(f: f64, g: f64, node: u32) -> Reverse<Self> {
        Reverse(Self {
            f: total_key(f),
            later_first: !total_key(g),
            node,
        })
    }
}

/// The time whose [`total_key`] is `key`, as bits.
fn untotal_key(key: u64) -> u64 {
    let bits = (key ^ (1 << 63)) as i64;
    (bits ^ ((((bits >> 63) as u64) >> 1) as i64)) as u64
}

/// `x` as an unsigned integer in [`f64::total_cmp`]'s order.
fn total_key(x: f64) -> u64 {
    let bits = x.to_bits() as i64;
    let key = bits ^ ((((bits >> 63) as u64) >> 1) as i64);
    (key as u64) ^ (1 << 63)
}

/// Grids of up to this many cells index the reached cells in an array (4 bytes a cell,
/// zeroed lazily by the allocator); larger ones in a hash map.
const DENSE_CELLS: usize = 1 << 22;

/// Each reached cell's safe intervals, asked of the timeline once, one after another in one
/// arena, with the search's best state of each (cell, safe interval) beside them.
struct SafeCache {
    /// Per cell (row-major index): where its intervals start in `intervals`, plus one (0:
    /// not asked yet).
    dense: Vec<u32>,
    sparse: HashMap<u32, u32>,
    intervals: Vec<Interval>,
    /// The best state of each interval, or [`NONE`], with its arrival beside it (so a move
    /// compares arrivals without reading the state).
    best: Vec<(u32, f64)>,
    /// Per cell, the number of its intervals: at `intervals[start - 1]`'s slot of `counts`.
    counts: Vec<u32>,
    /// The blocked times of the cell being asked, reused.
    scratch: Vec<Interval>,
}

impl SafeCache {
    fn new(grid: &Grid2) -> Self {
        Self {
            dense: if grid.len() <= DENSE_CELLS {
                vec![0; grid.len()]
            } else {
                Vec::new()
            },
            sparse: HashMap::new(),
            intervals: Vec::new(),
            best: Vec::new(),
            counts: Vec::new(),
            scratch: Vec::new(),
        }
    }

    /// Where the safe intervals of `cell` are in the arena: `(start, count)`.
    fn span(&mut self, grid: &Grid2, cell: Cell, timeline: &mut dyn Timeline) -> (usize, usize) {
        let index = grid.index(cell);
        let known = if self.dense.is_empty() {
            self.sparse.get(&(index as u32)).copied().unwrap_or(0)
        } else {
            self.dense[index]
        };
        if known != 0 {
            let start = known as usize - 1;
            return (start, self.counts[start] as usize);
        }
        self.scratch.clear();
        timeline.blocked_into(cell, &mut self.scratch);
        merge_in_place(&mut self.scratch);
        let start = self.intervals.len();
        push_safe_intervals(&self.scratch, &mut self.intervals);
        let count = self.intervals.len() - start;
        self.best
            .resize(self.intervals.len(), (NONE, f64::INFINITY));
        self.counts.resize(self.intervals.len(), 0);
        self.counts[start] = count as u32;
        let at = start as u32 + 1;
        if self.dense.is_empty() {
            self.sparse.insert(index as u32, at);
        } else {
            self.dense[index] = at;
        }
        (start, count)
    }

    /// The safe intervals of `cell`.
    fn of(&mut self, grid: &Grid2, cell: Cell, timeline: &mut dyn Timeline) -> &[Interval] {
        let (start, count) = self.span(grid, cell, timeline);
        &self.intervals[start..start + count]
    }
}

/// The earliest arrival (unless [`SippQuery::exact_until`] stops the proof: see
/// [`SippPath::earliest_bound_s`]) at `q.goal` from `q.start`, leaving at a time in
/// `[0, q.latest_departure_s]` (waiting before departure costs nothing and occupies nothing),
/// over the free cells of `grid` and the safe intervals `timeline` gives. Of the routes that
/// arrive first, the one found waits on the ground rather than in the air where the window
/// and the others allow (its waits moved to a later departure).
///
/// ```
/// use skyplan_cspace::{Cell, Grid2};
/// use skyplan_fleet::sipp::{Interval, SippQuery, sipp};
/// // A corridor whose middle cell is blocked from 0 to 10 s: the flight waits short of it.
/// let grid = Grid2::from_ascii(".....")?;
/// let q = SippQuery {
///     start: Cell::new(0, 0), goal: Cell::new(0, 4), cell_s: 1.0,
///     latest_departure_s: 0.0, horizon_s: 100.0, diagonals: true, max_expansions: 10_000,
///     deadline: None,
///     exact_until: None,
/// };
/// let mut timeline = |c: Cell| if c.col == 2 { vec![Interval { start_s: 0.0, end_s: 10.0 }] } else { vec![] };
/// let path = sipp(&grid, &q, &mut timeline)?;
/// assert!((path.arrival_s() - 13.001).abs() < 1e-9);
/// assert!((path.hover_s() - 9.001).abs() < 1e-9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn sipp(
    grid: &Grid2,
    q: &SippQuery,
    timeline: &mut dyn Timeline,
) -> Result<SippPath, SippError> {
    sipp_with(grid, q, timeline, Bound::GridDistance, None)
}

/// The lower bound on the time to the goal that orders [`sipp_with`]'s queue.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Bound {
    /// The shortest distance over the grid's free cells ([`StaticDistance`]).
    GridDistance,
    /// The octile distance, blind to obstacles (the tests' second opinion).
    #[cfg_attr(not(test), allow(dead_code))]
    Octile,
}

/// [`sipp`] with the bound `bound`, and (for the tests) the proof stopped at the
/// `stop_proving_at`-th state as at [`SippQuery::exact_until`].
fn sipp_with(
    grid: &Grid2,
    q: &SippQuery,
    timeline: &mut dyn Timeline,
    bound: Bound,
    stop_proving_at: Option<usize>,
) -> Result<SippPath, SippError> {
    for (which, cell) in [("start", q.start), ("goal", q.goal)] {
        if !grid.contains(cell) || grid.is_blocked(cell) {
            return Err(SippError::Endpoint { which, cell });
        }
    }
    let mut safe = SafeCache::new(grid);
    let mut to_goal = StaticDistance::new(grid, q, bound);
    let mut h = |c: Cell| to_goal.seconds(grid, c, q);
    let mut nodes: Vec<Node> = Vec::new();
    let mut open = BinaryHeap::new();
    let (first, count) = safe.span(grid, q.start, timeline);
    for k in 0..count {
        let iv = safe.intervals[first + k];
        if iv.end_s < 0.0 || iv.start_s > q.latest_departure_s {
            continue;
        }
        let g = iv.start_s.max(0.0);
        let id = nodes.len() as u32;
        nodes.push(Node {
            cell: q.start,
            interval: k as u32,
            arrive_s: g,
            left_parent_s: g,
            parent: NONE,
            stale: false,
        });
        safe.best[first + k] = (id, g);
        open.push(Queued::new(g + h(q.start), g, id));
    }
    let moves = moves(q.diagonals);
    let free = |r: i64, c: i64| grid.is_free_at(r, c);
    let mut expansions = 0;
    // The weight on the time left: 1 while the search proves the earliest arrival.
    let mut weight = 1.0;
    // No route arrives before this (the smallest `f` open when the proof stopped).
    let mut earliest_bound_s = f64::INFINITY;
    while let Some(Reverse(Queued { node, f, .. })) = open.pop() {
        // The entry's arrival, as pushed.
        let g = nodes[node as usize].arrive_s;
        let (cell, interval) = (nodes[node as usize].cell, nodes[node as usize].interval);
        if nodes[node as usize].stale {
            continue;
        }
        expansions += 1;
        if cell == q.goal {
            let mut cells = walk_back(&nodes, node);
            ground_waits(&mut cells, q.latest_departure_s, &mut |c| {
                safe.of(grid, c, timeline).to_vec()
            });
            return Ok(SippPath {
                cells,
                expansions,
                earliest_bound_s: earliest_bound_s.min(g),
            });
        }
        if expansions > q.max_expansions {
            return Err(SippError::Budget(q.max_expansions));
        }
        let look =
            expansions % DEADLINE_EVERY == 1 && (q.deadline.is_some() || q.exact_until.is_some());
        let now = look.then(std::time::Instant::now);
        if let Some(now) = now
            && q.deadline.is_some_and(|d| now >= d)
        {
            return Err(SippError::Deadline(expansions));
        }
        let stop_proving = stop_proving_at == Some(expansions)
            || now.is_some_and(|now| q.exact_until.is_some_and(|t| now >= t));
        if weight == 1.0 && stop_proving {
            // Stop proving: what is proven is the smallest `f` open, this state's.
            earliest_bound_s = f64::from_bits(untotal_key(f));
            weight = HEADLONG_WEIGHT;
            open.push(Reverse(Queued {
                node,
                f,
                later_first: !total_key(g),
            }));
            let entries = std::mem::take(&mut open).into_vec();
            for Reverse(e) in entries {
                let n = &nodes[e.node as usize];
                if !n.stale {
                    let (a, c) = (n.arrive_s, n.cell);
                    open.push(Queued::new(a + weight * h(c), a, e.node));
                }
            }
            expansions -= 1;
            continue;
        }
        let here_end = safe.of(grid, cell, timeline)[interval as usize].end_s;
        let (r, c) = (i64::from(cell.row), i64::from(cell.col));
        for &(dr, dc) in moves {
            let (nr, nc) = (r + dr, c + dc);
            let diagonal = dr != 0 && dc != 0;
            if !free(nr, nc) || (diagonal && !(free(r + dr, c) && free(r, nc))) {
                continue;
            }
            let len = if diagonal {
                std::f64::consts::SQRT_2
            } else {
                1.0
            };
            let Some(next) = grid.checked_cell(nr, nc) else {
                continue;
            };
            let tau = len * q.cell_s;
            let h_next = h(next);
            if g + tau + h_next > q.horizon_s + HORIZON_TOLERANCE_S {
                continue;
            }
            let (first, count) = safe.span(grid, next, timeline);
            for k in 0..count {
                let iv = safe.intervals[first + k];
                let leave = g.max(iv.start_s);
                let arrive = leave + tau;
                if iv.start_s > here_end {
                    break;
                }
                if arrive > here_end.min(iv.end_s)
                    || arrive + h_next > q.horizon_s + HORIZON_TOLERANCE_S
                {
                    continue;
                }
                let (known, known_s) = safe.best[first + k];
                if known_s <= arrive {
                    continue;
                }
                let id = nodes.len() as u32;
                nodes.push(Node {
                    cell: next,
                    interval: k as u32,
                    arrive_s: arrive,
                    left_parent_s: leave,
                    parent: node,
                    stale: false,
                });
                if known != NONE {
                    nodes[known as usize].stale = true;
                }
                safe.best[first + k] = (id, arrive);
                open.push(Queued::new(arrive + weight * h_next, arrive, id));
            }
        }
    }
    Err(SippError::NoRoute {
        latest_departure_s: q.latest_departure_s,
        horizon_s: q.horizon_s,
        expansions,
    })
}

/// A lower bound on the time from a cell to the goal: its shortest distance to the goal over
/// the grid's free cells and moves, ignoring the safe intervals, at full speed. It comes from a
/// backward A\* from the goal towards the start, resumed whenever the search asks for a cell
/// it has not closed yet ("Reverse Resumable A\*", Silver, "Cooperative Pathfinding", AIIDE
/// 2005), so only the part of the grid the search needs is covered. Its move costs are integers
/// a little under the true ones ([`STATIC_STRAIGHT`], [`STATIC_DIAGONAL`]) and its own heuristic
/// the octile distance in the same units, so its queue is a ring of buckets and the bound stays
/// below the true time and consistent. A cell it cannot reach is cut off from the goal: no
/// bound (infinite). Grids over [`DENSE_CELLS`] cells use the octile distance instead (as
/// does [`Bound::Octile`]).
struct StaticDistance {
    /// Per cell (row-major): the best distance found, in units of 1 / [`STATIC_STRAIGHT`] cell,
    /// or [`UNSEEN`]; the top bit marks it closed (final). Empty: the octile distance.
    units: Vec<u32>,
    /// Open cells by `f` modulo the ring's length.
    ring: Vec<Vec<u32>>,
    /// The `f` of the bucket being taken, and the open entries in all.
    f: u32,
    pending: usize,
    /// The backward search's target (the forward search's start) and the grid's width.
    target: (i64, i64),
    cols: usize,
    diagonals: bool,
}

/// The moves, straight ones first ([`skyplan_cspace::NEIGHBOURS_8`]): four, or with
/// `diagonals` eight.
fn moves(diagonals: bool) -> &'static [(i64, i64)] {
    let all = &skyplan_cspace::NEIGHBOURS_8;
    if diagonals { all } else { &all[..4] }
}

/// A straight move's cost in [`StaticDistance`]'s units.
const STATIC_STRAIGHT: u32 = 29;
/// A diagonal move's: 41 / 29 = 1.41379… < √2, so no distance found exceeds the true one.
const STATIC_DIAGONAL: u32 = 41;
/// [`StaticDistance::units`]' mark of a closed cell.
const CLOSED: u32 = 1 << 31;
/// [`StaticDistance::units`] of a cell not reached yet (open, above every real distance).
const UNSEEN: u32 = CLOSED - 1;

impl StaticDistance {
    fn new(grid: &Grid2, q: &SippQuery, bound: Bound) -> Self {
        let mut me = Self {
            units: Vec::new(),
            ring: Vec::new(),
            f: 0,
            pending: 0,
            target: (i64::from(q.start.row), i64::from(q.start.col)),
            cols: grid.cols() as usize,
            diagonals: q.diagonals,
        };
        if grid.len() > DENSE_CELLS || bound == Bound::Octile {
            return me;
        }
        me.units = vec![UNSEEN; grid.len()];
        // A successor's f exceeds its parent's by at most two diagonal moves' cost.
        me.ring = vec![Vec::new(); 2 * STATIC_DIAGONAL as usize + 1];
        let goal = grid.index(q.goal);
        me.units[goal] = 0;
        me.f = me.octile_to_target(i64::from(q.goal.row), i64::from(q.goal.col));
        let slot = me.f as usize % me.ring.len();
        me.ring[slot].push(goal as u32);
        me.pending = 1;
        me
    }

    /// The octile distance from (r, c) to the target, in units.
    #[inline]
    fn octile_to_target(&self, r: i64, c: i64) -> u32 {
        let (dr, dc) = (r.abs_diff(self.target.0), c.abs_diff(self.target.1));
        let (lo, hi) = (dr.min(dc) as u32, dr.max(dc) as u32);
        if self.diagonals {
            (hi - lo) * STATIC_STRAIGHT + lo * STATIC_DIAGONAL
        } else {
            (hi + lo) * STATIC_STRAIGHT
        }
    }

    /// Expands the backward search until cell `index` is closed or nothing is left open.
    fn close(&mut self, grid: &Grid2, index: usize) {
        let free = |r: i64, c: i64| grid.is_free_at(r, c);
        let moves = moves(self.diagonals);
        let n = self.ring.len();
        while self.units[index] & CLOSED == 0 && self.pending > 0 {
            let slot = self.f as usize % n;
            let Some(i) = self.ring[slot].pop() else {
                self.f += 1;
                continue;
            };
            self.pending -= 1;
            let d = self.units[i as usize];
            let (r, c) = (
                (i as usize / self.cols) as i64,
                (i as usize % self.cols) as i64,
            );
            // Stale (closed already, or queued again at a lower f since).
            if d & CLOSED != 0 || d + self.octile_to_target(r, c) != self.f {
                continue;
            }
            self.units[i as usize] = d | CLOSED;
            for &(dr, dc) in moves {
                let (nr, nc) = (r + dr, c + dc);
                let diagonal = dr != 0 && dc != 0;
                // Moves are symmetric: the corner rule asks for the same two cells both ways.
                if !free(nr, nc) || (diagonal && !(free(r + dr, c) && free(r, nc))) {
                    continue;
                }
                let cost = if diagonal {
                    STATIC_DIAGONAL
                } else {
                    STATIC_STRAIGHT
                };
                let j = nr as usize * self.cols + nc as usize;
                let nd = d + cost;
                // A closed cell's distance is final (the heuristic is consistent).
                let known = self.units[j];
                if known & CLOSED == 0 && nd < known {
                    self.units[j] = nd;
                    let nf = nd + self.octile_to_target(nr, nc);
                    self.ring[nf as usize % n].push(j as u32);
                    self.pending += 1;
                }
            }
        }
    }

    /// Seconds at full speed from `c` to the goal at least; infinite if `c` is cut off from it.
    fn seconds(&mut self, grid: &Grid2, c: Cell, q: &SippQuery) -> f64 {
        if self.units.is_empty() {
            let dr = f64::from(c.row.abs_diff(q.goal.row));
            let dc = f64::from(c.col.abs_diff(q.goal.col));
            let octile = if q.diagonals {
                dr.max(dc) + (std::f64::consts::SQRT_2 - 1.0) * dr.min(dc)
            } else {
                dr + dc
            };
            return octile * q.cell_s;
        }
        let index = grid.index(c);
        if self.units[index] & CLOSED == 0 {
            self.close(grid, index);
        }
        match self.units[index] {
            u if u & CLOSED != 0 => f64::from(u & !CLOSED) * q.cell_s / f64::from(STATIC_STRAIGHT),
            _ => f64::INFINITY,
        }
    }
}

/// Whether `[from, to]` lies in one of `safe`.
fn within(safe: &[Interval], from: f64, to: f64) -> bool {
    safe.iter().any(|iv| iv.start_s <= from && to <= iv.end_s)
}

/// Moves waits in the air to the ground where the window allows: a wait at the start becomes a
/// later departure (up to the latest), and a wait further on moves to the start — the route
/// before it shifted later by the whole wait — when every cell of that part stays safe over
/// its shifted occupancy (from the move into it starting to the move out of it ending). The
/// arrival does not change; hovering only shrinks.
fn ground_waits(
    cells: &mut [TimedCell],
    latest_departure_s: f64,
    safe_of: &mut dyn FnMut(Cell) -> Vec<Interval>,
) {
    let Some(first) = cells.first_mut() else {
        return;
    };
    first.arrive_s = first.leave_s.min(latest_departure_s).max(first.arrive_s);
    for k in 1..cells.len().saturating_sub(1) {
        let wait = cells[k].leave_s - cells[k].arrive_s;
        if wait <= 0.0 || cells[0].arrive_s + wait > latest_departure_s {
            continue;
        }
        // The occupancy of cell j ≤ k after the shift.
        let ok = (0..=k).all(|j| {
            let from = if j == 0 {
                cells[0].arrive_s + wait
            } else {
                cells[j - 1].leave_s + wait
            };
            let to = if j == k {
                cells[k + 1].arrive_s
            } else {
                cells[j + 1].arrive_s + wait
            };
            within(&safe_of(cells[j].cell), from, to)
        });
        if ok {
            for c in cells[..k].iter_mut() {
                c.arrive_s += wait;
                c.leave_s += wait;
            }
            cells[k].arrive_s += wait;
        }
    }
}

fn walk_back(nodes: &[Node], goal: u32) -> Vec<TimedCell> {
    let mut out = Vec::new();
    let mut leave = nodes[goal as usize].arrive_s;
    let mut at = goal;
    while at != NONE {
        let n = &nodes[at as usize];
        out.push(TimedCell {
            cell: n.cell,
            arrive_s: n.arrive_s,
            leave_s: leave,
        });
        leave = n.left_parent_s;
        at = n.parent;
    }
    out.reverse();
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// A random grid (a quarter blocked) with random blocked times, fractional, per cell, and
    /// its free cells.
    fn random_case(rng: &mut rand_chacha::ChaCha8Rng) -> (Grid2, Vec<Vec<Interval>>, Vec<Cell>) {
        let (rows, cols) = (rng.random_range(3..12u32), rng.random_range(3..12u32));
        let cells: Vec<bool> = (0..rows * cols).map(|_| rng.random_bool(0.25)).collect();
        let grid =
            Grid2::new(rows, cols, cells, skyplan_cspace::GridFrame::default()).expect("grid");
        let blocked = (0..grid.len())
            .map(|_| {
                (0..rng.random_range(0..3))
                    .map(|_| {
                        let a = rng.random_range(0.0..15.0);
                        Interval {
                            start_s: a,
                            end_s: a + rng.random_range(0.0..5.0),
                        }
                    })
                    .collect()
            })
            .collect();
        let free = (0..grid.len())
            .map(|i| grid.cell(i))
            .filter(|&c| !grid.is_blocked(c))
            .collect();
        (grid, blocked, free)
    }

    /// A query between two of `free` (possibly the same) with a random speed, latest
    /// departure, horizon and moves.
    fn random_query(rng: &mut rand_chacha::ChaCha8Rng, free: &[Cell]) -> SippQuery {
        SippQuery {
            start: free[rng.random_range(0..free.len())],
            goal: free[rng.random_range(0..free.len())],
            cell_s: rng.random_range(0.3..1.5),
            latest_departure_s: rng.random_range(0.0..4.0),
            horizon_s: rng.random_range(5.0..40.0),
            diagonals: rng.random_bool(0.5),
            max_expansions: 1_000_000,
            deadline: None,
            exact_until: None,
        }
    }

    /// The grid-distance bound against an independent Dijkstra over the true move lengths: never
    /// above the true distance, within 41 / (29 √2) of it, infinite exactly where the goal is
    /// cut off.
    #[test]
    fn the_grid_distance_bound_is_below_the_true_distance_and_close() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut checked = (0, 0);
        for _ in 0..200 {
            let (grid, _, free) = random_case(&mut rng);
            let diagonals = rng.random_bool(0.5);
            if free.len() < 2 {
                continue;
            }
            let goal = free[rng.random_range(0..free.len())];
            let start = free[rng.random_range(0..free.len())];
            let q = SippQuery {
                start,
                goal,
                cell_s: 0.5,
                latest_departure_s: 0.0,
                horizon_s: 100.0,
                diagonals,
                max_expansions: 1_000,
                deadline: None,
                exact_until: None,
            };
            // Dijkstra from the goal, f64 lengths, over a sorted list (small grids).
            let mut dist = vec![f64::INFINITY; grid.len()];
            dist[grid.index(goal)] = 0.0;
            let mut done = vec![false; grid.len()];
            while let Some(u) = (0..grid.len())
                .filter(|&i| !done[i] && dist[i].is_finite())
                .min_by(|&a, &b| dist[a].total_cmp(&dist[b]))
            {
                done[u] = true;
                let c = grid.cell(u);
                let (r, k) = (i64::from(c.row), i64::from(c.col));
                for dr in -1..=1i64 {
                    for dk in -1..=1i64 {
                        let diagonal = dr != 0 && dk != 0;
                        if (dr, dk) == (0, 0) || (diagonal && !diagonals) {
                            continue;
                        }
                        let ok = grid.is_free_at(r + dr, k + dk)
                            && (!diagonal
                                || (grid.is_free_at(r + dr, k) && grid.is_free_at(r, k + dk)));
                        if ok {
                            let v = grid.index(Cell::new((r + dr) as u32, (k + dk) as u32));
                            let len = if diagonal {
                                std::f64::consts::SQRT_2
                            } else {
                                1.0
                            };
                            dist[v] = dist[v].min(dist[u] + len);
                        }
                    }
                }
            }
            let mut bound = StaticDistance::new(&grid, &q, Bound::GridDistance);
            // Ask in a random order: the backward search resumes for each.
            let mut asked: Vec<(u32, Cell)> = free
                .iter()
                .map(|&c| (rng.random_range(0..1000), c))
                .collect();
            asked.sort_by_key(|&(key, _)| key);
            for (_, c) in asked {
                let truth = dist[grid.index(c)] * q.cell_s;
                let got = bound.seconds(&grid, c, &q);
                if truth.is_infinite() {
                    assert!(got.is_infinite(), "{c:?}: {got} for a cut-off cell");
                    checked.1 += 1;
                } else {
                    assert!(got <= truth + 1e-12, "{c:?}: {got} above {truth}");
                    let floor = truth * (41.0 / 29.0) / std::f64::consts::SQRT_2;
                    assert!(got >= floor - 1e-12, "{c:?}: {got} below {floor}");
                    checked.0 += 1;
                }
            }
        }
        assert!(checked.0 > 3000 && checked.1 > 50, "{checked:?}");
    }

    /// Two admissible bounds, one search: the grid-distance bound finds the same earliest
    /// arrival as the obstacle-blind octile one, with diagonals and without, and refuses the
    /// same queries.
    #[test]
    fn the_grid_distance_bound_finds_the_octile_bound_s_arrival() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
        let (mut same, mut refused) = (0, 0);
        for case in 0..300 {
            let (grid, blocked, free) = random_case(&mut rng);
            if free.len() < 2 {
                continue;
            }
            let q = random_query(&mut rng, &free);
            let mut timeline = |c: Cell| blocked[grid.index(c)].clone();
            let a = sipp_with(&grid, &q, &mut timeline, Bound::GridDistance, None);
            let b = sipp_with(&grid, &q, &mut timeline, Bound::Octile, None);
            match (&a, &b) {
                (Ok(a), Ok(b)) => {
                    assert!(
                        (a.arrival_s() - b.arrival_s()).abs() < 1e-9,
                        "case {case}: {} against {}",
                        a.arrival_s(),
                        b.arrival_s()
                    );
                    same += 1;
                }
                (Err(SippError::NoRoute { .. }), Err(SippError::NoRoute { .. })) => refused += 1,
                _ => panic!("case {case}: {a:?} against {b:?}"),
            }
        }
        assert!(same > 100 && refused > 20, "{same} {refused}");
    }

    /// The integer keys order entries exactly as the search crate's open list does.
    #[test]
    fn the_queue_keys_order_as_the_open_entries() {
        use skyplan_search::OpenEntry;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let values = [0.0, -0.0, 1.0, 2.5, 1e-300, 1e300, -1.0, f64::INFINITY];
        let pick = |rng: &mut rand_chacha::ChaCha8Rng| {
            if rng.random_range(0..3) == 0 {
                values[rng.random_range(0..values.len())]
            } else {
                f64::from(rng.random_range(0..20u32)) * 0.25
            }
        };
        for _ in 0..20_000 {
            let a = OpenEntry {
                f: pick(&mut rng),
                g: pick(&mut rng),
                node: rng.random_range(0..4),
            };
            let b = OpenEntry {
                f: pick(&mut rng),
                g: pick(&mut rng),
                node: rng.random_range(0..4),
            };
            let (ka, kb) = (Queued::new(a.f, a.g, a.node), Queued::new(b.f, b.g, b.node));
            assert_eq!(ka.cmp(&kb), a.cmp(&b), "{a:?} {b:?}");
        }
    }

    #[test]
    fn a_passed_deadline_stops_the_search() {
        let grid = Grid2::new(60, 60, vec![false; 3600], Default::default()).expect("grid");
        let q = SippQuery {
            start: Cell::new(0, 0),
            goal: Cell::new(59, 59),
            cell_s: 1.0,
            latest_departure_s: 0.0,
            horizon_s: 1e4,
            diagonals: true,
            max_expansions: 1_000_000,
            deadline: None,
            exact_until: None,
        };
        // The goal is blocked for a long while: the search fans out over the whole grid.
        let mut timeline = |c: Cell| {
            if c == Cell::new(59, 59) {
                vec![Interval {
                    start_s: 0.0,
                    end_s: 500.0,
                }]
            } else {
                vec![]
            }
        };
        let free = sipp(&grid, &q, &mut timeline).expect("a route without a deadline");
        assert!(free.expansions > DEADLINE_EVERY, "{}", free.expansions);
        let passed = SippQuery {
            deadline: Some(std::time::Instant::now()),
            ..q
        };
        assert_eq!(
            sipp(&grid, &passed, &mut timeline),
            Err(SippError::Deadline(1))
        );
    }

    #[test]
    fn waits_move_to_the_ground_when_the_window_allows() {
        let grid = Grid2::from_ascii(".....").expect("grid");
        let mut timeline = |c: Cell| {
            if c.col == 2 {
                vec![Interval {
                    start_s: 0.0,
                    end_s: 10.0,
                }]
            } else {
                vec![]
            }
        };
        let q = |latest_departure_s| SippQuery {
            start: Cell::new(0, 0),
            goal: Cell::new(0, 4),
            cell_s: 1.0,
            latest_departure_s,
            horizon_s: 100.0,
            diagonals: true,
            max_expansions: 1000,
            deadline: None,
            exact_until: None,
        };
        // No window: it hovers short of the blocked cell.
        let air = sipp(&grid, &q(0.0), &mut timeline).expect("a route");
        assert!((air.hover_s() - 9.001).abs() < 1e-9 && air.departure_s() == 0.0);
        // A window: the same arrival, leaving later, no hovering.
        let ground = sipp(&grid, &q(20.0), &mut timeline).expect("a route");
        assert!((ground.arrival_s() - 13.001).abs() < 1e-9);
        assert!((ground.departure_s() - 9.001).abs() < 1e-9 && ground.hover_s() == 0.0);
        // Too short a window for the whole wait: it stays in the air.
        let short = sipp(&grid, &q(5.0), &mut timeline).expect("a route");
        assert!((short.arrival_s() - 13.001).abs() < 1e-9 && short.hover_s() > 0.0);
    }

    /// The route moves between neighbours (no corner cutting, each move its length over the
    /// speed), starts within the window, ends by the horizon, and each cell it occupies — from
    /// the move into it starting to the move out of it ending — is safe over all of it.
    fn assert_safe_route(
        grid: &Grid2,
        blocked: &[Vec<Interval>],
        q: &SippQuery,
        path: &SippPath,
        case: usize,
    ) {
        let cells = &path.cells;
        assert_eq!(cells.first().map(|c| c.cell), Some(q.start), "case {case}");
        assert_eq!(cells.last().map(|c| c.cell), Some(q.goal), "case {case}");
        assert!(path.departure_s() >= 0.0 && path.departure_s() <= q.latest_departure_s + 1e-9);
        assert!(path.arrival_s() <= q.horizon_s + 1e-6, "case {case}");
        for w in cells.windows(2) {
            let (a, b) = (w[0].cell, w[1].cell);
            let (dr, dc) = (
                i64::from(b.row) - i64::from(a.row),
                i64::from(b.col) - i64::from(a.col),
            );
            assert!(
                dr.abs() <= 1 && dc.abs() <= 1 && (dr, dc) != (0, 0),
                "case {case}"
            );
            let diagonal = dr != 0 && dc != 0;
            assert!(!diagonal || q.diagonals, "case {case}");
            let (r, c) = (i64::from(a.row), i64::from(a.col));
            assert!(
                grid.is_free_at(r + dr, c + dc),
                "case {case}: into a blocked cell"
            );
            assert!(
                !diagonal || (grid.is_free_at(r + dr, c) && grid.is_free_at(r, c + dc)),
                "case {case}: cuts a corner"
            );
            let len = if diagonal {
                std::f64::consts::SQRT_2
            } else {
                1.0
            };
            assert!(
                (w[1].arrive_s - w[0].leave_s - len * q.cell_s).abs() < 1e-9,
                "case {case}: a move's time"
            );
        }
        for (j, c) in cells.iter().enumerate() {
            let from = if j == 0 {
                c.arrive_s
            } else {
                cells[j - 1].leave_s
            };
            let to = cells.get(j + 1).map_or(c.arrive_s, |n| n.arrive_s);
            let safe = safe_intervals(&merge_intervals(blocked[grid.index(c.cell)].clone()));
            assert!(
                within(&safe, from, to),
                "case {case}: cell {j} occupied over [{from}, {to}] outside its safe intervals"
            );
        }
    }

    /// The proof stopped at every state of the exact search in turn (and once past its end):
    /// a route exactly when the exact search has one, safe, never before the earliest arrival,
    /// with a bound never above it, "proven" only when it is the earliest; no route when there
    /// is none.
    #[test]
    fn stopping_the_proof_at_any_state_gives_a_safe_route_and_a_true_bound() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(13);
        let (mut runs, mut later, mut mid_search) = (0, 0, 0);
        for case in 0..300 {
            let (grid, blocked, free) = random_case(&mut rng);
            if free.len() < 2 {
                continue;
            }
            let q = random_query(&mut rng, &free);
            let mut timeline = |c: Cell| blocked[grid.index(c)].clone();
            let exact = sipp_with(&grid, &q, &mut timeline, Bound::GridDistance, None);
            let states = match &exact {
                Ok(p) => p.expansions,
                Err(SippError::NoRoute { expansions, .. }) => *expansions,
                Err(e) => panic!("case {case}: {e}"),
            };
            for k in 1..=states + 1 {
                let got = sipp_with(&grid, &q, &mut timeline, Bound::GridDistance, Some(k));
                runs += 1;
                match (&exact, got) {
                    (Ok(e), Ok(p)) => {
                        let earliest = e.arrival_s();
                        assert_safe_route(&grid, &blocked, &q, &p, case);
                        assert!(p.arrival_s() >= earliest - 1e-9, "case {case}, k {k}");
                        assert!(
                            p.earliest_bound_s <= earliest + 1e-9,
                            "case {case}, k {k}: bound {} above the earliest {earliest}",
                            p.earliest_bound_s
                        );
                        if p.proven_earliest() {
                            assert!((p.arrival_s() - earliest).abs() < 1e-9, "case {case}");
                        } else {
                            later += 1;
                            mid_search += usize::from(k > 1);
                        }
                    }
                    (Err(SippError::NoRoute { .. }), Err(SippError::NoRoute { .. })) => {}
                    (e, g) => panic!("case {case}, k {k}: exact {e:?}, stopped {g:?}"),
                }
            }
        }
        assert!(
            runs > 2000 && later > 100 && mid_search > 50,
            "{runs} runs, {later} later, {mid_search} stopped mid-search"
        );
    }

    #[test]
    fn safe_intervals_leave_gaps_around_the_blocked_ones() {
        let iv = |start_s, end_s| Interval { start_s, end_s };
        let safe = safe_intervals(&[iv(0.0, 1.0), iv(3.0, 4.0)]);
        assert_eq!(safe.len(), 3);
        assert_eq!(safe[0].end_s, -GAP_S);
        assert_eq!((safe[1].start_s, safe[1].end_s), (1.0 + GAP_S, 3.0 - GAP_S));
        assert_eq!(safe[2].start_s, 4.0 + GAP_S);
        assert!(safe[2].end_s.is_infinite());
    }
}

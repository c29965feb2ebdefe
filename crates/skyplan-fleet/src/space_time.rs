//! Planning around the others in space and time: a plan's flight re-routed on its grid by
//! [`crate::sipp`] with the stored intents as moving obstacles — a later departure, hovering
//! and detours allowed, the earliest arrival the objective — then its volumes reserved with the
//! store's exact check-and-insert.
//!
//! **Why the search's answer passes the exact check.** The route's volumes are cut every
//! [`STRETCH_S`] and wherever a point would stray more than `δ` ([`BULGE_CELLS`] of a cell) from
//! the straight line between a stretch's ends ([`volumes_hugging_path`]), so each volume's
//! footprint is within `2δ` of the route flown in its stretch, grown by the lateral margin `L`
//! (an 8-gon circumscribing the disc, so no wider than `L / cos 22.5°`), and its time window is
//! that stretch's times grown by the time buffer `B`. A stored volume meets it only if some point
//! of the stretch's route is within that width of the stored footprint while the windows
//! overlap; that point is within half a cell's diagonal of a cell the flight is in at that
//! moment, at a time within `B + STRETCH_S` of the stored window. So each cell is blocked, for
//! the search, over each stored window grown by `B + STRETCH_S` (and a millisecond for
//! rounding) when its centre is within `L / cos 22.5° + half a diagonal + 2δ` (and [`SLACK_M`]
//! for the projections) of the stored footprint, and the altitude bands overlap.
//!
//! **Why the search knows every intent in its way.** The store is read around the planned
//! route, grown by [`READ_REACH_M`]; the search keeps to the cells whose centres are within
//! that distance less the reach above, so any stored volume that could block one of them
//! reaches into the footprint read. The check-and-insert is still the judge; an intent it
//! names that the read missed (stored meanwhile, by another request or server) is added and the
//! search run again.

use crate::flight::FlightRequest;
use crate::sipp::{Interval, SippError, SippQuery, TimedCell, sipp};
use foldhash::{HashMap, HashMapExt};
use skyplan_airspace::{
    AirspaceError, FlightVolumes, IntentRef, IntentState, OperationalIntent, Timestamp, Timing,
    Volume4D, volumes_from_plan, volumes_hugging_path,
};
use skyplan_airspace_store::{Insert, IntentStore, RESERVE_TRIES, ReserveError, StoredRow, new_id};
use skyplan_cspace::{Cell, Grid2};
use skyplan_frames::{Lla, LocalFrame};
use skyplan_map::nofly::Zone;
use skyplan_plan::Plan;

/// Longest stretch of time in one volume of a space-time route, seconds.
pub const STRETCH_S: f64 = 5.0;
/// Longest stretch of a space-time route in one volume, metres.
pub const STRETCH_M: f64 = 50.0;
/// Added to the distance at which a stored footprint blocks a cell, metres: the projections
/// between latitude/longitude and the map's frame (a few millimetres over a city).
pub const SLACK_M: f64 = 0.5;
/// How far a volume's stretch of route may stray from the straight line between its ends, in
/// cells. 0: a volume per straight piece. Measured on 100 random flights on the city, half a
/// cell gave 13 % fewer volumes (the 5 s cut makes most of them) but 24 % more arrival delay
/// (twice the bulge is kept from the others as well).
pub const BULGE_CELLS: f64 = 0.0;
/// How far around the planned route stored intents are read, metres; the search keeps within
/// it (less the reach of a blocked cell), so it never routes through sky it has not read. On
/// 1,000 random flights over the 3 × 3 tiled city (`fleet --random 1000 --space-time`), 600 m
/// planned 97.3 % of them at p99 384 ms where an unbounded search planned 98.1 % at p99 3.3 s
/// (its tail: searches across the whole map, then retries because their routes ran through
/// intents never read); 300 m planned 93.5 % at p99 210 ms.
pub const READ_REACH_M: f64 = 600.0;
/// The cell size the fleet searches in space and time on (or the plan's, if coarser), metres:
/// far coarser than the lateral margin would not pay, finer costs time for nothing.
pub const SEARCH_CELL_M: f64 = 4.0;
/// The search's budget of states.
pub const MAX_EXPANSIONS: usize = 4_000_000;

/// With a deadline ([`FlightRequest::deadline`]), the share of the time left to it that the
/// search spends proving the earliest arrival; after that it heads for the goal
/// ([`SippQuery::exact_until`]).
pub const EXACT_SHARE: f64 = 0.5;
/// With a deadline, the share of the time left to it after which the search gives up: the
/// rest is for checking and storing the route found.
pub const SEARCH_SHARE: f64 = 0.8;

/// The instant `share` of the way from now to `deadline`, if there is one.
fn share_of_time_left(
    deadline: Option<std::time::Instant>,
    share: f64,
) -> Option<std::time::Instant> {
    deadline.map(|d| {
        let now = std::time::Instant::now();
        now + d.saturating_duration_since(now).mul_f64(share)
    })
}

/// A flight reserved along a space-time route.
#[derive(Debug, Clone)]
pub struct SpaceTimeFlight {
    /// The intent stored.
    pub intent: OperationalIntent,
    /// Its departure.
    pub departure: Timestamp,
    /// Milliseconds after the window's earliest departure.
    pub delay_ms: i64,
    /// Seconds hovering after departure.
    pub hover_s: f64,
    /// Metres longer than the same search's route in an empty sky.
    pub detour_m: f64,
    /// Seconds later at the goal than the same search's route in an empty sky, leaving at
    /// the window's start.
    pub arrival_delay_s: f64,
    /// At most this many seconds later at the goal than the earliest arrival possible: 0 when
    /// the search proved its arrival the earliest, which it does unless a deadline made it stop
    /// proving part way ([`SippQuery::exact_until`]).
    pub arrival_gap_s: f64,
    /// The empty sky's shortest route on the same grid, metres (cell centre to cell centre).
    pub alone_m: f64,
    /// The route flown: corners and hover points, `[north_m, east_m, alt_m]`.
    pub route_nea: Vec<[f64; 3]>,
    /// The route flown cell by cell with its times, seconds after `departure`.
    pub path: Vec<skyplan_airspace::TimedPoint>,
    /// Its volumes (departure at the epoch) and duration.
    pub flight: FlightVolumes,
    /// States the last search took from its queue.
    pub expansions: usize,
    /// Stored intents read near the flight.
    pub nearby: usize,
    /// Searches run.
    pub tries: usize,
}

impl SpaceTimeFlight {
    /// What the search did, as the HTTP API and Python report it: `hover_s`, `detour_m`,
    /// `arrival_delay_s`, `arrival_gap_s` and `route_ne` (`[north_m, east_m]` corners and hover
    /// points).
    pub fn search_json(&self) -> serde_json::Value {
        serde_json::json!({
            "hover_s": self.hover_s,
            "detour_m": self.detour_m,
            "arrival_delay_s": self.arrival_delay_s,
            "arrival_gap_s": self.arrival_gap_s,
            "route_ne": self.route_nea.iter().map(|p| [p[0], p[1]]).collect::<Vec<_>>(),
        })
    }
}

/// Where the space-time search may go: its grid and the no-fly zones it keeps out of.
#[derive(Debug, Clone)]
pub struct SearchSpace {
    /// The plan's map at its altitude and margin in cells of [`SEARCH_CELL_M`] (or the plan's
    /// own, if coarser), with the request's no-fly zones that have no time window (and every
    /// inclusion boundary) blocked.
    pub grid: std::sync::Arc<Grid2>,
    /// The request's no-fly zones in the map's frame: the route found is checked against them
    /// exactly before it is reserved, each while it is active.
    pub zones: Vec<Zone>,
    /// The exclusion zones with a time window, by their index in `zones`, and the grid cells
    /// each blocks while active (cell indices, row-major).
    pub timed: Vec<(usize, Vec<u32>)>,
    /// The plan's margin, metres.
    pub margin_m: f64,
}

/// Where the space-time search runs for `plan` of `request`, from `session` (the map's grid
/// built once there); `None` for a plan without a grid (the 3D planners).
pub fn search_grid(
    session: &mut skyplan_plan::Session,
    request: &skyplan_plan::PlanRequest,
    plan: &Plan,
) -> Result<Option<SearchSpace>, skyplan_plan::PlanFailure> {
    let Some(g) = plan.grid else {
        return Ok(None);
    };
    let cell_m = g.cell_m.max(SEARCH_CELL_M);
    let map = session.grid(g.alt_m, g.safety_m, cell_m)?;
    let zones = session.zones_for(request)?;
    let spec = skyplan_cspace::GridSpec {
        alt_m: g.alt_m,
        safety_m: g.safety_m,
        cell_m,
    };
    let bad = |e: skyplan_cspace::GridError| {
        skyplan_plan::PlanFailure::bad_request(format!("no_fly: {e}"))
    };
    let is_timed = |z: &Zone| !z.inclusion && (z.start_unix_s.is_some() || z.end_unix_s.is_some());
    let fixed: Vec<Zone> = zones.iter().filter(|z| !is_timed(z)).cloned().collect();
    // The map's own grid, kept by the session, unless some untimed zones are blocked on a copy.
    let grid = if fixed.is_empty() {
        std::sync::Arc::clone(&map)
    } else {
        let mut grid = map.as_ref().clone();
        grid.block_zones(&fixed, spec).map_err(bad)?;
        std::sync::Arc::new(grid)
    };
    let mut timed = Vec::new();
    for (k, z) in zones.iter().enumerate().filter(|(_, z)| is_timed(z)) {
        let mut alone = Grid2::new(
            map.rows(),
            map.cols(),
            vec![false; map.blocked_cells().len()],
            map.frame(),
        )
        .map_err(bad)?;
        alone
            .block_zones(std::slice::from_ref(z), spec)
            .map_err(bad)?;
        let cells: Vec<u32> = (alone.blocked_cells().iter().enumerate())
            .filter(|(_, b)| **b)
            .map(|(i, _)| i as u32)
            .collect();
        timed.push((k, cells));
    }
    Ok(Some(SearchSpace {
        grid,
        zones,
        timed,
        margin_m: g.safety_m,
    }))
}

/// The first zone (feature index, clearance) the timed route at `alt_m` keeps less than the
/// margin from while the zone is active (`departure_unix_s` + the points' times against its
/// window): an exclusion zone whose band grown by the margin holds the altitude and that the
/// route nears; an inclusion boundary whose band shrunk by the margin does not hold the
/// altitude, that the route starts outside of, or whose boundary it nears.
fn zone_in_the_way(
    path: &[skyplan_airspace::TimedPoint],
    departure_unix_s: f64,
    zones: &[Zone],
    alt_m: f64,
    margin_m: f64,
) -> Option<(usize, f64)> {
    // A millimetre for the projections' rounding.
    let enough = margin_m - 1e-3;
    for z in zones {
        // Whether the zone is active at some moment of the stretch from `a` to `b`.
        let active = |a: f64, b: f64| {
            let (from, to) = (departure_unix_s + a, departure_unix_s + b);
            z.start_unix_s.is_none_or(|s| (s as f64) <= to)
                && z.end_unix_s.is_none_or(|e| (e as f64) > from)
        };
        let segments = || {
            path.windows(2)
                .filter(|w| active(w[0].t_s, w[1].t_s))
                .map(|w| ([w[0].nea[0], w[0].nea[1]], [w[1].nea[0], w[1].nea[1]]))
        };
        let (bad, clearance) = if z.inclusion {
            let inside = (path.first())
                .is_some_and(|p| z.clearance_m([p.nea[0], p.nea[1]], [p.nea[0], p.nea[1]]) == 0.0);
            let c = segments()
                .map(|(a, b)| z.boundary_clearance_m(a, b))
                .fold(f64::INFINITY, f64::min);
            (
                !z.holds_altitude(alt_m, margin_m) || !inside || c < enough,
                c,
            )
        } else {
            let c = segments()
                .map(|(a, b)| z.clearance_m(a, b))
                .fold(f64::INFINITY, f64::min);
            (z.meets_altitude(alt_m, margin_m) && c < enough, c)
        };
        if bad {
            return Some((z.feature, clearance));
        }
    }
    None
}

/// A stored volume as the search sees it: its footprint in the map's frame and its grown
/// time window, seconds after the window's start.
struct Obstacle {
    /// The footprint's convex hull, counter-clockwise.
    ring_ne: Vec<[f64; 2]>,
    /// Each hull edge's outward unit normal `u` and offset `u · a`: the largest `u · p − c`
    /// is a lower bound of the distance outside and ≤ 0 inside.
    edges: Vec<([f64; 2], f64)>,
    bbox_ne: [f64; 4],
    blocked: Interval,
}

impl Obstacle {
    fn new(points: &[[f64; 2]], blocked: Interval) -> Self {
        let ring_ne = skyplan_airspace::geometry::convex_hull(points);
        let n = ring_ne.len();
        let edges = if n >= 3 {
            (0..n)
                .filter_map(|i| {
                    let (a, b) = (ring_ne[i], ring_ne[(i + 1) % n]);
                    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                    let len = dx.hypot(dy);
                    (len > 0.0).then(|| {
                        let u = [dy / len, -dx / len];
                        (u, u[0] * a[0] + u[1] * a[1])
                    })
                })
                .collect()
        } else {
            Vec::new()
        };
        let bbox_ne = ring_ne.iter().fold(
            [
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            ],
            |b, p| {
                [
                    b[0].min(p[0]),
                    b[1].min(p[1]),
                    b[2].max(p[0]),
                    b[3].max(p[1]),
                ]
            },
        );
        Self {
            ring_ne,
            edges,
            bbox_ne,
            blocked,
        }
    }

    /// Whether a cell centred at `(n, e)` is within `r` of the footprint: its box first.
    fn blocks(&self, n: f64, e: f64, r: f64) -> bool {
        n >= self.bbox_ne[0] - r
            && n <= self.bbox_ne[2] + r
            && e >= self.bbox_ne[1] - r
            && e <= self.bbox_ne[3] + r
            && self.near([n, e], r)
    }

    /// Whether `p` is within `r` of the footprint. Squared distances (no square roots: this
    /// runs for every candidate volume of every cell the search reaches).
    fn near(&self, p: [f64; 2], r: f64) -> bool {
        if self.edges.is_empty() {
            // A point or a segment: no inside.
            return ring_distance2(&self.ring_ne, p) <= r * r;
        }
        let outside = self
            .edges
            .iter()
            .map(|(u, c)| u[0] * p[0] + u[1] * p[1] - c)
            .fold(f64::NEG_INFINITY, f64::max);
        // Outside the convex hull, its distance is the nearest edge's.
        outside <= 0.0 || (outside <= r && ring_distance2(&self.ring_ne, p) <= r * r)
    }
}

/// The squared distance from `p` to the nearest edge of a closed ring (its vertices for one or
/// two points).
fn ring_distance2(ring: &[[f64; 2]], p: [f64; 2]) -> f64 {
    let n = ring.len();
    let mut best = f64::INFINITY;
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        best = best.min(skyplan_map::planar::point_segment2_m2(p, a, b));
    }
    best
}

/// Side of the square buckets the obstacles are filed in, metres.
const BUCKET_M: f64 = 32.0;

/// The stored volumes that bind the flight and share its altitudes, as obstacles, filed by
/// the buckets their footprint grown by the reach touches.
struct Obstacles {
    list: Vec<Obstacle>,
    reach_m: f64,
    buckets: HashMap<(i64, i64), Vec<u32>>,
}

fn bucket_of(m: f64) -> i64 {
    (m / BUCKET_M).floor() as i64
}

impl Obstacles {
    fn new(reach_m: f64) -> Self {
        Self {
            list: Vec::new(),
            reach_m,
            buckets: HashMap::new(),
        }
    }

    fn clear(&mut self) {
        self.list.clear();
        self.buckets.clear();
    }

    fn file(&mut self, o: Obstacle) {
        let r = self.reach_m;
        let id = self.list.len() as u32;
        let (n0, n1) = (bucket_of(o.bbox_ne[0] - r), bucket_of(o.bbox_ne[2] + r));
        let (e0, e1) = (bucket_of(o.bbox_ne[1] - r), bucket_of(o.bbox_ne[3] + r));
        for bn in n0..=n1 {
            for be in e0..=e1 {
                self.buckets.entry((bn, be)).or_default().push(id);
            }
        }
        self.list.push(o);
    }

    /// Adds the volumes of `intent` that share the band `[lo, hi]` (W84 metres).
    fn add(
        &mut self,
        intent: &OperationalIntent,
        band: (f64, f64),
        frame: &LocalFrame,
        t0: Timestamp,
        pad_s: f64,
    ) -> Result<(), AirspaceError> {
        for v in &intent.volumes {
            if v.volume.altitude_upper.value < band.0 || v.volume.altitude_lower.value > band.1 {
                continue;
            }
            let points = outline_ne(frame, v)?;
            let s = |t: &skyplan_airspace::Time| t.value.ms_since(t0) as f64 / 1000.0;
            self.file(Obstacle::new(
                &points,
                Interval {
                    start_s: s(&v.time_start) - pad_s,
                    end_s: s(&v.time_end) + pad_s,
                },
            ));
        }
        Ok(())
    }

    /// When the cell centred at `(n, e)` is blocked.
    fn blocked_at(&self, n: f64, e: f64) -> Vec<Interval> {
        let r = self.reach_m;
        let Some(ids) = self.buckets.get(&(bucket_of(n), bucket_of(e))) else {
            return Vec::new();
        };
        ids.iter()
            .map(|&k| &self.list[k as usize])
            .filter(|o| o.blocks(n, e, r))
            .map(|o| o.blocked)
            .collect()
    }
}

/// The search's clock and the stretch of time it can use.
#[derive(Debug, Clone, Copy)]
struct SearchWindow {
    /// Time 0 of the search, Unix milliseconds.
    t0_ms: i64,
    /// How much each stored window is grown, seconds.
    pad_s: f64,
    /// The first and last moment the search can use, Unix milliseconds.
    from_ms: i64,
    to_ms: i64,
}

/// When each cell is blocked for one search: the stored intents (cached, and those read
/// since) and the timed no-fly zones.
struct SkyTimeline<'a> {
    grid: &'a Grid2,
    obstacles: &'a Obstacles,
    cache: Option<&'a SpaceTimeCache>,
    band: (f64, f64),
    window: &'a SearchWindow,
    zone_times: &'a HashMap<u32, Vec<Interval>>,
}

impl crate::sipp::Timeline for SkyTimeline<'_> {
    fn blocked(&mut self, cell: Cell) -> Vec<Interval> {
        let mut out = Vec::new();
        self.blocked_into(cell, &mut out);
        out
    }

    fn blocked_into(&mut self, cell: Cell, out: &mut Vec<Interval>) {
        let index = self.grid.index(cell) as u32;
        if !self.obstacles.list.is_empty() {
            let (n, e) = self.grid.center_ne(cell);
            out.extend(self.obstacles.blocked_at(n, e));
        }
        if let Some(cache) = self.cache {
            cache.blocked(index, self.band, self.window, out);
        }
        if let Some(zoned) = self.zone_times.get(&index) {
            out.extend_from_slice(zoned);
        }
    }
}

/// Most stored intents a [`SpaceTimeCache::new`] keeps (about 100 to 150 kB each on the
/// bundled city); past it, those named longest ago go, down to half.
pub const CACHE_INTENTS: usize = 2048;

/// A stored volume as the cache keeps it: its band (W84 metres) and window (Unix ms).
#[derive(Debug, Clone, Copy)]
struct CachedVolume {
    lower_m: f64,
    upper_m: f64,
    start_ms: i64,
    end_ms: i64,
}

/// A cached intent: what decides whether it binds (its volumes left out), and its volumes.
#[derive(Debug)]
struct CachedIntent {
    row: StoredRow,
    head: OperationalIntent,
    volumes: Vec<CachedVolume>,
}

/// What a cache's rasters were made for: the map's home, the grid's frame and size and the
/// distance at which a footprint blocks a cell (bit patterns: any change starts afresh).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct CacheKey {
    home: [u64; 2],
    frame: [u64; 3],
    size: [u32; 2],
    reach: u64,
}

/// Stored intents decoded, converted to the map's frame and rasterised on the space-time
/// search's grid, kept between the searches of [`reserve_space_time_cached`] (a fleet run
/// keeps one): each cell lists the stored volumes whose footprint is within the search's
/// reach of its centre (the exact test of the uncached search, made once per volume), so the
/// search looks a cell's blocked times up instead of testing geometry.
///
/// Keyed by the store's rows ([`StoredRow`]: never rewritten nor reused), so a cached intent
/// is never stale; an intent no longer stored is simply never named by the store again (and
/// goes when the cache is full, [`CACHE_INTENTS`]). It only saves time: what is reserved is
/// still checked exactly against the store in its check-and-insert.
#[derive(Debug)]
pub struct SpaceTimeCache {
    capacity: usize,
    key: Option<CacheKey>,
    reach_m: f64,
    by_row: HashMap<StoredRow, u32>,
    slots: Vec<Option<CachedIntent>>,
    free: Vec<u32>,
    /// Per slot: the request that last named it, the last in which it binds, and whether
    /// then every volume of it met the flight's band.
    named: Vec<u64>,
    binding: Vec<u64>,
    in_band: Vec<bool>,
    /// Per grid cell (row-major index): the volumes that block it, in order of their starts.
    cells: CellLists,
    request: u64,
    /// The empty sky's search, kept so its tables of the grid are built once.
    alone: skyplan_search::GridSearch,
}

impl Default for SpaceTimeCache {
    fn default() -> Self {
        Self::with_capacity(CACHE_INTENTS)
    }
}

impl SpaceTimeCache {
    /// An empty cache of up to [`CACHE_INTENTS`] intents.
    pub fn new() -> Self {
        Self::default()
    }

    /// An empty cache of up to `capacity` intents (more while one search needs them).
    pub fn with_capacity(capacity: usize) -> Self {
        Self {
            capacity,
            key: None,
            reach_m: 0.0,
            by_row: HashMap::new(),
            slots: Vec::new(),
            free: Vec::new(),
            named: Vec::new(),
            binding: Vec::new(),
            in_band: Vec::new(),
            alone: skyplan_search::GridSearch::new(),
            cells: CellLists::default(),
            request: 0,
        }
    }

    /// Stored intents kept.
    pub fn len(&self) -> usize {
        self.by_row.len()
    }

    /// Whether it keeps none.
    pub fn is_empty(&self) -> bool {
        self.by_row.is_empty()
    }

    /// Made for this map's `home`, `grid` and `reach_m`: emptied if it was for others.
    fn bind(&mut self, home: &skyplan_plan::Home, grid: &Grid2, reach_m: f64) {
        let f = grid.frame();
        let key = CacheKey {
            home: [home.lat_deg.to_bits(), home.lon_deg.to_bits()],
            frame: [
                f.origin_north_m.to_bits(),
                f.origin_east_m.to_bits(),
                f.cell_m.to_bits(),
            ],
            size: [grid.rows(), grid.cols()],
            reach: reach_m.to_bits(),
        };
        if self.key != Some(key) {
            *self = Self {
                key: Some(key),
                reach_m,
                request: self.request,
                cells: CellLists::for_grid(grid.len()),
                ..Self::with_capacity(self.capacity)
            };
        }
    }

    /// Reads, converts and rasterises the intents of `rows` not kept yet; makes room first.
    fn refresh(
        &mut self,
        store: &dyn IntentStore,
        rows: &[StoredRow],
        frame: &LocalFrame,
        grid: &Grid2,
    ) -> Result<(), ReserveError> {
        self.request += 1;
        let missing: Vec<i64> = rows
            .iter()
            .filter(|r| !self.by_row.contains_key(*r))
            .map(|r| r.row)
            .collect();
        if self.by_row.len() + missing.len() > self.capacity {
            self.evict(rows, self.capacity / 2);
        }
        if missing.is_empty() {
            return Ok(());
        }
        let named: HashMap<i64, &StoredRow> = rows.iter().map(|r| (r.row, r)).collect();
        for (row, intent) in store.get_rows(&missing)? {
            // The row read is the one named (rows are never rewritten; checked all the same).
            let Some(&stored) = named.get(&row) else {
                continue;
            };
            if stored.id != intent.id || stored.version != intent.version {
                continue;
            }
            self.insert(stored.clone(), intent, frame, grid)
                .map_err(ReserveError::Invalid)?;
        }
        Ok(())
    }

    fn insert(
        &mut self,
        row: StoredRow,
        mut intent: OperationalIntent,
        frame: &LocalFrame,
        grid: &Grid2,
    ) -> Result<(), AirspaceError> {
        let slot = match self.free.pop() {
            Some(s) => s,
            None => {
                self.slots.push(None);
                self.named.push(0);
                self.binding.push(0);
                self.in_band.push(false);
                (self.slots.len() - 1) as u32
            }
        };
        let volumes = std::mem::take(&mut intent.volumes);
        let mut kept = Vec::with_capacity(volumes.len());
        let mut footprints = Vec::with_capacity(volumes.len());
        for v in &volumes {
            let points = outline_ne(frame, v)?;
            kept.push(CachedVolume {
                lower_m: v.volume.altitude_lower.value,
                upper_m: v.volume.altitude_upper.value,
                start_ms: v.time_start.value.unix_ms(),
                end_ms: v.time_end.value.unix_ms(),
            });
            footprints.push(Obstacle::new(
                &points,
                Interval {
                    start_s: 0.0,
                    end_s: 0.0,
                },
            ));
        }
        self.slots[slot as usize] = Some(CachedIntent {
            row: row.clone(),
            head: intent,
            volumes: kept,
        });
        // In each cell, the intent's volumes of one band whose windows overlap make one
        // entry over their windows' union: the union of their grown windows, the same blocked
        // times (consecutive volumes overlap by the time buffer; a cell near the route is in
        // two or three of them).
        let volumes = self.slots[slot as usize]
            .as_ref()
            .map_or(&[][..], |c| &c.volumes);
        let mut open: HashMap<u32, CellEntry> = HashMap::new();
        let mut done: Vec<(u32, CellEntry)> = Vec::new();
        for (k, (o, v)) in footprints.iter().zip(volumes).enumerate() {
            let entry = CellEntry {
                start_ms: v.start_ms,
                end_ms: v.end_ms,
                slot,
                volume: k as u32,
            };
            rasterise(o, self.reach_m, grid, |index| match open.get_mut(&index) {
                Some(e)
                    if same_band(&volumes[e.volume as usize], v)
                        && e.start_ms.max(v.start_ms) <= e.end_ms.min(v.end_ms) =>
                {
                    e.start_ms = e.start_ms.min(v.start_ms);
                    e.end_ms = e.end_ms.max(v.end_ms);
                }
                Some(e) => done.push((index, std::mem::replace(e, entry))),
                None => {
                    open.insert(index, entry);
                }
            });
        }
        done.extend(open);
        // Each cell's list kept in order of the entries' starts: the search's timelines then
        // come sorted (and merging them costs no sort).
        for (index, entry) in done {
            self.cells.longest_ms = self
                .cells
                .longest_ms
                .max(entry.end_ms.saturating_sub(entry.start_ms));
            let list = self.cells.list_mut(index);
            let at = list.partition_point(|e| e.start_ms <= entry.start_ms);
            list.insert(at, entry);
        }
        self.named[slot as usize] = self.request;
        self.binding[slot as usize] = 0;
        self.by_row.insert(row, slot);
        Ok(())
    }

    /// Drops the intents not named in `rows`, longest unnamed first, down to `keep`.
    fn evict(&mut self, rows: &[StoredRow], keep: usize) {
        let current: foldhash::HashSet<&StoredRow> = rows.iter().collect();
        let mut old: Vec<(u64, u32)> = self
            .by_row
            .iter()
            .filter(|(r, _)| !current.contains(r))
            .map(|(_, &s)| (self.named[s as usize], s))
            .collect();
        old.sort_unstable();
        let excess = self.by_row.len().saturating_sub(keep);
        let mut dead = vec![false; self.slots.len()];
        for &(_, s) in old.iter().take(excess) {
            dead[s as usize] = true;
            if let Some(c) = self.slots[s as usize].take() {
                self.by_row.remove(&c.row);
            }
            self.free.push(s);
        }
        self.cells.retain(|e| !dead[e.slot as usize]);
    }

    /// Marks the intents of `rows` this request; those `binds` accepts block the search, with
    /// their volumes that meet `band` (W84 metres).
    fn select(
        &mut self,
        rows: &[StoredRow],
        band: (f64, f64),
        mut binds: impl FnMut(&OperationalIntent) -> bool,
    ) {
        for r in rows {
            // A row deleted between the two reads is not kept: nothing to block.
            let Some(&slot) = self.by_row.get(r) else {
                continue;
            };
            let Some(c) = &self.slots[slot as usize] else {
                continue;
            };
            self.named[slot as usize] = self.request;
            if binds(&c.head) {
                self.binding[slot as usize] = self.request;
                self.in_band[slot as usize] = c.volumes.iter().all(|v| meets(v, band));
            }
        }
    }

    /// Adds to `out` when the cell of row-major `index` is blocked by this request's binding
    /// intents' volumes that meet `band` (W84 metres): their windows in seconds after `t0_ms`,
    /// grown by `pad_s`.
    fn blocked(
        &self,
        index: u32,
        band: (f64, f64),
        window: &SearchWindow,
        out: &mut Vec<Interval>,
    ) {
        let (t0_ms, pad_s) = (window.t0_ms, window.pad_s);
        let list = self.cells.list(index);
        // The list is in order of starts: only the entries starting in the search's window
        // (grown by the pad), or up to the longest entry before it, can reach into it.
        let pad_ms = (pad_s * 1000.0).ceil() as i64;
        let from_ms = window.from_ms.saturating_sub(pad_ms);
        let to_ms = window.to_ms.saturating_add(pad_ms);
        let earliest_start_ms = from_ms.saturating_sub(self.cells.longest_ms);
        let first = list.partition_point(|e| e.start_ms < earliest_start_ms);
        let last = list.partition_point(|e| e.start_ms <= to_ms);
        for e in &list[first..last.max(first)] {
            if e.end_ms < from_ms {
                continue;
            }
            let slot = e.slot as usize;
            if self.binding[slot] != self.request {
                continue;
            }
            if !self.in_band[slot] {
                let Some(c) = &self.slots[slot] else {
                    continue;
                };
                if !meets(&c.volumes[e.volume as usize], band) {
                    continue;
                }
            }
            out.push(Interval {
                start_s: (e.start_ms - t0_ms) as f64 / 1000.0 - pad_s,
                end_s: (e.end_ms - t0_ms) as f64 / 1000.0 + pad_s,
            });
        }
    }
}

/// Grids of up to this many cells keep the cache's lists in an array over the grid (24 bytes
/// a cell); larger ones in a hash map.
const DENSE_LIST_CELLS: usize = 1 << 20;

/// The cache's entries per grid cell (row-major index).
#[derive(Debug, Default)]
struct CellLists {
    dense: bool,
    array: Vec<Vec<CellEntry>>,
    map: HashMap<u32, Vec<CellEntry>>,
    /// No entry ever listed is longer than this, milliseconds: how far before a window's
    /// start the entries that reach into it can start.
    longest_ms: i64,
}

impl CellLists {
    fn for_grid(cells: usize) -> Self {
        let dense = cells <= DENSE_LIST_CELLS;
        Self {
            dense,
            array: if dense {
                vec![Vec::new(); cells]
            } else {
                Vec::new()
            },
            map: HashMap::new(),
            longest_ms: 0,
        }
    }

    fn list(&self, index: u32) -> &[CellEntry] {
        if self.dense {
            self.array.get(index as usize).map_or(&[], Vec::as_slice)
        } else {
            self.map.get(&index).map_or(&[], Vec::as_slice)
        }
    }

    fn list_mut(&mut self, index: u32) -> &mut Vec<CellEntry> {
        let index = index as usize;
        if self.dense && index < self.array.len() {
            &mut self.array[index]
        } else {
            self.map.entry(index as u32).or_default()
        }
    }

    fn retain(&mut self, keep: impl Fn(&CellEntry) -> bool) {
        for list in &mut self.array {
            list.retain(&keep);
        }
        self.map.retain(|_, list| {
            list.retain(&keep);
            !list.is_empty()
        });
    }
}

/// Whether two cached volumes have the same band.
fn same_band(a: &CachedVolume, b: &CachedVolume) -> bool {
    a.lower_m.to_bits() == b.lower_m.to_bits() && a.upper_m.to_bits() == b.upper_m.to_bits()
}

/// Whether a cached volume's band meets `band` (W84 metres).
fn meets(v: &CachedVolume, band: (f64, f64)) -> bool {
    !(v.upper_m < band.0 || v.lower_m > band.1)
}

/// A stored volume that blocks a cell: its window (Unix ms), its intent's slot and its index
/// among the intent's volumes.
#[derive(Debug, Clone, Copy)]
struct CellEntry {
    start_ms: i64,
    end_ms: i64,
    slot: u32,
    volume: u32,
}

/// Calls `blocks` with the row-major index of every cell of `grid` whose centre is within
/// `reach_m` of `o`'s footprint: the same test as [`Obstacles::blocked_at`]'s, cell by cell
/// over the footprint's box grown by the reach.
fn rasterise(o: &Obstacle, reach_m: f64, grid: &Grid2, mut blocks: impl FnMut(u32)) {
    let f = grid.frame();
    let r = reach_m;
    if !(o.bbox_ne.iter().all(|x| x.is_finite()) && r.is_finite()) {
        return;
    }
    // Rows and columns whose centres may pass the box test, a cell more each side for the
    // rounding; the box test itself decides.
    let span = |lo: f64, hi: f64, origin: f64, count: u32| {
        let a = ((lo - r - origin) / f.cell_m - 0.5).floor() as i64 - 1;
        let b = ((hi + r - origin) / f.cell_m - 0.5).ceil() as i64 + 1;
        (a.max(0), b.min(i64::from(count) - 1))
    };
    let (r0, r1) = span(o.bbox_ne[0], o.bbox_ne[2], f.origin_north_m, grid.rows());
    let (c0, c1) = span(o.bbox_ne[1], o.bbox_ne[3], f.origin_east_m, grid.cols());
    for row in r0..=r1 {
        for col in c0..=c1 {
            let c = Cell::new(row as u32, col as u32);
            let (n, e) = grid.center_ne(c);
            if o.blocks(n, e, r) {
                blocks(grid.index(c) as u32);
            }
        }
    }
}

/// The free cell for a place: its own, or the nearest free one.
fn cell_for(grid: &Grid2, north_m: f64, east_m: f64) -> Option<Cell> {
    grid.cell_at_ne(north_m, east_m)
        .filter(|&c| !grid.is_blocked(c))
        .or_else(|| grid.nearest_free_ne(north_m, east_m))
}

/// `grid` with every cell whose centre is farther than `within_m` from the route (local
/// north, east; at least one point) blocked: where the space-time search may go. Row by row,
/// each segment's capsule meets the row's centre line in one stretch of columns.
fn corridor(grid: &Grid2, route: &[[f64; 3]], within_m: f64) -> Grid2 {
    let f = grid.frame();
    let cols = grid.cols() as usize;
    let was = grid.blocked_cells();
    let mut blocked = vec![true; grid.len()];
    let segments: Vec<([f64; 2], [f64; 2])> = match route {
        [one] => vec![([one[0], one[1]], [one[0], one[1]])],
        _ => route
            .windows(2)
            .map(|w| ([w[0][0], w[0][1]], [w[1][0], w[1][1]]))
            .collect(),
    };
    for (a, b) in segments {
        let rows = centres_within(
            a[0].min(b[0]) - within_m,
            a[0].max(b[0]) + within_m,
            f.origin_north_m,
            f.cell_m,
            grid.rows(),
        );
        for row in rows {
            let north_m = f.origin_north_m + (row as f64 + 0.5) * f.cell_m;
            let Some((lo, hi)) = capsule_on_row(a, b, within_m, north_m) else {
                continue;
            };
            for col in centres_within(lo, hi, f.origin_east_m, f.cell_m, grid.cols()) {
                let i = row * cols + col;
                blocked[i] &= was[i];
            }
        }
    }
    // Same size and frame as `grid`, so this cannot fail; the whole grid if it did.
    Grid2::new(grid.rows(), grid.cols(), blocked, f).unwrap_or_else(|_| grid.clone())
}

/// The rows (or columns) of a grid axis whose centres lie in `[lo, hi]` metres.
fn centres_within(
    lo: f64,
    hi: f64,
    origin_m: f64,
    cell_m: f64,
    count: u32,
) -> std::ops::Range<usize> {
    let first = ((lo - origin_m) / cell_m - 0.5).ceil().max(0.0);
    let end = (((hi - origin_m) / cell_m - 0.5).floor() + 1.0).min(f64::from(count));
    if first < end {
        first as usize..end as usize
    } else {
        0..0
    }
}

/// The east extent of the points on the line `north = north_m` within `r` of the segment
/// `a`–`b` (north, east): the union of the two end discs' chords and the band beside the
/// segment, one interval since the capsule is convex.
fn capsule_on_row(a: [f64; 2], b: [f64; 2], r: f64, north_m: f64) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in [a, b] {
        let h2 = r * r - (north_m - p[0]).powi(2);
        if h2 >= 0.0 {
            let h = h2.sqrt();
            lo = lo.min(p[1] - h);
            hi = hi.max(p[1] + h);
        }
    }
    let (dn, de) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dn * dn + de * de;
    if len2 > 0.0 {
        // With x = east − a's east: the projection (p − a)·d = (north − a's north)·dn + x·de
        // in [0, |d|²], and the cross product x·dn − (north − a's north)·de in ±r|d|.
        let up = north_m - a[0];
        let side = r * len2.sqrt();
        if let (Some(along), Some(across)) = (
            linear_range(up * dn, de, 0.0, len2),
            linear_range(-up * de, dn, -side, side),
        ) {
            let (x0, x1) = (along.0.max(across.0), along.1.min(across.1));
            if x0 <= x1 {
                lo = lo.min(a[1] + x0);
                hi = hi.max(a[1] + x1);
            }
        }
    }
    (lo <= hi).then_some((lo, hi))
}

/// The `x` where `lo ≤ c0 + c1·x ≤ hi`.
fn linear_range(c0: f64, c1: f64, lo: f64, hi: f64) -> Option<(f64, f64)> {
    if c1 == 0.0 {
        return (lo <= c0 && c0 <= hi).then_some((f64::NEG_INFINITY, f64::INFINITY));
    }
    let (p, q) = ((lo - c0) / c1, (hi - c0) / c1);
    Some((p.min(q), p.max(q)))
}

fn route_length(points: &[[f64; 3]]) -> f64 {
    points
        .windows(2)
        .map(|w| {
            ((w[1][0] - w[0][0]).powi(2)
                + (w[1][1] - w[0][1]).powi(2)
                + (w[1][2] - w[0][2]).powi(2))
            .sqrt()
        })
        .sum()
}

/// The searched cells as a route with times (seconds after departure): each cell's centre at
/// its arrival and, where the flight waits, at its departure; the plan's own start and goal
/// points at the ends.
fn timed_points(
    grid: &Grid2,
    cells: &[TimedCell],
    start: [f64; 2],
    goal: [f64; 2],
    alt_m: f64,
) -> Vec<skyplan_airspace::TimedPoint> {
    let t0 = cells.first().map_or(0.0, |c| c.arrive_s);
    let mut out = Vec::with_capacity(cells.len() + 8);
    let last = cells.len().saturating_sub(1);
    // The plan's own start and goal where they are inside the end cells (else the centres:
    // the straight leg from a point outside a cell is not the grid's to vouch for).
    let inside = |p: [f64; 2], c: Cell| grid.cell_at_ne(p[0], p[1]) == Some(c);
    for (k, c) in cells.iter().enumerate() {
        let (n, e) = grid.center_ne(c.cell);
        let ne = match k {
            0 if inside(start, c.cell) => start,
            k if k == last && inside(goal, c.cell) => goal,
            _ => [n, e],
        };
        let nea = [ne[0], ne[1], alt_m];
        out.push(skyplan_airspace::TimedPoint {
            t_s: c.arrive_s - t0,
            nea,
        });
        if c.leave_s > c.arrive_s && k != last {
            out.push(skyplan_airspace::TimedPoint {
                t_s: c.leave_s - t0,
                nea,
            });
        }
    }
    out
}

/// The length of the cells' moves, in cells.
fn moves_cells(cells: &[TimedCell]) -> f64 {
    cells
        .windows(2)
        .map(|w| {
            let (a, b) = (w[0].cell, w[1].cell);
            if a.row != b.row && a.col != b.col {
                std::f64::consts::SQRT_2
            } else {
                1.0
            }
        })
        .sum()
}

/// The corners and hover points of a route with times (points where it turns or waits).
fn corners(path: &[skyplan_airspace::TimedPoint]) -> Vec<[f64; 3]> {
    let mut out: Vec<[f64; 3]> = Vec::new();
    for (k, p) in path.iter().enumerate() {
        let keep = k == 0 || k + 1 == path.len() || {
            let (a, b, c) = (path[k - 1].nea, p.nea, path[k + 1].nea);
            let (u, v) = ([b[0] - a[0], b[1] - a[1]], [c[0] - b[0], c[1] - b[1]]);
            let cross = u[0] * v[1] - u[1] * v[0];
            let dot = u[0] * v[0] + u[1] * v[1];
            cross.abs() > 1e-9 || dot <= 0.0
        };
        // A hover is the same point twice: kept once.
        if keep && out.last() != Some(&p.nea) {
            out.push(p.nea);
        }
    }
    out
}

/// Re-routes `plan` (a 2D grid plan at one altitude) in `space` ([`search_grid`]: a grid of
/// the same map at the plan's altitude and margin with its no-fly zones) in space and time
/// around the stored intents that bind it, checks the route against the zones exactly, and
/// reserves it; the counts of what was read as in [`skyplan_airspace_store::reserve_counted`].
///
/// ```
/// use skyplan_fleet::{FlightRequest, reserve_space_time, search_grid};
/// use skyplan_airspace::{DepartureWindow, Timestamp};
/// use skyplan_airspace_store::SqliteStore;
/// use skyplan_plan::{PlanRequest, Session, World};
/// let mut session = Session::new(World::fcnd_city());
/// let plan = session.plan(&PlanRequest::default())?;
/// let grid = search_grid(&mut session, &PlanRequest::default(), &plan)?.expect("a grid plan");
/// let store = SqliteStore::open_url("sqlite::memory:")?;
/// let t0: Timestamp = "2026-03-01T12:00:00Z".parse()?;
/// let window = DepartureWindow { earliest: t0, latest: t0.plus_ms(600_000) };
/// let request = FlightRequest::new(window, 0, "demo".into());
/// let first = reserve_space_time(&store, &grid, &plan, &request).0?;
/// assert_eq!((first.delay_ms, first.hover_s), (0, 0.0));
/// assert!(first.arrival_delay_s.abs() < 1e-9 && first.detour_m.abs() < 1e-9);
/// // The same flight again in the same window: it arrives later than alone.
/// let second = reserve_space_time(&store, &grid, &plan, &request).0?;
/// assert!(second.arrival_delay_s > 0.0);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn reserve_space_time(
    store: &dyn IntentStore,
    space: &SearchSpace,
    plan: &Plan,
    request: &FlightRequest,
) -> (Result<SpaceTimeFlight, ReserveError>, usize) {
    let mut nearby = 0;
    let result = space_time_inner(store, space, plan, request, None, &mut nearby);
    (result, nearby)
}

/// [`reserve_space_time`] with the stored intents kept in `cache` between calls: only the
/// rows of the intents near the flight are read from the store ([`IntentStore::nearby_rows`]),
/// and only those not seen before are read, decoded, converted to the map's frame and
/// rasterised on the search's grid. The answer is the same as [`reserve_space_time`]'s (the
/// cells a stored volume blocks are those the exact test blocks, found once per volume
/// instead of once per search), and the store's exact check-and-insert still decides.
/// Use one cache with one store.
pub fn reserve_space_time_cached(
    store: &dyn IntentStore,
    space: &SearchSpace,
    plan: &Plan,
    request: &FlightRequest,
    cache: &mut SpaceTimeCache,
) -> (Result<SpaceTimeFlight, ReserveError>, usize) {
    let mut nearby = 0;
    let result = space_time_inner(store, space, plan, request, Some(cache), &mut nearby);
    (result, nearby)
}

/// [`reserve_space_time_cached`] with a cache several threads share (a server's, a Python
/// `Airspace`'s): the cache when it is free, else — another search holds it, or one panicked
/// holding it — [`reserve_space_time`], which reads the store afresh and gives the same answer.
pub fn reserve_space_time_shared(
    store: &dyn IntentStore,
    space: &SearchSpace,
    plan: &Plan,
    request: &FlightRequest,
    cache: &std::sync::Mutex<SpaceTimeCache>,
) -> (Result<SpaceTimeFlight, ReserveError>, usize) {
    match cache.try_lock() {
        Ok(mut cache) => reserve_space_time_cached(store, space, plan, request, &mut cache),
        Err(_) => reserve_space_time(store, space, plan, request),
    }
}

/// A volume's outline in the map's frame: north and east of its vertices, metres.
fn outline_ne(frame: &LocalFrame, v: &Volume4D) -> Result<Vec<[f64; 2]>, AirspaceError> {
    (v.volume.outline_polygon.vertices.iter())
        .map(|p| {
            let ned = frame.ned_from_lla(Lla {
                lat_deg: p.lat,
                lon_deg: p.lng,
                alt_m: 0.0,
            })?;
            Ok([ned.north_m, ned.east_m])
        })
        .collect()
}

fn invalid(field: &str, why: impl Into<String>) -> ReserveError {
    ReserveError::Invalid(AirspaceError::Invalid {
        field: field.into(),
        why: why.into(),
    })
}

fn space_time_inner(
    store: &dyn IntentStore,
    space: &SearchSpace,
    plan: &Plan,
    request: &FlightRequest,
    mut cache: Option<&mut SpaceTimeCache>,
    nearby_count: &mut usize,
) -> Result<SpaceTimeFlight, ReserveError> {
    let grid = space.grid.as_ref();
    let o = request.volumes;
    let window = request.window;
    if window.latest < window.earliest {
        return Err(invalid("departure", "the window ends before it starts"));
    }
    let home = plan
        .home
        .ok_or(ReserveError::Invalid(AirspaceError::NoHome))?;
    let frame = LocalFrame::new(Lla {
        lat_deg: home.lat_deg,
        lon_deg: home.lon_deg,
        alt_m: 0.0,
    })
    .map_err(|e| ReserveError::Invalid(e.into()))?;
    let Some(g) = plan.grid else {
        return Err(invalid(
            "planner",
            format!(
                "planning in space and time needs a 2D grid planner's plan; {} has no grid",
                plan.planner.name()
            ),
        ));
    };
    let planned = plan.points_nea();
    let alt_m = planned.first().map_or(g.alt_m, |p| p[2]);
    if planned.iter().any(|p| (p[2] - alt_m).abs() > 1e-6) {
        return Err(invalid(
            "planner",
            "planning in space and time needs a route at one altitude",
        ));
    }
    // The stored intents are read around the planned route, grown by READ_REACH_M.
    let reach = skyplan_airspace::VolumeOptions {
        lateral_margin_m: o.lateral_margin_m + READ_REACH_M,
        ..o
    };
    let read_volumes = volumes_from_plan(plan, &reach)
        .map_err(ReserveError::Invalid)?
        .at(window.earliest);
    let span_ms = window.latest.ms_since(window.earliest).max(0);
    let length_m = route_length(&planned);
    let cell_m = grid.frame().cell_m;
    let cell_s = cell_m / o.cruise_m_s;
    let latest_departure_s = span_ms as f64 / 1000.0;
    let horizon_s = latest_departure_s + 3.0 * (length_m / o.cruise_m_s) + 600.0;
    let later_ms = (horizon_s * 1000.0) as i64;
    let start = cell_for(grid, plan.start.north_m, plan.start.east_m)
        .ok_or_else(|| invalid("start", "no free cell on the grid"))?;
    let goal = cell_for(grid, plan.goal.north_m, plan.goal.east_m)
        .ok_or_else(|| invalid("goal", "no free cell on the grid"))?;
    let band = (
        o.home_alt_w84_m + alt_m - o.vertical_buffer_m,
        o.home_alt_w84_m + alt_m + o.vertical_buffer_m,
    );
    let bulge_m = BULGE_CELLS * cell_m;
    let reach_m = o.lateral_margin_m.max(0.01) / (std::f64::consts::PI / 8.0).cos()
        + cell_m * std::f64::consts::SQRT_2 / 2.0
        + 2.0 * bulge_m
        + SLACK_M;
    let pad_s = o.time_buffer_s + STRETCH_S + 0.002;
    // The search keeps to where the store was read: a cell whose centre lies within
    // `lateral margin + READ_REACH_M − reach` of the planned route can only be blocked by
    // volumes that reach into the read footprint (the route grown by that margin + reach).
    let within_m = o.lateral_margin_m + READ_REACH_M - reach_m - SLACK_M;
    let searched = corridor(grid, &planned, within_m);
    let mut obstacles = Obstacles::new(reach_m);
    if let Some(cache) = cache.as_deref_mut() {
        cache.bind(&home, grid, reach_m);
    }
    // When each cell a timed no-fly zone blocks is blocked, on the search's clock (seconds
    // after the window's start), grown by the same pad as the others' volumes.
    let mut zone_times: HashMap<u32, Vec<Interval>> = HashMap::new();
    for (k, cells) in &space.timed {
        let z = &space.zones[*k];
        if !z.meets_altitude(alt_m, space.margin_m) {
            continue;
        }
        let after_start_s =
            |unix_s: i64| (unix_s as f64 * 1000.0 - window.earliest.unix_ms() as f64) / 1000.0;
        let active = Interval {
            start_s: z
                .start_unix_s
                .map_or(f64::NEG_INFINITY, |s| after_start_s(s) - pad_s),
            end_s: z
                .end_unix_s
                .map_or(f64::INFINITY, |e| after_start_s(e) + pad_s),
        };
        for &c in cells {
            zone_times.entry(c).or_default().push(active);
        }
    }
    let mut extra: Vec<OperationalIntent> = Vec::new();
    let mut last_conflicts: Vec<IntentRef> = Vec::new();
    let stretch = skyplan_airspace::VolumeOptions {
        stretch_s: STRETCH_S,
        stretch_m: STRETCH_M,
        ..o
    };
    let query = SippQuery {
        start,
        goal,
        cell_s,
        latest_departure_s,
        horizon_s,
        diagonals: true,
        max_expansions: MAX_EXPANSIONS,
        // Set for each search, from the time then left.
        deadline: None,
        exact_until: None,
    };
    // The shortest route on the same grid in an empty sky (JPS): what the delay and the
    // detour are measured against.
    let mut fresh = None;
    let alone_search = match cache.as_deref_mut() {
        Some(cache) => &mut cache.alone,
        None => fresh.insert(skyplan_search::GridSearch::new()),
    };
    let alone_cells = alone_search
        .search(
            grid,
            start,
            goal,
            skyplan_search::MoveModel::Octile,
            skyplan_search::Planner::Jps,
        )
        .map_err(|e| invalid("route", e.to_string()))?
        .cost_cells();
    let t0_ms = window.earliest.unix_ms();
    // The times the search can use: from its earliest departure to its horizon (a second
    // more each side); blocked times wholly outside change none of its answers.
    let window_ms = SearchWindow {
        t0_ms,
        pad_s,
        from_ms: t0_ms.saturating_sub(1000),
        to_ms: t0_ms.saturating_add(((horizon_s + 1.0) * 1000.0).ceil() as i64),
    };
    for tries in 1..=RESERVE_TRIES {
        obstacles.clear();
        let mut binding = Vec::new();
        let mut near = match cache.as_deref_mut() {
            Some(cache) => {
                // The rows near the flight; the intents not cached yet read and rasterised.
                let rows = store.nearby_rows(&read_volumes, later_ms)?;
                *nearby_count = rows.len();
                cache.refresh(store, &rows, &frame, grid)?;
                cache.select(&rows, band, |head| {
                    let binds = request.rule.binds(request.priority, head);
                    if binds {
                        binding.push(head.reference());
                    }
                    binds
                });
                Vec::new()
            }
            None => {
                let near = store.nearby(&read_volumes, later_ms)?;
                *nearby_count = near.len();
                near
            }
        };
        near.extend(extra.iter().cloned());
        for intent in &near {
            if request.rule.binds(request.priority, intent) {
                obstacles
                    .add(intent, band, &frame, window.earliest, pad_s)
                    .map_err(ReserveError::Invalid)?;
                binding.push(intent.reference());
            }
        }
        let mut timeline = SkyTimeline {
            grid,
            obstacles: &obstacles,
            cache: cache.as_deref(),
            band,
            window: &window_ms,
            zone_times: &zone_times,
        };
        // Each search (a retry too) splits the time left when it starts.
        let query = SippQuery {
            deadline: share_of_time_left(request.deadline, SEARCH_SHARE),
            exact_until: share_of_time_left(request.deadline, EXACT_SHARE),
            ..query
        };
        let found = match sipp(&searched, &query, &mut timeline) {
            Ok(found) => found,
            Err(SippError::Endpoint { which, cell }) => {
                return Err(invalid(
                    which,
                    format!("cell (row {}, col {}) is blocked", cell.row, cell.col),
                ));
            }
            Err(SippError::Deadline(states)) => return Err(ReserveError::Deadline { states }),
            Err(_) => {
                binding.sort();
                binding.dedup();
                return Err(ReserveError::Blocked(skyplan_airspace::Blocked {
                    window,
                    blocking: binding,
                }));
            }
        };
        let path = timed_points(
            grid,
            &found.cells,
            [plan.start.north_m, plan.start.east_m],
            [plan.goal.north_m, plan.goal.east_m],
            alt_m,
        );
        let route_nea = corners(&path);
        // The cells kept the route out of the zones; this is the exact word on it.
        let departure_unix_s =
            (window.earliest.unix_ms() as f64 + (found.departure_s() * 1000.0).ceil()) / 1000.0;
        if let Some((feature, c)) =
            zone_in_the_way(&path, departure_unix_s, &space.zones, alt_m, space.margin_m)
        {
            return Err(invalid(
                "no_fly",
                format!(
                    "the route found in space and time comes {c:.2} m from no-fly zone {feature}, within the margin of {} m; nothing reserved",
                    space.margin_m
                ),
            ));
        }
        let timed_path = path.clone();
        let flight = volumes_hugging_path(path, Timing::SpaceTime, &frame, &stretch, bulge_m)
            .map_err(ReserveError::Invalid)?;
        let delay_ms = (found.departure_s() * 1000.0).ceil() as i64;
        let departure = window.earliest.plus_ms(delay_ms);
        let volumes: Vec<Volume4D> = flight.at(departure);
        let intent = OperationalIntent {
            id: new_id(),
            version: 1,
            state: IntentState::Accepted,
            priority: request.priority,
            owner: request.owner.clone(),
            volumes,
        };
        match store.insert_if_clear(&intent, request.rule)? {
            Insert::Accepted { .. } => {
                let flown = moves_cells(&found.cells);
                return Ok(SpaceTimeFlight {
                    departure,
                    delay_ms,
                    hover_s: found.hover_s(),
                    // Never below the empty sky's: a negative value is rounding.
                    detour_m: ((flown - alone_cells) * cell_m).max(0.0),
                    arrival_delay_s: (found.arrival_s() - alone_cells * cell_s).max(0.0),
                    arrival_gap_s: if found.proven_earliest() {
                        0.0
                    } else {
                        found.arrival_s() - found.earliest_bound_s
                    },
                    alone_m: alone_cells * cell_m,
                    route_nea,
                    path: timed_path,
                    intent,
                    flight,
                    expansions: found.expansions,
                    nearby: *nearby_count,
                    tries,
                });
            }
            Insert::Conflicts(c) => {
                // Stored since the read (by another request or server): read them and search again.
                last_conflicts = c
                    .iter()
                    .map(skyplan_airspace::Conflict::reference)
                    .collect();
                for r in &c {
                    if let Some(i) = store.get(&r.id)? {
                        extra.push(i);
                    }
                }
            }
        }
    }
    last_conflicts.sort();
    Err(ReserveError::Blocked(skyplan_airspace::Blocked {
        window,
        blocking: last_conflicts,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// The corridor keeps exactly the free cells whose centres are within the distance of the
    /// route, against a brute-force distance to each segment.
    #[test]
    fn the_corridor_keeps_the_free_cells_near_the_route() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (mut kept, mut cut) = (0, 0);
        for _ in 0..60 {
            let (rows, cols) = (rng.random_range(1..40u32), rng.random_range(1..40u32));
            let frame = skyplan_cspace::GridFrame {
                origin_north_m: rng.random_range(-60.0..0.0),
                origin_east_m: rng.random_range(-60.0..0.0),
                cell_m: rng.random_range(0.5..5.0),
            };
            let cells: Vec<bool> = (0..rows * cols).map(|_| rng.random_bool(0.2)).collect();
            let grid = Grid2::new(rows, cols, cells, frame).expect("grid");
            let route: Vec<[f64; 3]> = (0..rng.random_range(1..6))
                .map(|_| {
                    [
                        rng.random_range(-80.0..80.0),
                        rng.random_range(-80.0..80.0),
                        20.0,
                    ]
                })
                .collect();
            let within_m = rng.random_range(0.0..40.0);
            let searched = corridor(&grid, &route, within_m);
            let ends: Vec<([f64; 3], [f64; 3])> = if route.len() == 1 {
                vec![(route[0], route[0])]
            } else {
                route.windows(2).map(|w| (w[0], w[1])).collect()
            };
            for i in 0..grid.len() {
                let cell = grid.cell(i);
                let (n, e) = grid.center_ne(cell);
                let d_m = ends
                    .iter()
                    .map(|(a, b)| {
                        skyplan_testkit::distance_to_segment([n, e], [a[0], a[1]], [b[0], b[1]])
                    })
                    .fold(f64::INFINITY, f64::min);
                if (d_m - within_m).abs() < 1e-6 {
                    continue;
                }
                let free = !grid.is_blocked(cell) && d_m < within_m;
                assert_eq!(
                    !searched.is_blocked(cell),
                    free,
                    "cell {i}: {d_m} m, within {within_m} m"
                );
                kept += usize::from(free);
                cut += usize::from(!grid.is_blocked(cell) && !free);
            }
        }
        assert!(kept > 1000 && cut > 1000, "{kept} kept, {cut} cut");
    }

    #[test]
    fn the_edge_test_agrees_with_the_exact_distance() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut near = 0;
        for _ in 0..2000 {
            let points: Vec<[f64; 2]> = (0..rng.random_range(1..9))
                .map(|_| [rng.random_range(-20.0..20.0), rng.random_range(-20.0..20.0)])
                .collect();
            let o = Obstacle::new(
                &points,
                Interval {
                    start_s: 0.0,
                    end_s: 1.0,
                },
            );
            let hull = skyplan_airspace::geometry::convex_hull(&points);
            for _ in 0..20 {
                let p = [rng.random_range(-40.0..40.0), rng.random_range(-40.0..40.0)];
                let r = rng.random_range(0.0..10.0);
                // Brute force: the hull's edges and the point-in-hull test by cross products.
                let inside = hull.len() >= 3
                    && (0..hull.len()).all(|i| {
                        skyplan_airspace::geometry::cross(hull[i], hull[(i + 1) % hull.len()], p)
                            >= 0.0
                    });
                let d = if inside {
                    0.0
                } else {
                    (0..hull.len())
                        .map(|i| {
                            let j = (i + 1) % hull.len();
                            skyplan_map::nofly::point_segment_m(p, hull[i], hull[j])
                        })
                        .fold(f64::INFINITY, f64::min)
                };
                assert_eq!(o.near(p, r), d <= r, "{points:?} {p:?} {r}");
                near += usize::from(d <= r);
            }
        }
        assert!(near > 2000, "{near}");
    }

    /// The cache's raster blocks exactly the cells the uncached search's exact test blocks
    /// (bucket lookup, box test, distance to the hull), volume by volume, on a grid whose
    /// origin and cell size are not round numbers.
    #[test]
    fn the_raster_blocks_exactly_the_cells_the_exact_test_blocks() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let frame = skyplan_cspace::GridFrame {
            origin_north_m: -37.3,
            origin_east_m: 12.9,
            cell_m: 3.7,
        };
        let (rows, cols) = (60u32, 70u32);
        let grid =
            Grid2::new(rows, cols, vec![false; (rows * cols) as usize], frame).expect("grid");
        let (mut blocked_cells, mut volumes) = (0, 0);
        for _ in 0..40 {
            let reach_m = rng.random_range(0.5..12.0);
            let mut exact = Obstacles::new(reach_m);
            let mut raster: HashMap<u32, Vec<u32>> = HashMap::new();
            for k in 0..rng.random_range(1..12) {
                // Footprints inside, across the edge of and outside the grid.
                let c = [
                    rng.random_range(-80.0..260.0),
                    rng.random_range(-60.0..300.0),
                ];
                let points: Vec<[f64; 2]> = (0..rng.random_range(1..9))
                    .map(|_| {
                        [
                            c[0] + rng.random_range(-30.0..30.0),
                            c[1] + rng.random_range(-30.0..30.0),
                        ]
                    })
                    .collect();
                let mark = Interval {
                    start_s: f64::from(k),
                    end_s: f64::from(k),
                };
                let o = Obstacle::new(&points, mark);
                rasterise(&o, reach_m, &grid, |i| raster.entry(i).or_default().push(k));
                exact.file(o);
                volumes += 1;
            }
            for i in 0..grid.len() {
                let (n, e) = grid.center_ne(grid.cell(i));
                let mut want: Vec<u32> = exact
                    .blocked_at(n, e)
                    .iter()
                    .map(|b| b.start_s as u32)
                    .collect();
                want.sort_unstable();
                let mut got = raster.get(&(i as u32)).cloned().unwrap_or_default();
                got.sort_unstable();
                assert_eq!(got, want, "cell {i} at N {n:.2}, E {e:.2}, reach {reach_m}");
                blocked_cells += usize::from(!want.is_empty());
            }
        }
        // The footprints blocked a good share of the cells, and many volumes.
        assert!(
            volumes > 150 && blocked_cells > 10_000,
            "{volumes} {blocked_cells}"
        );
    }
}

//! [`Replanner`]: the [`RouteWatcher`] that learns from readings and replans the route still to
//! fly.

use crate::dstar::DStarLite;
use crate::world_model::WorldModel;
use skyplan_cspace::{Cell, Grid2, GridFrame, Touch};
use skyplan_flight::executor::Target;
use skyplan_flight::sensing::{ObstacleReading, ReplanEvent, RouteDecision, RouteWatcher};
use skyplan_plan::{Plan, PlanFailure, PlanRequest, PlannerId, Session};
use skyplan_postprocess::{prune_collinear, shortcut, touch_for};
use skyplan_search::{GridSearch, MoveModel, Planner};
use std::fmt;
use std::str::FromStr;
use std::time::Instant;

/// Which search replans.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum ReplannerKind {
    /// D\* Lite, one search kept and repaired across replans (`dstar-lite`).
    #[default]
    DStarLite,
    /// JPS from scratch on the known and learned grid at every replan (`scratch`).
    Scratch,
}

impl ReplannerKind {
    /// The name users type (`dstar-lite`, `scratch`).
    pub fn name(self) -> &'static str {
        match self {
            ReplannerKind::DStarLite => "dstar-lite",
            ReplannerKind::Scratch => "scratch",
        }
    }
}

impl fmt::Display for ReplannerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A replanner name that is neither `dstar-lite` nor `scratch`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown replanner `{0}`: expected dstar-lite or scratch")]
pub struct UnknownReplanner(pub String);

impl FromStr for ReplannerKind {
    type Err = UnknownReplanner;
    /// ```
    /// use skyplan_replan::ReplannerKind;
    /// assert_eq!("scratch".parse(), Ok(ReplannerKind::Scratch));
    /// assert!("dstar".parse::<ReplannerKind>().is_err());
    /// ```
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "dstar-lite" => Ok(ReplannerKind::DStarLite),
            "scratch" => Ok(ReplannerKind::Scratch),
            other => Err(UnknownReplanner(other.to_string())),
        }
    }
}

/// Options of a [`Replanner`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReplanOptions {
    /// The search that replans at the flight altitude.
    pub replanner: ReplannerKind,
    /// Highest altitude a replanned route may climb to, metres above home.
    pub max_alt_m: f64,
    /// Altitude step between the layers tried when climbing, metres.
    pub climb_step_m: f64,
    /// D\* Lite: most expansions one reading may spend repairing (about 1 µs each); over it,
    /// that replan searches from scratch (JPS) and D\* Lite goes on repairing, within the same
    /// budget, at the readings that follow until it has caught up. `None`: no limit.
    pub dstar_budget_expansions: Option<u64>,
    /// The vehicle's braking deceleration, m/s²: a replan made while the vehicle moves starts
    /// where it comes to rest along its heading (v² / 2a ahead) when the way there is free, so
    /// that the new route begins where the vehicle can turn onto it instead of behind it.
    /// `None`: every new route starts where the vehicle is (what a trajectory replanned from
    /// the vehicle's motion wants).
    pub brake_accel_m_s2: Option<f64>,
}

impl Default for ReplanOptions {
    fn default() -> Self {
        Self {
            replanner: ReplannerKind::DStarLite,
            max_alt_m: 30.0,
            climb_step_m: 5.0,
            dstar_budget_expansions: Some(2_000),
            brake_accel_m_s2: None,
        }
    }
}

/// What one replan cost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReplanSample {
    /// Wall-clock time from the reading to the new route, milliseconds.
    pub latency_ms: f64,
    /// CPU time on the replanning thread, milliseconds (`None` where the platform has no
    /// thread clock).
    pub cpu_ms: Option<f64>,
    /// Search expansions.
    pub expansions: u64,
}

/// Nearest-rank percentiles of some durations, milliseconds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spread {
    /// Median.
    pub p50_ms: f64,
    /// 99th percentile.
    pub p99_ms: f64,
    /// Largest.
    pub max_ms: f64,
}

impl Spread {
    /// The spread of `samples_ms` (`None` when there is none).
    ///
    /// ```
    /// let s = skyplan_replan::Spread::of(&[3.0, 1.0, 2.0]).unwrap();
    /// assert_eq!((s.p50_ms, s.p99_ms, s.max_ms), (2.0, 3.0, 3.0));
    /// assert_eq!(skyplan_replan::Spread::of(&[]), None);
    /// ```
    pub fn of(samples_ms: &[f64]) -> Option<Spread> {
        Some(Spread {
            p50_ms: percentile(samples_ms, 50.0)?,
            p99_ms: percentile(samples_ms, 99.0)?,
            max_ms: percentile(samples_ms, 100.0)?,
        })
    }
}

/// What the replanner did so far (for the flight summary and `bench --replan`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReplanStats {
    /// Readings received.
    pub readings: u64,
    /// Routes replaced.
    pub replans: u64,
    /// Holds decided.
    pub holds: u64,
    /// What each replan cost, in order.
    pub samples: Vec<ReplanSample>,
}

impl ReplanStats {
    /// Every flight's replans together (for a row over many flights).
    pub fn merged<'a>(all: impl IntoIterator<Item = &'a ReplanStats>) -> ReplanStats {
        all.into_iter().fold(ReplanStats::default(), |mut sum, s| {
            sum.readings += s.readings;
            sum.replans += s.replans;
            sum.holds += s.holds;
            sum.samples.extend_from_slice(&s.samples);
            sum
        })
    }

    /// The spread of the replans' wall-clock latencies (`None` before the first replan).
    ///
    /// ```
    /// use skyplan_replan::{ReplanSample, ReplanStats};
    /// let sample = |latency_ms| ReplanSample { latency_ms, cpu_ms: None, expansions: 0 };
    /// let stats = ReplanStats { samples: vec![sample(3.0), sample(1.0), sample(2.0)], ..Default::default() };
    /// let spread = stats.latency().unwrap();
    /// assert_eq!((spread.p50_ms, spread.max_ms), (2.0, 3.0));
    /// assert_eq!(stats.cpu(), None);
    /// ```
    pub fn latency(&self) -> Option<Spread> {
        let ms: Vec<f64> = self.samples.iter().map(|s| s.latency_ms).collect();
        Spread::of(&ms)
    }

    /// The spread of the replans' CPU times (`None` without a thread clock or a replan).
    pub fn cpu(&self) -> Option<Spread> {
        let ms: Vec<f64> = self.samples.iter().filter_map(|s| s.cpu_ms).collect();
        Spread::of(&ms)
    }

    /// Mean search expansions per replan (`None` before the first replan).
    pub fn expansions_per_replan(&self) -> Option<f64> {
        let n = self.samples.len();
        (n > 0).then(|| self.samples.iter().map(|s| s.expansions).sum::<u64>() as f64 / n as f64)
    }

    /// The account in one sentence: replans, readings, latency and CPU percentiles,
    /// expansions per replan, learned cells (`kind` names the replanner).
    ///
    /// ```
    /// use skyplan_replan::{ReplanSample, ReplanStats};
    /// let stats = ReplanStats { readings: 40, replans: 2, samples: vec![
    ///     ReplanSample { latency_ms: 1.0, cpu_ms: Some(0.5), expansions: 10 },
    ///     ReplanSample { latency_ms: 3.0, cpu_ms: Some(2.0), expansions: 30 },
    /// ], ..Default::default() };
    /// assert_eq!(stats.account("dstar-lite", 12),
    ///     "2 (dstar-lite) from 40 sensor readings: latency p50 1.00 ms, p99 3.00 ms, max 3.00 ms \
    ///      (CPU p50 0.50 ms, p99 2.00 ms); 20 expansions per replan; 12 cells learned");
    /// ```
    pub fn account(&self, kind: &str, learned_cells: usize) -> String {
        let latency = self
            .latency()
            .map_or("p50 - ms, p99 - ms, max - ms".into(), |s| {
                format!(
                    "p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms",
                    s.p50_ms, s.p99_ms, s.max_ms
                )
            });
        let cpu = self.cpu().map_or(String::new(), |s| {
            format!(" (CPU p50 {:.2} ms, p99 {:.2} ms)", s.p50_ms, s.p99_ms)
        });
        let expansions = self
            .expansions_per_replan()
            .map_or("-".into(), |x| format!("{x:.0}"));
        format!(
            "{} ({kind}) from {} sensor readings: latency {latency}{cpu}; {expansions} expansions per replan; {learned_cells} cells learned",
            self.replans, self.readings,
        )
    }
}

/// When a reading's handling started, by the wall clock and the thread's CPU clock.
#[derive(Clone, Copy)]
struct Started {
    wall: Instant,
    cpu_s: Option<f64>,
}

impl Started {
    fn now() -> Self {
        Self {
            wall: Instant::now(),
            cpu_s: crate::clock::thread_cpu_s(),
        }
    }

    /// Wall-clock and CPU milliseconds since then.
    fn elapsed_ms(&self) -> (f64, Option<f64>) {
        let cpu = match (self.cpu_s, crate::clock::thread_cpu_s()) {
            (Some(a), Some(b)) => Some((b - a).max(0.0) * 1e3),
            _ => None,
        };
        (self.wall.elapsed().as_secs_f64() * 1e3, cpu)
    }
}

/// The `p`-th percentile (nearest rank) of `values`.
pub(crate) fn percentile(values: &[f64], p: f64) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let rank = ((p.clamp(0.0, 100.0) / 100.0) * v.len() as f64).ceil() as usize;
    v.get(rank.saturating_sub(1).min(v.len() - 1)).copied()
}

/// One altitude the replanner may fly at: the map's grid there and what was learned there.
struct Layer {
    alt_m: f64,
    world: WorldModel,
}

/// A route found at one layer.
struct Found {
    points: Vec<[f64; 3]>,
    expansions: u64,
    planner: String,
}

/// The replanning brain: a [`RouteWatcher`] over a world model per flight altitude.
///
/// Built from a [`Session`] and the flight's [`PlanRequest`] (a 2D grid planner); it plans the
/// first route itself ([`Replanner::initial_plan`]). On each reading it learns, and if a learned
/// cell lies on the route still to fly (its segments against the learned cells, which are grown
/// by the margin) it replans from the vehicle to the goal at the flight altitude (D\* Lite or JPS
/// from scratch), else climbs (layers `alt + k · climb_step_m` up to `max_alt_m`), else holds.
/// Every new route passes the planning API's grid re-check against the map's grid and against
/// the known and learned grid of its altitude.
///
/// ```
/// use skyplan_flight::sensing::{ObstacleReading, RouteDecision, RouteWatcher, SectorRange};
/// use skyplan_plan::{PlanRequest, Session, World};
/// use skyplan_replan::{ReplanOptions, Replanner};
/// // A straight leg of the city's default route.
/// let request = PlanRequest { start_ne: Some([250.5, -38.5]), goal_ne: Some([390.5, -58.5]), ..Default::default() };
/// let mut replanner = Replanner::new(Session::new(World::fcnd_city()), &request, ReplanOptions::default())?;
/// let route = replanner.initial_targets();
/// assert_eq!(route.len(), 2);
/// // Something 15 m ahead (bearing 350°), right on the route.
/// let mut ranges = vec![SectorRange::Clear; 72];
/// ranges[70] = SectorRange::Obstacle(15.0);
/// let reading = ObstacleReading { time_s: 1.0, position_ned: [250.5, -38.5, -5.0], velocity_ned_m_s: [0.0; 3], first_bearing_rad: 0.0,
///     increment_rad: 5f64.to_radians(), min_range_m: 0.2, max_range_m: 30.0, ranges };
/// match replanner.on_reading(&reading, &route) {
///     RouteDecision::Replace { targets, event } => {
///         assert!(event.reason.contains("learned obstacle"), "{}", event.reason);
///         assert_eq!(event.planner, "dstar-lite");
///         let last = targets.last().map(|t| (t.north_m, t.east_m));
///         assert_eq!(last, Some((390.5, -58.5)));
///         assert!(targets.len() > 2);
///     }
///     other => panic!("expected a new route, got {other:?}"),
/// }
/// # Ok::<(), skyplan_plan::PlanFailure>(())
/// ```
pub struct Replanner {
    session: Session,
    plan: Plan,
    request: PlanRequest,
    options: ReplanOptions,
    model: MoveModel,
    touch: Touch,
    safety_m: f64,
    goal_ne: [f64; 2],
    layers: Vec<Layer>,
    dstar: Option<DStarLite>,
    /// D\* Lite spent its budget before it was consistent: it catches up at later readings.
    dstar_behind: bool,
    pending: Vec<(Cell, bool)>,
    search: GridSearch,
    stats: ReplanStats,
    events: Vec<ReplanEvent>,
}

impl Replanner {
    /// Plans the first route with `request` (which must use a 2D grid planner, on a colliders
    /// map or a grid map) and prepares the layers and, for D\* Lite, the search.
    pub fn new(
        mut session: Session,
        request: &PlanRequest,
        options: ReplanOptions,
    ) -> Result<Self, PlanFailure> {
        if !(options.max_alt_m.is_finite() && options.climb_step_m.is_finite())
            || options.climb_step_m <= 0.0
        {
            return Err(PlanFailure::bad_request(format!(
                "replanning: max_alt_m {} and climb_step_m {}: expected finite numbers, the step > 0",
                options.max_alt_m, options.climb_step_m
            )));
        }
        let plan = session.plan(request)?;
        let Some(info) = plan.grid else {
            return Err(PlanFailure::bad_request(format!(
                "replanning needs a 2D grid planner ({}), not {}",
                PlannerId::names_where(PlannerId::is_cell_search),
                plan.planner
            )));
        };
        let model = plan.spec.move_model;
        let touch = touch_for(model);
        let goal_ne = [plan.goal.north_m, plan.goal.east_m];
        let mut layers = Vec::new();
        let mut k = 0u32;
        loop {
            let alt_m = info.alt_m + f64::from(k) * options.climb_step_m;
            // Grid maps have one grid whatever the altitude: nothing to climb to.
            let flat = session.world().colliders().is_none();
            if k > 0 && (flat || alt_m > options.max_alt_m + 1e-9) {
                break;
            }
            // The request's no-fly zones are as much in the way as the map's obstacles.
            let known = session.zoned_grid(request, alt_m)?;
            layers.push(Layer {
                alt_m,
                world: WorldModel::new(known, info.safety_m),
            });
            k += 1;
            if k > 1000 {
                break;
            }
        }
        let base = &layers[0].world;
        let dstar = match options.replanner {
            ReplannerKind::DStarLite => {
                let grid = base.grid();
                let start = cell_near(grid, [plan.start.north_m, plan.start.east_m]);
                let goal = grid.cell_at_ne(goal_ne[0], goal_ne[1]);
                match (start, goal) {
                    (Some(s), Some(g)) => {
                        let mut d = DStarLite::new(grid, s, g, model)
                            .map_err(|e| PlanFailure::internal(format!("replanning: {e}")))?;
                        d.compute();
                        Some(d)
                    }
                    _ => None,
                }
            }
            ReplannerKind::Scratch => None,
        };
        // The scratch search's node arrays are allocated here, not during the first replan.
        let mut search = GridSearch::new();
        let base = layers[0].world.grid();
        if let (Some(s), Some(g)) = (
            cell_near(base, [plan.start.north_m, plan.start.east_m]),
            base.cell_at_ne(goal_ne[0], goal_ne[1]),
        ) {
            let _ = search.search(base, s, g, model, Planner::Jps);
        }
        Ok(Self {
            session,
            plan,
            request: request.clone(),
            options,
            model,
            touch,
            safety_m: info.safety_m,
            goal_ne,
            layers,
            dstar,
            dstar_behind: false,
            pending: Vec::new(),
            search,
            stats: ReplanStats::default(),
            events: Vec::new(),
        })
    }

    /// The first route, as the session planned it.
    pub fn initial_plan(&self) -> &Plan {
        &self.plan
    }

    /// The first route's waypoints as targets (north, east, alt, heading).
    pub fn initial_targets(&self) -> Vec<Target> {
        self.plan
            .waypoints
            .iter()
            .map(|w| Target {
                north_m: w[0],
                east_m: w[1],
                alt_m: w[2],
                heading_rad: w[3],
            })
            .collect()
    }

    /// The session (its world and caches).
    pub fn session(&self) -> &Session {
        &self.session
    }

    /// Where the grids lie: origin and cell size (every layer shares it).
    pub fn grid_frame(&self) -> GridFrame {
        self.layers[0].world.known().frame()
    }

    /// The world model at the flight altitude.
    pub fn world(&self) -> &WorldModel {
        &self.layers[0].world
    }

    /// Learned cells at every layer: altitude, then the cells' centres (north, east, metres).
    pub fn learned_points_ne(&self) -> Vec<(f64, Vec<[f64; 2]>)> {
        self.layers
            .iter()
            .map(|l| (l.alt_m, l.world.learned_points_ne()))
            .filter(|(_, p)| !p.is_empty())
            .collect()
    }

    /// The cells learned at the layer of `alt_m` (within a millimetre of a layer's altitude),
    /// alone, as a grid ([`WorldModel::learned_grid`]); `None` off every layer.
    pub fn learned_grid_at(&self, alt_m: f64) -> Option<Grid2> {
        self.layers
            .iter()
            .find(|l| (l.alt_m - alt_m).abs() <= 1e-3)
            .map(|l| l.world.learned_grid())
    }

    /// The free space the first plan's trajectory was made in
    /// ([`Session::trajectory_space`]): a trajectory replanned in flight keeps to it and out
    /// of the learned cells ([`Replanner::learned_grid_at`]).
    pub fn trajectory_space(
        &mut self,
    ) -> Result<std::sync::Arc<dyn skyplan_plan::trajectory::FreeSpace + Send + Sync>, PlanFailure>
    {
        self.session.trajectory_space(&self.request, &self.plan)
    }

    /// Cells learned as occupied, summed over the layers.
    pub fn learned_count(&self) -> usize {
        self.layers.iter().map(|l| l.world.learned_count()).sum()
    }

    /// What was done so far.
    pub fn stats(&self) -> &ReplanStats {
        &self.stats
    }

    /// Every replan so far, in order (what the flight log's replan rows show).
    pub fn events(&self) -> &[ReplanEvent] {
        &self.events
    }

    /// The layer an altitude belongs to (nearest).
    fn layer_of(&self, alt_m: f64) -> usize {
        let k = ((alt_m - self.layers[0].alt_m) / self.options.climb_step_m).round();
        if k.is_finite() && k > 0.0 {
            (k as usize).min(self.layers.len() - 1)
        } else {
            0
        }
    }

    /// The first learned cell on the route still to fly, and the index of the target whose leg
    /// it blocks.
    fn blocked_leg(&self, from_ne: [f64; 3], route: &[Target]) -> Option<(Cell, usize, usize)> {
        let mut prev = from_ne;
        // True until the first leg that moves horizontally: it starts where the vehicle is.
        let mut from_vehicle = true;
        for (i, t) in route.iter().enumerate() {
            let next = [t.north_m, t.east_m, t.alt_m];
            let (la, lb) = (self.layer_of(prev[2]), self.layer_of(next[2]));
            let moves = (prev[0], prev[1]) != (next[0], next[1]);
            let leaving = from_vehicle;
            from_vehicle &= !moves;
            if la == lb && moves {
                let world = &self.layers[la].world;
                if !world.grid().segment_is_free_ne(
                    (prev[0], prev[1]),
                    (next[0], next[1]),
                    self.touch,
                ) && let Some(cell) = first_learned_on(
                    world,
                    [prev[0], prev[1]],
                    [next[0], next[1]],
                    self.touch,
                    leaving,
                ) {
                    return Some((cell, i, la));
                }
            }
            prev = next;
        }
        None
    }

    /// A route from `from` to the goal at layer `k`, checked; `None` if there is none.
    fn route_at(&mut self, k: usize, from: [f64; 2]) -> Option<Found> {
        let grid = self.layers[k].world.grid();
        let start = cell_near(grid, from)?;
        let goal = grid.cell_at_ne(self.goal_ne[0], self.goal_ne[1])?;
        let budget = self.options.dstar_budget_expansions.unwrap_or(u64::MAX);
        let mut repaired = None;
        if let (Some(d), 0) = (&mut self.dstar, k) {
            let before = d.expansions();
            d.update_cells(&self.pending);
            self.pending.clear();
            d.move_start(start);
            let spent = |d: &DStarLite| d.expansions() - before;
            let result = d.compute_within(budget);
            self.dstar_behind = result.is_err();
            repaired = Some(match result {
                Ok(path) => (path?.cells, spent(d), "dstar-lite".to_string()),
                // Over budget: this once from scratch (D* Lite catches up at later readings).
                Err(_) => {
                    let path = self
                        .search
                        .search(grid, start, goal, self.model, Planner::Jps)
                        .ok()?;
                    let name = "dstar-lite, over budget: scratch".to_string();
                    (path.cells, spent(d) + path.expansions, name)
                }
            });
        }
        let (cells, expansions, planner) = match repaired {
            Some(r) => r,
            None => {
                let path = self
                    .search
                    .search(grid, start, goal, self.model, Planner::Jps)
                    .ok()?;
                let name = if k == 0 { "scratch" } else { "scratch-climb" };
                (path.cells, path.expansions, name.to_string())
            }
        };
        let alt_m = self.layers[k].alt_m;
        let kept = shortcut(grid, &prune_collinear(&cells), self.touch);
        let points =
            skyplan_plan::waypoint_points(grid, &kept, from, self.goal_ne, self.touch, alt_m);
        // The re-checks: the map's grid (the planning API's check), then known and learned; a
        // first hop out of a learned margin the vehicle is already in is exempt from the latter.
        let known = self.layers[k].world.known();
        skyplan_plan::recheck_grid_route(known, &points, self.touch).ok()?;
        let inside = grid
            .cell_at_ne(from[0], from[1])
            .is_none_or(|c| grid.is_blocked(c));
        let checked = if inside && points.len() > 2 {
            &points[1..]
        } else {
            &points[..]
        };
        skyplan_plan::recheck_grid_route(grid, checked, self.touch).ok()?;
        Some(Found {
            points,
            expansions,
            planner,
        })
    }

    /// D\* Lite went over budget at a replan: repair on (within the budget) from where the
    /// vehicle is, so the next replan finds the search consistent.
    fn catch_up(&mut self, from_ne: [f64; 2]) {
        if !self.dstar_behind {
            return;
        }
        let grid = self.layers[0].world.grid();
        let Some(start) = cell_near(grid, from_ne) else {
            return;
        };
        let budget = self.options.dstar_budget_expansions.unwrap_or(u64::MAX);
        if let Some(d) = &mut self.dstar {
            d.update_cells(&self.pending);
            self.pending.clear();
            d.move_start(start);
            self.dstar_behind = d.compute_within(budget).is_err();
        }
    }

    /// Where the vehicle comes to rest on layer `k` if it brakes now, going straight on (see
    /// [`ReplanOptions::brake_accel_m_s2`]): `None` when it is (nearly) at rest, when braking is
    /// not modelled, or when it cannot go on freely at all.
    fn rest_point(&self, reading: &ObstacleReading, k: usize) -> Option<[f64; 2]> {
        let a = self.options.brake_accel_m_s2?;
        let [vn, ve, _] = reading.velocity_ned_m_s;
        let v = vn.hypot(ve);
        if !(a.is_finite() && a > 0.0 && v.is_finite() && v > 0.5) {
            return None;
        }
        let stop_m = v * v / (2.0 * a);
        let [n, e, _] = reading.position_ned;
        let grid = self.layers[k].world.grid();
        let rest = [n + vn / v * stop_m, e + ve / v * stop_m];
        // Only where the vehicle can come to rest in free space: short of that, a target ahead
        // lets the autopilot brake more gently than one behind it (ArduCopter SITL stopped ~1 m
        // farther, inside the margin), so the route begins where the vehicle is.
        (stop_m >= 1.0 && grid.segment_is_free_ne((n, e), (rest[0], rest[1]), self.touch))
            .then_some(rest)
    }

    fn replan(&mut self, reading: &ObstacleReading, reason: String, t0: Started) -> RouteDecision {
        let [n, e, d] = reading.position_ned;
        let alt_m = -d;
        let from = [n, e];
        let here = self.layer_of(alt_m);
        let rest = self.rest_point(reading, here);
        let mut tried = Vec::new();
        let mut overhead = None;
        for k in here..self.layers.len() {
            // Climbing goes straight up where the vehicle is: its cell must be free at every
            // layer on the way (the map's boxes and what was learned there).
            let column_free = (here + 1..=k).all(|j| {
                let g = self.layers[j].world.grid();
                g.cell_at_ne(n, e).is_some_and(|c| !g.is_blocked(c))
            });
            if !column_free {
                overhead = Some(self.layers[k].alt_m);
                break;
            }
            tried.push(format!("{:.1}", self.layers[k].alt_m));
            // At the flight's layer the new route begins where the vehicle comes to rest, if
            // one starts there; a climb begins where it is.
            let resting = rest.filter(|_| k == here);
            let Some(found) = resting
                .and_then(|p| self.route_at(k, p))
                .or_else(|| self.route_at(k, from))
            else {
                continue;
            };
            let mut points = found.points;
            if k != here || (alt_m - self.layers[k].alt_m).abs() > 0.5 {
                // Climb over where the vehicle is first.
                points.insert(0, [n, e, self.layers[k].alt_m]);
                if points.len() > 1 && (points[1][0], points[1][1]) == (n, e) {
                    points.remove(1);
                }
            }
            let targets = targets_from(&points, [n, e]);
            let route_length_m = length_m([n, e, alt_m], &points);
            let (latency_ms, cpu_ms) = t0.elapsed_ms();
            self.stats.replans += 1;
            self.stats.samples.push(ReplanSample {
                latency_ms,
                cpu_ms,
                expansions: found.expansions,
            });
            let reason = if k == here {
                reason
            } else {
                format!(
                    "{reason}; no way round at {:.1} m, climbing to {:.1} m",
                    self.layers[here].alt_m, self.layers[k].alt_m
                )
            };
            let event = ReplanEvent {
                time_s: reading.time_s,
                position_ned: reading.position_ned,
                reason,
                planner: found.planner,
                latency_ms,
                cpu_ms,
                expansions: found.expansions,
                route_length_m,
                learned_cells: self.learned_count(),
            };
            self.events.push(event.clone());
            return RouteDecision::Replace { targets, event };
        }
        self.stats.holds += 1;
        let overhead = overhead
            .map(|a| format!(" (an obstacle above the vehicle at {a:.1} m stops the climb)"))
            .unwrap_or_default();
        RouteDecision::Hold {
            reason: format!(
                "{reason}, and no route to the goal (N {:.1} E {:.1}) was found from N {n:.1} E {e:.1}: planned at {} m (up to the limit of {:.1} m){overhead} with the {:.1} m margin around the map's obstacles and {} learned cells",
                self.goal_ne[0],
                self.goal_ne[1],
                tried.join(", "),
                self.options.max_alt_m,
                self.safety_m,
                self.learned_count()
            ),
        }
    }
}

impl RouteWatcher for Replanner {
    fn on_reading(&mut self, reading: &ObstacleReading, route: &[Target]) -> RouteDecision {
        let t0 = Started::now();
        self.stats.readings += 1;
        let [n, e, d] = reading.position_ned;
        if !(n.is_finite() && e.is_finite() && d.is_finite()) {
            return RouteDecision::Keep;
        }
        let k = self.layer_of(-d);
        let changed = self.layers[k].world.apply(reading);
        if k == 0 && self.dstar.is_some() {
            self.pending.extend(changed);
        }
        let Some((cell, target, layer)) = self.blocked_leg([n, e, -d], route) else {
            self.catch_up([n, e]);
            return RouteDecision::Keep;
        };
        let (cn, ce) = self.layers[layer].world.known().center_ne(cell);
        let t = &route[target];
        let reason = format!(
            "learned obstacle at N {cn:.1} E {ce:.1} blocks the leg to waypoint {} (N {:.1} E {:.1}, {} still to fly)",
            target + 1,
            t.north_m,
            t.east_m,
            route.len()
        );
        self.replan(reading, reason, t0)
    }
}

/// The free cell holding `ne`, else the nearest free cell.
fn cell_near(grid: &Grid2, ne: [f64; 2]) -> Option<Cell> {
    match grid.cell_at_ne(ne[0], ne[1]) {
        Some(c) if !grid.is_blocked(c) => Some(c),
        _ => grid.nearest_free_ne(ne[0], ne[1]),
    }
}

/// The first learned cell along the cells a segment crosses (in order from `a`). With
/// `leaving` (the leg from the vehicle), the learned cells around the vehicle's own cell are
/// skipped until the segment leaves them: flying out of a margin is allowed, back in is not.
fn first_learned_on(
    world: &WorldModel,
    a: [f64; 2],
    b: [f64; 2],
    touch: Touch,
    leaving: bool,
) -> Option<Cell> {
    let grid = world.known();
    let (ca, cb) = (grid.cell_at_ne(a[0], a[1])?, grid.cell_at_ne(b[0], b[1])?);
    let mut inside = leaving && world.is_learned(ca);
    let mut found = None;
    Grid2::supercover(ca, cb, touch, |r, c| {
        let learned = grid
            .checked_cell(r, c)
            .filter(|&cell| world.is_learned(cell));
        match learned {
            Some(_) if inside => {}
            Some(cell) => {
                found = Some(cell);
                return false;
            }
            None => inside = false,
        }
        true
    });
    found
}

/// Targets with FCND headings (towards each target from the one before; kept when climbing).
fn targets_from(points: &[[f64; 3]], from_ne: [f64; 2]) -> Vec<Target> {
    let mut prev = (from_ne[0], from_ne[1]);
    let mut heading: Option<f64> = None;
    let mut out: Vec<Target> = points
        .iter()
        .map(|p| {
            let here = (p[0], p[1]);
            if here != prev {
                heading = Some(skyplan_mission::heading_rad(prev, here));
            }
            prev = here;
            Target {
                north_m: p[0],
                east_m: p[1],
                alt_m: p[2],
                heading_rad: heading.unwrap_or(f64::NAN),
            }
        })
        .collect();
    // Targets before the first horizontal move take its heading.
    let first = out
        .iter()
        .map(|t| t.heading_rad)
        .find(|h| !h.is_nan())
        .unwrap_or(0.0);
    for t in &mut out {
        if t.heading_rad.is_nan() {
            t.heading_rad = first;
        }
    }
    out
}

fn length_m(from: [f64; 3], points: &[[f64; 3]]) -> f64 {
    let mut prev = from;
    let mut total = 0.0;
    for p in points {
        total +=
            ((p[0] - prev[0]).powi(2) + (p[1] - prev[1]).powi(2) + (p[2] - prev[2]).powi(2)).sqrt();
        prev = *p;
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;
    use skyplan_flight::sensing::SectorRange;
    use skyplan_plan::World;
    use std::sync::Arc;

    const FROM: [f64; 2] = [250.5, -38.5];
    const TO: [f64; 2] = [390.5, -58.5];

    fn replanner(kind: ReplannerKind) -> Replanner {
        let request = PlanRequest {
            start_ne: Some(FROM),
            goal_ne: Some(TO),
            ..Default::default()
        };
        let options = ReplanOptions {
            replanner: kind,
            ..Default::default()
        };
        Replanner::new(Session::new(World::fcnd_city()), &request, options).unwrap()
    }

    /// One obstacle `range_m` away at sector `sector` (of 72, 5° each, from north).
    fn reading(sector: usize, range_m: f64) -> ObstacleReading {
        let mut ranges = vec![SectorRange::Clear; 72];
        ranges[sector] = SectorRange::Obstacle(range_m);
        ObstacleReading {
            time_s: 1.0,
            position_ned: [FROM[0], FROM[1], -5.0],
            velocity_ned_m_s: [0.0; 3],
            first_bearing_rad: 0.0,
            increment_rad: 5f64.to_radians(),
            min_range_m: 0.2,
            max_range_m: 30.0,
            ranges,
        }
    }

    /// A replanner on an empty 21 m × 41 m grid, from its west end to its east end, 1 m margin.
    fn strip(options: ReplanOptions) -> Replanner {
        let grid = skyplan_cspace::Grid2::new(
            21,
            41,
            vec![false; 21 * 41],
            skyplan_cspace::GridFrame::default(),
        )
        .unwrap();
        let request = PlanRequest {
            start_ne: Some([10.5, 0.5]),
            goal_ne: Some([10.5, 40.5]),
            safety_m: Some(1.0),
            ..Default::default()
        };
        let world = World::from_grid("strip", grid);
        Replanner::new(Session::new(world), &request, options).unwrap()
    }

    #[test]
    fn a_wall_across_a_grid_map_holds_without_climbing() {
        let mut r = strip(ReplanOptions::default());
        let route = r.initial_targets();
        // A wall 15 m east, from the southern edge to the northern one: 41 sectors of 1 m.
        let ranges = (0..=20)
            .map(|row| {
                let dn = row as f64 - 10.0;
                let bearing = 15f64.atan2(dn);
                (bearing, SectorRange::Obstacle(dn.hypot(15.0)))
            })
            .collect::<Vec<_>>();
        for (bearing, range) in ranges {
            let reading = ObstacleReading {
                time_s: 1.0,
                position_ned: [10.5, 0.5, -5.0],
                velocity_ned_m_s: [0.0; 3],
                first_bearing_rad: bearing,
                increment_rad: 0.1,
                min_range_m: 0.2,
                max_range_m: 30.0,
                ranges: vec![range],
            };
            if let RouteDecision::Hold { reason } = r.on_reading(&reading, &route) {
                assert!(reason.contains("no route to the goal"), "{reason}");
                assert!(
                    reason.contains("planned at 5.0 m"),
                    "only the grid's altitude: {reason}"
                );
                return;
            }
        }
        panic!("no hold after the wall was seen whole");
    }

    /// A replan at speed begins where the vehicle comes to rest going straight on (v² / 2a
    /// ahead) when the way there is free; short of that, at rest, or without braking modelled,
    /// it begins where the vehicle is.
    #[test]
    fn a_replan_at_speed_begins_where_the_vehicle_comes_to_rest() {
        let first_target = |speed_m_s: f64, brake: Option<f64>| {
            let mut r = strip(ReplanOptions {
                brake_accel_m_s2: brake,
                ..ReplanOptions::default()
            });
            let route = r.initial_targets();
            // Heading east along the route; a pole 15 m ahead, on it.
            let reading = ObstacleReading {
                time_s: 1.0,
                position_ned: [10.5, 0.5, -5.0],
                velocity_ned_m_s: [0.0, speed_m_s, 0.0],
                first_bearing_rad: std::f64::consts::FRAC_PI_2,
                increment_rad: 0.01,
                min_range_m: 0.2,
                max_range_m: 30.0,
                ranges: vec![SectorRange::Obstacle(15.0)],
            };
            let RouteDecision::Replace { targets, .. } = r.on_reading(&reading, &route) else {
                panic!("a pole on the route is a replan");
            };
            let learned = r.world().grid().clone();
            let t = targets[0];
            assert!(
                learned.segment_is_free_ne((10.5, 0.5), (t.north_m, t.east_m), r.touch),
                "the way to the first target is free"
            );
            [t.north_m, t.east_m]
        };
        // 6 m/s at 2 m/s²: 9 m on.
        assert_eq!(first_target(6.0, Some(2.0)), [10.5, 9.5]);
        // At 10 m/s it would stop 25 m on, past the pole's learned margin (about 13 m on); at
        // rest, or not braking: the route leaves the vehicle's spot for a corner.
        for [n, e] in [
            first_target(10.0, Some(2.0)),
            first_target(0.0, Some(2.0)),
            first_target(10.0, None),
        ] {
            assert!(n != 10.5 || e < 9.5 - 1e-9, "{n}, {e}");
        }
    }

    #[test]
    fn an_obstacle_off_the_route_keeps_it() {
        let mut r = replanner(ReplannerKind::DStarLite);
        let route = r.initial_targets();
        assert_eq!(route.len(), 2, "a straight leg");
        // 12 m to the east or west of the vehicle (the route heads north-north-west), in the
        // first sector whose hit lands outside the map's obstacles.
        let known = Arc::clone(r.world().known());
        let sector = (9..27)
            .chain(45..63)
            .find(|&k| {
                let b = (5.0 * k as f64).to_radians();
                let at = known.cell_at_ne(FROM[0] + 12.0 * b.cos(), FROM[1] + 12.0 * b.sin());
                at.is_some_and(|c| !known.is_blocked(c))
            })
            .expect("a free sector");
        assert_eq!(
            r.on_reading(&reading(sector, 12.0), &route),
            RouteDecision::Keep
        );
        assert!(r.learned_count() > 0);
        assert_eq!(r.stats().readings, 1);
        assert_eq!(r.stats().replans, 0);
    }

    #[test]
    fn flying_out_of_a_learned_margin_is_not_a_block() {
        let mut r = replanner(ReplannerKind::Scratch);
        let route = r.initial_targets();
        // 3 m due south: the vehicle is inside the learned margin, flying away from it.
        assert_eq!(r.on_reading(&reading(36, 3.0), &route), RouteDecision::Keep);
        let here = r.world().known().cell_at_ne(FROM[0], FROM[1]).unwrap();
        assert!(r.world().is_learned(here));
    }

    #[test]
    fn both_replanners_find_routes_of_equal_grid_cost_around_the_same_obstacle() {
        let mut costs = Vec::new();
        for kind in [ReplannerKind::DStarLite, ReplannerKind::Scratch] {
            let mut r = replanner(kind);
            let route = r.initial_targets();
            let RouteDecision::Replace { targets, event } =
                r.on_reading(&reading(70, 15.0), &route)
            else {
                panic!("{kind}: expected a new route");
            };
            assert_eq!(event.planner, kind.name());
            assert!(
                event.reason.contains("blocks the leg to waypoint 2"),
                "{}",
                event.reason
            );
            let pts: Vec<[f64; 3]> = targets
                .iter()
                .map(|t| [t.north_m, t.east_m, t.alt_m])
                .collect();
            // Clear of everything learned and known, under the corner rule.
            assert!(
                skyplan_plan::recheck_grid_route(r.world().grid(), &pts, Touch::Closed).is_ok()
            );
            assert!(pts.iter().all(|p| p[2] == 5.0));
            // Octile cost of the new grid path, from the search itself.
            costs.push((kind, event.route_length_m));
        }
        // Both are shortcuts of optimal octile paths: within a few metres of each other.
        assert!((costs[0].1 - costs[1].1).abs() < 5.0, "{costs:?}");
    }
}

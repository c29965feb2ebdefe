//! Hidden obstacles: buildings the map does not know, placed on or near a route, and the true
//! world they make (for simulators, tests and `--hidden-random N --seed S`).

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use skyplan_cspace::{Grid2, GridSpec};
use skyplan_map::colliders::{CollidersMap, ObstacleBox};
use skyplan_map::footprints::{Footprint, FootprintMap};
use skyplan_plan::{PlanFailure, World};
use skyplan_search::{GridSearch, MoveModel, Planner};

/// Where and how to place hidden buildings.
#[derive(Debug, Clone, PartialEq)]
pub struct HiddenSpec {
    /// How many buildings.
    pub count: usize,
    /// Seed: the same seed gives the same buildings everywhere (ChaCha8).
    pub seed: u64,
    /// The planned route, north/east points, metres (the buildings go on or near it).
    pub route_ne: Vec<[f64; 2]>,
    /// Start, north/east metres (never covered, with the margin).
    pub start_ne: [f64; 2],
    /// Goal, north/east metres (never covered, with the margin).
    pub goal_ne: [f64; 2],
    /// Flight altitude, metres (every building rises above it).
    pub alt_m: f64,
    /// Safety margin, metres.
    pub safety_m: f64,
    /// Grid cell size of the reachability check, metres.
    pub cell_m: f64,
    /// Move model of the reachability check.
    pub model: MoveModel,
}

/// Why hidden buildings could not be placed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HiddenError {
    /// A parameter is out of range.
    #[error("hidden buildings: {0}")]
    BadSpec(String),
    /// Not every building found a place that keeps the goal reachable.
    #[error(
        "hidden buildings: placed {placed} of {wanted} after {attempts} attempts; every other place covered the start or the goal or walled the goal off"
    )]
    NoRoom {
        /// Buildings placed.
        placed: usize,
        /// Buildings asked for.
        wanted: usize,
        /// Placements tried.
        attempts: usize,
    },
    /// The map's grid could not be built.
    #[error("hidden buildings: {0}")]
    Grid(String),
}

/// Attempts per building before giving up.
const ATTEMPTS_PER_BOX: usize = 40;

/// `spec.count` random buildings on or near the route: each centred within 6 m of a random
/// point of the route (away from both ends), 2–6 m half sizes, from the ground to 15–40 m above
/// the flight altitude. None covers the start or the goal grown by the margin, and after each
/// one the goal stays reachable at the flight altitude (a JPS search on the grid of the map's
/// boxes plus the hidden ones); a place that fails is drawn again (at most 40 times per
/// building).
///
/// ```
/// use skyplan_replan::hidden::{HiddenSpec, place_hidden};
/// use skyplan_search::MoveModel;
/// let map = skyplan_map::colliders::parse_colliders(skyplan_plan::FCND_CITY_CSV).unwrap();
/// let spec = HiddenSpec {
///     count: 3, seed: 7, route_ne: vec![[250.5, -38.5], [390.5, -58.5]], start_ne: [250.5, -38.5],
///     goal_ne: [390.5, -58.5], alt_m: 5.0, safety_m: 5.0, cell_m: 1.0, model: MoveModel::Octile,
/// };
/// let hidden = place_hidden(&map, &spec)?;
/// assert_eq!(hidden.len(), 3);
/// assert_eq!(place_hidden(&map, &spec)?, hidden); // deterministic for a seed
/// # Ok::<(), skyplan_replan::hidden::HiddenError>(())
/// ```
pub fn place_hidden(
    map: &CollidersMap,
    spec: &HiddenSpec,
) -> Result<Vec<ObstacleBox>, HiddenError> {
    place_with(spec, |hidden, grid_spec| {
        let mut trial = map.clone();
        trial.boxes.extend_from_slice(hidden);
        Grid2::from_colliders(&trial, grid_spec)
    })
}

/// [`place_hidden`] on a map of building footprints: the reachability check's grid is the
/// footprints' with each hidden box as one more (rectangular) footprint.
///
/// ```
/// use skyplan_replan::hidden::{HiddenSpec, place_hidden_among_footprints};
/// use skyplan_search::MoveModel;
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/footprints-sample.geojson"));
/// let map = skyplan_map::footprints::parse_geojson(text, 10.0).unwrap().project(None).unwrap();
/// let spec = HiddenSpec {
///     count: 2, seed: 7, route_ne: vec![[0.0, 0.0], [62.5, -21.5], [62.5, -49.5], [118.0, -61.0]],
///     start_ne: [0.0, 0.0], goal_ne: [118.0, -61.0], alt_m: 5.0, safety_m: 5.0, cell_m: 1.0,
///     model: MoveModel::Octile,
/// };
/// assert_eq!(place_hidden_among_footprints(&map, &spec)?.len(), 2);
/// # Ok::<(), skyplan_replan::hidden::HiddenError>(())
/// ```
pub fn place_hidden_among_footprints(
    map: &FootprintMap,
    spec: &HiddenSpec,
) -> Result<Vec<ObstacleBox>, HiddenError> {
    place_with(spec, |hidden, grid_spec| {
        let mut trial = map.clone();
        trial.footprints.extend(hidden.iter().map(|b| Footprint {
            feature: usize::MAX,
            rings: vec![vec![
                [b.north_m - b.half_north_m, b.east_m - b.half_east_m],
                [b.north_m + b.half_north_m, b.east_m - b.half_east_m],
                [b.north_m + b.half_north_m, b.east_m + b.half_east_m],
                [b.north_m - b.half_north_m, b.east_m + b.half_east_m],
            ]],
            min_height_m: b.up_m - b.half_up_m,
            height_m: b.up_m + b.half_up_m,
        }));
        Grid2::from_footprints(&trial, grid_spec)
    })
}

/// The placement, with `grid_with(hidden, spec)` the map's grid with the `hidden` boxes added.
fn place_with(
    spec: &HiddenSpec,
    grid_with: impl Fn(&[ObstacleBox], GridSpec) -> Result<Grid2, skyplan_cspace::GridError>,
) -> Result<Vec<ObstacleBox>, HiddenError> {
    let finite = spec.alt_m.is_finite()
        && spec.safety_m.is_finite()
        && spec.safety_m >= 0.0
        && spec.cell_m.is_finite()
        && spec.cell_m > 0.0;
    if !finite {
        return Err(HiddenError::BadSpec(format!(
            "alt_m {}, safety_m {}, cell_m {}: expected finite numbers, margin ≥ 0, cell > 0",
            spec.alt_m, spec.safety_m, spec.cell_m
        )));
    }
    if spec.route_ne.len() < 2 {
        return Err(HiddenError::BadSpec(
            "the route needs at least two points".to_string(),
        ));
    }
    let legs: Vec<(f64, [f64; 2], [f64; 2])> = spec
        .route_ne
        .windows(2)
        .map(|w| ((w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]), w[0], w[1]))
        .collect();
    let total: f64 = legs.iter().map(|l| l.0).sum();
    if !(total.is_finite() && total > 0.0) {
        return Err(HiddenError::BadSpec("the route has no length".to_string()));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let mut hidden = Vec::new();
    let mut search = GridSearch::new();
    let attempts_max = ATTEMPTS_PER_BOX * spec.count.max(1);
    let mut attempts = 0;
    let keep_clear = |b: &ObstacleBox, p: [f64; 2]| {
        let m = spec.safety_m + spec.cell_m;
        (b.north_m - p[0]).abs() > b.half_north_m + m || (b.east_m - p[1]).abs() > b.half_east_m + m
    };
    while hidden.len() < spec.count && attempts < attempts_max {
        attempts += 1;
        // A point along the route, away from both ends.
        let lo = (spec.safety_m + 10.0).min(total / 3.0);
        let mut s = rng.random_range(lo..(total - lo).max(lo + 1e-9));
        let mut at = legs[0].1;
        for &(len, a, b) in &legs {
            if s <= len && len > 0.0 {
                let t = s / len;
                at = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
                break;
            }
            s -= len;
        }
        let height = spec.alt_m + rng.random_range(15.0..40.0);
        let b = ObstacleBox {
            north_m: at[0] + rng.random_range(-6.0..6.0),
            east_m: at[1] + rng.random_range(-6.0..6.0),
            up_m: height / 2.0,
            half_north_m: rng.random_range(2.0..6.0),
            half_east_m: rng.random_range(2.0..6.0),
            half_up_m: height / 2.0,
        };
        if !keep_clear(&b, spec.start_ne) || !keep_clear(&b, spec.goal_ne) {
            continue;
        }
        hidden.push(b);
        if !reachable(&grid_with, &hidden, spec, &mut search)? {
            hidden.pop();
        }
    }
    if hidden.len() < spec.count {
        return Err(HiddenError::NoRoom {
            placed: hidden.len(),
            wanted: spec.count,
            attempts,
        });
    }
    Ok(hidden)
}

/// True if the goal is reachable from the start at the flight altitude among the map's
/// obstacles and the `hidden` boxes.
fn reachable(
    grid_with: &impl Fn(&[ObstacleBox], GridSpec) -> Result<Grid2, skyplan_cspace::GridError>,
    hidden: &[ObstacleBox],
    spec: &HiddenSpec,
    search: &mut GridSearch,
) -> Result<bool, HiddenError> {
    let grid = grid_with(
        hidden,
        GridSpec {
            alt_m: spec.alt_m,
            safety_m: spec.safety_m,
            cell_m: spec.cell_m,
        },
    )
    .map_err(|e| HiddenError::Grid(e.to_string()))?;
    let cell = |p: [f64; 2]| grid.cell_at_ne(p[0], p[1]);
    let (Some(s), Some(g)) = (cell(spec.start_ne), cell(spec.goal_ne)) else {
        return Ok(false);
    };
    Ok(search.search(&grid, s, g, spec.model, Planner::Jps).is_ok())
}

/// The true world: `world`'s boxes and the hidden ones, as a planning [`World`] with the same
/// name (plus " + hidden") and default endpoints (for the full-knowledge optimum and the
/// simulator's collision check).
///
/// ```
/// use skyplan_map::colliders::ObstacleBox;
/// use skyplan_plan::{PlanRequest, Session, World};
/// let city = World::fcnd_city();
/// let extra = ObstacleBox { north_m: 320.0, east_m: -48.0, up_m: 20.0, half_north_m: 4.0, half_east_m: 7.0, half_up_m: 20.0 };
/// let truth = skyplan_replan::hidden::true_world(&city, &[extra])?;
/// assert_eq!(truth.colliders().map(|m| m.boxes.len()), city.colliders().map(|m| m.boxes.len() + 1));
/// let blocked = |world: World| -> Result<bool, skyplan_plan::PlanFailure> {
///     let grid = Session::new(world).grid(5.0, 5.0, 1.0)?;
///     Ok(grid.cell_at_ne(320.0, -48.0).is_some_and(|c| grid.is_blocked(c)))
/// };
/// assert!(!blocked(city.clone())? && blocked(truth.clone())?);
/// assert_eq!(truth.default_endpoints_ne(), city.default_endpoints_ne());
/// assert!(Session::new(truth).plan(&PlanRequest::default()).is_ok());
/// # Ok::<(), skyplan_plan::PlanFailure>(())
/// ```
pub fn true_world(world: &World, hidden: &[ObstacleBox]) -> Result<World, PlanFailure> {
    let Some(map) = world.colliders() else {
        return Err(PlanFailure::bad_request(format!(
            "hidden buildings need a colliders map; {} is a grid map",
            world.name()
        )));
    };
    let mut all = map.clone();
    all.boxes.extend_from_slice(hidden);
    let (start, goal) = world.default_endpoints_ne();
    Ok(
        World::from_colliders(&format!("{} + hidden", world.name()), all)?
            .with_defaults(start, goal),
    )
}

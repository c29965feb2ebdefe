//! The 3D planners among the map's boxes (grown by the margin in all three axes): PRM, lazy
//! PRM, RRT-Connect, Informed RRT\* (`skyplan-sampling`) and voxel A\* (`skyplan-voxel`).

use crate::failure::{FailureKind, PlanFailure};
use crate::session::{Check, Query, Route, Session, micros};
use rand::SeedableRng;
use serde_json::json;
use skyplan_map::nofly::Zone;
use skyplan_sampling::prm::{PrmConfig, Roadmap, solve, solve_from};
use skyplan_sampling::{Budget, CollisionChecker, PlannerKind, Request, Solution, Status};
use skyplan_world3::{BoxWorld3, Neu};
use std::sync::Arc;
use std::time::Instant;

fn at(p: Neu) -> String {
    format!("N {:.2} m, E {:.2} m, altitude {:.2} m", p[0], p[1], p[2])
}

/// Why a point is not free: below the floor, outside the volume, within the margin of a no-fly
/// zone (the last `zones.len()` prisms of the world) or of an obstacle.
fn why_invalid(world: &BoxWorld3, p: Neu, safety_m: f64, zones: &[Zone]) -> String {
    let first_zone = world.inflated_boxes().len() + world.prisms().len() - zones.len();
    if let Some(k) = world.box_containing(p).filter(|&k| k >= first_zone) {
        return format!(
            "within {safety_m} m of no-fly zone {}",
            zones[k - first_zone].feature
        );
    }
    let b = world.bounds();
    if p[2] < b.min[2] && b.min[2] > 0.0 {
        format!(
            "below the floor of the flight volume (min_alt_m {} m)",
            b.min[2]
        )
    } else if p[2] < b.min[2] {
        "below the ground".to_string()
    } else if !b.contains(p) {
        format!(
            "outside the flight volume N {:.1}..{:.1}, E {:.1}..{:.1}, altitude {:.1}..{:.1} m",
            b.min[0], b.max[0], b.min[1], b.max[1], b.min[2], b.max[2]
        )
    } else {
        format!("within {safety_m} m of an obstacle")
    }
}

fn ends(q: &Query) -> (Neu, Neu) {
    (
        [q.start_ne[0], q.start_ne[1], q.r.start.alt_m],
        [q.goal_ne[0], q.goal_ne[1], q.r.goal.alt_m],
    )
}

fn check_ends(world: &BoxWorld3, q: &Query) -> Result<(Neu, Neu), PlanFailure> {
    let (start, goal) = ends(q);
    for (p, which, kind) in [
        (start, "start", FailureKind::InvalidStart),
        (goal, "goal", FailureKind::InvalidGoal),
    ] {
        if !world.is_free(p) {
            return Err(PlanFailure::new(
                kind,
                format!(
                    "{which} {} is {}",
                    at(p),
                    why_invalid(world, p, q.r.safety_m, q.zones)
                ),
            ));
        }
    }
    Ok((start, goal))
}

fn volume(world: &BoxWorld3) -> serde_json::Value {
    json!({ "min": world.bounds().min, "max": world.bounds().max })
}

/// What a sampling run hands back beside its solution.
#[derive(Default)]
struct Extras {
    /// Roadmap or tree edges (with geometry).
    edges: Vec<(Neu, Neu)>,
    /// The path before shortcutting (PRM, with geometry).
    raw_path: Vec<Neu>,
    /// The roadmap's bytes, when asked to save it.
    saved: Option<Vec<u8>>,
    details: serde_json::Map<String, serde_json::Value>,
}

/// PRM, lazy PRM, RRT-Connect or RRT\*.
pub(crate) fn sampling(
    session: &mut Session,
    q: &Query,
    kind: PlannerKind,
) -> Result<Route, PlanFailure> {
    let r = q.r;
    let t_world = Instant::now();
    let world = session.boxes(r, q.zones)?;
    let world_us = micros(t_world.elapsed());
    let (start, goal) = check_ends(&world, q)?;
    let budget = Budget::time(r.time_limit);
    let (solution, extras) = match kind {
        PlannerKind::Prm | PlannerKind::LazyPrm => prm(session, &world, kind, q, budget)?,
        PlannerKind::RrtConnect | PlannerKind::RrtStar => {
            let req = Request {
                start,
                goal,
                seed: r.seed,
                budget,
                range_m: None,
                simplify: true,
            };
            let mut extras = Extras::default();
            let s = if r.geometry {
                let (s, tree) = skyplan_sampling::plan_with_tree(world.as_ref(), kind, &req);
                extras.edges = tree;
                s
            } else {
                skyplan_sampling::plan(world.as_ref(), kind, &req)
            };
            (s, extras)
        }
    };
    let mut route = finish(&world, q, r.planner.name(), solution, world_us)?;
    route.details.extend(extras.details);
    route.saved_roadmap = extras.saved;
    if r.geometry {
        route.geometry.edges = extras.edges.into_iter().map(|(a, b)| [a, b]).collect();
        route.geometry.edges_label = match kind {
            PlannerKind::Prm => "PRM roadmap",
            PlannerKind::LazyPrm => "lazy PRM roadmap (unchecked edges included)",
            PlannerKind::RrtConnect => "RRT-Connect trees",
            PlannerKind::RrtStar => "RRT* tree",
        }
        .into();
        route.geometry.raw_path = extras.raw_path;
    }
    Ok(route)
}

/// The key of the session's kept PRM roadmap: the volume, the margin, and over terrain the
/// height above it (the columns' tops depend on it).
fn prm_key(session: &Session, r: &crate::request::Resolved, lazy: bool) -> crate::session::Key {
    crate::session::key([
        r.safety_m,
        r.min_alt_m,
        r.max_alt_m,
        if lazy { 1.0 } else { 0.0 },
        session.world().terrain().map_or(-1.0, |_| r.alt_m),
    ])
}

/// PRM or lazy PRM: the run, its roadmap's statistics (saved if asked), the shortcut path, and
/// the roadmap kept by the session for the next request on this volume.
fn prm(
    session: &mut Session,
    world: &Arc<BoxWorld3>,
    kind: PlannerKind,
    q: &Query,
    budget: Budget,
) -> Result<(Solution, Extras), PlanFailure> {
    let r = q.r;
    let mut extras = Extras::default();
    let (roadmap, mut solution) = run_prm(session, world, kind, q, budget)?;
    let st = roadmap.stats;
    let mut info = json!({
        "vertices": roadmap.vertices().len(),
        "edges": roadmap.edges(),
        "unchecked_edges": roadmap.unchecked_edges(),
        "edges_tested": st.edges_tested,
        "edges_removed": st.edges_removed,
        "connector_tests": st.connector_tests,
        "build_us": st.build_us,
        "loaded_from": q.roadmap.load.as_ref().map(|(name, _)| name.clone()),
    });
    if q.roadmap.save {
        let bytes = roadmap.to_json(world);
        info["saved_bytes"] = json!(bytes.len());
        extras.saved = Some(bytes);
    }
    extras.details.insert("roadmap".into(), info);
    if r.geometry {
        let points = roadmap.vertices();
        extras.edges = (roadmap.edge_list().into_iter())
            .map(|(a, b)| (points[a as usize], points[b as usize]))
            .collect();
    }
    if solution.status == Status::Exact {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(r.seed ^ 0x5eed_5eed);
        extras.raw_path = solution.path.clone();
        solution.path =
            skyplan_sampling::shortcut::simplify(world.as_ref(), &solution.path, &mut rng, 200);
        solution.cost_m = skyplan_world3::path_length_m(&solution.path);
    }
    // A roadmap among no-fly zones is for those zones only: not kept.
    if q.zones.is_empty() {
        let key = prm_key(session, r, kind == PlannerKind::LazyPrm);
        if session.prm.len() >= 8 {
            session.prm.clear();
        }
        session.prm.insert(key, roadmap);
    }
    Ok((solution, extras))
}

/// A PRM run keeping the roadmap: from a saved roadmap, from the session's last roadmap for
/// this world, or built anew, and grown until start and goal connect.
fn run_prm(
    session: &mut Session,
    world: &BoxWorld3,
    kind: PlannerKind,
    q: &Query,
    budget: Budget,
) -> Result<(Roadmap, Solution), PlanFailure> {
    let r = q.r;
    let lazy = kind == PlannerKind::LazyPrm;
    let (start, goal) = ends(q);
    if let Some((name, bytes)) = &q.roadmap.load {
        let roadmap = Roadmap::from_json(bytes, world)
            .map_err(|e| PlanFailure::bad_request(format!("roadmap {name}: {e}")))?;
        if roadmap.is_lazy() != lazy {
            let built = if roadmap.is_lazy() { "lazy-prm" } else { "prm" };
            return Err(PlanFailure::bad_request(format!(
                "roadmap {name}: the roadmap was built by planner {built}; use that planner"
            )));
        }
        return Ok(solve_from(world, roadmap, start, goal, 0, budget));
    }
    let key = prm_key(session, r, lazy);
    if q.zones.is_empty()
        && let Some(roadmap) = session.prm.remove(&key)
    {
        return Ok(solve_from(world, roadmap, start, goal, 0, budget));
    }
    let config = PrmConfig {
        seed: r.seed,
        lazy,
        ..Default::default()
    };
    Ok(solve(world, start, goal, &config, budget))
}

/// A sampling or voxel solution as a route, or the failure it means.
fn finish(
    world: &Arc<BoxWorld3>,
    q: &Query,
    name: &str,
    s: Solution,
    world_us: u64,
) -> Result<Route, PlanFailure> {
    let (start, goal) = ends(q);
    let invalid = |kind: FailureKind, end: &str, p: Neu| {
        let why = why_invalid(world, p, q.r.safety_m, q.zones);
        Err(PlanFailure::new(kind, format!("{end} {} is {why}", at(p))))
    };
    match s.status {
        Status::Exact => {}
        Status::InvalidStart => return invalid(FailureKind::InvalidStart, "start", start),
        Status::InvalidGoal => return invalid(FailureKind::InvalidGoal, "goal", goal),
        Status::Timeout | Status::Approximate => {
            let nearest = if s.status == Status::Approximate {
                format!(
                    "; the nearest point reached is {:.2} m from the goal",
                    s.goal_gap_m
                )
            } else {
                String::new()
            };
            return Err(PlanFailure::new(
                FailureKind::Timeout,
                format!(
                    "{name}: no path from {} to {} within {} ms ({} samples, {} vertices){nearest}; allow more time with time_limit_ms",
                    at(start),
                    at(goal),
                    q.r.time_limit_ms,
                    s.iterations,
                    s.vertices
                ),
            ));
        }
    }
    let mut route = Route::new(s.path, s.cost_m, Check::Boxes(Arc::clone(world)));
    route.expansions = s.iterations as u64;
    route.timings.grid_build_us = world_us;
    route.timings.search_us = s.elapsed_us;
    for (k, v) in [
        ("planner_status", json!(s.status.name())),
        ("seed", json!(q.r.seed)),
        ("time_limit_ms", json!(q.r.time_limit_ms)),
        ("flight_volume", volume(world)),
        ("iterations", json!(s.iterations)),
        ("vertices", json!(s.vertices)),
        ("first_solution_us", json!(s.first_solution_us)),
        ("world_build_us", json!(world_us)),
    ] {
        route.details.insert(k.into(), v);
    }
    Ok(route)
}

/// Voxel A\*: the lattice over the box world (built per request), 26-connected with a climb cost.
pub(crate) fn voxel(session: &mut Session, q: &Query) -> Result<Route, PlanFailure> {
    use skyplan_voxel::{End, Query as VoxelQuery, VoxelError, VoxelGrid, VoxelSpec};
    let r = q.r;
    let t_world = Instant::now();
    let world = session.boxes(r, q.zones)?;
    let world_us = micros(t_world.elapsed());
    let (start, goal) = ends(q);
    let spec = VoxelSpec {
        cell_m: r.voxel_m,
        layer_m: r.layer_m,
    };
    let grid = VoxelGrid::build(&world, &spec)
        .map_err(|e| PlanFailure::bad_request(format!("voxel_m/layer_m: {e}")))?;
    let query = VoxelQuery {
        start,
        goal,
        climb_weight: r.climb_weight,
        shortcut: true,
    };
    let found = match grid.plan(&query) {
        Ok(found) => found,
        Err(VoxelError::Invalid(end)) => {
            let (p, kind) = if end == End::Start {
                (start, FailureKind::InvalidStart)
            } else {
                (goal, FailureKind::InvalidGoal)
            };
            return Err(PlanFailure::new(
                kind,
                format!(
                    "{} {} is {}",
                    end.name(),
                    at(p),
                    why_invalid(&world, p, r.safety_m, q.zones)
                ),
            ));
        }
        Err(e @ (VoxelError::NoConnector(_) | VoxelError::NoPath { .. })) => {
            return Err(PlanFailure::new(
                FailureKind::NoPath,
                format!("voxel: no path from {} to {}: {e}", at(start), at(goal)),
            ));
        }
        Err(e @ VoxelError::InvalidSpec(_)) => return Err(PlanFailure::bad_request(e.to_string())),
        Err(e @ VoxelError::Internal(_)) => return Err(PlanFailure::internal(e.to_string())),
    };
    let info = json!({
        "cell_m": spec.cell_m,
        "layer_m": spec.layer_m,
        "dims": grid.dims(),
        "voxels": grid.len(),
        "blocked": grid.blocked_count(),
        "build_us": grid.build_us(),
        "climb_weight": r.climb_weight,
        "climb_m": found.climb_m,
        "objective": found.cost,
        "lattice_objective": found.raw_cost,
        "lattice_waypoints": found.raw.len(),
        "expansions": found.expansions,
        "edge_checks": found.edge_checks,
    });
    let solution = Solution {
        status: Status::Exact,
        cost_m: found.length_m,
        goal_gap_m: 0.0,
        iterations: found.expansions,
        vertices: grid.len(),
        first_solution_us: Some(found.search_us),
        elapsed_us: found.search_us,
        path: found.path,
    };
    let mut route = finish(&world, q, "voxel", solution, world_us + grid.build_us())?;
    route.details.insert("voxel".into(), info);
    if r.geometry {
        route.geometry.raw_path = found.raw;
    }
    Ok(route)
}

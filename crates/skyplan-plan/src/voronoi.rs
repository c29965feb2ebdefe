//! The Voronoi roadmap of the grown obstacles at the flight altitude, with the grid (JPS) as
//! the fallback; the roadmap is built once per altitude/margin/cell size in a session. On a
//! colliders map its sites sample the grown boxes' sides; on a footprint map they are the
//! blocked cells along the free space (footprints of any shape).

use crate::failure::{FailureKind, PlanFailure};
use crate::grid::grid_for;
use crate::session::{Check, Query, Route, Session, micros};
use serde_json::json;
use skyplan_cspace::Touch;
use skyplan_roadmap::{Roadmap, RoadmapError, RoadmapSpec};
use std::sync::Arc;
use std::time::Instant;

/// The session's roadmap at the request's altitude, margin and cell size, built if it has none.
fn kept_roadmap(
    session: &mut Session,
    map: Option<&skyplan_map::colliders::CollidersMap>,
    grid: &skyplan_cspace::Grid2,
    r: &crate::request::Resolved,
) -> Arc<Roadmap> {
    let k = [r.alt_m, r.safety_m, r.cell_m, 0.0, 0.0].map(f64::to_bits);
    if let Some(m) = session.voronoi.get(&k) {
        return Arc::clone(m);
    }
    let spec = RoadmapSpec::default();
    let m = Arc::new(match map {
        Some(map) => Roadmap::build(map, grid, r.alt_m, r.safety_m, &spec),
        None => Roadmap::from_sites(grid, &skyplan_roadmap::grid_boundary_sites(grid), &spec),
    });
    if session.voronoi.len() >= 8 {
        session.voronoi.clear();
    }
    session.voronoi.insert(k, Arc::clone(&m));
    m
}

pub(crate) fn plan(session: &mut Session, q: &Query) -> Result<Route, PlanFailure> {
    let r = q.r;
    let map = q.world.colliders();
    let (grid, grid_us) = grid_for(session, q)?;
    let t_build = Instant::now();
    let roadmap = kept_roadmap(session, map, &grid, r);
    let build_us = grid_us + micros(t_build.elapsed());
    let t = Instant::now();
    let found = roadmap.query(&grid, q.start_ne, q.goal_ne);
    let search_us = micros(t.elapsed());
    let at = format!("at {} m with a {} m margin", r.alt_m, r.safety_m);
    let route = match found {
        Ok(route) => route,
        Err(e @ RoadmapError::StartBlocked(..)) => {
            return Err(PlanFailure::new(
                FailureKind::InvalidStart,
                format!("{e} {at}"),
            ));
        }
        Err(e @ RoadmapError::GoalBlocked(..)) => {
            return Err(PlanFailure::new(
                FailureKind::InvalidGoal,
                format!("{e} {at}"),
            ));
        }
        Err(e @ RoadmapError::NoPath) => {
            return Err(PlanFailure::new(
                FailureKind::NoPath,
                format!(
                    "voronoi: {e} (the graph has {} components)",
                    roadmap.component_count()
                ),
            ));
        }
    };
    let points = route
        .points_ne
        .iter()
        .map(|p| [p[0], p[1], r.alt_m])
        .collect();
    let mut out = Route::new(
        points,
        route.cost_m,
        Check::Grid {
            grid: Arc::clone(&grid),
            touch: Touch::Closed,
        },
    );
    let stats = roadmap.stats();
    out.expansions = route.expansions as u64;
    out.timings.grid_build_us = build_us;
    out.timings.search_us = search_us;
    for (k, v) in [
        ("graph_cost_m", json!(route.graph_cost_m)),
        ("components", json!(roadmap.component_count())),
        ("largest_component", json!(roadmap.largest_component())),
        ("nodes", json!(roadmap.nodes().len())),
        ("edges", json!(roadmap.edge_count())),
        ("sites", json!(stats.sites)),
        ("fallback", json!(route.fallback)),
        (
            "connectors",
            json!([route.connectors.0, route.connectors.1]),
        ),
        ("build_time_us", json!(stats.build_us)),
    ] {
        out.details.insert(k.into(), v);
    }
    if r.geometry {
        let seg = |a: [f64; 2], b: [f64; 2]| [[a[0], a[1], r.alt_m], [b[0], b[1], r.alt_m]];
        out.geometry.edges = roadmap.edges().map(|(a, b)| seg(a, b)).collect();
        out.geometry.edges_label = "Voronoi graph".into();
        for end in [q.start_ne, q.goal_ne] {
            for node in roadmap.connector_nodes(&grid, end) {
                out.geometry.connectors.push(seg(end, node));
            }
        }
        out.geometry.raw_path = route.raw_ne.iter().map(|p| [p[0], p[1], r.alt_m]).collect();
    }
    out.grid = Some(grid);
    Ok(out)
}

//! `auto` against the exact Dijkstra oracle whichever planner it picks (JPS, JPS+, CH: the
//! batch sizes below reach each), the pick against the rule, and a session's switch from JPS
//! to the JPS+ table it builds once and then reuses, told in the plan's details and summary.

use proptest::prelude::*;
use skyplan_cspace::{Cell, Grid2};
use skyplan_plan::auto::{CH_QUERIES, JPS_PLUS_QUERIES, MapStats, pick};
use skyplan_plan::{CellSearch, PlanRequest, PlannerId, Session, World};
use skyplan_search::{MoveModel, oracle::dijkstra_exact};

fn grid_and_ends() -> impl Strategy<Value = (Grid2, Cell, Cell)> {
    skyplan_testkit::arb_grid_and_ends(16)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(if std::env::var_os("CI").is_some() { 300 } else { 100 }))]
    #[test]
    fn auto_equals_the_oracle_for_every_batch_size((grid, start, goal) in grid_and_ends(), model_ix in 0usize..3) {
        let model = [MoveModel::Octile, MoveModel::OctileCornerCutting, MoveModel::FourConnected][model_ix];
        let truth = dijkstra_exact(&grid, start, goal, model);
        let stats = MapStats::of(&grid);
        for queries in [1, JPS_PLUS_QUERIES, CH_QUERIES] {
            let mut s = CellSearch::for_queries(&grid, PlannerId::Auto, model, queries).unwrap();
            let picked = s.auto_pick().map(|p| p.planner);
            prop_assert_eq!(picked, Some(pick(&stats, queries).planner));
            match (truth, s.search(start, goal)) {
                (Some(t), Ok(p)) => prop_assert!((p.cost_cells() - t.to_f64()).abs() < 1e-9,
                    "auto ({:?}) for {} queries: {} vs {}", picked, queries, p.cost_cells(), t.to_f64()),
                (None, Err(_)) => {}
                (t, r) => prop_assert!(false, "auto ({picked:?}), {queries} queries: oracle {t:?}, search {:?}", r.map(|p| p.cost_cells())),
            }
        }
    }
}

/// A 24 × 24 switchback maze of 2-cell corridors (a wall every third row, its gap at alternate
/// ends) and its far corners.
fn maze() -> (Grid2, Cell, Cell) {
    let text: Vec<String> = (0..24)
        .map(|r| {
            (0..24)
                .map(|c| {
                    let gap = if (r / 3) % 2 == 0 { c < 2 } else { c >= 22 };
                    if r % 3 == 2 && !gap { '#' } else { '.' }
                })
                .collect()
        })
        .collect();
    let grid = Grid2::from_ascii(&text.join("\n")).unwrap();
    (grid, Cell::new(0, 23), Cell::new(22, 0))
}

#[test]
fn a_session_moves_from_jps_to_jps_plus_to_ch_as_queries_add_up_and_reuses_each() {
    let (grid, start, goal) = maze();
    assert!(MapStats::of(&grid).mean_run <= skyplan_plan::auto::CH_MAX_RUN);
    let truth = dijkstra_exact(&grid, start, goal, MoveModel::Octile)
        .expect("the maze connects its corners")
        .to_f64();
    let (sn, se) = grid.center_ne(start);
    let (gn, ge) = grid.center_ne(goal);
    let mut session = Session::new(World::from_grid("maze", grid));
    let request = PlanRequest {
        planner: Some(PlannerId::Auto),
        start_ne: Some([sn, se]),
        goal_ne: Some([gn, ge]),
        ..Default::default()
    };
    for k in 1..=CH_QUERIES + 1 {
        let plan = session.plan(&request).unwrap();
        assert!(
            (plan.cost_m - truth).abs() < 1e-9,
            "query {k}: {} vs {truth}",
            plan.cost_m
        );
        assert_eq!(plan.planner, PlannerId::Auto);
        let auto = &plan.details["auto"];
        assert_eq!(auto["queries"].as_u64(), Some(k));
        let built = |first| Some(if k == first { "built" } else { "reused" });
        let (planner, table, ch) = match k {
            k if k < JPS_PLUS_QUERIES => ("jps", None, None),
            k if k < CH_QUERIES => ("jps-plus", built(JPS_PLUS_QUERIES), None),
            _ => ("ch", None, built(CH_QUERIES)),
        };
        assert_eq!(auto["planner"], planner, "query {k}: {auto}");
        let detail = |key: &str| plan.details.get(key).and_then(|v| v.as_str());
        assert_eq!(detail("jps_plus_table"), table, "query {k}");
        assert_eq!(detail("contraction_hierarchy"), ch, "query {k}");
        let summary = plan.to_string();
        let line = summary.lines().find(|l| l.starts_with("auto ")).unwrap();
        let label = match planner {
            "jps" => "JPS",
            "jps-plus" => "JPS+",
            _ => "CH",
        };
        assert!(
            line.starts_with(&format!("auto       picked {label}: ")),
            "{line}"
        );
        if k == 1 {
            assert_eq!(
                line,
                "auto       picked JPS: 1 query < 150: no preprocessing pays for itself"
            );
        }
        if k == CH_QUERIES {
            assert!(
                line.ends_with("and 250 queries ≥ 250: the contraction hierarchy pays for itself"),
                "{line}"
            );
        }
    }
}

#[test]
fn a_session_reuses_a_kept_table_for_a_single_query() {
    let (grid, start, goal) = maze();
    let (sn, se) = grid.center_ne(start);
    let (gn, ge) = grid.center_ne(goal);
    let mut session = Session::new(World::from_grid("maze", grid));
    let jps_plus = PlanRequest {
        planner: Some(PlannerId::JpsPlus),
        start_ne: Some([sn, se]),
        goal_ne: Some([gn, ge]),
        ..Default::default()
    };
    let named = session.plan(&jps_plus).unwrap();
    let auto = session
        .plan(&PlanRequest {
            planner: Some(PlannerId::Auto),
            ..jps_plus
        })
        .unwrap();
    assert_eq!(auto.cost_m, named.cost_m);
    assert_eq!(auto.details["auto"]["planner"], "jps-plus");
    assert_eq!(auto.details["jps_plus_table"], "reused");
    assert_eq!(
        auto.details["auto"]["why"],
        "the JPS+ table kept for this grid (built or loaded) answers fastest"
    );
}

#[test]
fn a_kept_first_move_table_answers_auto_from_then_on_and_its_pick_pays_on_small_maps() {
    let (grid, start, goal) = maze();
    let stats = MapStats::of(&grid);
    // 24 × 24 with 400 free cells: a 115 kB table pays after 400² / 100 = 1,600 queries.
    assert_eq!(stats.free, 400);
    let pays = stats.free * stats.free / skyplan_plan::auto::FIRST_MOVE_PAIRS_PER_QUERY;
    assert_eq!(pick(&stats, pays - 1).planner, PlannerId::Ch);
    assert_eq!(pick(&stats, pays).planner, PlannerId::FirstMove);
    let truth = dijkstra_exact(&grid, start, goal, MoveModel::Octile)
        .unwrap()
        .to_f64();
    let (sn, se) = grid.center_ne(start);
    let (gn, ge) = grid.center_ne(goal);
    let mut session = Session::new(World::from_grid("maze", grid));
    let named = PlanRequest {
        planner: Some(PlannerId::FirstMove),
        start_ne: Some([sn, se]),
        goal_ne: Some([gn, ge]),
        ..Default::default()
    };
    let first = session.plan(&named).unwrap();
    assert!((first.cost_m - truth).abs() < 1e-9);
    assert_eq!(first.details["first_move_table"], "built");
    let auto = session
        .plan(&PlanRequest {
            planner: Some(PlannerId::Auto),
            ..named
        })
        .unwrap();
    assert_eq!(auto.cost_m, first.cost_m);
    assert_eq!(auto.details["auto"]["planner"], "first-move");
    assert_eq!(auto.details["first_move_table"], "reused");
    assert_eq!(
        auto.details["auto"]["why"],
        "a first-move table at hand (built or loaded): one lookup per cell of the path, no search"
    );
}

#[test]
fn a_saved_hierarchy_is_loaded_by_a_later_session_and_auto_uses_it_from_the_first_query() {
    let (grid, start, goal) = maze();
    let truth = dijkstra_exact(&grid, start, goal, MoveModel::Octile)
        .unwrap()
        .to_f64();
    let (sn, se) = grid.center_ne(start);
    let (gn, ge) = grid.center_ne(goal);
    let request = PlanRequest {
        planner: Some(PlannerId::Auto),
        start_ne: Some([sn, se]),
        goal_ne: Some([gn, ge]),
        ..Default::default()
    };
    let mut bytes = Vec::new();
    let written = Session::new(World::from_grid("maze", grid.clone()))
        .save_ch(&request, &mut bytes)
        .unwrap();
    assert_eq!(written, bytes.len() as u64);
    let mut later = Session::new(World::from_grid("maze", grid.clone()));
    later.load_ch(&request, &bytes[..]).unwrap();
    let plan = later.plan(&request).unwrap();
    assert!((plan.cost_m - truth).abs() < 1e-9);
    assert_eq!(plan.details["auto"]["planner"], "ch");
    assert_eq!(plan.details["contraction_hierarchy"], "reused");
    // Refused by name: damaged, cut short, another map, another move model.
    let mut damaged = bytes.clone();
    let last = damaged.len() - 1;
    damaged[last] ^= 1;
    let e = later.load_ch(&request, &damaged[..]).unwrap_err();
    assert_eq!(e.kind, skyplan_plan::FailureKind::BadRequest);
    assert!(
        e.message.contains("checksum does not match"),
        "{}",
        e.message
    );
    let e = later.load_ch(&request, &bytes[..100]).unwrap_err();
    assert!(e.message.contains("truncated or damaged"), "{}", e.message);
    let mut other = grid.clone();
    other.set_blocked(Cell::new(0, 0), true);
    let e = Session::new(World::from_grid("other", other))
        .load_ch(&request, &bytes[..])
        .unwrap_err();
    assert!(
        e.message.contains("another map") && e.message.ends_with("this session's map is other"),
        "{}",
        e.message
    );
    let four = PlanRequest {
        connectivity: Some(4),
        ..request.clone()
    };
    let e = later.load_ch(&four, &bytes[..]).unwrap_err();
    assert!(
        e.message.contains("(octile); this grid is 24 × 24"),
        "{}",
        e.message
    );
}

#[test]
fn a_hierarchy_over_the_memory_limit_is_not_built_and_jps_plus_answers() {
    let (grid, start, goal) = maze();
    let (sn, se) = grid.center_ne(start);
    let (gn, ge) = grid.center_ne(goal);
    // 576 cells: JPS+ (68 bytes a cell) fits in 100 kB, a hierarchy (400 bytes a cell) does not.
    let limits = skyplan_plan::Limits {
        max_memory_bytes: 100_000,
    };
    let mut session = Session::new(World::from_grid("maze", grid)).with_limits(limits);
    let request = PlanRequest {
        planner: Some(PlannerId::Auto),
        start_ne: Some([sn, se]),
        goal_ne: Some([gn, ge]),
        ..Default::default()
    };
    for _ in 1..CH_QUERIES {
        session.plan(&request).unwrap();
    }
    let plan = session.plan(&request).unwrap();
    assert_eq!(plan.details["auto"]["planner"], "jps-plus");
    assert!(
        plan.details["auto"]["why"]
            .as_str()
            .unwrap()
            .ends_with("but a hierarchy would need more memory than the limit: JPS+ instead")
    );
    assert!(plan.details.get("contraction_hierarchy").is_none());
}

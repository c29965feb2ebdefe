//! The session keeps the JPS+ table across requests, saves it, and loads it in another session;
//! foreign or damaged tables are refused with the reason. Costs are checked against JPS (exact).

use skyplan_plan::{FailureKind, PlanRequest, PlannerId, Session, World};

fn request(planner: PlannerId) -> PlanRequest {
    PlanRequest {
        planner: Some(planner),
        ..Default::default()
    }
}

fn table_use(plan: &skyplan_plan::Plan) -> Option<&str> {
    plan.details.get("jps_plus_table").and_then(|v| v.as_str())
}

#[test]
fn the_session_builds_the_table_once_and_a_saved_table_serves_another_session() {
    let mut session = Session::new(World::fcnd_city());
    let jps = session.plan(&request(PlannerId::Jps)).expect("jps plans");
    let first = session
        .plan(&request(PlannerId::JpsPlus))
        .expect("jps-plus plans");
    let second = session.plan(&request(PlannerId::JpsPlus)).expect("again");
    assert_eq!(table_use(&first), Some("built"));
    assert_eq!(table_use(&second), Some("reused"));
    assert_eq!(first.cost_m, jps.cost_m);
    assert_eq!(second.cost_m, jps.cost_m);

    let mut bytes = Vec::new();
    let written = session
        .save_jps_plus(&PlanRequest::default(), &mut bytes)
        .expect("saves");
    assert_eq!(written, bytes.len() as u64);
    let mut later = Session::new(World::fcnd_city());
    later.load_jps_plus(&bytes[..]).expect("loads");
    let loaded = later.plan(&request(PlannerId::JpsPlus)).expect("plans");
    assert_eq!(table_use(&loaded), Some("reused"));
    assert_eq!(loaded.cost_m, jps.cost_m);
    assert_eq!(loaded.waypoints.len(), first.waypoints.len());

    // Another altitude is another grid: that request builds its own table.
    let high = later
        .plan(&PlanRequest {
            alt_m: Some(40.0),
            ..request(PlannerId::JpsPlus)
        })
        .expect("plans at 40 m");
    assert_eq!(table_use(&high), Some("built"));
}

#[test]
fn foreign_and_damaged_tables_are_refused_with_the_reason() {
    let mut session = Session::new(World::fcnd_city());
    let mut bytes = Vec::new();
    let written = session
        .save_jps_plus(&PlanRequest::default(), &mut bytes)
        .expect("saves");
    assert_eq!(written, bytes.len() as u64);

    // A MovingAI-style fixed grid is another grid.
    let map = "type octile\nheight 3\nwidth 4\nmap\n....\n.@@.\n....\n";
    let mut other = Session::new(World::from_movingai("tiny.map", map).expect("map parses"));
    let e = other.load_jps_plus(&bytes[..]).expect_err("another grid");
    assert_eq!(e.kind, FailureKind::BadRequest);
    assert!(e.message.contains("another map"), "{}", e.message);

    let mut damaged = bytes.clone();
    let last = damaged.len() - 1;
    damaged[last] ^= 0x55;
    let e = session.load_jps_plus(&damaged[..]).expect_err("damaged");
    assert_eq!(e.kind, FailureKind::BadRequest);
    assert!(e.message.contains("damaged"), "{}", e.message);

    let e = session
        .load_jps_plus(&bytes[..bytes.len() / 2])
        .expect_err("cut short");
    assert!(e.message.contains("truncated"), "{}", e.message);
    let e = session
        .load_jps_plus(&b"not a table"[..])
        .expect_err("garbage");
    assert!(
        e.message.contains("not a skyplan JPS+ table"),
        "{}",
        e.message
    );
}

/// A reader that hands out at most 1,000 bytes per call (as a pipe or a slow disk may).
struct Trickle<'a>(&'a [u8]);

impl std::io::Read for Trickle<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = buf.len().min(self.0.len()).min(1000);
        buf[..n].copy_from_slice(&self.0[..n]);
        self.0 = &self.0[n..];
        Ok(n)
    }
}

#[test]
fn a_table_streamed_in_small_pieces_loads_and_answers_like_jps() {
    let mut session = Session::new(World::fcnd_city());
    let jps = session.plan(&request(PlannerId::Jps)).expect("jps plans");
    let mut bytes = Vec::new();
    session
        .save_jps_plus(&PlanRequest::default(), &mut bytes)
        .expect("saves");
    let mut later = Session::new(World::fcnd_city());
    later.load_jps_plus(Trickle(&bytes)).expect("loads");
    let loaded = later.plan(&request(PlannerId::JpsPlus)).expect("plans");
    assert_eq!(table_use(&loaded), Some("reused"));
    assert_eq!(loaded.cost_m, jps.cost_m);
}

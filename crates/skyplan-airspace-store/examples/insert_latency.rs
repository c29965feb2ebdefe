//! p50/p99 of `insert_if_clear` with 1,000 intents stored, on SQLite (a file) and, when
//! `SKYPLAN_TEST_POSTGRES` names a server, on PostgreSQL (a new database on it).
//!
//! ```text
//! cargo run --release -p skyplan-airspace-store --example insert_latency
//! SKYPLAN_TEST_POSTGRES=postgres://postgres@127.0.0.1:5432/postgres cargo run --release -p skyplan-airspace-store --example insert_latency
//! ```
//!
//! The intents: the city's crossing flights at 10, 40 and 70 m, spread over 24 hours (the
//! store fills to 1,000 accepted), then 500 more inserts timed one by one (accepted or not).

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use skyplan_airspace::*;
use skyplan_airspace_store::{Insert, IntentStore, PostgresStore, SqliteStore, new_id};
use skyplan_plan::{PlanRequest, Session, World};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut session = Session::new(World::fcnd_city());
    let mut flights = Vec::new();
    for alt in [10.0, 40.0, 70.0] {
        for (s, g) in [
            ([0.0, 0.0], [420.0, 390.0]),
            ([420.0, 390.0], [0.0, 0.0]),
            ([300.0, 0.0], [48.5, 399.5]),
            ([48.5, 399.5], [300.0, 0.0]),
        ] {
            let request = PlanRequest {
                start_ne: Some(s),
                goal_ne: Some(g),
                alt_m: Some(alt),
                ..Default::default()
            };
            flights.push(volumes_from_plan(
                &session.plan(&request)?,
                &VolumeOptions::default(),
            )?);
        }
    }
    let dir = tempfile::tempdir()?;
    let sqlite = SqliteStore::open(&dir.path().join("airspace.db"))?;
    measure("SQLite (file, WAL, synchronous=FULL)", &sqlite, &flights);
    if let Ok(url) = std::env::var("SKYPLAN_TEST_POSTGRES") {
        let name = format!("skyplan_bench_{}", std::process::id());
        let url = PostgresStore::create_database(&url, &name)?;
        let pg = PostgresStore::open_url(&url)?;
        measure("PostgreSQL (SERIALIZABLE)", &pg, &flights);
    } else {
        println!("PostgreSQL: skipped (SKYPLAN_TEST_POSTGRES is not set)");
    }
    Ok(())
}

fn measure(name: &str, store: &dyn IntentStore, flights: &[FlightVolumes]) {
    let t0: Timestamp = "2026-03-01T00:00:00Z".parse().expect("a time");
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let intent = |rng: &mut ChaCha8Rng| OperationalIntent {
        id: new_id(),
        version: 1,
        state: IntentState::Accepted,
        priority: 0,
        owner: "bench".into(),
        volumes: flights[rng.random_range(0..flights.len())]
            .at(t0.plus_ms(rng.random_range(0..86_400_000))),
    };
    let mut stored = 0;
    while stored < 1000 {
        if let Ok(Insert::Accepted { .. }) =
            store.insert_if_clear(&intent(&mut rng), PriorityRule::EqualOrHigher)
        {
            stored += 1;
        }
    }
    let mut times_us = Vec::new();
    let (mut accepted, mut checked) = (0, 0);
    for _ in 0..500 {
        let i = intent(&mut rng);
        let start = Instant::now();
        let done = store.insert_if_clear(&i, PriorityRule::EqualOrHigher);
        times_us.push(start.elapsed().as_micros());
        match done {
            Ok(Insert::Accepted { checked: c }) => {
                accepted += 1;
                checked += c;
            }
            Ok(Insert::Conflicts(_)) => {}
            Err(e) => eprintln!("{name}: {e}"),
        }
    }
    times_us.sort_unstable();
    let q = |p: f64| times_us[((times_us.len() - 1) as f64 * p).round() as usize] as f64 / 1000.0;
    println!(
        "{name}: insert_if_clear with {stored}+ intents stored, 500 timed: p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms ({accepted} accepted, {:.1} intents checked per accepted insert)",
        q(0.5),
        q(0.99),
        q(1.0),
        checked as f64 / f64::from(accepted.max(1))
    );
}

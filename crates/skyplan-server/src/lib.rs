//! # skyplan's planning service and live view
//!
//! The planning API ([`skyplan_plan`]) over HTTP, and one embedded page that draws the map,
//! plans on click and shows flights live:
//!
//! | endpoint | what |
//! |---|---|
//! | `GET /` | the page (HTML, inline JS/CSS, 2D canvas; no CDN) |
//! | `GET /api/map` | name, home, bounds, obstacles; `?alt_m=&safety_m=&cell_m=` adds the grid as run-length rows |
//! | `POST /api/plan` | a `PlanRequest` (the CLI's long options with underscores) → the `Plan` as `skyplan plan --json` prints it |
//! | `GET /api/planners` | the planner registry |
//! | `GET /api/status` | workers, busy, queued, queue depth, served/rejected/timed-out counters |
//! | `POST /api/intents` | a plan request, a `departure` (RFC 3339, or a window `{earliest, latest}`), a `priority` (0–100) and an `owner` → 201 with the operational intent reserved at the earliest free departure and its plan, or 409 naming the intents in the way (ids and versions) |
//! | `GET /api/intents`, `GET`/`DELETE /api/intents/{id}` | the stored intents; one; one removed (404 when there is none) |
//! | `GET /api/events` | server-sent events: plan results, flight states, routes, intents accepted or deleted ([`ViewEvent`]) |
//! | `GET /api/openapi.json` | the OpenAPI 3 description of all of this |
//!
//! [`ViewServer`] serves the same page from a background thread of `fly`/`sim` (`--view`), and
//! [`Recorder`] writes the same events as an MCAP file for Foxglove and Lichtblick (`--record`);
//! [`live::Live`] turns a flight (progress, sensor readings, replans, the simulator's state) into
//! those events for both.
//!
//! Safe by default: request bodies over 1 MiB get 413, at most N plans run at once and a bounded
//! queue holds the rest first in first out (503 with `Retry-After` when it is full, or when its
//! expected wait leaves no time to plan), each request has a time budget from its arrival, queue
//! included (504 past it: `queue_timeout` while waiting, `over_budget` while planning), clients
//! never name files, and a
//! server bound to loopback answers only requests whose `Host` is its address or `localhost`
//! (403 otherwise: DNS-rebinding protection, [`with_host_check`]).
//!
//! ```
//! use skyplan_server::{ServerConfig, router};
//! use skyplan_plan::World;
//! let app = router(World::fcnd_city(), ServerConfig::default());
//! # drop(app);
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod error;
mod events;
mod handlers;
mod host;
mod intents;
pub mod live;
mod map;
mod pool;
mod record;
mod view;

pub use error::{ApiError, ErrorKind};
pub use events::{
    EventSink, FlightEvent, IntentEvent, PlanEvent, RouteEvent, SensedEvent, TrajectoryEvent,
    ViewEvent,
};
pub use host::{host_allowed, with_host_check};
pub use intents::{DEPARTURE_STEP_MS, HORIZON_MS, MAX_OWNER_CHARS, PAST_SLACK_MS};
pub use map::MAX_GRID_CELLS;
pub use record::{RecordError, Recorder};
pub use view::{ViewError, ViewServer};

use axum::Router;
use axum::extract::DefaultBodyLimit;
use axum::routing::{get, post};
use skyplan_airspace_store::IntentStore;
use skyplan_plan::World;
use std::sync::Arc;
use std::sync::atomic::AtomicU64;
use std::time::Duration;

/// Largest request body, bytes (1 MiB); larger bodies get 413.
pub const MAX_BODY_BYTES: usize = 1 << 20;

/// The page, compiled in.
pub const PAGE_HTML: &str = include_str!("../page/index.html");

/// The OpenAPI 3 description, compiled in.
pub const OPENAPI_JSON: &str = include_str!("../openapi.json");

/// The default queue depth per planning worker.
pub const QUEUE_PER_WORKER: usize = 64;

/// The default airspace store: SQLite in this server's memory.
pub const DEFAULT_AIRSPACE: &str = "sqlite::memory:";

/// Opens the airspace store at `url` (`sqlite:FILE`, `sqlite::memory:` or
/// `postgres://USER@HOST:PORT/DATABASE`; `postgresql://` too).
pub fn open_airspace(
    url: &str,
) -> Result<Arc<dyn IntentStore>, skyplan_airspace_store::StoreError> {
    Ok(Arc::from(skyplan_airspace_store::open_url(url)?))
}

/// How the server runs.
#[derive(Debug, Clone, PartialEq)]
pub struct ServerConfig {
    /// Plans (and grids) computed at once; more wait in the queue. Defaults to the number of
    /// cores.
    pub max_concurrent: usize,
    /// Requests that may wait for a worker, first in first out; more get 503. `None`: 64 per
    /// worker ([`QUEUE_PER_WORKER`]); 0: no queue (503 as soon as every worker is busy).
    pub queue_depth: Option<usize>,
    /// Time budget of one request from its arrival, queue included; past it the answer is 504.
    /// Default 10 s.
    pub timeout: Duration,
    /// Event-stream clients at once; more get 503. Default 64.
    pub max_event_clients: usize,
    /// Where the shared airspace's intents are kept: `sqlite:FILE` (a file in WAL mode, shared
    /// by every server on it), `postgres://USER@HOST:PORT/DATABASE` (PostgreSQL, shared by
    /// every server on the database, on any machine) or `sqlite::memory:` (the default: this
    /// server's memory, gone when it stops).
    pub airspace: String,
    /// No-fly zones (a GeoJSON FeatureCollection, as `--no-fly` reads) the page draws and sends
    /// with its plans; API requests give their own `no_fly`. `None`: no zones.
    pub no_fly: Option<String>,
}

impl ServerConfig {
    /// The queue depth in effect: [`ServerConfig::queue_depth`], or 64 per worker.
    pub fn effective_queue_depth(&self) -> usize {
        self.queue_depth
            .unwrap_or_else(|| QUEUE_PER_WORKER.saturating_mul(self.max_concurrent.max(1)))
    }
}

impl Default for ServerConfig {
    fn default() -> Self {
        Self {
            max_concurrent: std::thread::available_parallelism().map_or(1, usize::from),
            queue_depth: None,
            timeout: Duration::from_secs(10),
            max_event_clients: 64,
            airspace: DEFAULT_AIRSPACE.into(),
            no_fly: None,
        }
    }
}

/// What every handler shares.
pub(crate) struct Shared {
    pub pool: Arc<pool::Pool>,
    pub config: ServerConfig,
    pub events: EventSink,
    pub event_slots: Arc<tokio::sync::Semaphore>,
    pub map_info: serde_json::Value,
    pub planners: serde_json::Value,
    pub next_request_id: AtomicU64,
    /// The airspace store, or why it could not be opened (the intents endpoints answer 503).
    pub airspace: Result<Arc<dyn IntentStore>, String>,
    /// The stored intents as the space-time search saw them, kept between requests (one
    /// search at a time uses it; another meanwhile reads the store afresh).
    pub space_time_cache: std::sync::Mutex<skyplan_fleet::SpaceTimeCache>,
}

/// The server's state: cheap to clone.
pub(crate) type AppState = Arc<Shared>;

/// A router and the event sink that feeds its `/api/events`.
pub struct App {
    /// The router, ready for `axum::serve` or `tower::ServiceExt::oneshot`.
    pub router: Router,
    /// Publishes events to the router's `/api/events` clients.
    pub events: EventSink,
}

/// The whole API and page over `world`, with its event sink.
pub fn app(world: World, config: ServerConfig) -> App {
    let events = EventSink::new();
    let shared = Arc::new(Shared {
        pool: Arc::new(pool::Pool::new(
            world.clone(),
            config.max_concurrent,
            config.effective_queue_depth(),
            config.timeout,
        )),
        map_info: map::map_info(&world, config.no_fly.as_deref()),
        planners: handlers::planners_json(&world),
        event_slots: Arc::new(tokio::sync::Semaphore::new(config.max_event_clients)),
        airspace: open_airspace(&config.airspace).map_err(|e| e.to_string()),
        config,
        events: events.clone(),
        next_request_id: AtomicU64::new(1),
        space_time_cache: std::sync::Mutex::new(skyplan_fleet::SpaceTimeCache::new()),
    });
    let router = Router::new()
        .route("/", get(handlers::page))
        .route("/api/map", get(handlers::map))
        .route("/api/plan", post(handlers::plan))
        .route("/api/planners", get(handlers::planners))
        .route("/api/status", get(handlers::status))
        .route("/api/intents", post(intents::create).get(intents::list))
        .route(
            "/api/intents/{id}",
            get(intents::get).delete(intents::delete),
        )
        .route("/api/events", get(handlers::events))
        .route("/api/openapi.json", get(handlers::openapi))
        .fallback(handlers::not_found)
        .method_not_allowed_fallback(handlers::method_not_allowed)
        .layer(DefaultBodyLimit::max(MAX_BODY_BYTES))
        .with_state(shared);
    App { router, events }
}

/// The whole API and page over `world`.
pub fn router(world: World, config: ServerConfig) -> Router {
    app(world, config).router
}

/// Serves `app` on `listener` until the process ends (or the future is dropped), with the
/// `Host` check of [`with_host_check`] for the bound address.
pub async fn serve(listener: tokio::net::TcpListener, app: Router) -> std::io::Result<()> {
    let bound = listener.local_addr()?;
    axum::serve(listener, with_host_check(app, bound)).await
}

/// Binds `addr`, calls `on_listening` with the bound address (port 0 picks one), then serves
/// the API and page over `world` until the process ends. For programs that are not async (the
/// CLI): it builds its own runtime.
pub fn run(
    world: World,
    config: ServerConfig,
    addr: std::net::SocketAddr,
    on_listening: impl FnOnce(std::net::SocketAddr),
) -> std::io::Result<()> {
    let threads = config.max_concurrent.clamp(1, 4);
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(threads)
        .enable_all()
        .build()?;
    runtime.block_on(async move {
        let listener = tokio::net::TcpListener::bind(addr).await?;
        on_listening(listener.local_addr()?);
        serve(listener, router(world, config)).await
    })
}

//! [`ViewServer`]: the page and API served from a background thread of a program that is not
//! async (`fly --view`, `sim --view`), fed by [`ViewServer::publish`] from any thread.

use crate::events::{EventSink, ViewEvent};
use crate::{ServerConfig, app};
use skyplan_plan::World;
use std::net::SocketAddr;
use std::thread::JoinHandle;
use std::time::Duration;
use tokio::sync::oneshot;

/// Why a view server could not start.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// The address is not `HOST:PORT` with a numeric host.
    #[error("{given}: expected an address like 127.0.0.1:8080")]
    Address {
        /// What was given.
        given: String,
    },
    /// The address could not be bound or the runtime not started.
    #[error("{given}: {source}")]
    Io {
        /// What was given.
        given: String,
        /// Why.
        source: std::io::Error,
    },
}

/// A running server on a background thread: the page, the API and `/api/events`. Stops when
/// dropped.
///
/// ```no_run
/// use skyplan_server::{FlightEvent, ViewEvent, ViewServer};
/// let view = ViewServer::start(skyplan_plan::World::fcnd_city(), "127.0.0.1:8080")?;
/// view.publish(&ViewEvent::Flight(FlightEvent {
///     time_s: 0.0, north_m: 0.0, east_m: 0.0, alt_m: 0.0, heading_deg: 0.0, speed_m_s: 0.0,
///     state: "MANUAL".into(), waypoint_index: None, armed: false,
/// }));
/// # Ok::<(), skyplan_server::ViewError>(())
/// ```
pub struct ViewServer {
    events: EventSink,
    addr: SocketAddr,
    stop: Option<oneshot::Sender<()>>,
    thread: Option<JoinHandle<()>>,
}

impl ViewServer {
    /// Binds `addr` (port 0 picks a free port) and serves `world` with the default
    /// configuration on a background thread.
    pub fn start(world: World, addr: &str) -> Result<Self, ViewError> {
        Self::start_with(world, addr, ServerConfig::default())
    }

    /// As [`ViewServer::start`], with a configuration.
    pub fn start_with(world: World, addr: &str, config: ServerConfig) -> Result<Self, ViewError> {
        let given = addr.to_string();
        let parsed: SocketAddr = addr.parse().map_err(|_| ViewError::Address {
            given: given.clone(),
        })?;
        let io = |source| ViewError::Io {
            given: given.clone(),
            source,
        };
        let listener = std::net::TcpListener::bind(parsed).map_err(io)?;
        listener.set_nonblocking(true).map_err(io)?;
        let addr = listener.local_addr().map_err(io)?;
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .enable_all()
            .build()
            .map_err(io)?;
        let app = app(world, config);
        let events = app.events.clone();
        let (stop, stopped) = oneshot::channel::<()>();
        let thread = std::thread::Builder::new()
            .name("skyplan-view".into())
            .spawn(move || {
                runtime.block_on(async move {
                    // Errors end the serving thread; the flight goes on without its view.
                    let Ok(listener) = tokio::net::TcpListener::from_std(listener) else {
                        return;
                    };
                    tokio::select! {
                        _ = crate::serve(listener, app.router) => {}
                        _ = stopped => {}
                    }
                });
                runtime.shutdown_timeout(Duration::from_secs(1));
            })
            .map_err(io)?;
        Ok(Self {
            events,
            addr,
            stop: Some(stop),
            thread: Some(thread),
        })
    }

    /// The bound address (with the port picked for port 0).
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Sends `event` to every page connected now.
    pub fn publish(&self, event: &ViewEvent) {
        self.events.publish(event);
    }

    /// A publisher to hand to other threads.
    pub fn sink(&self) -> EventSink {
        self.events.clone()
    }
}

impl Drop for ViewServer {
    fn drop(&mut self) {
        if let Some(stop) = self.stop.take() {
            let _ = stop.send(());
        }
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

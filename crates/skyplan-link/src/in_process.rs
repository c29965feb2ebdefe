//! The simulated vehicle run in-process: a [`SimServer`] on a free loopback port, on its own
//! thread, with its notes on a channel (`skyplan fly --sim`, `skyplan bench --replan`).

use crate::vehicle::{SimNote, SimReport, SimServer, SimServerConfig};
use crate::{Address, LinkError};
use skyplan_flight::collision::BoxWorld;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::thread::JoinHandle;

/// A simulator running on a thread of this process until [`InProcessSim::finish`].
///
/// ```no_run
/// use skyplan_flight::collision::BoxWorld;
/// use skyplan_frames::Lla;
/// use skyplan_link::in_process::InProcessSim;
/// use skyplan_link::vehicle::SimServerConfig;
/// let home = Lla { lat_deg: 37.79, lon_deg: -122.39, alt_m: 0.0 };
/// let sim = InProcessSim::start(SimServerConfig::at(home), BoxWorld::new(&[]))?;
/// println!("connect to {}", sim.address());
/// let (report, _notes) = sim.finish();
/// assert!(report.is_some());
/// # Ok::<(), skyplan_link::LinkError>(())
/// ```
pub struct InProcessSim {
    stop: Arc<AtomicBool>,
    thread: JoinHandle<SimReport>,
    notes: mpsc::Receiver<SimNote>,
    port: u16,
}

impl InProcessSim {
    /// Binds a free loopback TCP port and starts the simulator; `world` (the true world: the
    /// map's boxes and any hidden ones), if any, is what the flown track is checked against.
    pub fn start(
        config: SimServerConfig,
        world: impl Into<Option<BoxWorld>>,
    ) -> Result<Self, LinkError> {
        let world = world.into();
        let server = SimServer::bind(&Address::TcpIn("127.0.0.1:0".into()), config)?;
        let port = server
            .local_addr()
            .map(|a| a.port())
            .ok_or_else(|| LinkError::Open {
                address: "tcpin:127.0.0.1:0".into(),
                source: std::io::Error::other("the bound socket has no local address"),
            })?;
        let stop = Arc::new(AtomicBool::new(false));
        let (tx, notes) = mpsc::channel();
        let thread_stop = Arc::clone(&stop);
        let thread = std::thread::spawn(move || {
            server.run(world.as_ref(), &thread_stop, |n| {
                let _ = tx.send(n);
            })
        });
        Ok(Self {
            stop,
            thread,
            notes,
            port,
        })
    }

    /// Where a ground station connects.
    pub fn address(&self) -> Address {
        Address::TcpOut(format!("127.0.0.1:{}", self.port))
    }

    /// The loopback port.
    pub fn port(&self) -> u16 {
        self.port
    }

    /// The notes that came since the last call.
    pub fn notes(&self) -> Vec<SimNote> {
        self.notes.try_iter().collect()
    }

    /// Stops the simulator: its report (`None` if its thread panicked) and its last notes.
    pub fn finish(self) -> (Option<SimReport>, Vec<SimNote>) {
        self.stop.store(true, Ordering::Relaxed);
        let report = self.thread.join().ok();
        (report, self.notes.try_iter().collect())
    }
}

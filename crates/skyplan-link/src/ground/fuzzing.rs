//! Fuzzing and hostile-input tests only (not an API): the ground station's handling of one
//! received message — `absorb` (what the station learns, which vehicle it listens to), the
//! position converted to the map's frame, the executor fed, its commands sent — without a
//! vehicle. Every station talks over one loopback connection whose peer never speaks and
//! drains what it is sent (a connection per station would exhaust the ports in TIME_WAIT).

use super::*;
use skyplan_flight::executor::{ExecutorConfig, MissionExecutor};
use std::io::Read;
use std::net::{TcpListener, TcpStream};
use std::sync::OnceLock;

/// The shared connection's station end (the peer is drained on its own thread).
fn shared_stream() -> std::io::Result<TcpStream> {
    static STREAM: OnceLock<Option<TcpStream>> = OnceLock::new();
    let stream = STREAM.get_or_init(|| {
        let listener = TcpListener::bind("127.0.0.1:0").ok()?;
        let ours = TcpStream::connect(listener.local_addr().ok()?).ok()?;
        let (mut peer, _) = listener.accept().ok()?;
        std::thread::spawn(move || {
            let mut buf = [0u8; 65536];
            while let Ok(1..) = peer.read(&mut buf) {}
        });
        Some(ours)
    });
    match stream {
        Some(s) => s.try_clone(),
        None => Err(std::io::Error::other("no loopback connection")),
    }
}

/// A ground station flying a short GUIDED route, driven one message at a time.
pub struct GroundHarness {
    station: GroundStation,
    executor: MissionExecutor,
    frame: LocalFrame,
    now_s: f64,
}

impl GroundHarness {
    /// A station over the shared loopback connection, with its executor ready.
    pub fn new() -> std::io::Result<Self> {
        let link = Link::from_tcp_stream(shared_stream()?, SYSTEM_ID, COMPONENT_ID)
            .map_err(|e| std::io::Error::other(e.to_string()))?;
        let station = GroundStation::over(link, GroundConfig::default());
        let home = Lla {
            lat_deg: 37.79248,
            lon_deg: -122.39745,
            alt_m: 0.0,
        };
        let frame = LocalFrame::new(home).map_err(|e| std::io::Error::other(e.to_string()))?;
        let targets = [
            Target {
                north_m: 0.0,
                east_m: 0.0,
                alt_m: 5.0,
                heading_rad: 0.0,
            },
            Target {
                north_m: 30.0,
                east_m: 20.0,
                alt_m: 5.0,
                heading_rad: 0.5,
            },
        ];
        let executor = MissionExecutor::new(&targets, ExecutorConfig::default())
            .map_err(|e| std::io::Error::other(e.to_string()))?;
        Ok(Self {
            station,
            executor,
            frame,
            now_s: 0.0,
        })
    }

    /// One message from `system_id`/`component_id`, then a tick of `dt_s` executor seconds.
    pub fn handle(&mut self, system_id: u8, component_id: u8, message: MavMessage, dt_s: f64) {
        let r = Received {
            header: mavlink::MavHeader {
                system_id: u32::from(system_id),
                component_id,
                sequence: 0,
            },
            message,
        };
        let mut events: Vec<Event> = self.station.absorb(&r).into_iter().collect();
        if let MavMessage::GLOBAL_POSITION_INT(g) = &r.message
            && self.station.is_from_vehicle(&r)
        {
            let at = global_lla(g);
            if let (Ok(convergence_rad), Ok(ned)) = (
                grid_convergence_rad(&self.frame, at),
                self.frame.ned_from_lla(at),
            ) {
                events.push(Event::Telemetry(Telemetry {
                    north_m: ned.north_m,
                    east_m: ned.east_m,
                    down_m: -f64::from(g.relative_alt) * 1e-3,
                    velocity_ned_m_s: [
                        f64::from(g.vx) * 0.01,
                        f64::from(g.vy) * 0.01,
                        f64::from(g.vz) * 0.01,
                    ],
                    yaw_rad: wrap_angle_rad(self.station.yaw_rad - convergence_rad),
                    armed: self.station.armed,
                    guided: self.station.guided(),
                    on_ground: self.station.on_ground,
                }));
            }
        }
        self.now_s += dt_s.clamp(0.0, 10.0);
        events.push(Event::Tick);
        for e in events {
            let out = self.executor.handle(self.now_s, e);
            for c in out.commands {
                let _ = self.station.send(c, &self.frame, 0.0);
            }
        }
    }

    /// The executor's last telemetry, in the map's frame (for tests).
    pub fn last_telemetry(&self) -> Option<Telemetry> {
        self.executor.last_telemetry().cloned()
    }

    /// The executor's state now (for tests).
    pub fn state(&self) -> FlightState {
        self.executor.state()
    }
}

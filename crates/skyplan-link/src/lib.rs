//! The MAVLink link layer of skyplan: the only library crate that touches sockets and clocks,
//! and only in short loops: the ground station's protocol ([`ground::protocol`]) and the
//! simulator's ([`vehicle::protocol`]) are state machines fed messages and time that return
//! messages, driven as they are by the fuzz harnesses.
//!
//! - [`Link`]: one MAVLink connection (TCP client or accepted server socket, UDP in/out) with a
//!   reader thread, so that nothing blocks on the network, and an optional heartbeat thread that
//!   keeps sending at 1 Hz whatever the caller does (planning included).
//! - [`vehicle`]: `skyplan sim`'s vehicle side: the simulated multicopter of `skyplan-flight`
//!   behind a MAVLink server (heartbeat, commands, position targets, mission upload, telemetry).
//! - [`obstacle`]: MAVLink `OBSTACLE_DISTANCE` to and from skyplan-flight's `ObstacleReading`.
//! - [`ground`]: `skyplan fly`'s side: vehicle messages → executor events, executor commands →
//!   MAVLink, link-loss detection, the flight loop and the mission upload.
//! - [`in_process`]: the simulator on a thread of this process (`fly --sim`, `bench --replan`).
//! - [`streams`]: the one table of streamed messages (the dialect's ids, rates, groups).
//! - [`messages`]: MAVLink messages built in one place (commands, heartbeats, frames).
//!
//! Only the `common` dialect is compiled (build time); ArduPilot's and PX4's custom modes are
//! numbers, tabled once in `skyplan_flight::modes`.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod ground;
pub mod in_process;
pub mod messages;
pub mod obstacle;
pub mod streams;
pub mod vehicle;

use mavlink::dialects::common::MavMessage;
use mavlink::error::MessageReadError;
use mavlink::{MavConnection, MavHeader};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

pub use mavlink;

/// Link errors.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// The address is not one of the supported forms.
    #[error("bad MAVLink address {address:?}: {message}")]
    Address {
        /// The address as given.
        address: String,
        /// What is wrong.
        message: String,
    },
    /// Connecting, binding or accepting failed.
    #[error("cannot open {address}")]
    Open {
        /// The address.
        address: String,
        /// The cause.
        source: std::io::Error,
    },
    /// Sending failed (the peer went away).
    #[error("cannot send {message}: {detail}")]
    Send {
        /// The message name.
        message: &'static str,
        /// The cause.
        detail: String,
    },
}

/// Which side of a connection we are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// We connect (ground station: `skyplan fly`).
    Client,
    /// We listen (vehicle: `skyplan sim`).
    Server,
}

/// A parsed MAVLink address.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Address {
    /// Connect to a TCP server (`tcpout:HOST:PORT`; `tcp:` as a client).
    TcpOut(String),
    /// Listen for TCP clients (`tcpin:HOST:PORT`; `tcp:` as a server).
    TcpIn(String),
    /// Listen for UDP datagrams and answer their sender (`udpin:HOST:PORT`; `udp:`).
    UdpIn(String),
    /// Send UDP datagrams to a host (`udpout:HOST:PORT`).
    UdpOut(String),
}

impl Address {
    /// Parses `tcp:HOST:PORT` (a client or a server by `role`), `tcpin:`, `tcpout:`, `udp:`
    /// (= `udpin:`), `udpin:` and `udpout:`.
    ///
    /// ```
    /// use skyplan_link::{Address, Role};
    /// assert_eq!(Address::parse("tcp:127.0.0.1:5760", Role::Client)?, Address::TcpOut("127.0.0.1:5760".into()));
    /// assert_eq!(Address::parse("tcp:127.0.0.1:5760", Role::Server)?, Address::TcpIn("127.0.0.1:5760".into()));
    /// assert_eq!(Address::parse("udpin:0.0.0.0:14550", Role::Client)?, Address::UdpIn("0.0.0.0:14550".into()));
    /// assert!(Address::parse("serial:/dev/ttyUSB0:57600", Role::Client).is_err());
    /// # Ok::<(), skyplan_link::LinkError>(())
    /// ```
    pub fn parse(text: &str, role: Role) -> Result<Self, LinkError> {
        let bad = |message: &str| LinkError::Address {
            address: text.to_string(),
            message: message.to_string(),
        };
        let Some((scheme, rest)) = text.split_once(':') else {
            return Err(bad(
                "expected SCHEME:HOST:PORT with scheme tcp, tcpin, tcpout, udp, udpin or udpout",
            ));
        };
        let Some((host, port)) = rest.rsplit_once(':') else {
            return Err(bad("expected HOST:PORT after the scheme"));
        };
        if host.is_empty() {
            return Err(bad("the host is empty"));
        }
        if port.parse::<u16>().is_err() {
            return Err(bad(&format!("the port {port:?} is not a number 0–65535")));
        }
        let hp = rest.to_string();
        Ok(match scheme {
            "tcp" => match role {
                Role::Client => Address::TcpOut(hp),
                Role::Server => Address::TcpIn(hp),
            },
            "tcpout" => Address::TcpOut(hp),
            "tcpin" => Address::TcpIn(hp),
            "udp" | "udpin" => Address::UdpIn(hp),
            "udpout" => Address::UdpOut(hp),
            "serial" => {
                return Err(bad(
                    "serial ports are not built in; bridge with mavproxy to udp or tcp",
                ));
            }
            other => {
                return Err(bad(&format!(
                    "unknown scheme {other:?}: use tcp, tcpin, tcpout, udp, udpin or udpout"
                )));
            }
        })
    }

    /// The address in the `mavlink` crate's form.
    pub fn mavlink_form(&self) -> String {
        match self {
            Address::TcpOut(a) => format!("tcpout:{a}"),
            Address::TcpIn(a) => format!("tcpin:{a}"),
            Address::UdpIn(a) => format!("udpin:{a}"),
            Address::UdpOut(a) => format!("udpout:{a}"),
        }
    }
}

impl std::fmt::Display for Address {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.mavlink_form())
    }
}

/// A received message.
#[derive(Debug, Clone)]
pub struct Received {
    /// Its header (sender system and component).
    pub header: MavHeader,
    /// The message.
    pub message: MavMessage,
}

/// What the reader thread hands over.
#[derive(Debug)]
enum Inbound {
    Message(Box<Received>),
    Closed(String),
}

type Conn = Arc<dyn MavConnection<MavMessage> + Send + Sync>;

/// One MAVLink connection with a reader thread (and, if started, a heartbeat thread).
pub struct Link {
    conn: Conn,
    header: MavHeader,
    rx: Receiver<Inbound>,
    stop: Arc<AtomicBool>,
    closed: Option<String>,
    heartbeat: Arc<Mutex<Option<MavMessage>>>,
}

impl std::fmt::Debug for Link {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Link")
            .field("header", &self.header)
            .field("closed", &self.closed)
            .finish_non_exhaustive()
    }
}

fn is_timeout(e: &MessageReadError) -> bool {
    matches!(e, MessageReadError::Io(io) if matches!(io.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut | std::io::ErrorKind::Interrupted))
}

impl Link {
    /// Opens a connection (a TCP server address waits for one client) and starts its reader.
    /// `system_id`/`component_id` go into every message sent.
    pub fn open(address: &Address, system_id: u8, component_id: u8) -> Result<Self, LinkError> {
        let form = address.mavlink_form();
        let mut conn = mavlink::connect::<MavMessage>(&form).map_err(|source| LinkError::Open {
            address: form.clone(),
            source,
        })?;
        conn.set_allow_recv_any_version(true);
        Ok(Self::from_connection(
            Arc::new(conn),
            system_id,
            component_id,
        ))
    }

    /// Wraps an accepted TCP stream.
    pub fn from_tcp_stream(
        stream: std::net::TcpStream,
        system_id: u8,
        component_id: u8,
    ) -> Result<Self, LinkError> {
        use mavlink::Connectable;
        let peer = stream
            .peer_addr()
            .map(|a| a.to_string())
            .unwrap_or_else(|_| "TCP peer".into());
        let open_err = |source| LinkError::Open {
            address: peer.clone(),
            source,
        };
        stream.set_nonblocking(false).map_err(open_err)?;
        stream
            .set_read_timeout(Some(Duration::from_millis(100)))
            .map_err(open_err)?;
        let _ = stream.set_nodelay(true);
        let config = mavlink::TcpConfig::from_stream(stream).map_err(open_err)?;
        let mut conn = config.connect::<MavMessage>().map_err(open_err)?;
        conn.set_allow_recv_any_version(true);
        Ok(Self::from_connection(
            Arc::new(conn),
            system_id,
            component_id,
        ))
    }

    fn from_connection(conn: Conn, system_id: u8, component_id: u8) -> Self {
        let (tx, rx) = mpsc::channel();
        let stop = Arc::new(AtomicBool::new(false));
        let reader = Arc::clone(&conn);
        let reader_stop = Arc::clone(&stop);
        std::thread::spawn(move || {
            while !reader_stop.load(Ordering::Relaxed) {
                match reader.recv() {
                    Ok((header, message)) => {
                        if tx
                            .send(Inbound::Message(Box::new(Received { header, message })))
                            .is_err()
                        {
                            return;
                        }
                    }
                    Err(e) if is_timeout(&e) => {}
                    Err(MessageReadError::Io(e)) => {
                        let _ = tx.send(Inbound::Closed(e.to_string()));
                        return;
                    }
                    Err(_) => {} // a frame we cannot parse: skip it
                }
            }
        });
        Self {
            conn,
            header: MavHeader {
                system_id: u32::from(system_id),
                component_id,
                sequence: 0,
            },
            rx,
            stop,
            closed: None,
            heartbeat: Arc::new(Mutex::new(None)),
        }
    }

    /// Starts a thread that sends `heartbeat` every `period` until the link is dropped, so that
    /// heartbeats keep flowing while the caller plans or waits. The message can be changed with
    /// [`Link::set_heartbeat`].
    pub fn start_heartbeat(&self, heartbeat: MavMessage, period: Duration) {
        if let Ok(mut h) = self.heartbeat.lock() {
            *h = Some(heartbeat);
        }
        let conn = Arc::clone(&self.conn);
        let header = self.header;
        let stop = Arc::clone(&self.stop);
        let message = Arc::clone(&self.heartbeat);
        std::thread::spawn(move || {
            while !stop.load(Ordering::Relaxed) {
                let msg = message.lock().ok().and_then(|m| m.clone());
                if let Some(msg) = msg
                    && conn.send(&header, &msg).is_err()
                {
                    return;
                }
                // Sleep in short slices so that dropping the link ends the thread soon.
                let until = Instant::now() + period;
                while Instant::now() < until && !stop.load(Ordering::Relaxed) {
                    std::thread::sleep(Duration::from_millis(20).min(period));
                }
            }
        });
    }

    /// Replaces the message the heartbeat thread sends.
    pub fn set_heartbeat(&self, heartbeat: MavMessage) {
        if let Ok(mut h) = self.heartbeat.lock() {
            *h = Some(heartbeat);
        }
    }

    /// Sends a message.
    pub fn send(&self, message: &MavMessage) -> Result<(), LinkError> {
        self.conn
            .send(&self.header, message)
            .map(|_| ())
            .map_err(|e| LinkError::Send {
                message: message_name(message),
                detail: e.to_string(),
            })
    }

    /// The next message, waiting at most `timeout`; `None` on timeout or once the connection is
    /// closed (see [`Link::closed`]).
    pub fn recv_timeout(&mut self, timeout: Duration) -> Option<Received> {
        if self.closed.is_some() {
            std::thread::sleep(timeout);
            return None;
        }
        match self.rx.recv_timeout(timeout) {
            Ok(Inbound::Message(r)) => Some(*r),
            Ok(Inbound::Closed(why)) => {
                self.closed = Some(why);
                None
            }
            Err(RecvTimeoutError::Timeout) => None,
            Err(RecvTimeoutError::Disconnected) => {
                self.closed = Some("the reader stopped".into());
                None
            }
        }
    }

    /// Why the connection closed, once it has.
    pub fn closed(&self) -> Option<&str> {
        self.closed.as_deref()
    }
}

impl Drop for Link {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

/// The MAVLink name of a message, for messages and logs.
pub fn message_name(message: &MavMessage) -> &'static str {
    use mavlink::Message;
    message.message_name()
}

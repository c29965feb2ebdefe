//! Shared by the MAVLink fuzz targets: fuzz bytes → a sequence of decoded messages.
//!
//! Even first byte: records `[system id][message choice][dt][payload length][payload]`, each
//! payload decoded as the chosen message without a checksum (so every field value is reached);
//! odd: the rest is a raw byte stream through the `mavlink` crate's frame reader, as a socket
//! delivers it (garbage, truncated frames, bad checksums, MAVLink 1 and 2).

use mavlink::dialects::common::MavMessage;
use mavlink::{MavlinkVersion, Message, MessageData};

/// One message as a peer sends it.
pub struct Incoming {
    /// The sender's system id.
    pub system_id: u8,
    /// The sender's component id.
    pub component_id: u8,
    /// The message.
    pub message: MavMessage,
    /// Seconds of the receiver's clock before the next one.
    pub dt_s: f64,
}

/// Decodes the fuzz input, choosing record message ids from `ids` (any id when the choice's
/// top bit is set).
pub fn incoming(data: &[u8], ids: &[u32]) -> Vec<Incoming> {
    let Some((&mode, mut rest)) = data.split_first() else {
        return Vec::new();
    };
    let mut out = Vec::new();
    if mode % 2 == 0 {
        while let [system_id, choice, dt, len, tail @ ..] = rest {
            let n = usize::from(*len).min(tail.len());
            let (payload, next) = tail.split_at(n);
            rest = next;
            let id = if choice & 0x80 != 0 {
                u32::from(*choice & 0x7f) * 2 + u32::from(mode >> 1 & 1)
            } else {
                ids[usize::from(*choice) % ids.len()]
            };
            if let Ok(message) = MavMessage::parse(MavlinkVersion::V2, id, payload) {
                out.push(Incoming {
                    system_id: *system_id,
                    component_id: 1,
                    message,
                    dt_s: f64::from(*dt) * 0.02,
                });
            }
        }
    } else {
        let mut reader = mavlink::MavlinkReader::new(std::io::Cursor::new(rest));
        for _ in 0..10_000 {
            match reader.read_any_message::<MavMessage>() {
                Ok((header, message)) => out.push(Incoming {
                    system_id: header.system_id as u8,
                    component_id: header.component_id,
                    message,
                    dt_s: 0.05,
                }),
                Err(mavlink::error::MessageReadError::Parse(_)) => {}
                Err(_) => break,
            }
        }
    }
    out
}

/// The messages a vehicle sends a ground station.
#[allow(deprecated)]
pub fn to_ground_ids() -> Vec<u32> {
    use mavlink::dialects::common::*;
    vec![
        HEARTBEAT_DATA::ID,
        GLOBAL_POSITION_INT_DATA::ID,
        LOCAL_POSITION_NED_DATA::ID,
        ATTITUDE_DATA::ID,
        GPS_GLOBAL_ORIGIN_DATA::ID,
        EXTENDED_SYS_STATE_DATA::ID,
        COMMAND_ACK_DATA::ID,
        MISSION_ITEM_REACHED_DATA::ID,
        MISSION_CURRENT_DATA::ID,
        STATUSTEXT_DATA::ID,
        MISSION_REQUEST_INT_DATA::ID,
        MISSION_REQUEST_DATA::ID,
        MISSION_ACK_DATA::ID,
    ]
}

/// The messages a ground station sends a vehicle.
#[allow(deprecated)]
pub fn to_vehicle_ids() -> Vec<u32> {
    use mavlink::dialects::common::*;
    vec![
        HEARTBEAT_DATA::ID,
        COMMAND_LONG_DATA::ID,
        COMMAND_INT_DATA::ID,
        SET_MODE_DATA::ID,
        REQUEST_DATA_STREAM_DATA::ID,
        SET_POSITION_TARGET_GLOBAL_INT_DATA::ID,
        SET_POSITION_TARGET_LOCAL_NED_DATA::ID,
        MISSION_COUNT_DATA::ID,
        MISSION_ITEM_INT_DATA::ID,
        MISSION_ITEM_DATA::ID,
        MISSION_CLEAR_ALL_DATA::ID,
        MISSION_REQUEST_LIST_DATA::ID,
    ]
}

//! The one table of the telemetry the flight needs: which messages (the dialect's ids), at what
//! rate the ground station asks for them, at what period the simulator streams them by default,
//! and in which REQUEST_DATA_STREAM group they come.

// REQUEST_DATA_STREAM groups are deprecated by MAVLink, still what ArduPilot honours.
#![allow(deprecated)]

use mavlink::MessageData;
use mavlink::dialects::common::*;

/// One streamed message.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stream {
    /// The message id (the dialect's `…_DATA::ID`).
    pub id: u32,
    /// The rate the ground station asks for with SET_MESSAGE_INTERVAL, Hz.
    pub ground_rate_hz: f64,
    /// The simulator's period when asked for the default rate (interval 0), seconds.
    pub default_period_s: f64,
    /// The REQUEST_DATA_STREAM group that turns it on (ArduPilot's grouping).
    pub group: MavDataStream,
}

/// The messages the flight needs, in the order the simulator sends those due together (the
/// attitude before the position, so that a position's heading is the latest).
pub const STREAMS: [Stream; 7] = [
    Stream {
        id: ATTITUDE_DATA::ID,
        ground_rate_hz: 10.0,
        default_period_s: 0.1,
        group: MavDataStream::MAV_DATA_STREAM_EXTRA1,
    },
    Stream {
        id: MISSION_ITEM_REACHED_DATA::ID,
        ground_rate_hz: 2.0,
        default_period_s: 1.0,
        group: MavDataStream::MAV_DATA_STREAM_EXTENDED_STATUS,
    },
    Stream {
        id: LOCAL_POSITION_NED_DATA::ID,
        ground_rate_hz: 2.0,
        default_period_s: 0.1,
        group: MavDataStream::MAV_DATA_STREAM_POSITION,
    },
    Stream {
        id: GLOBAL_POSITION_INT_DATA::ID,
        ground_rate_hz: 10.0,
        default_period_s: 0.1,
        group: MavDataStream::MAV_DATA_STREAM_POSITION,
    },
    Stream {
        id: MISSION_CURRENT_DATA::ID,
        ground_rate_hz: 2.0,
        default_period_s: 0.5,
        group: MavDataStream::MAV_DATA_STREAM_EXTENDED_STATUS,
    },
    Stream {
        id: GPS_GLOBAL_ORIGIN_DATA::ID,
        ground_rate_hz: 1.0,
        default_period_s: 1.0,
        group: MavDataStream::MAV_DATA_STREAM_EXTENDED_STATUS,
    },
    Stream {
        id: EXTENDED_SYS_STATE_DATA::ID,
        ground_rate_hz: 2.0,
        default_period_s: 0.5,
        group: MavDataStream::MAV_DATA_STREAM_EXTENDED_STATUS,
    },
];

/// Whether a REQUEST_DATA_STREAM `group` turns on `stream` (`MAV_DATA_STREAM_ALL`: every one).
pub fn in_group(stream: &Stream, group: MavDataStream) -> bool {
    group == MavDataStream::MAV_DATA_STREAM_ALL || stream.group == group
}

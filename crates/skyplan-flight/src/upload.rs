//! The ground side of the MAVLink mission upload, without I/O.
//!
//! [`mission_items`] turns a planned mission into the items a flight controller flies in AUTO:
//! (ArduPilot's item 0, the home) → NAV_TAKEOFF → one NAV_WAYPOINT per waypoint (its heading as
//! the yaw in `param4`, degrees, which PX4 honours), each preceded on ArduPilot by a
//! CONDITION_YAW to the same heading (ArduCopter ignores `param4`; it starts the "do" commands
//! between two NAV commands when the first completes, and its CONDITION_YAW then holds the heading
//! over the next leg) → NAV_LAND, all in the relative-altitude frame
//! (`MAV_FRAME_GLOBAL_RELATIVE_ALT_INT`). [`MissionUpload`] is the protocol: MISSION_COUNT → the
//! vehicle requests each item (MISSION_REQUEST_INT or the older MISSION_REQUEST, answered the
//! same way) → MISSION_ITEM_INT → MISSION_ACK, with a retry when the vehicle goes quiet and a
//! clear failure after too many. Events in, messages to send out; the link layer does the rest.
//!
//! ```
//! use skyplan_flight::upload::{MissionUpload, UploadConfig, UploadEvent, UploadSend, UploadStatus};
//! let mut up = MissionUpload::new(2, UploadConfig::default());
//! assert_eq!(up.start(0.0), vec![UploadSend::Count(2)]);
//! assert_eq!(up.handle(0.1, UploadEvent::Request { seq: 0 }), vec![UploadSend::Item(0)]);
//! assert_eq!(up.handle(0.2, UploadEvent::Request { seq: 1 }), vec![UploadSend::Item(1)]);
//! up.handle(0.3, UploadEvent::Ack(Ok(())));
//! assert_eq!(up.status(), &UploadStatus::Done);
//! ```

use crate::executor::ConfigError;

/// What a mission item does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ItemCommand {
    /// MAV_CMD_NAV_WAYPOINT (16): fly to the point, facing `yaw_deg`.
    Waypoint,
    /// MAV_CMD_NAV_TAKEOFF (22): climb to `alt_m`.
    Takeoff,
    /// MAV_CMD_NAV_LAND (21): land at the point.
    Land,
    /// MAV_CMD_CONDITION_YAW (115): face `yaw_deg` (absolute, `param1`) on the way to the
    /// NAV_WAYPOINT after it.
    ConditionYaw,
    /// MAV_CMD_DO_CHANGE_SPEED (178): fly the leg to the NAV_WAYPOINT after it at `speed_m_s`
    /// (`param1` 1: ground speed, `param2` the speed, `param3` −1: throttle unchanged).
    ChangeSpeed,
}

impl ItemCommand {
    /// The MAV_CMD number.
    pub fn mav_cmd(self) -> u16 {
        match self {
            ItemCommand::Waypoint => 16,
            ItemCommand::Takeoff => 22,
            ItemCommand::Land => 21,
            ItemCommand::ConditionYaw => 115,
            ItemCommand::ChangeSpeed => 178,
        }
    }
}

/// MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: latitude/longitude in degrees × 10⁷, altitude above home.
pub const FRAME_GLOBAL_RELATIVE_ALT_INT: u8 = 6;

/// One mission item as it goes on the wire (MISSION_ITEM_INT), frame
/// [`FRAME_GLOBAL_RELATIVE_ALT_INT`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MissionItem {
    /// Its index in the mission.
    pub seq: u16,
    /// What it does.
    pub command: ItemCommand,
    /// Latitude, degrees × 10⁷.
    pub lat_e7: i32,
    /// Longitude, degrees × 10⁷.
    pub lon_e7: i32,
    /// Metres above home.
    pub alt_m: f32,
    /// The yaw at the point, degrees clockwise from north in [0, 360) (`param4` of
    /// NAV_WAYPOINT, `param1` of CONDITION_YAW); NaN keeps the vehicle's heading.
    pub yaw_deg: f32,
    /// DO_CHANGE_SPEED: the ground speed, m/s (`param2`); NaN on other items.
    pub speed_m_s: f32,
    /// NAV_WAYPOINT: the acceptance radius, metres (`param2`; PX4 honours it, ArduCopter turns by
    /// its own waypoint radius); 0 leaves it to the autopilot.
    pub acceptance_radius_m: f32,
}

/// The items and where the flown parts are in them.
#[derive(Debug, Clone, PartialEq)]
pub struct MissionPlan {
    /// Every item, in order (`items[i].seq == i`).
    pub items: Vec<MissionItem>,
    /// The NAV_TAKEOFF item.
    pub takeoff_seq: u16,
    /// The NAV_WAYPOINT of the first waypoint; waypoint `k` is item
    /// `first_waypoint_seq + waypoint_stride · k`.
    pub first_waypoint_seq: u16,
    /// Items per waypoint: 1, plus 1 when each NAV_WAYPOINT is preceded by its CONDITION_YAW,
    /// plus 1 when it is preceded by a DO_CHANGE_SPEED (a paced mission).
    pub waypoint_stride: u16,
    /// The NAV_LAND item (the last one).
    pub land_seq: u16,
}

impl MissionPlan {
    /// The waypoint index of item `seq`, if it is a waypoint's NAV_WAYPOINT.
    pub fn waypoint_index(&self, seq: u16) -> Option<usize> {
        let stride = self.waypoint_stride.max(1);
        (seq >= self.first_waypoint_seq
            && seq < self.land_seq
            && (seq - self.first_waypoint_seq).is_multiple_of(stride))
        .then(|| usize::from((seq - self.first_waypoint_seq) / stride))
    }
}

/// A waypoint of the mission in global coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlobalWaypoint {
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Metres above home.
    pub alt_m: f64,
    /// Heading, radians clockwise from north.
    pub heading_rad: f64,
}

impl From<&skyplan_mission::Waypoint> for GlobalWaypoint {
    fn from(w: &skyplan_mission::Waypoint) -> Self {
        GlobalWaypoint {
            lat_deg: w.lat_deg,
            lon_deg: w.lon_deg,
            alt_m: w.alt_m,
            heading_rad: w.heading_rad,
        }
    }
}

fn e7(deg: f64) -> i32 {
    (deg * 1e7).round() as i32
}

/// A heading as `param4`: degrees in [0, 360).
pub fn yaw_param_deg(heading_rad: f64) -> f32 {
    let d = heading_rad.to_degrees().rem_euclid(360.0);
    (if d >= 359.999_999 { 0.0 } else { d }) as f32
}

/// The mission items for these waypoints. `home` (latitude, longitude) adds ArduPilot's item 0,
/// the home, which it overwrites and never flies; PX4 starts at item 0, so pass `None` for it.
/// `condition_yaw` puts a CONDITION_YAW to each waypoint's heading before its NAV_WAYPOINT (for
/// ArduCopter, which ignores `param4`).
pub fn mission_items(
    waypoints: &[GlobalWaypoint],
    home: Option<(f64, f64)>,
    condition_yaw: bool,
) -> Result<MissionPlan, ConfigError> {
    paced_mission_items(waypoints, home, condition_yaw, None)
}

/// How one leg of a paced mission is flown: the leg to a waypoint and that waypoint's radius.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegPace {
    /// The ground speed on the leg to the waypoint, m/s (a DO_CHANGE_SPEED before it).
    pub speed_m_s: f64,
    /// The waypoint's acceptance radius, metres (NAV_WAYPOINT `param2`).
    pub acceptance_radius_m: f64,
}

/// As [`mission_items`]; with `pace` (one per waypoint), each NAV_WAYPOINT is preceded by a
/// DO_CHANGE_SPEED to its leg's speed and carries its acceptance radius. The "do" items between
/// two NAV items start when the first is reached, so the speed holds on the leg to the waypoint.
///
/// ```
/// use skyplan_flight::upload::{paced_mission_items, GlobalWaypoint, ItemCommand, LegPace};
/// let w = |lat_deg| GlobalWaypoint { lat_deg, lon_deg: -122.4, alt_m: 5.0, heading_rad: 0.0 };
/// let pace = [LegPace { speed_m_s: 2.0, acceptance_radius_m: 0.5 }; 2];
/// let p = paced_mission_items(&[w(37.79), w(37.791)], None, true, Some(&pace)).unwrap();
/// // take-off, then CONDITION_YAW, DO_CHANGE_SPEED, NAV_WAYPOINT for each waypoint, land.
/// assert_eq!(p.waypoint_stride, 3);
/// assert_eq!(p.items[2].command, ItemCommand::ChangeSpeed);
/// assert_eq!(p.items[2].speed_m_s, 2.0);
/// assert_eq!(p.items[3].acceptance_radius_m, 0.5);
/// assert_eq!(p.land_seq, 7);
/// ```
pub fn paced_mission_items(
    waypoints: &[GlobalWaypoint],
    home: Option<(f64, f64)>,
    condition_yaw: bool,
    pace: Option<&[LegPace]>,
) -> Result<MissionPlan, ConfigError> {
    if let Some(pace) = pace {
        if pace.len() != waypoints.len() {
            return Err(ConfigError(format!(
                "{} leg paces for {} waypoints: one per waypoint expected",
                pace.len(),
                waypoints.len()
            )));
        }
        let fine = |l: &LegPace| {
            l.speed_m_s.is_finite()
                && l.speed_m_s > 0.0
                && l.acceptance_radius_m.is_finite()
                && l.acceptance_radius_m >= 0.0
        };
        if let Some(k) = pace.iter().position(|l| !fine(l)) {
            return Err(ConfigError(format!(
                "leg {k}: the speed must be a positive number of m/s and the acceptance radius a non-negative number of metres"
            )));
        }
    }
    let (Some(first), Some(last)) = (waypoints.first(), waypoints.last()) else {
        return Err(ConfigError("the mission has no waypoint".into()));
    };
    let finite = |w: &GlobalWaypoint| {
        w.lat_deg.is_finite()
            && w.lon_deg.is_finite()
            && w.alt_m.is_finite()
            && w.heading_rad.is_finite()
            && w.lat_deg.abs() <= 90.0
            && w.lon_deg.abs() <= 180.0
    };
    if !waypoints.iter().all(finite) {
        return Err(ConfigError(
            "a waypoint is not a finite latitude/longitude/altitude/heading".into(),
        ));
    }
    // Home (optional), take-off, the waypoints, land: must fit the u16 sequence numbers.
    let waypoint_stride: u16 = 1 + u16::from(condition_yaw) + u16::from(pace.is_some());
    if usize::from(waypoint_stride) * waypoints.len() + 3 > usize::from(u16::MAX) {
        return Err(ConfigError(format!(
            "{} waypoints do not fit in one MAVLink mission",
            waypoints.len()
        )));
    }
    let mut items = Vec::with_capacity(usize::from(waypoint_stride) * waypoints.len() + 3);
    // (speed, acceptance radius): NaN and 0 unless a leg's pace says otherwise.
    let mut push = |command, lat_deg, lon_deg, alt_m: f64, yaw_deg, (speed, radius)| {
        let seq = items.len() as u16;
        items.push(MissionItem {
            seq,
            command,
            lat_e7: e7(lat_deg),
            lon_e7: e7(lon_deg),
            alt_m: alt_m as f32,
            yaw_deg,
            speed_m_s: speed,
            acceptance_radius_m: radius,
        });
        seq
    };
    let unpaced = (f32::NAN, 0.0);
    if let Some((lat, lon)) = home {
        push(ItemCommand::Waypoint, lat, lon, 0.0, f32::NAN, unpaced);
    }
    let (lat, lon, alt) = (first.lat_deg, first.lon_deg, first.alt_m);
    let takeoff_seq = push(ItemCommand::Takeoff, lat, lon, alt, f32::NAN, unpaced);
    let first_waypoint_seq = takeoff_seq + waypoint_stride;
    for (k, w) in waypoints.iter().enumerate() {
        let yaw_deg = yaw_param_deg(w.heading_rad);
        if condition_yaw {
            push(ItemCommand::ConditionYaw, 0.0, 0.0, 0.0, yaw_deg, unpaced);
        }
        let mut radius = 0.0;
        if let Some(leg) = pace.and_then(|p| p.get(k)) {
            let speed = (leg.speed_m_s as f32, 0.0);
            push(ItemCommand::ChangeSpeed, 0.0, 0.0, 0.0, f32::NAN, speed);
            radius = leg.acceptance_radius_m as f32;
        }
        let (lat, lon, alt) = (w.lat_deg, w.lon_deg, w.alt_m);
        push(
            ItemCommand::Waypoint,
            lat,
            lon,
            alt,
            yaw_deg,
            (f32::NAN, radius),
        );
    }
    let land_seq = push(
        ItemCommand::Land,
        last.lat_deg,
        last.lon_deg,
        0.0,
        f32::NAN,
        unpaced,
    );
    Ok(MissionPlan {
        items,
        takeoff_seq,
        first_waypoint_seq,
        waypoint_stride,
        land_seq,
    })
}

/// Retries of the upload.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UploadConfig {
    /// Resend the last message when the vehicle has said nothing for this long, seconds.
    pub retry_s: f64,
    /// Give up after this many resends in a row.
    pub max_retries: u32,
}

impl Default for UploadConfig {
    fn default() -> Self {
        Self {
            retry_s: 1.5,
            max_retries: 5,
        }
    }
}

/// What the vehicle said.
#[derive(Debug, Clone, PartialEq)]
pub enum UploadEvent {
    /// MISSION_REQUEST_INT or MISSION_REQUEST for this item.
    Request {
        /// The item.
        seq: u16,
    },
    /// MISSION_ACK: `Ok` for MAV_MISSION_ACCEPTED, else the result's name.
    Ack(Result<(), String>),
    /// Time passes.
    Tick,
}

/// What to send.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UploadSend {
    /// MISSION_COUNT with this count.
    Count(u16),
    /// MISSION_ITEM_INT of this item.
    Item(u16),
}

/// Where the upload is.
#[derive(Debug, Clone, PartialEq)]
pub enum UploadStatus {
    /// Not started, or under way.
    InProgress,
    /// The vehicle acknowledged every item.
    Done,
    /// It failed, with the reason.
    Failed(String),
}

/// The upload protocol, ground side. See the module documentation.
#[derive(Debug, Clone)]
pub struct MissionUpload {
    count: u16,
    config: UploadConfig,
    requested: Vec<bool>,
    last: Option<(f64, UploadSend)>,
    retries_in_a_row: u32,
    resends: u32,
    requests: u32,
    ignored: u32,
    status: UploadStatus,
}

impl MissionUpload {
    /// An upload of `count` items.
    pub fn new(count: u16, config: UploadConfig) -> Self {
        Self {
            count,
            config,
            requested: vec![false; usize::from(count)],
            last: None,
            retries_in_a_row: 0,
            resends: 0,
            requests: 0,
            ignored: 0,
            status: UploadStatus::InProgress,
        }
    }

    /// Starts: the MISSION_COUNT to send.
    pub fn start(&mut self, now_s: f64) -> Vec<UploadSend> {
        self.last = Some((now_s, UploadSend::Count(self.count)));
        vec![UploadSend::Count(self.count)]
    }

    /// Where the upload is.
    pub fn status(&self) -> &UploadStatus {
        &self.status
    }

    /// Messages resent after a silence.
    pub fn resends(&self) -> u32 {
        self.resends
    }

    /// Item requests answered (a re-requested item counts again).
    pub fn requests(&self) -> u32 {
        self.requests
    }

    /// Requests ignored (for items that do not exist).
    pub fn ignored(&self) -> u32 {
        self.ignored
    }

    /// Feeds one event at `now_s` (seconds, monotonic) and returns what to send.
    pub fn handle(&mut self, now_s: f64, event: UploadEvent) -> Vec<UploadSend> {
        if self.status != UploadStatus::InProgress {
            return Vec::new();
        }
        match event {
            UploadEvent::Request { seq } => {
                if seq >= self.count {
                    self.ignored += 1;
                    return Vec::new();
                }
                self.requested[usize::from(seq)] = true;
                self.requests += 1;
                self.retries_in_a_row = 0;
                self.last = Some((now_s, UploadSend::Item(seq)));
                vec![UploadSend::Item(seq)]
            }
            UploadEvent::Ack(Ok(())) => {
                let missing = self.requested.iter().filter(|r| !**r).count();
                self.status = if missing == 0 {
                    UploadStatus::Done
                } else {
                    UploadStatus::Failed(format!(
                        "the vehicle acknowledged the mission without requesting {missing} of its {} items",
                        self.count
                    ))
                };
                Vec::new()
            }
            UploadEvent::Ack(Err(answer)) => {
                self.status =
                    UploadStatus::Failed(format!("the vehicle rejected the mission: {answer}"));
                Vec::new()
            }
            UploadEvent::Tick => {
                let Some((t, what)) = self.last else {
                    return Vec::new();
                };
                if now_s - t < self.config.retry_s && now_s >= t {
                    return Vec::new();
                }
                if self.retries_in_a_row >= self.config.max_retries {
                    let after = match what {
                        UploadSend::Count(n) => format!("MISSION_COUNT ({n} items)"),
                        UploadSend::Item(seq) if seq + 1 == self.count => {
                            format!("the last item ({seq})")
                        }
                        UploadSend::Item(seq) => format!("item {seq}"),
                    };
                    self.status = UploadStatus::Failed(format!(
                        "no answer from the vehicle to {after} after {} tries, {:.1} s apart",
                        self.retries_in_a_row + 1,
                        self.config.retry_s
                    ));
                    return Vec::new();
                }
                self.retries_in_a_row += 1;
                self.resends += 1;
                self.last = Some((now_s, what));
                vec![what]
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wps() -> Vec<GlobalWaypoint> {
        vec![
            GlobalWaypoint {
                lat_deg: 37.792_480_1,
                lon_deg: -122.397_450_4,
                alt_m: 5.0,
                heading_rad: 0.0,
            },
            GlobalWaypoint {
                lat_deg: 37.793,
                lon_deg: -122.397,
                alt_m: 5.0,
                heading_rad: -std::f64::consts::FRAC_PI_2,
            },
        ]
    }

    #[test]
    fn items_are_home_takeoff_waypoints_land() {
        let p = mission_items(&wps(), Some((37.7924801, -122.3974504)), false).unwrap();
        let cmds: Vec<ItemCommand> = p.items.iter().map(|i| i.command).collect();
        use ItemCommand::*;
        assert_eq!(cmds, [Waypoint, Takeoff, Waypoint, Waypoint, Land]);
        assert_eq!((p.takeoff_seq, p.first_waypoint_seq, p.land_seq), (1, 2, 4));
        assert!(
            p.items
                .iter()
                .enumerate()
                .all(|(i, it)| it.seq as usize == i)
        );
        assert_eq!(p.items[1].alt_m, 5.0);
        assert_eq!(p.items[2].lat_e7, 377_924_801);
        assert_eq!(p.items[2].lon_e7, -1_223_974_504);
        assert_eq!(p.items[2].yaw_deg, 0.0);
        assert_eq!(p.items[3].yaw_deg, 270.0);
        assert_eq!(p.items[4].alt_m, 0.0);
        assert_eq!(p.waypoint_index(2), Some(0));
        assert_eq!(p.waypoint_index(3), Some(1));
        assert_eq!(p.waypoint_index(4), None);
        assert_eq!(p.waypoint_index(1), None);
        let px4 = mission_items(&wps(), None, false).unwrap();
        assert_eq!(px4.items.len(), 4);
        assert_eq!(
            (px4.takeoff_seq, px4.first_waypoint_seq, px4.land_seq),
            (0, 1, 3)
        );
    }

    #[test]
    fn on_ardupilot_each_waypoint_is_preceded_by_its_condition_yaw() {
        let p = mission_items(&wps(), Some((37.7924801, -122.3974504)), true).unwrap();
        let cmds: Vec<ItemCommand> = p.items.iter().map(|i| i.command).collect();
        use ItemCommand::*;
        assert_eq!(
            cmds,
            [
                Waypoint,
                Takeoff,
                ConditionYaw,
                Waypoint,
                ConditionYaw,
                Waypoint,
                Land
            ]
        );
        assert_eq!(ConditionYaw.mav_cmd(), 115);
        assert_eq!(
            (
                p.takeoff_seq,
                p.first_waypoint_seq,
                p.waypoint_stride,
                p.land_seq
            ),
            (1, 3, 2, 6)
        );
        assert_eq!((p.items[2].yaw_deg, p.items[4].yaw_deg), (0.0, 270.0));
        let wp_of: Vec<Option<usize>> = (0..7).map(|s| p.waypoint_index(s)).collect();
        assert_eq!(wp_of, [None, None, None, Some(0), None, Some(1), None]);
    }

    #[test]
    fn a_paced_mission_has_a_change_of_speed_before_each_waypoint() {
        let pace = [
            LegPace {
                speed_m_s: 3.5,
                acceptance_radius_m: 0.5,
            },
            LegPace {
                speed_m_s: 7.25,
                acceptance_radius_m: 1.5,
            },
        ];
        let home = Some((37.7924801, -122.3974504));
        let p = paced_mission_items(&wps(), home, true, Some(&pace)).unwrap();
        let cmds: Vec<ItemCommand> = p.items.iter().map(|i| i.command).collect();
        use ItemCommand::*;
        assert_eq!(
            cmds,
            [
                Waypoint,
                Takeoff,
                ConditionYaw,
                ChangeSpeed,
                Waypoint,
                ConditionYaw,
                ChangeSpeed,
                Waypoint,
                Land
            ]
        );
        assert_eq!(ChangeSpeed.mav_cmd(), 178);
        let layout = (p.takeoff_seq, p.first_waypoint_seq, p.waypoint_stride);
        assert_eq!((layout, p.land_seq), ((1, 4, 3), 8));
        assert_eq!((p.items[3].speed_m_s, p.items[6].speed_m_s), (3.5, 7.25));
        let radii = (
            p.items[4].acceptance_radius_m,
            p.items[7].acceptance_radius_m,
        );
        assert_eq!(radii, (0.5, 1.5));
        // The waypoints are where the unpaced mission has them.
        let plain = mission_items(&wps(), home, true).unwrap();
        assert_eq!(p.items[4].lat_e7, plain.items[3].lat_e7);
        assert_eq!(p.items[7].lon_e7, plain.items[5].lon_e7);
        let wp_of: Vec<Option<usize>> = (0..9).map(|s| p.waypoint_index(s)).collect();
        let mut want = [None; 9];
        (want[4], want[7]) = (Some(0), Some(1));
        assert_eq!(wp_of, want);
        // Without CONDITION_YAW (PX4): stride 2.
        let px4 = paced_mission_items(&wps(), None, false, Some(&pace)).unwrap();
        assert_eq!(
            (px4.first_waypoint_seq, px4.waypoint_stride, px4.land_seq),
            (2, 2, 5)
        );
        // One pace per waypoint, each a positive speed and a non-negative radius.
        assert!(paced_mission_items(&wps(), None, false, Some(&pace[..1])).is_err());
        for bad in [
            (0.0, 1.0),
            (f64::NAN, 1.0),
            (2.0, -1.0),
            (2.0, f64::INFINITY),
        ] {
            let mut p2 = pace;
            (p2[1].speed_m_s, p2[1].acceptance_radius_m) = bad;
            assert!(paced_mission_items(&wps(), None, false, Some(&p2)).is_err());
        }
    }

    #[test]
    fn bad_missions_are_refused() {
        assert!(mission_items(&[], None, false).is_err());
        let mut w = wps();
        w[1].lat_deg = f64::NAN;
        assert!(mission_items(&w, None, false).is_err());
        w[1].lat_deg = 91.0;
        assert!(mission_items(&w, None, false).is_err());
    }

    #[test]
    fn yaw_is_degrees_in_0_360() {
        assert_eq!(yaw_param_deg(0.0), 0.0);
        assert_eq!(yaw_param_deg(std::f64::consts::PI), 180.0);
        assert_eq!(yaw_param_deg(-std::f64::consts::FRAC_PI_2), 270.0);
        assert_eq!(yaw_param_deg(2.0 * std::f64::consts::PI), 0.0);
        assert!((0.0..360.0).contains(&yaw_param_deg(-1e-12)));
    }

    /// A vehicle side that loses every `drop_every`-th message it would send or receive.
    struct LossyVehicle {
        count: Option<u16>,
        got: Vec<Option<u16>>,
        next: u16,
        counter: u32,
        drop_every: u32,
        done: bool,
    }

    impl LossyVehicle {
        fn lost(&mut self) -> bool {
            self.counter += 1;
            self.drop_every > 0 && self.counter.is_multiple_of(self.drop_every)
        }
        /// Receives what the ground sent; returns the answer (if it gets through).
        fn receive(&mut self, s: UploadSend) -> Option<UploadEvent> {
            if self.lost() {
                return None;
            }
            let answer = match s {
                UploadSend::Count(n) => {
                    self.count = Some(n);
                    self.got = vec![None; usize::from(n)];
                    self.next = 0;
                    UploadEvent::Request { seq: 0 }
                }
                UploadSend::Item(seq) => {
                    let n = self.count?;
                    if seq == self.next {
                        self.got[usize::from(seq)] = Some(seq);
                        self.next += 1;
                    }
                    if self.next == n {
                        self.done = true;
                        UploadEvent::Ack(Ok(()))
                    } else {
                        UploadEvent::Request { seq: self.next }
                    }
                }
            };
            (!self.lost()).then_some(answer)
        }
    }

    fn run(n: u16, drop_every: u32) -> (MissionUpload, LossyVehicle) {
        let mut up = MissionUpload::new(n, UploadConfig::default());
        let mut v = LossyVehicle {
            count: None,
            got: Vec::new(),
            next: 0,
            counter: 0,
            drop_every,
            done: false,
        };
        let mut outbox = up.start(0.0);
        let mut t = 0.0;
        while *up.status() == UploadStatus::InProgress && t < 1000.0 {
            t += 0.1;
            let mut events = vec![UploadEvent::Tick];
            for s in outbox.drain(..) {
                events.extend(v.receive(s));
            }
            for e in events {
                outbox.extend(up.handle(t, e));
            }
        }
        (up, v)
    }

    #[test]
    fn a_clean_upload_needs_no_retry() {
        let (up, v) = run(17, 0);
        assert_eq!(up.status(), &UploadStatus::Done);
        assert_eq!(up.resends(), 0);
        assert_eq!(up.requests(), 17);
        assert!(v.done && v.got.iter().all(Option::is_some));
    }

    #[test]
    fn lost_messages_are_retried_until_the_upload_completes() {
        for drop_every in [3, 4, 5, 7] {
            let (up, v) = run(17, drop_every);
            assert_eq!(up.status(), &UploadStatus::Done, "drop every {drop_every}");
            assert!(up.resends() > 0);
            assert!(v.got.iter().all(Option::is_some));
        }
    }

    #[test]
    fn a_silent_vehicle_fails_after_the_retries() {
        let mut up = MissionUpload::new(3, UploadConfig::default());
        up.start(0.0);
        let mut sent = 0;
        let mut t = 0.0;
        while *up.status() == UploadStatus::InProgress {
            t += 0.1;
            sent += up.handle(t, UploadEvent::Tick).len();
        }
        assert_eq!(sent, 5);
        let UploadStatus::Failed(why) = up.status() else {
            unreachable!()
        };
        assert!(
            why.contains("MISSION_COUNT (3 items) after 6 tries"),
            "{why}"
        );
        assert!((9.0..9.7).contains(&t), "{t}");
    }

    #[test]
    fn rejections_early_acks_and_bad_requests() {
        let mut up = MissionUpload::new(2, UploadConfig::default());
        up.start(0.0);
        assert!(up.handle(0.1, UploadEvent::Request { seq: 7 }).is_empty());
        assert_eq!(up.ignored(), 1);
        up.handle(0.2, UploadEvent::Ack(Err("NO_SPACE".into())));
        assert_eq!(
            up.status(),
            &UploadStatus::Failed("the vehicle rejected the mission: NO_SPACE".into())
        );
        let mut up = MissionUpload::new(2, UploadConfig::default());
        up.start(0.0);
        up.handle(0.1, UploadEvent::Request { seq: 0 });
        up.handle(0.2, UploadEvent::Ack(Ok(())));
        assert!(matches!(up.status(), UploadStatus::Failed(w) if w.contains("1 of its 2")));
        // A re-request (the vehicle missed an item) is answered again.
        let mut up = MissionUpload::new(2, UploadConfig::default());
        up.start(0.0);
        up.handle(0.1, UploadEvent::Request { seq: 0 });
        assert_eq!(
            up.handle(0.6, UploadEvent::Request { seq: 0 }),
            vec![UploadSend::Item(0)]
        );
        // An empty mission: the count alone, then the ack.
        let mut up = MissionUpload::new(0, UploadConfig::default());
        assert_eq!(up.start(0.0), vec![UploadSend::Count(0)]);
        up.handle(0.1, UploadEvent::Ack(Ok(())));
        assert_eq!(up.status(), &UploadStatus::Done);
    }
}

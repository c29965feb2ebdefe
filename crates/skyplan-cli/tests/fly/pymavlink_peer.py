"""An independent MAVLink peer (pymavlink) drives `skyplan sim` like a ground station would.

Usage: python3 pymavlink_peer.py tcp:127.0.0.1:PORT
Prints one line per check and exits 0 only if all pass.
"""
import math
import os
import sys
import time

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil  # noqa: E402

DEADLINE = time.time() + 60


def fail(msg):
    print("FAIL", msg, flush=True)
    sys.exit(1)


LAST_HEARTBEAT = [0.0]
TEXTS = []


def heartbeat(conn):
    """A ground station heartbeat at 1 Hz (the vehicle's GCS failsafe watches for it)."""
    if time.time() - LAST_HEARTBEAT[0] >= 1.0:
        LAST_HEARTBEAT[0] = time.time()
        conn.mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_GCS, mavutil.mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)


def wait(conn, types, pred=lambda m: True, timeout=15):
    end = min(time.time() + timeout, DEADLINE)
    while time.time() < end:
        heartbeat(conn)
        wanted = [types] if isinstance(types, str) else list(types)
        m = conn.recv_match(type=wanted + ["STATUSTEXT"], blocking=True, timeout=0.5)
        if m is not None and m.get_type() == "STATUSTEXT":
            TEXTS.append(m.text)
            if "STATUSTEXT" not in wanted:
                continue
        if m is not None and pred(m):
            return m
    fail(f"timed out waiting for {types}")


def command(conn, cmd, *params):
    p = list(params) + [0.0] * (7 - len(params))
    conn.mav.command_long_send(conn.target_system, conn.target_component, cmd, 0, *p)
    ack = wait(conn, "COMMAND_ACK", lambda m: m.command == cmd)
    return ack.result


conn = mavutil.mavlink_connection(sys.argv[1], source_system=250, source_component=190)
hb = conn.wait_heartbeat(timeout=10)
if hb is None:
    fail("no heartbeat")
print("heartbeat from system", conn.target_system, "autopilot", hb.autopilot, "type", hb.type, flush=True)
assert hb.autopilot == mavutil.mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA
heartbeat(conn)

# Like ArduCopter, nothing streams until asked for: no telemetry in the first second.
early = conn.recv_match(type=["GLOBAL_POSITION_INT", "LOCAL_POSITION_NED", "ATTITUDE"], blocking=True, timeout=1.0)
if early is not None:
    fail(f"{early.get_type()} arrived before any stream was requested")
print("no telemetry before it is requested", flush=True)

# Telemetry streams, requested with SET_MESSAGE_INTERVAL (microseconds).
for msg_id, hz in [(33, 10), (32, 10), (30, 10), (245, 2), (42, 2)]:
    if command(conn, mavutil.mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, msg_id, 1e6 / hz) != 0:
        fail(f"SET_MESSAGE_INTERVAL {msg_id} refused")
g = wait(conn, "GLOBAL_POSITION_INT")
wait(conn, "LOCAL_POSITION_NED")
wait(conn, "ATTITUDE")
print(f"global position lat {g.lat / 1e7:.7f} lon {g.lon / 1e7:.7f}", flush=True)

# Refusal: takeoff before arming is FAILED, with a STATUSTEXT reason.
r = command(conn, mavutil.mavlink.MAV_CMD_DO_SET_MODE, 1, 4)
if r != 0:
    fail(f"GUIDED refused: {r}")
r = command(conn, mavutil.mavlink.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 5)
if r != mavutil.mavlink.MAV_RESULT_FAILED:
    fail(f"takeoff while disarmed answered {r}")
if not TEXTS:
    wait(conn, "STATUSTEXT")
print("refusal reason:", TEXTS[-1], flush=True)

# PARAM_SET -> PARAM_VALUE, as ArduPilot answers it (RTL_ALT in centimetres).
conn.mav.param_set_send(conn.target_system, conn.target_component, b"RTL_ALT", 4200.0,
                        mavutil.mavlink.MAV_PARAM_TYPE_REAL32)
pv = wait(conn, "PARAM_VALUE", lambda m: m.param_id == "RTL_ALT")
print(f"param RTL_ALT = {pv.param_value:.0f}", flush=True)

# Mission upload: COUNT -> REQUEST_INT -> ITEM_INT -> ACK (item 0 is the home, as on ArduPilot).
lat0, lon0 = g.lat, g.lon
items = [
    (mavutil.mavlink.MAV_CMD_NAV_WAYPOINT, lat0, lon0, 0.0),
    (mavutil.mavlink.MAV_CMD_NAV_TAKEOFF, 0, 0, 5.0),
    (mavutil.mavlink.MAV_CMD_NAV_WAYPOINT, lat0 + 900, lon0, 5.0),
    (mavutil.mavlink.MAV_CMD_NAV_LAND, 0, 0, 0.0),
]
conn.mav.mission_count_send(conn.target_system, conn.target_component, len(items))
sent = 0
while True:
    m = wait(conn, ["MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK"])
    if m.get_type() == "MISSION_ACK":
        if m.type != mavutil.mavlink.MAV_MISSION_ACCEPTED:
            fail(f"mission refused: {m.type}")
        break
    cmd, x, y, z = items[m.seq]
    conn.mav.mission_item_int_send(
        conn.target_system, conn.target_component, m.seq,
        mavutil.mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, cmd, 0, 1, 0, 0, 0, float("nan"), x, y, z)
    sent += 1
print(f"mission upload accepted after {sent} items", flush=True)

# Guided flight: arm, take off, fly to a position target with a heading.
if command(conn, mavutil.mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1) != 0:
    fail("arming refused")
wait(conn, "HEARTBEAT", lambda m: m.get_srcSystem() == 1 and m.base_mode & mavutil.mavlink.MAV_MODE_FLAG_SAFETY_ARMED)
if command(conn, mavutil.mavlink.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 5) != 0:
    fail("takeoff refused")
wait(conn, "GLOBAL_POSITION_INT", lambda m: m.relative_alt >= 4750, timeout=30)
print("took off to 95 % of 5 m", flush=True)
deadline = time.time() + 30
reached = None
while time.time() < deadline and reached is None:
    conn.mav.set_position_target_local_ned_send(
        0, conn.target_system, conn.target_component, mavutil.mavlink.MAV_FRAME_LOCAL_NED,
        0x9F8, 10.0, 5.0, -5.0, 0, 0, 0, 0, 0, 0, math.radians(90), 0)
    m = wait(conn, "LOCAL_POSITION_NED")
    a = wait(conn, "ATTITUDE")
    if math.hypot(m.x - 10.0, m.y - 5.0) < 0.5 and abs(m.z + 5.0) < 0.5 and abs(a.yaw - math.radians(90)) < 0.05:
        reached = (m.x, m.y, m.z, math.degrees(a.yaw))
if reached is None:
    fail("position target not reached")
print("position target reached: N %.2f E %.2f D %.2f heading %.1f" % reached, flush=True)

# Land: LAND mode descends and disarms on the ground.
if command(conn, mavutil.mavlink.MAV_CMD_NAV_LAND) != 0:
    fail("land refused")
wait(conn, "EXTENDED_SYS_STATE", lambda m: m.landed_state == mavutil.mavlink.MAV_LANDED_STATE_ON_GROUND, timeout=30)
wait(conn, "HEARTBEAT", lambda m: m.get_srcSystem() == 1 and not (m.base_mode & mavutil.mavlink.MAV_MODE_FLAG_SAFETY_ARMED), timeout=30)
print("landed and disarmed", flush=True)

# AUTO: fly the uploaded mission; MISSION_ITEM_REACHED for take-off, waypoint and land.
if command(conn, mavutil.mavlink.MAV_CMD_DO_SET_MODE, 1, 4) != 0:
    fail("GUIDED refused after landing")
if command(conn, mavutil.mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1) != 0:
    fail("re-arming refused")
if command(conn, mavutil.mavlink.MAV_CMD_MISSION_START) != 0:
    fail("mission start refused")
seen = []
while len(seen) < 3:
    m = wait(conn, "MISSION_ITEM_REACHED", timeout=40)
    if m.seq not in seen:
        seen.append(m.seq)
print("mission items reached:", seen, flush=True)
if seen != [1, 2, 3]:
    fail(f"mission items reached {seen}")
wait(conn, "HEARTBEAT", lambda m: m.get_srcSystem() == 1 and not (m.base_mode & mavutil.mavlink.MAV_MODE_FLAG_SAFETY_ARMED), timeout=30)
print("OK", flush=True)

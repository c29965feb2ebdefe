"""MAVSDK as the AUTOPILOT side: skyplan uploads its mission to MAVSDK's MissionRawServer.

Usage: python3 mavsdk_autopilot.py PORT HOME_LAT HOME_LON PLAN.json [SAMPLES.csv]
Listens on udpin://127.0.0.1:PORT as an autopilot component (MAVSDK's C++ core, `pip install
mavsdk`), publishes a position with TelemetryServer (skyplan waits for one before planning),
prints "listening PORT", then waits for one mission upload, prints its items and checks them
against skyplan's plan (PLAN.json, written by `skyplan fly --out` before it uploads): the home,
NAV_TAKEOFF to the altitude, one NAV_WAYPOINT per waypoint (lat/lon within 1e-7°, altitude, yaw
in param4: the plan's grid heading turned to true north), NAV_LAND at the last one, all in MAV_FRAME_GLOBAL_RELATIVE_ALT_INT. With
SAMPLES.csv (the trajectory's samples from `skyplan plan --trajectory --samples`: a mission
uploaded by `fly --trajectory --upload`), each NAV_WAYPOINT comes after a DO_CHANGE_SPEED (frame
MISSION, param1 1 = ground speed, param2 the speed, param3 -1) whose speed is within the
trajectory's ground speeds, the fastest leg at the trajectory's top speed, and carries an
acceptance radius (param2) between 0.5 m and half the 5 m margin. Prints "OK" at the end, or
"FAIL ..." and exits 1.
"""
import json
import math
import sys
import threading
import time

from mavsdk import ComponentType, Configuration, ConnectionResult, Mavsdk
from mavsdk.plugins.mission_raw_server import MissionRawServer, MissionRawServerResult
from mavsdk.plugins.telemetry_server import (
    Heading,
    Position,
    PositionNed,
    PositionVelocityNed,
    TelemetryServer,
    VelocityNed,
)


def fail(msg):
    print("FAIL", msg, flush=True)
    sys.exit(1)


port = int(sys.argv[1])
home_lat, home_lon = float(sys.argv[2]), float(sys.argv[3])
plan_path = sys.argv[4]
samples_path = sys.argv[5] if len(sys.argv) > 5 else None

mavsdk = Mavsdk(Configuration.create_with_component_type(ComponentType.AUTOPILOT))
result = mavsdk.add_any_connection(f"udpin://127.0.0.1:{port}")
if result != ConnectionResult.SUCCESS:
    fail(f"cannot listen on udp port {port}: {result!r}")
component = mavsdk.server_component()
mission_server = MissionRawServer(component)
telemetry = TelemetryServer(component)

received = []
done = threading.Event()


def on_mission(result, plan, _user_data):
    received.append((result, plan))
    done.set()


mission_server.subscribe_incoming_mission(on_mission)
print("listening", port, "mavsdk", mavsdk.version(), flush=True)

deadline = time.time() + 60
while not done.is_set() and time.time() < deadline:
    zero = VelocityNed(0.0, 0.0, 0.0)
    try:
        telemetry.publish_position(Position(home_lat, home_lon, 0.0, 0.0), zero, Heading(0.0))
        telemetry.publish_position_velocity_ned(
            PositionVelocityNed(PositionNed(0.0, 0.0, 0.0), zero)
        )
    except Exception as e:  # not connected yet: MAVSDK has no ground station address
        if "NO_SYSTEM" not in repr(e) and "NoSystem" not in repr(e):
            print("publish:", repr(e), flush=True)
    time.sleep(0.2)
if not done.is_set():
    fail("no mission upload within 60 s")

result, plan = received[0]
if result != MissionRawServerResult.SUCCESS:
    fail(f"the upload ended with {result!r}")
for it in plan.mission_items:
    print(
        "item",
        json.dumps(
            {
                "seq": it.seq,
                "frame": it.frame,
                "command": it.command,
                "autocontinue": it.autocontinue,
                "param1": it.param1,
                "param2": it.param2,
                "param3": it.param3,
                "param4": None if it.param4 != it.param4 else it.param4,  # NaN → null
                "x": it.x,
                "y": it.y,
                "z": it.z,
                "mission_type": it.mission_type,
            }
        ),
        flush=True,
    )
items = plan.mission_items
print("received", len(items), "items", flush=True)
# Let MAVSDK's MISSION_ACK go out before checking and tearing down.
time.sleep(0.5)
mavsdk.destroy()

with open(plan_path) as f:
    wps = json.load(f)["waypoints_lla"]
n = len(wps)
NAV_WAYPOINT, NAV_LAND, NAV_TAKEOFF = 16, 21, 22
GLOBAL_RELATIVE_ALT_INT = 6


def check(cond, msg):
    if not cond:
        fail(msg)


def near_deg(e7, deg, what):
    check(abs(e7 * 1e-7 - deg) <= 1e-7, f"{what}: {e7} vs {deg}")


DO_CHANGE_SPEED, MISSION_FRAME = 178, 2
check([it.seq for it in items] == list(range(len(items))), "sequence numbers")
if samples_path:
    with open(samples_path) as f:
        header = f.readline().strip().split(",")
        check(header[4:6] == ["v_north", "v_east"], f"samples columns {header}")
        samples = [[float(v) for v in line.split(",")] for line in f if line.strip()]
    fastest = max(math.hypot(r[4], r[5]) for r in samples)
    speeds = items[2:-1:2]
    check(len(speeds) == n, f"{len(speeds)} DO_CHANGE_SPEED for {n} waypoints")
    for k, it in enumerate(speeds):
        check(it.command == DO_CHANGE_SPEED and it.frame == MISSION_FRAME, f"item {it.seq}: command {it.command} frame {it.frame}")
        check(it.param1 == 1 and it.param3 == -1, f"item {it.seq}: speed type {it.param1}, throttle {it.param3}")
        check(0.5 <= it.param2 <= fastest + 1e-4, f"leg {k + 1}: speed {it.param2} m/s, the trajectory at most {fastest}")
    check(max(it.param2 for it in speeds) >= fastest - 0.15, f"fastest leg {max(it.param2 for it in speeds)} vs {fastest}")
    for it in items[3:-1:2]:
        check(0.5 <= it.param2 <= 2.5, f"item {it.seq}: acceptance radius {it.param2}")
    print(f"checked {n} DO_CHANGE_SPEED items ({min(it.param2 for it in speeds):.1f}..{max(it.param2 for it in speeds):.1f} m/s, the trajectory at most {fastest:.2f} m/s)", flush=True)
    items = items[:2] + items[3:-1:2] + items[-1:]
check(len(items) == n + 3, f"{len(items)} items for {n} waypoints (expected home + takeoff + {n} + land)")
check(all(it.frame == GLOBAL_RELATIVE_ALT_INT for it in items), f"frames {[it.frame for it in items]}")
check(all(it.autocontinue == 1 for it in items), "autocontinue")
check(all(it.mission_type == 0 for it in items), "mission_type MISSION")
commands = [it.command for it in items]
check(commands == [NAV_WAYPOINT, NAV_TAKEOFF] + [NAV_WAYPOINT] * n + [NAV_LAND], f"commands {commands}")
near_deg(items[0].x, home_lat, "home latitude")
near_deg(items[0].y, home_lon, "home longitude")
check(abs(items[1].z - wps[0]["alt_m"]) < 1e-4, f"takeoff altitude {items[1].z}")
# The plan's headings are from the map's grid north (UTM); the items' yaw from true north. The
# convergence between them is the true bearing of the plan's first-to-last line minus its grid
# bearing (0.37 deg at the FCND home).
with open(plan_path) as f:
    rows = json.load(f)["waypoints"]
first, last = wps[0], wps[-1]
mid_lat = math.radians((first["lat_deg"] + last["lat_deg"]) / 2)
# WGS84 radii of curvature: metres per radian north (meridian) and east (prime vertical).
a, e2 = 6378137.0, 6.69437999014e-3
w = 1 - e2 * math.sin(mid_lat) ** 2
m_north, m_east = a * (1 - e2) / w**1.5, a / w**0.5 * math.cos(mid_lat)
true_bearing = math.degrees(math.atan2((last["lon_deg"] - first["lon_deg"]) * m_east, (last["lat_deg"] - first["lat_deg"]) * m_north))
grid_bearing = math.degrees(math.atan2(rows[-1][1] - rows[0][1], rows[-1][0] - rows[0][0]))
convergence = true_bearing - grid_bearing
check(0.2 < convergence < 0.6, f"grid convergence {convergence} deg")
for k, (it, w) in enumerate(zip(items[2:-1], wps)):
    near_deg(it.x, w["lat_deg"], f"waypoint {k + 1} latitude")
    near_deg(it.y, w["lon_deg"], f"waypoint {k + 1} longitude")
    check(abs(it.z - w["alt_m"]) < 1e-4, f"waypoint {k + 1} altitude {it.z} vs {w['alt_m']}")
    want = (w["heading_deg"] + convergence) % 360.0
    diff = abs((it.param4 - want + 180.0) % 360.0 - 180.0)
    check(not math.isnan(it.param4) and diff < 0.01, f"waypoint {k + 1} yaw {it.param4} vs {want}")
land = items[-1]
near_deg(land.x, wps[-1]["lat_deg"], "land latitude")
near_deg(land.y, wps[-1]["lon_deg"], "land longitude")
print(f"checked home, takeoff to {items[1].z} m, {n} waypoints (lat/lon within 1e-7 deg, altitude, yaw), land", flush=True)
print("OK", flush=True)

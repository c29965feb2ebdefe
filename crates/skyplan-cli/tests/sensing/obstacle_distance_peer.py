"""An independent MAVLink client (pymavlink) reads `skyplan sim`'s OBSTACLE_DISTANCE.

Usage: python3 obstacle_distance_peer.py tcp:127.0.0.1:PORT EXPECTED_CM EAST_SECTOR
The simulator runs on an empty map with one hidden box whose west face is EXPECTED_CM / 100 m
due east of the home. Checks the message as common.xml defines it, the sector facing the box and
the opposite (west) half, which must read "no obstacle" (max_distance + 1).
Prints one line per check and exits 0 only if all pass.
"""
import os
import sys
import time

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil  # noqa: E402


def fail(msg):
    print("FAIL", msg, flush=True)
    sys.exit(1)


address, expected_cm, east = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
conn = mavutil.mavlink_connection(address, source_system=250, source_component=190)
if conn.wait_heartbeat(timeout=10) is None:
    fail("no heartbeat")
m = None
deadline = time.time() + 20
stamps = []
while time.time() < deadline and len(stamps) < 20:
    conn.mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_GCS, mavutil.mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)
    got = conn.recv_match(type="OBSTACLE_DISTANCE", blocking=True, timeout=1.0)
    if got is not None:
        m = got
        stamps.append(got.time_usec)
if m is None:
    fail("no OBSTACLE_DISTANCE within 20 s")
print("OBSTACLE_DISTANCE received", len(stamps), "times", flush=True)
if len(m.distances) != 72:
    fail(f"{len(m.distances)} distances")
if m.frame != mavutil.mavlink.MAV_FRAME_LOCAL_NED:
    fail(f"frame {m.frame}, expected MAV_FRAME_LOCAL_NED")
if m.increment != 5 or abs(m.increment_f - 5.0) > 1e-6 or m.angle_offset != 0.0:
    fail(f"increment {m.increment}, increment_f {m.increment_f}, angle_offset {m.angle_offset}")
if (m.min_distance, m.max_distance) != (20, 3000):
    fail(f"min/max distance {m.min_distance}/{m.max_distance} cm")
print("frame LOCAL_NED, 72 sectors of 5 degrees, 20..3000 cm", flush=True)
# Vehicle time between sweeps: at most 0.1 s (>= 10 Hz).
gaps = [b - a for a, b in zip(stamps, stamps[1:])]
if not gaps or max(gaps) > 100_000 + 1_000:
    fail(f"sweeps {gaps} us apart")
print("sweeps every", max(gaps), "us of vehicle time", flush=True)
d = m.distances[east]
if abs(d - expected_cm) > 3:
    fail(f"sector {east} (east) reads {d} cm, expected {expected_cm}")
print(f"east sector reads {d} cm (expected {expected_cm})", flush=True)
west = [m.distances[i] for i in range(east + 19, east + 54)]
if any(x != m.max_distance + 1 for x in west):
    fail(f"the western sectors read {west}")
print("western half reads no obstacle (max_distance + 1)", flush=True)
print("OK", flush=True)

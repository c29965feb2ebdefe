"""An independent vehicle (pymavlink) that `skyplan fly --fence` uploads its fence to.

Usage: python3 pymavlink_fence_vehicle.py PORT LAT LON accept|refuse

Listens on udpin:127.0.0.1:PORT; behaves like ArduCopter where `fly` needs it (heartbeat,
positions, command acks, PARAM_VALUE echoes, the mission upload). The fence (mission_type 1):
  accept: requests every item, stores it, acks MAV_MISSION_ACCEPTED, and answers the read-back
          (MISSION_REQUEST_LIST -> MISSION_COUNT -> MISSION_REQUEST_INT -> MISSION_ITEM_INT);
  refuse: answers the fence's MISSION_COUNT with MISSION_ACK MAV_MISSION_UNSUPPORTED.
Prints one JSON line per fence item received ("item {...}") as pymavlink decoded it, a line per
protocol step, "armed requested" if an arm command ever arrives, and "OK" when it ends as
expected. Any message of the fence exchange without mission_type 1 is a failure.
"""
import json
import os
import sys
import time

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil  # noqa: E402

port, lat, lon, mode = int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
m = mavutil.mavlink
conn = mavutil.mavlink_connection(f"udpin:127.0.0.1:{port}", source_system=1, source_component=1)
print("listening", flush=True)

FENCE = m.MAV_MISSION_TYPE_FENCE
fence_count = None
fence_items = []
stored = []
mission_count = None
mission_got = 0
armed_requested = False
readback_acked = False
refused_at = None
mission_done_at = None
last_hb = 0.0
last_stream = 0.0
t0 = time.time()
deadline = t0 + 60


def fail(msg):
    print("FAIL", msg, flush=True)
    sys.exit(1)


def send(msg):
    conn.mav.send(msg)


while time.time() < deadline:
    now = time.time()
    # Once a ground station has been heard (pymavlink answers the addresses it heard from).
    if getattr(conn, "clients", None) or getattr(conn, "last_address", None) is not None:
        if now - last_hb >= 0.5:
            last_hb = now
            conn.mav.heartbeat_send(m.MAV_TYPE_QUADROTOR, m.MAV_AUTOPILOT_ARDUPILOTMEGA,
                                    m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 0, m.MAV_STATE_STANDBY)
        if now - last_stream >= 0.1:
            last_stream = now
            tb = int((now - t0) * 1000)
            conn.mav.global_position_int_send(tb, int(round(lat * 1e7)), int(round(lon * 1e7)), 0, 0, 0, 0, 0, 0)
            conn.mav.local_position_ned_send(tb, 0, 0, 0, 0, 0, 0)
            conn.mav.attitude_send(tb, 0, 0, 0, 0, 0, 0)
            conn.mav.gps_global_origin_send(int(round(lat * 1e7)), int(round(lon * 1e7)), 0)
            conn.mav.extended_sys_state_send(m.MAV_VTOL_STATE_UNDEFINED, m.MAV_LANDED_STATE_ON_GROUND)
    if refused_at is not None and now - refused_at > 3.0:
        break
    if mission_done_at is not None and now - mission_done_at > 1.0:
        break
    msg = conn.recv_match(blocking=True, timeout=0.05)
    if msg is None:
        continue
    t = msg.get_type()
    src = msg.get_srcSystem()
    if t == "COMMAND_LONG":
        if msg.command == m.MAV_CMD_COMPONENT_ARM_DISARM and msg.param1 >= 0.5:
            armed_requested = True
            print("armed requested", flush=True)
        conn.mav.command_ack_send(msg.command, m.MAV_RESULT_ACCEPTED)
    elif t == "PARAM_SET":
        conn.mav.param_value_send(msg.param_id.encode(), msg.param_value, msg.param_type, 2, 0)
    elif t == "MISSION_COUNT" and msg.mission_type == FENCE:
        print(f"fence count {msg.count}", flush=True)
        if mode == "refuse":
            conn.mav.mission_ack_send(src, msg.get_srcComponent(), m.MAV_MISSION_UNSUPPORTED, FENCE)
            print("fence refused: MAV_MISSION_UNSUPPORTED", flush=True)
            refused_at = time.time()
        else:
            fence_count = msg.count
            fence_items = []
            conn.mav.mission_request_int_send(src, msg.get_srcComponent(), 0, FENCE)
    elif t == "MISSION_ITEM_INT" and fence_count is not None and len(fence_items) < fence_count:
        if msg.mission_type != FENCE:
            fail(f"a fence item with mission_type {msg.mission_type}")
        if msg.seq != len(fence_items):
            conn.mav.mission_request_int_send(src, msg.get_srcComponent(), len(fence_items), FENCE)
            continue
        item = {"seq": msg.seq, "command": msg.command, "frame": msg.frame, "param1": msg.param1,
                "x": msg.x, "y": msg.y, "mission_type": msg.mission_type}
        fence_items.append(item)
        print("item " + json.dumps(item), flush=True)
        if len(fence_items) < fence_count:
            conn.mav.mission_request_int_send(src, msg.get_srcComponent(), len(fence_items), FENCE)
        else:
            stored = list(fence_items)
            fence_count = None
            conn.mav.mission_ack_send(src, msg.get_srcComponent(), m.MAV_MISSION_ACCEPTED, FENCE)
            print(f"fence stored: {len(stored)} items", flush=True)
    elif t == "MISSION_REQUEST_LIST":
        if msg.mission_type != FENCE:
            fail(f"MISSION_REQUEST_LIST with mission_type {msg.mission_type}")
        print("read-back requested", flush=True)
        conn.mav.mission_count_send(src, msg.get_srcComponent(), len(stored), FENCE)
    elif t in ("MISSION_REQUEST_INT", "MISSION_REQUEST") and src != 1:
        if msg.mission_type != FENCE:
            fail(f"{t} with mission_type {msg.mission_type}")
        it = stored[msg.seq]
        conn.mav.mission_item_int_send(src, msg.get_srcComponent(), it["seq"], it["frame"], it["command"],
                                       0, 1, it["param1"], 0, 0, 0, it["x"], it["y"], 0, FENCE)
    elif t == "MISSION_ACK" and src != 1:
        if msg.mission_type != FENCE:
            fail(f"MISSION_ACK with mission_type {msg.mission_type}")
        readback_acked = msg.type == m.MAV_MISSION_ACCEPTED
        print(f"read-back acknowledged: {readback_acked}", flush=True)
    elif t == "MISSION_COUNT":
        mission_count, mission_got = msg.count, 0
        conn.mav.mission_request_int_send(src, msg.get_srcComponent(), 0, 0)
    elif t == "MISSION_ITEM_INT" and mission_count is not None:
        if msg.seq == mission_got:
            mission_got += 1
        if mission_got < mission_count:
            conn.mav.mission_request_int_send(src, msg.get_srcComponent(), mission_got, 0)
        else:
            conn.mav.mission_ack_send(src, msg.get_srcComponent(), m.MAV_MISSION_ACCEPTED, 0)
            print(f"mission of {mission_count} items accepted", flush=True)
            mission_count = None
            mission_done_at = time.time()

if mode == "refuse":
    if refused_at is None:
        fail("no fence upload arrived")
    if armed_requested:
        fail("the vehicle was asked to arm after refusing the fence")
    print("no arming after the refusal", flush=True)
else:
    if not stored:
        fail("no fence stored")
    if not readback_acked:
        fail("the read-back was not closed with MISSION_ACK")
    if mission_done_at is None:
        fail("no mission upload after the fence")
print("OK", flush=True)

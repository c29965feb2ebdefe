"""Writes the seed corpora of fuzz/corpus/<target>/ from the repository's real files and
MAVLink frames encoded by pymavlink (an independent implementation). Run from fuzz/:
    $SKYPLAN_PYTHON seeds/make_seeds.py
"""
import os, struct, zlib

from pymavlink.dialects.v20 import common as mav

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
CORPUS = os.path.join(os.path.dirname(__file__), "..", "corpus")


def put(target, name, data):
    d = os.path.join(CORPUS, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def read(path):
    with open(os.path.join(ROOT, path), "rb") as f:
        return f.read()


# colliders: the FCND map's head (home line, header, boxes), a box with an overflowing position.
city = read("data/colliders.csv").split(b"\n")
put("colliders", "city_head", b"\n".join(city[:40]) + b"\n")
put("colliders", "city_small", b"\n".join(city[:6]) + b"\n")
put("colliders", "huge_pos", b"\n".join(city[:2]) + b"\n1e308,0,10,5,5,5\n")

# movingai: first byte even = map, odd = scen.
put("movingai", "den312d_map", b"\x00" + read("data/movingai/den312d.map"))
put("movingai", "tiny_map", b"\x00type octile\nheight 3\nwidth 4\nmap\n..@.\n.T..\n....\n")
scen = read("data/movingai/den312d.map.scen").split(b"\n")
put("movingai", "den312d_scen", b"\x01" + b"\n".join(scen[:12]) + b"\n")

# imagemap: u16 LE yaml length, yaml, image.
def pgm(rows):
    body = "\n".join(" ".join("0" if c == "#" else "255" for c in r) for r in rows)
    return f"P2\n{len(rows[0])} {len(rows)}\n255\n{body}\n".encode()

def framed(yaml, image):
    return struct.pack("<H", len(yaml)) + yaml + image

yaml = b"image: u.pgm\nresolution: 2.0\norigin: [100.0, 50.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
u = pgm(["......", ".#..#.", ".#..#.", ".####.", "......"])
put("imagemap", "u_pgm_yaml", framed(yaml, u))
put("imagemap", "blocks160_png", framed(b"", read("data/blocks160.png")))
p5 = b"P5\n4 3\n255\n" + bytes([0, 255, 255, 0, 255, 0, 255, 255, 205, 205, 0, 255])
put("imagemap", "p5_trinary", framed(b"image: m.pgm\nresolution: 0.5\norigin: [0, 0, 0]\nmode: trinary\n", p5))

def png(width, height, color_type, bit_depth, raw):
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    ihdr = struct.pack(">IIBBBBB", width, height, bit_depth, color_type, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")

rgba = b"".join(b"\x00" + bytes([255, 255, 255, 255, 0, 0, 0, 128]) for _ in range(2))
put("imagemap", "rgba_2x2", framed(b"", png(2, 2, 6, 8, rgba)))
put("imagemap", "huge_header", framed(b"", png(20000, 20000, 0, 8, b"")))

# plan_request: first byte even = TOML config, odd = JSON body.
put("plan_request", "fcnd_toml", b"\x00target_altitude = 10.0\nsafety_distance = 3.0\ngoal_ne = [9.5, 0.5]\nmethod = \"dijkstra\"\nout = \"cfg.csv\"\n")
put("plan_request", "toml_3d", b"\x00planner = \"rrt-connect\"\nalt_m = 5\nmax_alt_m = 30\ntime_limit_ms = 5\nseed = 3\n")
put("plan_request", "json_jps", b'\x01{"planner": "jps-plus", "goal_ne": [10, 12], "alt_m": 10}')
put("plan_request", "json_costmap", b'\x01{"planner": "costmap", "inflation_radius_m": 3, "cost_weight": 2, "geometry": true}')
put("plan_request", "json_voxel", b'\x01{"planner": "voxel", "voxel_m": 2, "layer_m": 2, "climb_weight": 1}')

# MAVLink: odd first byte = raw stream of frames encoded by pymavlink; even = records.
def frames(msgs, sysid=1, compid=1):
    m = mav.MAVLink(None, srcSystem=sysid, srcComponent=compid)
    return b"".join(x.pack(m) for x in msgs)

to_ground = [
    mav.MAVLink_heartbeat_message(2, 3, 217, 4, 4, 3),
    mav.MAVLink_gps_global_origin_message(377924800, -1223974500, 0, 0),
    mav.MAVLink_global_position_int_message(1000, 377924800, -1223974500, 5000, 5000, 10, 0, 0, 0),
    mav.MAVLink_attitude_message(1000, 0.0, 0.0, 0.3, 0.0, 0.0, 0.0),
    mav.MAVLink_extended_sys_state_message(0, 1),
    mav.MAVLink_command_ack_message(400, 0),
    mav.MAVLink_statustext_message(4, b"PreArm: waiting"),
    mav.MAVLink_mission_item_reached_message(1),
    mav.MAVLink_mission_current_message(1),
]
raw = frames(to_ground)
put("mavlink_ground", "pymavlink_frames", b"\x01" + raw)
put("mavlink_ground", "truncated", b"\x01" + raw[: len(raw) // 2 + 3])
put("mavlink_ground", "other_sysid", b"\x01" + frames(to_ground[:3], sysid=7) + frames(to_ground))

to_vehicle = [
    mav.MAVLink_heartbeat_message(6, 8, 0, 0, 4, 3),
    mav.MAVLink_command_long_message(1, 1, 511, 0, 33, 100000, 0, 0, 0, 0, 0),
    mav.MAVLink_command_long_message(1, 1, 176, 0, 1, 4, 0, 0, 0, 0, 0),
    mav.MAVLink_command_long_message(1, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0),
    mav.MAVLink_command_long_message(1, 1, 22, 0, 0, 0, 0, 0, 0, 0, 10),
    mav.MAVLink_set_position_target_global_int_message(0, 1, 1, 6, 0x0DF8, 377925000, -1223974000, 10, 0, 0, 0, 0, 0, 0, 0, 0),
    mav.MAVLink_mission_count_message(1, 1, 2, 0),
    mav.MAVLink_mission_item_int_message(1, 1, 0, 6, 16, 0, 1, 0, 0, 0, 0, 377925000, -1223974000, 10, 0),
    mav.MAVLink_mission_item_int_message(1, 1, 1, 6, 21, 0, 1, 0, 0, 0, 0, 377925000, -1223974000, 0, 0),
    mav.MAVLink_request_data_stream_message(1, 1, 0, 10, 1),
]
raw = frames(to_vehicle, sysid=255, compid=190)
put("mavlink_sim", "pymavlink_frames", b"\x01" + raw)
put("mavlink_sim", "truncated", b"\x01" + raw[: len(raw) // 2 + 5])
# Records: [system id][choice][dt][len][payload]: payloads of pymavlink's messages, unframed.
def records(msgs, ids, sysid):
    out = b""
    m = mav.MAVLink(None, srcSystem=sysid, srcComponent=1)
    for x in msgs:
        x.pack(m)
        payload = x.get_payload()
        out += bytes([sysid, ids.index(x.id), 10, len(payload)]) + payload
    return out
ground_ids = [0, 33, 32, 30, 49, 245, 77, 46, 42, 253, 51, 40, 47]
vehicle_ids = [0, 76, 75, 11, 66, 86, 84, 44, 73, 39, 45, 43]
put("mavlink_ground", "records", b"\x00" + records(to_ground, ground_ids, 1))
put("mavlink_sim", "records", b"\x00" + records(to_vehicle, vehicle_ids, 255))
print("seeds written")

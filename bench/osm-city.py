"""A big OpenStreetMap extract for read-time benchmarks: the bundled Helsinki buildings copied
K x K times side by side (ids offset, coordinates shifted), as .osm.pbf. Needs osmium-tool
(apt install osmium-tool) for the XML <-> PBF conversions.

    python3 bench/osm-city.py 15 /tmp/city-100k.osm.pbf   # 15 x 15 copies: 100,350 buildings

Then, for example (docs/BENCHMARKS.md, "OpenStreetMap at city scale"):

    /usr/bin/time -f "%e s, %M KB" skyplan plan --map /tmp/city-100k.osm.pbf --cell-m 20 --goal-ne 9000,9000
"""
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET


def attr(v):
    return v.replace("&", "&amp;").replace('"', "&quot;").replace("<", "&lt;")


def write_element(f, kind, e, off):
    """A way or relation with its ids (and its nodes' or members' ids) offset by `off`."""
    f.write(f'<{kind} id="{int(e.get("id")) + off}" version="1">')
    for ch in e:
        if ch.tag == "nd":
            f.write(f'<nd ref="{int(ch.get("ref")) + off}"/>')
        elif ch.tag == "member":
            f.write(f'<member type="{ch.get("type")}" ref="{int(ch.get("ref")) + off}" '
                    f'role="{attr(ch.get("role"))}"/>')
        elif ch.tag == "tag":
            f.write(f'<tag k="{attr(ch.get("k"))}" v="{attr(ch.get("v"))}"/>')
    f.write(f"</{kind}>\n")


k = int(sys.argv[1])
out = sys.argv[2]
here = os.path.dirname(os.path.abspath(__file__))
src = os.path.join(here, "..", "data", "osm", "helsinki-buildings.osm.pbf")
with tempfile.TemporaryDirectory() as tmp:
    xml_in = os.path.join(tmp, "in.osm")
    subprocess.run(["osmium", "cat", "-o", xml_in, "-f", "osm", src], check=True)
    root = ET.parse(xml_in).getroot()
    nodes = [n for n in root if n.tag == "node"]
    ways = [w for w in root if w.tag == "way"]
    rels = [r for r in root if r.tag == "relation"]
    lats = [float(n.get("lat")) for n in nodes]
    lons = [float(n.get("lon")) for n in nodes]
    dlat, dlon = max(lats) - min(lats), max(lons) - min(lons)
    step = 10 ** len(str(max(int(e.get("id")) for e in root if e.get("id"))))
    xml_out = os.path.join(tmp, "out.osm")
    with open(xml_out, "w") as f:
        f.write('<?xml version="1.0" encoding="UTF-8"?>\n<osm version="0.6" generator="skyplan bench">\n')
        copies = [(i, j) for i in range(k) for j in range(k)]
        for c, (i, j) in enumerate(copies):
            off = c * step
            for n in nodes:
                lat = float(n.get("lat")) + i * dlat
                lon = float(n.get("lon")) + j * dlon
                f.write(f'<node id="{int(n.get("id")) + off}" version="1" lat="{lat:.7f}" lon="{lon:.7f}"/>\n')
        for kind, elements in (("way", ways), ("relation", rels)):
            for c, _ in enumerate(copies):
                for e in elements:
                    write_element(f, kind, e, c * step)
        f.write("</osm>\n")
    subprocess.run(["osmium", "sort", "--overwrite", "-o", out, xml_out], check=True)
print(f"{out}: {k} x {k} copies of {len(ways)} ways and {len(rels)} relations, "
      f"{k * dlat:.4f} deg x {k * dlon:.4f} deg")

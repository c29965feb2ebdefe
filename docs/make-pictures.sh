#!/usr/bin/env bash
# Regenerates the pictures of README.md and docs/*.md from the bundled data, with the release
# binary (built first if missing): docs/plan.png, plan3d.png, voronoi.png, heatmap.png,
# trajectory.png, terrain.png, helsinki.png, flight.png.
# The server's screenshots (docs/serve.png, serve-flight.png) come from its browser test:
#   SKYPLAN_PYTHON=.ci-venv/bin/python SKYPLAN_SCREENSHOT=1 bash crates/skyplan-server/ci.sh
# Usage, from anywhere in the clone: bash docs/make-pictures.sh   (about 10 s once built)
set -euo pipefail
cd "$(dirname "$0")/.."
# The binary: $SKYPLAN if set, else the clone's release build (built first if missing).
skyplan=${SKYPLAN:-${CARGO_TARGET_DIR:-target}/release/skyplan}
[ -x "$skyplan" ] || cargo build --release
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# The README's first command: the default route on the city map.
"$skyplan" plan --out "$tmp/w.json" --plot docs/plan.png
# docs/PLANNING.md: voxel A* onto a 60 m roof; the Voronoi roadmap; navigate on a cost map.
"$skyplan" plan --planner voxel --goal-ne 200,330 --goal-alt-m 66 --out "$tmp/w.json" --plot docs/plan3d.png
"$skyplan" plan --planner voronoi --goal-ne 420,390 --out "$tmp/w.json" --plot docs/voronoi.png
"$skyplan" navigate --map data/blocks160.png --resolution 1 --start-ne 2.5,2.5 --targets "157.5,157.5" \
    --change-target-at "120:100.5,150.5" --inflation-radius-m 6 --plot docs/heatmap.png
# docs/PLANNING.md: the default route's trajectory, coloured by speed, with speed and acceleration.
"$skyplan" plan --trajectory --out "$tmp/w.json" --plot docs/trajectory.png
# README: a route 30 m above the hills of a real DEM (contours in the top view), with its side profile.
"$skyplan" plan --random 3000x3000 --density 0.0002 --home 36.56,-84.28 --terrain data/terrain/jacksboro.tif \
    --alt-agl-m 30 --start-ne 100,100 --goal-ne 2900,2800 --out "$tmp/w.json" --plot docs/terrain.png
# README: OpenStreetMap buildings as their polygons (courtyards open), each ringed by the margin.
"$skyplan" plan --map data/osm/helsinki-buildings.osm.pbf --goal-ne 500,250 --out "$tmp/w.json" --plot docs/helsinki.png
# docs/FLYING.md: a flight around three seeded buildings the map does not have.
"$skyplan" fly --sim --speedup 50 --hidden-random 3 --seed 1 --plot docs/flight.png
echo "pictures written: docs/plan.png docs/plan3d.png docs/voronoi.png docs/heatmap.png docs/trajectory.png docs/terrain.png docs/helsinki.png docs/flight.png"

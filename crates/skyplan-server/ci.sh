#!/usr/bin/env bash
# skyplan serve, end to end: the page in a real browser (Debian's chromium driven by
# playwright-core) planning on clicks and following a flight, schemathesis against
# /api/openapi.json, MCAP recordings read back in Python, and a load test on loopback.
#
#   SKYPLAN_PYTHON=.ci-venv/bin/python bash crates/skyplan-server/ci.sh
#
# Needs the release binary (target/release/skyplan; built here if missing), Node with npm, and
# $SKYPLAN_PYTHON, the python of a virtual environment (schemathesis and mcap go into it). Installs
# chromium with apt when missing and playwright-core into browser/node_modules (git-ignored).
# Leaves the work tree as it found it: the screenshot goes to a temporary folder unless
# SKYPLAN_SCREENSHOT=1, which writes docs/serve.png and docs/serve-flight.png.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
bin="${SKYPLAN_BIN:-$root/target/release/skyplan}"
py="${SKYPLAN_PYTHON:?set SKYPLAN_PYTHON to the python of a virtual environment}"
step() { printf '\n== %s ==\n' "$*"; }
tmp="$(mktemp -d)"
server_pid=""
cleanup() {
  if [ -n "$server_pid" ]; then kill "$server_pid" 2>/dev/null || true; fi
  rm -rf "$tmp"
}
trap cleanup EXIT

if [ ! -x "$bin" ]; then
  step "building the release binary"
  (cd "$root" && cargo build --release -p skyplan-cli --quiet)
fi
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
  apt-get update -qq && apt-get install -y -qq nodejs npm >/dev/null
fi
chromium_bin="${CHROMIUM:-$(command -v chromium || true)}"
if [ -z "$chromium_bin" ]; then
  apt-get update -qq && apt-get install -y -qq chromium >/dev/null
  chromium_bin="$(command -v chromium)"
fi
export CHROMIUM="$chromium_bin"

step "serve: the page in chromium ($("$chromium_bin" --version 2>/dev/null | head -n 1))"
(cd "$here/browser" && npm ci --no-audit --no-fund --silent)
shot="$tmp/serve.png"
if [ "${SKYPLAN_SCREENSHOT:-0}" = 1 ]; then shot="$root/docs/serve.png"; fi
node "$here/browser/page.test.mjs" "$bin" "$shot"

step "serve: real maps on the page (a DEM's contours, GeoJSON footprints)"
node "$here/browser/real_map.test.mjs" "$bin"

step "serve: the shared airspace on the page (intents by /api/events, the time slider)"
node "$here/browser/intents.test.mjs" "$bin"

step "serve: a flight on the page (the view_flight example: what fly --view publishes)"
(cd "$root" && cargo build -p skyplan-server --example view_flight --quiet)
flight_shot="$tmp/view-flight.png"
node "$here/browser/flight.test.mjs" "$root/target/debug/examples/view_flight" "$flight_shot"

step "serve: skyplan fly --sim --view, live on the page until the vehicle is back in MANUAL"
fly_shot="$tmp/serve-flight.png"
if [ "${SKYPLAN_SCREENSHOT:-0}" = 1 ]; then fly_shot="$root/docs/serve-flight.png"; fi
SKYPLAN_BIN="$bin" node "$here/browser/flight.test.mjs" "$here/browser/fly_sim.sh" "$fly_shot"

step "serve: skyplan sim --view: the simulator's vehicle and its sensed obstacle points on the page"
node "$here/browser/sim_view.test.mjs" "$bin"

step "serve: schemathesis against /api/openapi.json"
"$py" -m pip install --quiet --disable-pip-version-check schemathesis
st="$(dirname "$py")/schemathesis"
port="$("$py" -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')"
"$bin" serve --bind "127.0.0.1:$port" >"$tmp/serve.log" &
server_pid=$!
"$py" - "$port" <<'PY'
import sys, time, urllib.request
for _ in range(200):
    try:
        urllib.request.urlopen(f"http://127.0.0.1:{sys.argv[1]}/api/planners", timeout=1).read()
        break
    except OSError:
        time.sleep(0.1)
else:
    sys.exit("skyplan serve did not answer in 20 s")
PY
# The event stream never ends: it is tested in the browser and the Rust tests instead.
(cd "$tmp" && "$st" run "http://127.0.0.1:$port/api/openapi.json" \
  --checks not_a_server_error,status_code_conformance,content_type_conformance,response_schema_conformance \
  --exclude-path /api/events --max-examples "${SKYPLAN_SCHEMATHESIS_EXAMPLES:-100}" --seed 1 \
  --workers 1 --request-timeout 30 --generation-database none --no-color)
kill "$server_pid"
wait "$server_pid" 2>/dev/null || true
server_pid=""

step "serve: MCAP recordings read back with the Python mcap package"
"$py" -m pip install --quiet --disable-pip-version-check mcap
(cd "$root" && SKYPLAN_PYTHON="$py" cargo test -p skyplan-server --test record --quiet -- --include-ignored)

step "serve: load test, 200 concurrent plans on loopback"
node "$here/browser/load.mjs" "$bin" 200
echo "serve checks passed"

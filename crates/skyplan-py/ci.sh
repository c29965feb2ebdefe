#!/usr/bin/env bash
# CI for the Python package: builds the abi3 wheel of ./crates/skyplan-py with maturin, installs
# it into an existing virtual environment, and runs its pytest suite (FCND drop-ins against
# FCND's own algorithms, astar_path against pyastar2d, Planner.plan against the release CLI,
# threads, bad input).
#
#   SKYPLAN_PYTHON=/path/to/venv/bin/python bash crates/skyplan-py/ci.sh
#
# Works from a fresh clone; everything it builds goes under target/ (git-ignored) and the pip
# cache; it leaves no files in the work tree.
set -euo pipefail
cd "$(dirname "$0")/../.."
: "${SKYPLAN_PYTHON:?set SKYPLAN_PYTHON to the python of a virtual environment}"
py() { "$SKYPLAN_PYTHON" "$@"; }
pip() { py -m pip --disable-pip-version-check "$@"; }

pip install --quiet maturin pytest numpy mypy
# pyastar2d is the peer astar_path is compared with; if it cannot be installed here, those two
# tests are reported as skipped (the Dijkstra comparison still runs).
pip install --quiet pyastar2d || echo "pyastar2d did not install: its comparison will be skipped"

# The release CLI that Planner.plan is compared with (in cargo's target directory, wherever
# CARGO_TARGET_DIR puts it).
cargo build --release --quiet -p skyplan-cli
target=$(cargo metadata --format-version 1 --no-deps | py -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')

# The wheel, built by maturin through pip (PEP 517), as a user installs it.
pip install --quiet --force-reinstall --no-deps ./crates/skyplan-py
py -c "import skyplan; print('skyplan', skyplan.__version__, 'from', skyplan.__file__)"
# The type stubs match the module (mypy's cache under target/, git-ignored).
MYPY_CACHE_DIR="$target/mypy_cache" py -m mypy.stubtest skyplan

cd crates/skyplan-py
PYTHONDONTWRITEBYTECODE=1 SKYPLAN_CLI="$target/release/skyplan" \
  py -m pytest -p no:cacheprovider -q -rs tests

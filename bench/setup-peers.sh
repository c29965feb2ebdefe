#!/usr/bin/env bash
# Sets up the Python peers of `skyplan bench --peers` in bench/.venv (numpy, pyastar2d, pathfinding)
# and of `skyplan bench --3d --peers` (ompl: OMPL 2.x Python wheels, benchmark-only).
# `skyplan bench --peers` finds bench/.venv/bin/python from the repository root, or the Python
# named by SKYPLAN_PYTHON.
set -euo pipefail
cd "$(dirname "$0")"
python3 -m venv .venv
.venv/bin/pip install --quiet --disable-pip-version-check numpy pyastar2d pathfinding ompl toppra ruckig
.venv/bin/python -c "import numpy, pyastar2d, pathfinding, ompl; print('peers ready: numpy', numpy.__version__)"

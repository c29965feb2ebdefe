#!/usr/bin/env bash
# CI for the Python package: builds the abi3 wheel of ./crates/skyplan-py with maturin, installs
# it into an existing virtual environment, and runs its pytest suite (FCND drop-ins against
# FCND's own algorithms, astar_path against pyastar2d, Planner.plan against the release CLI,
# every planner of the registry, threads, bad input), then pyastar2d's own test suite (from its
# sdist on PyPI) with `import pyastar2d` resolved to skyplan.
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

# The pyastar2d release astar_path is compared with, and whose test suite it passes.
PYASTAR2D=1.1.4

pip install --quiet maturin pytest numpy mypy
# pyastar2d is the peer astar_path is compared with; if it cannot be installed here, those
# tests are reported as skipped (the Dijkstra comparisons still run).
pip install --quiet "pyastar2d==$PYASTAR2D" || echo "pyastar2d did not install: its comparison will be skipped"

# The release CLI that Planner.plan is compared with (in cargo's target directory, wherever
# CARGO_TARGET_DIR puts it).
cargo build --release --quiet -p skyplan-cli
target=$(cargo metadata --format-version 1 --no-deps | py -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')

# The wheel, built by maturin through pip (PEP 517), as a user installs it.
pip install --quiet --force-reinstall --no-deps ./crates/skyplan-py
py -c "import skyplan; print('skyplan', skyplan.__version__, 'from', skyplan.__file__)"
# The type stubs match the module (run from target/: mypy writes its cache there, git-ignored).
(cd "$target" && MYPY_CACHE_DIR="$target/mypy_cache" py -m mypy.stubtest skyplan)

# pyastar2d's own tests/test_astar.py, from its sdist on PyPI (under target/, git-ignored).
suite="$target/pyastar2d-suite"
rm -rf "$suite"
pip download --quiet --no-deps --no-binary pyastar2d "pyastar2d==$PYASTAR2D" -d "$suite"
py - "$suite" "$PYASTAR2D" <<'EOF'
import sys, tarfile
from pathlib import Path

suite, version = Path(sys.argv[1]), sys.argv[2]
with tarfile.open(suite / f"pyastar2d-{version}.tar.gz") as sdist:
    test = sdist.extractfile(f"pyastar2d-{version}/tests/test_astar.py")
    (suite / "test_astar.py").write_bytes(test.read())
EOF

cd crates/skyplan-py
PYTHONDONTWRITEBYTECODE=1 SKYPLAN_CLI="$target/release/skyplan" \
  py -m pytest -p no:cacheprovider -q -rs tests
# The suite with `import pyastar2d` resolved to skyplan (tests/pyastar2d_suite/pyastar2d); its
# plugin marks the tests skyplan deliberately fails as strict xfails, with the reason.
PYTHONDONTWRITEBYTECODE=1 PYTHONPATH="$PWD/tests/pyastar2d_suite" \
  py -m pytest -p no:cacheprovider -p skyplan_as_pyastar2d -q -rxXs \
  --rootdir "$suite" -c /dev/null "$suite/test_astar.py"

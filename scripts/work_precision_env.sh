#!/usr/bin/env bash
# The whole work-precision study from a fresh venv, with one command:
#
#     scripts/work_precision_env.sh [work_precision.py options, e.g. --repeats 3]
#
# Creates a venv (VENV, default a new temporary directory), installs the pinned packages
# (scripts/work_precision_requirements.txt), builds the release binary if it is missing,
# runs Drake's sanity test (scripts/test_drake_sanity.py), then the study in two processes
# side by side (the rover alone; the disk, the space robot and the sphere), and writes
# the figures and JSONs to docs/src/images, the tables to docs/src/work_precision_tables.md.
# Prints its wall time. Not run by .ci/run.
set -euo pipefail
cd "$(dirname "$0")/.."
t0=$(date +%s)
VENV=${VENV:-$(mktemp -d)/venv}
python3 -m venv "$VENV"
"$VENV/bin/pip" install --quiet --upgrade pip
"$VENV/bin/pip" install --quiet -r scripts/work_precision_requirements.txt
echo "venv $VENV ready after $(( $(date +%s) - t0 )) s"
[ -x target/release/anholonomy ] || cargo build --release --locked
"$VENV/bin/python" -m pytest -q scripts/test_drake_sanity.py
logs=$(mktemp -d)
"$VENV/bin/python" scripts/work_precision.py --systems rover "$@" > "$logs/rover.log" 2>&1 &
a=$!
"$VENV/bin/python" scripts/work_precision.py --systems disk,space,sphere "$@" > "$logs/others.log" 2>&1 &
b=$!
wait $a || { tail -30 "$logs/rover.log"; exit 1; }
wait $b || { tail -30 "$logs/others.log"; exit 1; }
grep -v -e '^WARNING' -e '^$' "$logs/others.log" "$logs/rover.log"
"$VENV/bin/python" scripts/work_precision.py --table > docs/src/work_precision_tables.md
echo "tables: docs/src/work_precision_tables.md; logs: $logs"
echo "wall time of the whole study: $(( $(date +%s) - t0 )) s"

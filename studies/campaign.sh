#!/usr/bin/env bash
# The paper's study campaign (issue 30), resumable: start it in the background first thing in a session,
#   setsid nohup studies/campaign.sh > ~/fvdem-runs/campaign.log 2>&1 < /dev/null &
# and before the session ends archive what finished into the repository:
#   .venv/bin/fvdem study ~/fvdem-runs/mema2020_stage1 --archive docs/data/mema2020_stage1
# Study folders live outside the work tree (~/fvdem-runs), so a new work tree loses nothing; finished
# runs are skipped, interrupted ones resume bit-for-bit from their checkpoints. Two runs at a time, one
# numba thread each (more threads than free cores stall OpenMP: docs/benchmarks.md).
set -u
cd "$(dirname "$0")/.."
[ -x .venv/bin/fvdem ] || make venv
OUT=${FVDEM_RUNS:-$HOME/fvdem-runs}
.venv/bin/fvdem study studies/mema2020_stage1.toml --out "$OUT/mema2020_stage1" --workers 2

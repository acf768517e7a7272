#!/usr/bin/env bash
# The paper's study campaign (issue 30), resumable: stage 2 (studies/mema2020_stage2.toml, the paper's 22
# runs, two replicas), after stage 1 (studies/mema2020_stage1.toml, why fvdem mixes slowly at 2 Umf). Start it
# in the background first thing in a session, from a clone of its own (a work tree being edited would
# change the code under a running campaign: the workers import it afresh whenever they restart):
#   git clone <repo> ~/fvdem-code && cd ~/fvdem-code        # once; later: git -C ~/fvdem-code pull
#   setsid nohup studies/campaign.sh > ~/fvdem-runs/campaign.log 2>&1 < /dev/null &
# (started twice, the second is refused: the study holds its folder's lock); where it stands, from anywhere:
#   .venv/bin/fvdem study ~/fvdem-runs/mema2020_stage2 --status
# and before the session ends archive what finished into the repository (from the work tree):
#   .venv/bin/fvdem study ~/fvdem-runs/mema2020_stage2 --archive docs/data/mema2020
# Study folders live outside the work tree (~/fvdem-runs), so a new work tree loses nothing; finished
# runs are skipped, interrupted ones resume bit-for-bit from their checkpoints (a run resumed by newer code
# says so in its run.log), and runs in progress go before runs not started. A machine handed back bare (the
# eighteenth session, 2026-12-03: ~/fvdem-runs was gone) loses only the runs in progress: the study starts
# with --restore from its archive, which copies the runs the archive holds at their end into the study
# folder (never over a run folder there), so that they are skipped and no bed settles again for them.
# Extra arguments go to fvdem study: after a setting of the study file changed, run it once as
# `studies/campaign.sh --supersede` (the runs of the old setting move to superseded/, nothing is deleted).
# The last hour of a session: a machine handed back bare loses the runs in progress (twice so far: the
# eighteenth and twenty-fifth sessions), so start it with the session's end less the half hour the archive takes,
# `studies/campaign.sh --until 04:40` (since the twenty-eighth session): a free worker then takes first the runs
# expected to end by then, and at 04:40 the running runs checkpoint and the study exits; archive what ended.
# (Before, the study was stopped by hand and started again with --only and the runs that end in that hour.)
# Two runs at a time, one numba thread each (more threads than free cores stall OpenMP: docs/benchmarks.md).
# Stage 1 (studies/mema2020_stage1.toml) runs beside it, one run at a time, while it has runs left (its ended
# runs come back from docs/data/mema2020_stage1 and are skipped; once all have ended it exits at once: every one
# had by 2026-12-04, twenty-fourth session, its last the 2.1 m column's AR-4 runs at 2.6-2.9 Umf). Where it
# stands: fvdem study ~/fvdem-runs/mema2020_stage1 --status; archive: --archive docs/data/mema2020_stage1.
# Timing anything else while it runs: pause the whole campaign (kill -STOP -- -<its process group>, then
# -CONT). Dask's scheduler restarts a worker that has not sent a heartbeat for its worker-ttl (default 5 min),
# killing its run back to the last checkpoint; that happened once after a series of pauses (2026-12-03), so
# the campaign's scheduler waits an hour: a local run that hangs still shows in its progress lines.
set -u
cd "$(dirname "$0")/.."
export DASK_DISTRIBUTED__SCHEDULER__WORKER_TTL="${DASK_DISTRIBUTED__SCHEDULER__WORKER_TTL:-1 hour}"
[ -x .venv/bin/fvdem ] || make venv
OUT=${FVDEM_RUNS:-$HOME/fvdem-runs}
.venv/bin/fvdem study studies/mema2020_stage1.toml --out "$OUT/mema2020_stage1" --workers 1 \
    --restore docs/data/mema2020_stage1 &
.venv/bin/fvdem study studies/mema2020_stage2.toml --out "$OUT/mema2020_stage2" --workers 2 \
    --restore docs/data/mema2020 "$@"
status=$?
wait
exit $status

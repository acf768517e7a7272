#!/usr/bin/env bash
# The bed-dynamics campaign (issue 66), resumable: two studies side by side, one run at a time each (the queue's two
# at a time once the contact study has ended), one numba thread a run (more threads than free cores stall OpenMP:
# docs/benchmarks.md):
#   - studies/contact_paper.toml: AR-1 and AR-4 MP at 2.0 Umf at the paper's contact stiffness and steps
#     (three replicas each; about 1.3 and 2.5 core-hours a run);
#   - studies/stochastic_bed.toml (issue 68: the stochastic drag force in the AR-1 bed, three runs of about 0.4
#     core-hours), then studies/screening_ar1.toml, studies/contact_candidates.toml (AR-1: two cheaper contact
#     settings against the paper's, three runs each of about 0.7 core-hours) and studies/screening_ar4.toml: the
#     designed screenings of the model choices (32 and 32 runs; about 0.27 and 1.4 core-hours a run).
# The paper's stage-2 study (studies/mema2020_stage2.toml) has ended: all 163 runs are in docs/data/mema2020.
# Start it in the background first thing, from a clone of its own (a work tree being edited would change the
# code under a running campaign: the workers import it afresh whenever they restart):
#   git clone <repo> ~/fvdem-code && cd ~/fvdem-code        # once; later: git -C ~/fvdem-code pull
#   setsid nohup studies/campaign.sh --until 07:05 > ~/fvdem-runs/campaign.log 2>&1 < /dev/null &
# (--until: the time the machine is yours until, less the half hour an archive takes; the running runs checkpoint then and
# the studies exit). Where each stands, from anywhere:
#   .venv/bin/fvdem study ~/fvdem-runs/screening_ar1 --status
# and before the machine goes, archive what ended into the repository (from the work tree):
#   .venv/bin/fvdem study ~/fvdem-runs/contact_paper --archive docs/data/contact_paper
#   .venv/bin/fvdem study ~/fvdem-runs/screening_ar1 --archive docs/data/screening_ar1
#   (and so for contact_candidates and screening_ar4 once they have begun)
# Study folders live outside the work tree (~/fvdem-runs). A machine handed back bare loses only the runs in
# progress: each study starts with --restore from its archive (the runs held there at their end are copied
# back and skipped). Extra arguments go to every `fvdem study` (e.g. --until, --supersede).
# Timing anything else while it runs: pause it (kill -STOP -- -<its process group>, then -CONT); the scheduler
# waits an hour for a silent worker, so a pause does not kill a run.
set -u
cd "$(dirname "$0")/.."
export DASK_DISTRIBUTED__SCHEDULER__WORKER_TTL="${DASK_DISTRIBUTED__SCHEDULER__WORKER_TTL:-1 hour}"
[ -x .venv/bin/fvdem ] || make venv
OUT=${FVDEM_RUNS:-$HOME/fvdem-runs}

# --until HH:MM names the clock time's next occurrence when each study starts: a study that starts after it (the
# next one in the queue, once the first has stopped at it) would take tomorrow's. Resolved once, here, to the
# moment it names now (an ISO date and time), so every study in the queue stops at the same moment.
args=()
while [ $# -gt 0 ]; do
    if [ "$1" = --until ] && [ $# -ge 2 ]; then
        moment=$(.venv/bin/python -c 'import sys, datetime; from fvdem.study.cluster import until_epoch
e = until_epoch(sys.argv[1])
print(datetime.datetime.fromtimestamp(e).astimezone().isoformat(timespec="seconds") if e else sys.argv[1])' "$2")
        args+=(--until "$moment"); shift 2
    else
        args+=("$1"); shift
    fi
done
set -- ${args[@]+"${args[@]}"}

study() {  # study NAME [ARGS]: one study, restored from its archive where one is committed
    local name=$1; shift
    local restore=()
    [ -f "docs/data/$name/study.json" ] && restore=(--restore "docs/data/$name")
    .venv/bin/fvdem study "studies/$name.toml" --out "$OUT/$name" --workers "${WORKERS:-1}" "${restore[@]}" "$@"
}

ended() {  # ended NAME: whether every run of a study has ended (its folder, else its committed archive)
    local where="$OUT/$1"
    [ -f "$where/study.json" ] || where="docs/data/$1"
    [ -f "$where/study.json" ] || return 1
    .venv/bin/fvdem study "$where" --status --json 2>/dev/null | .venv/bin/python -c 'import json, sys
lines = sys.stdin.read().strip().splitlines()
sys.exit(0 if lines and json.loads(lines[-1])["left_simulated_seconds"] == 0 else 1)'
}

# Once the contact study has ended, the queue below takes both cores (two runs at a time).
status=0
if ended contact_paper; then
    export WORKERS=2
    contact=
else
    study contact_paper "$@" &
    contact=$!
fi
[ -f studies/stochastic_bed.toml ] && { study stochastic_bed "$@" || status=$?; }
study screening_ar1 "$@" || status=$?
[ -f studies/contact_candidates.toml ] && { study contact_candidates "$@" || status=$?; }
[ -f studies/screening_ar4.toml ] && { study screening_ar4 "$@" || status=$?; }
[ -n "$contact" ] && { wait $contact || status=$?; }
exit $status

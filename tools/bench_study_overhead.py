"""What Dask itself costs a study while its runs compute: the CPU time of the client's process (scheduler and
client) and of each LocalCluster worker process over ``--seconds`` in which every worker holds a task that
only sleeps, with Dask's default monitoring and with fvdem's (``fvdem.study.cluster.QUIET_DASK``), in
alternated rounds. Prints one JSON object as its last line (per round and the medians, in % of a core)::

    python tools/bench_study_overhead.py --rounds 3 --seconds 40 --json

CPU time of the processes themselves (``/proc/<pid>/stat``), not wall time: other work on the machine does
not enter it, though it may slow Dask's loops. Linux only.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time



def _sleep(seconds: float) -> int:
    time.sleep(seconds)
    return os.getpid()


def _cpu_seconds(pid: int) -> float:
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def one_round(quiet: bool, workers: int, seconds: float) -> dict:
    """The client's process's and each worker's CPU, in % of a core, over ``seconds`` of sleeping tasks."""
    import fvdem.study.cluster as cluster
    from fvdem.study import close_client, make_client
    original = cluster.quiet_dask
    if not quiet:
        cluster.quiet_dask = lambda: {}
    try:
        client, _ = make_client(None, None, workers, 1)
    finally:
        cluster.quiet_dask = original
    try:
        pids = list(client.run(os.getpid).values())
        time.sleep(3.0)  # the workers' start-up done
        before = [_cpu_seconds(os.getpid())] + [_cpu_seconds(p) for p in pids]
        started = time.perf_counter()
        for future in [client.submit(_sleep, seconds, pure=False) for _ in pids]:
            future.result()
        wall = time.perf_counter() - started
        after = [_cpu_seconds(os.getpid())] + [_cpu_seconds(p) for p in pids]
    finally:
        close_client(client)
    used = [100.0 * (b - a) / wall for a, b in zip(before, after)]
    return {"monitoring": "fvdem" if quiet else "dask defaults", "client_process": used[0], "workers": used[1:]}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=3, help="rounds of each configuration, alternated")
    parser.add_argument("--seconds", type=float, default=40.0, help="how long the tasks sleep in each round")
    parser.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes")
    parser.add_argument("--json", action="store_true", help="one JSON object as the last line")
    parser.add_argument("--quick", action="store_true", help="one round of 3 s each (a check that it runs)")
    args = parser.parse_args(argv)
    if args.quick:
        args.rounds, args.seconds = 1, 3.0
    if args.rounds < 1 or args.seconds <= 0 or args.workers < 1:
        parser.error("--rounds and --workers at least 1, --seconds above 0")
    from fvdem.provenance import provenance
    rounds = []
    for k in range(args.rounds):
        for quiet in (False, True):
            rounds.append(one_round(quiet, args.workers, args.seconds))
            r = rounds[-1]
            print(f"round {k + 1}, {r['monitoring']}: client process {r['client_process']:.2f} % of a core, workers "
                  + ", ".join(f"{w:.2f}" for w in r["workers"]) + " %", flush=True)
    medians = {}
    for name in ("dask defaults", "fvdem"):
        mine = [r for r in rounds if r["monitoring"] == name]
        medians[name] = {"client_process": statistics.median(r["client_process"] for r in mine),
                         "per_worker": statistics.median(w for r in mine for w in r["workers"])}
    result = {"rounds": rounds, "medians_percent_of_a_core": medians, "seconds": args.seconds,
              "workers": args.workers, "provenance": provenance(), "load_average": os.getloadavg()}
    if args.json:
        print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())

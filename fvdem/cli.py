"""Command line: ``fvdem run | check | report | compare | study | info | schema | laws``.

Input problems (case file, options, output folder) exit with code 2 and a message, never a
traceback; a run that becomes unstable exits with code 3 and the cause.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import warnings
from pathlib import Path

from .case import CaseError, load_case, parse_override, schema_reference


def _overrides(pairs):
    return dict(parse_override(text) for text in pairs or [])


def _fail(message: str, code: int = 2) -> int:
    print(f"fvdem: error: {message}", file=sys.stderr)
    return code


def cmd_check(args) -> int:
    case = load_case(args.case, _overrides(args.set))
    if case.particles.initial_state is not None and case.particles.count > 0:
        from .model import load_initial_state
        load_initial_state(case)  # what `fvdem run` refuses before it starts
    print(f"{args.case}: OK ({case.particles.count} {case.particles.shape}s, end {case.time.end:g} s, "
          f"DEM step {case.time.dem_step:g} s = collision time / {case.collision_time() / case.time.dem_step:.1f})")
    return 0


class _StoppedBeforeStart(Exception):
    pass


def cmd_run(args) -> int:
    import signal
    from .simulation import Simulation
    # Ctrl-C or SIGTERM while the run is being set up (the case, the folder, numba's cache, the initial
    # state) stops it cleanly too; once it runs, Simulation.run's own handlers stop it at a checkpoint.
    # One that comes earlier, while the interpreter imports fvdem, ends the process before it has written
    # anything (exit status 143 in a shell)
    running = []

    def stop(*_):
        if running:  # between Simulation.run's own handlers: ask for a stop at the next checkpoint
            running[0].request_stop()
        else:
            raise _StoppedBeforeStart

    previous = {s: signal.signal(s, stop) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        case = load_case(args.case, _overrides(args.set))
        out = Path(args.out) if args.out else Path("runs") / case.name
        sim = Simulation(case, out, overwrite=args.overwrite, resume=args.resume,
                         progress=False if args.no_progress else None, threads=args.threads)
        running.append(sim)
        busy = busy_cores(sim.threads)
        if busy:
            print(f"fvdem: warning: {busy}", file=sys.stderr)
            sim.log.line(f"warning: {busy}")
        summary = sim.run()
    except _StoppedBeforeStart:
        print("stopped before the run started; nothing to resume from beyond the folder's last checkpoint "
              "(if any): start again with the same command (add --overwrite if the folder has no checkpoint)",
              file=sys.stderr)
        return 130
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    if sim.stopped_early:
        print(f"stopped at t = {sim.time:.6g} s; continue with: fvdem run {args.case} --out {out} --resume",
              file=sys.stderr)
        return 130
    from .timing import format_table
    print(format_table(summary["timings"], summary["threads"], summary["steps"], summary["simulated_time"]))
    keys = ("simulated_time", "ended", "steps", "wall_seconds", "bed_height", "solids_fraction",
            "contacts_per_particle", "max_overlap_over_diameter", "t95", "pressure_drop_over_weight",
            "porous_zone_pressure_gradient", "expected_pressure_gradient")
    print(json.dumps({k: round(summary[k], 12) if isinstance(summary[k], float) else summary[k]
                      for k in keys if k in summary and (k != "ended" or summary[k])}))  # ended early: why
    views = " and ".join(name for name in ("particles.pvd", "gas.pvd") if (out / name).exists())
    print(f"results in {out}/ ({views or 'no snapshots'} for ParaView, timeseries.csv, summary.json)")
    return 0


def cmd_report(args) -> int:
    from .analysis.plots import report
    from .scenes import plots_of
    out = Path(args.out)
    if not (out / "timeseries.csv").exists():
        return _fail(f"{out} is not a run folder (no timeseries.csv)")
    for path in report(out, plots_of(out)):
        print(path)
    return 0


def cmd_compare(args) -> int:
    from .analysis.compare import COMPARISONS, compare
    from .scenes import comparisons_of
    runs = [Path(r) for r in args.runs]
    for run in runs:
        if not (run / "timeseries.csv").exists() or not (run / "case.toml").exists():
            return _fail(f"{run} is not a run folder (needs timeseries.csv and case.toml)")
    names = comparisons_of(runs)
    for name in args.only or ():
        if name not in COMPARISONS:
            return _fail(f"--only: {name!r} is not a comparison; allowed: {', '.join(COMPARISONS)}")
    if args.only:
        names = tuple(args.only)
    try:
        paths = compare(runs, args.out, names, {"columns": args.columns})
    except ValueError as err:  # --columns naming what a run did not record
        return _fail(f"--columns: {err}")
    for path in paths:
        print(path)
    return 0


def cmd_study(args) -> int:
    from .study import load_study, report, request_stop, run_study, select_runs, write_index
    target = Path(args.study)
    if args.stop:
        if not target.is_dir() or not (target / "study.toml").exists():
            return _fail(f"--stop: {target} is not a study folder (no study.toml)")
        from .io.locks import describe_holder, holder
        running = holder(target)
        log_path = request_stop(target)  # also where the lock cannot be seen: the next start removes it
        if running is None:
            print(f"wrote {log_path}, but no fvdem study holds {target}'s lock (none runs there, or one runs where "
                  "its lock cannot be seen: an older fvdem without folder locks, a file system without locks); a "
                  "study running there stops, the next one started removes the file")
            return 0
        print(f"wrote {log_path}: {describe_holder(running)} stops; its running runs checkpoint at their next "
              "chunk; run the same fvdem study command to continue")
        return 0
    if args.status:
        if not target.is_dir() or not (target / "study.json").exists():
            return _fail(f"--status: {target} is not a study folder or an archive of one (no study.json)")
        from .study.status import format_status, study_status
        status = study_status(target)
        print(json.dumps(status) if args.json else format_status(status))
        return 0
    if args.archive:
        if not target.is_dir() or not (target / "study.json").exists():
            return _fail(f"--archive: {target} is not a study folder (no study.json)")
        from .study import archive
        for path in archive(target, args.archive):
            print(path)
        return 0
    if args.results:
        if not target.is_dir() or not (target / "study.json").exists():
            return _fail(f"--results: {target} is not a study folder or an archive of one (no study.json)")
        from .study import results
        print(results(target, args.results))
        return 0
    if args.report and target.is_dir():
        if not (target / "study.json").exists():
            return _fail(f"{target} is not a study folder (no study.json)")
        for path in report(target):
            print(path)
        return 0
    if args.report and args.out:  # a study file and its folder: report what the folder holds now
        if not Path(args.out).is_dir():
            return _fail(f"--out {args.out}: no such study folder")
        study = load_study(target, args.out)
        from .study.folders import changed_folders
        changed = changed_folders(study)
        if changed:  # the report still says what the folders hold; a warning names them
            print(f"fvdem: warning: {len(changed)} folder(s) in {args.out} hold other physics than {target} now sets; "
                  "their rows are of the old case (fvdem study ... --supersede runs them again):\n" + "\n".join(
                      f"  {spec.folder}: {keys}" for spec, keys in changed), file=sys.stderr)
        write_index(args.out, study)
        for path in report(args.out):
            print(path)
        return 0
    if not args.out:
        return _fail("fvdem study STUDY.toml needs --out DIR (or: fvdem study DIR --report)")
    study = select_runs(load_study(target, args.out), args.only)
    if args.cluster:  # the cluster apart from the physics: replaces the study file's [cluster]
        from dataclasses import replace

        from .study import load_cluster
        study = replace(study, cluster=load_cluster(args.cluster))
    log = (lambda line: print(line, file=sys.stderr, flush=True))
    from .study.runner import study_lock
    with study_lock(study, args.out):  # a study already running in --out is refused before anything moves
        code = _changed_folders(study, args.out, args.supersede, log)
        if code:
            return code
        sources = ([(args.restore, False)] if args.restore else []) + [(a, True) for a in args.adopt or ()]
        for source, adopt in sources:
            code = _restore(study, source, log, adopt)
            if code:
                return code
        durations = "/".join(f"{d:g}" for d in sorted({r.duration for r in study.runs})) or f"{study.duration:g}"
        log(f"study {study.name}: {len(study.runs)} runs and {len(study.beds)} beds of {durations} s into {args.out}")
        result = run_study(study, args.out, scheduler=args.scheduler, workers=args.workers,
                           threads=args.threads_per_worker, log=log, until=args.until)
        for path in report(args.out):
            log(f"report: {path}")
    failed = [r for r in result["runs"] if r["status"] == "failed"]
    for r in failed:
        log(f"failed: {r['name']}: {r['error']}")
        for line in r.get("log_tail") or []:  # the last lines of the run's run.log
            log(f"  {r['name']} run.log: {line}")
    stopped = [r["name"] for r in result["runs"] if r["status"] == "stopped"]
    if result.get("stopped"):
        log(f"stopped: {len(stopped)} run(s) checkpointed or not started ({', '.join(stopped)}); the same command "
            "continues the study")
    print(json.dumps(result) if args.json else json.dumps(result, indent=1))
    return 130 if result.get("stopped") else (1 if failed else 0)


def _changed_folders(study, out, supersede: bool, log) -> int:
    """Folders of ``out`` started with other physics than ``study`` now sets: refused (exit 2, each named with
    the keys that differ), or with ``--supersede`` moved to ``out/superseded/`` (one line each)."""
    from .study.folders import SUPERSEDED, changed_folders, unplanned_folders
    from .study.folders import supersede as move_aside
    changed = changed_folders(study)
    unplanned = unplanned_folders(study, out)
    if unplanned and not supersede:  # not in the way: the study never starts them, its status sets them apart
        log(f"note: {len(unplanned)} run(s) {study.path} no longer lists hold folders in {out} and have not ended "
            f"(not planned: neither run nor counted): {', '.join(name for name, _ in unplanned)}; --supersede moves "
            f"them to {out}/{SUPERSEDED}/")
    if not changed and not (unplanned and supersede):
        return 0
    lines = [f"  {spec.folder}: {keys}" for spec, keys in changed]
    if changed and not supersede:
        return _fail(f"{len(changed)} folder(s) in {out} were started with other physics than {study.path} now "
                     "sets:\n" + "\n".join(lines) + f"\nrun again with --supersede to move them to {out}/{SUPERSEDED}/ "
                     "and start their runs again, or restore the study file's settings")
    from .provenance import describe, provenance
    by = describe(provenance())
    moves = [(spec.name, spec.folder, keys) for spec, keys in changed]
    for (spec, keys), dest in zip(changed, move_aside(out, moves, by)):
        log(f"superseded: {spec.name} ({keys}) moved to {dest}; it starts again")
    for (name, _), dest in zip(unplanned, move_aside(out, [(name, folder, None) for name, folder in unplanned], by)):
        log(f"superseded: {name} (no longer in the study file) moved to {dest}")
    return 0


def _restore(study, source, log, adopt: bool = False) -> int:
    """``fvdem study --restore`` (``--adopt``): the archive's finished runs into the study's run folders, one line
    each."""
    from .study import restore
    option = "--adopt" if adopt else "--restore"
    if not Path(source, "study.json").exists():
        return _fail(f"{option} {source}: not an archive of a study (no study.json; fvdem study DIR --archive "
                     f"{source} writes one)")
    try:
        outcomes = restore(study, source, adopt)
    except ValueError as exc:
        return _fail(str(exc))
    counts = {}
    for name, outcome in outcomes:
        counts[outcome.split(":")[0]] = counts.get(outcome.split(":")[0], 0) + 1
        if outcome not in ("restored", "adopted", "exists"):
            log(f"{option[2:]}: {name}: {outcome}" + (" (starts again: an archive has no checkpoint)"
                                                      if outcome == "in progress" and not adopt else ""))
    log(f"{option[2:]} from {source}: " + (", ".join(f"{n} {k}" for k, n in counts.items()) or "no archived runs"))
    return 0


def cmd_info(args) -> int:
    import numba
    import numpy
    from numba import njit, prange

    @njit(parallel=True)
    def _touch(a):  # a parallel launch decides the threading layer
        for i in prange(a.shape[0]):
            a[i] += 1.0
    _touch(numpy.zeros(2))
    from .version import __version__
    print(json.dumps({"fvdem": __version__, "numpy": numpy.__version__, "numba": numba.__version__,
                      "threads_available": numba.config.NUMBA_NUM_THREADS,
                      "threading_layer": numba.threading_layer()}, indent=2))
    return 0


def registered(kind: str | None = None) -> dict:
    """What the registries hold: drag, lift and torque laws, voidage methods, stochastic forces, scenes, DEM
    backends, the early ends a run records and study reports, each name with what it is, where it applies and its
    reference."""
    from .coupling.closures import LAWS
    from .coupling.voidage import METHODS
    from .scenes import SCENES
    table = {k: {name: {"summary": l.summary, "shapes": list(l.shapes), "aspect_ratio": l.aspect_ratio,
                        "validity": l.validity, "reference": l.reference} for name, l in laws.items()}
             for k, laws in LAWS.items()}
    table["voidage"] = {name: {"summary": m.summary, "reference": m.reference} for name, m in METHODS.items()}
    from .coupling.stochastic import MODELS, NO_STOCHASTIC_FORCE
    table["stochastic_force"] = {name: {"summary": NO_STOCHASTIC_FORCE} if m is None else
                                 {"summary": m.summary, "validity": m.validity, "reference": m.reference}
                                 for name, m in MODELS.items()}
    table["scenes"] = {name: {"summary": s.summary} for name, s in SCENES.items()}
    from .dem.backends import BACKENDS
    table["dem_backend"] = {name: {"summary": description} for name, (_, description) in BACKENDS.items()}
    from .scenes.stops import STOP_CONDITIONS
    table["stop_condition"] = {name: {"summary": c.summary, "setting": c.setting}
                               for name, c in STOP_CONDITIONS.items()}
    from .study import REPORTS, report_for
    report_for(None)  # every registered report
    table["report"] = {name: {"summary": r.summary} for name, r in REPORTS.items()}
    return table if kind is None else {kind: table[kind]}


def cmd_compile(args) -> int:
    """Compile the kernels into numba's cache before the first run (``fvdem.warmup``)."""
    from .warmup import compile_kernels

    def report(name, result):
        if not args.json:
            print(f"{name}: {result['seconds']:.1f} s, " + (f"{len(result['compiled'])} kernel(s) compiled"
                                                           if result["compiled"] else "every kernel from the cache"),
                  file=sys.stderr, flush=True)
    try:
        result = compile_kernels(jobs=args.jobs, report=report)
    except RuntimeError as exc:  # a scene failed: its interpreter's last lines
        return _fail(str(exc), 1)
    compiled = sum(len(r["compiled"]) for r in result["scenes"].values())
    if args.json:
        print(json.dumps(result))
    else:
        print(f"fvdem compile: {compiled} kernel(s) compiled in {result['wall_seconds']:.0f} s "
              f"({args.jobs} process(es) at a time); later runs load them from numba's cache", flush=True)
    return 0


def cmd_laws(args) -> int:
    table = registered(args.kind)
    if args.json:
        print(json.dumps(table))
        return 0
    for kind, entries in table.items():
        print(f"{kind}:")
        for name, entry in entries.items():
            print(f"  {name}: {entry['summary']}")
            for key in ("shapes", "aspect_ratio", "validity", "reference", "setting"):
                if entry.get(key):
                    value = ", ".join(entry[key]) if isinstance(entry[key], list) else entry[key]
                    print(f"      {key.replace('_', ' ')}: {value}")
    return 0


def cmd_schema(args) -> int:
    if args.json_schema:
        from .json_schema import case_schema, dumps, study_schema
        print(dumps(case_schema() if args.json_schema == "case" else study_schema()), end="")
        return 0
    if args.docs:
        from .case import docs_reference
        print(docs_reference(), end="")
        return 0
    print(schema_reference())
    return 0


def cores() -> int:
    """The CPUs this process may run on (its affinity; a SLURM job's allocation, not the node's)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def busy_cores(threads: int) -> str | None:
    """Why ``threads`` numba threads are too many for the cores other work leaves free (the 1-minute load
    average against ``cores()``), else None. A step's parallel loops each end with every thread waiting for
    the others, so a thread that waits for a core stalls the whole step: the demo bed beside two busy cores
    ran 3 x slower on 2 threads than on 1 (docs/benchmarks.md, "More numba threads than free cores")."""
    try:
        load = os.getloadavg()[0]
    except (OSError, AttributeError):  # pragma: no cover - no load average on this system
        return None
    free = cores() - load
    if threads <= 1 or threads <= free + 0.5:
        return None
    return (f"the machine is busy (load average {load:.1f} on {cores()} cores): {threads} numba threads wait for "
            f"each other at every step when a core is taken; run with --threads {max(1, round(free))}")


def thread_count(text: str) -> int:
    """An argparse type: a thread count 1..cores (a wrong one ends with exit code 2 and the range)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: a whole number of threads, 1-{cores()}") from None
    if not 1 <= value <= cores():
        raise argparse.ArgumentTypeError(f"{value}: allowed 1-{cores()} (the CPUs this process may use)")
    return value


def deadline(text: str) -> float:
    """``--until``'s epoch seconds (``fvdem.study.cluster.until_epoch``), or a usage error naming the forms."""
    from .study.cluster import until_epoch
    value = until_epoch(text)
    if value is None:
        raise argparse.ArgumentTypeError(
            f"{text!r}: a time to come, as HH:MM or HH:MM:SS (local, its next occurrence), an ISO date and time "
            "(2026-12-05T04:45) or +DURATION from now (+90m, +2h, +1:30:00)")
    return value


def positive_count(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: a whole number, at least 1")
    return value


def version_text() -> str:
    from .version import __version__
    from .provenance import source_commit
    commit = source_commit()
    return f"fvdem {__version__}" + (f" (commit {commit})" if commit else "")


class _Version(argparse.Action):
    """``--version``: the version text is made only when asked (the commit costs a git call)."""

    def __call__(self, parser, namespace, values, option_string=None):
        print(version_text())
        parser.exit()


SET_HELP = "override a case value, e.g. --set particles.count=5000 (repeat for several; keys: fvdem schema)"


def make_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="fvdem", description="CFD-DEM for fluidized beds")
    parser.add_argument("--version", action=_Version, nargs=0,
                        help="the fvdem version (and git commit of a source checkout), then exit")
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run a case file")
    run.add_argument("case", help="the case file (TOML; cases/ has examples)")
    run.add_argument("--out", help="output folder (default runs/<case name>)")
    run.add_argument("--overwrite", action="store_true", help="replace an existing non-empty output folder")
    run.add_argument("--resume", action="store_true", help="continue from the output folder's checkpoint")
    run.add_argument("--threads", type=thread_count, help="numba threads, 1 to the CPUs available "
                                                          "(default: case run.threads, 0 there meaning all)")
    run.add_argument("--no-progress", action="store_true",
                     help="no progress bar or progress lines on standard error (run.log keeps its lines)")
    run.add_argument("--set", action="append", metavar="KEY=VALUE", help=SET_HELP)
    run.set_defaults(func=cmd_run)
    check = sub.add_parser("check", help="validate a case file without running it")
    check.add_argument("case", help="the case file (TOML)")
    check.add_argument("--set", action="append", metavar="KEY=VALUE", help=SET_HELP)
    check.set_defaults(func=cmd_check)
    report = sub.add_parser("report", help="write PNG plots for a run folder")
    report.add_argument("out", help="a run folder (the --out of fvdem run); the plots are written into it")
    report.set_defaults(func=cmd_report)
    compare = sub.add_parser("compare", help="several runs on one chart: the diagnostics they recorded in common, "
                             "and the comparisons their scenes declare (a fluidized bed's: mixing entropy against "
                             "time, t95 against U/Umf, where each bed is still unmixed)")
    compare.add_argument("runs", nargs="+", help="run folders")
    compare.add_argument("--out", default=".", help="folder for the charts (timeseries_compare.png, mixing_compare.png, "
                                                   "mixing_by_velocity.png, t95.png, ...)")
    compare.add_argument("--columns", nargs="+", metavar="COLUMN",
                         help="timeseries.csv columns to overlay (default: the first eight the runs recorded in common)")
    compare.add_argument("--only", nargs="+", metavar="NAME", help="draw only these comparisons (by name)")
    compare.set_defaults(func=cmd_compare)
    study = sub.add_parser("study", help="run a study file's runs on Dask (or --report a study folder)")
    study.add_argument("study", help="a study file (studies/*.toml), or a study folder with --report")
    study.add_argument("--out", help="study folder (runs/, beds/, study.json, the report)")
    study.add_argument("--workers", type=positive_count,
                       help="LocalCluster worker processes (default: cores / threads)")
    study.add_argument("--threads-per-worker", type=positive_count, default=1,
                       help="numba threads of each run (default 1)")
    study.add_argument("--scheduler", help="address of a running Dask scheduler (instead of a LocalCluster)")
    study.add_argument("--cluster", metavar="FILE",
                       help="where the runs go, apart from the study file: a TOML file of [cluster] keys "
                            "(kind = \"slurm\", memory, walltime, ...); replaces the study file's [cluster]")
    study.add_argument("--report", action="store_true",
                       help="only write the report of a study folder (or of an archive of one, --archive)")
    study.add_argument("--archive", metavar="DEST",
                       help="copy the compact results of a study folder's runs to DEST (time series, summaries, "
                            "void-fraction histograms, logs; no states or VTU), small enough to commit; "
                            "fvdem study DEST --report rebuilds the report from them")
    study.add_argument("--results", metavar="FILE",
                       help="write a study folder's (or an archive's) results as one JSON file: its table rows, "
                            "its findings and what made them (code, machine, how many runs ended); the report first")
    study.add_argument("--restore", metavar="ARCHIVE",
                       help="first copy into --out the runs an archive of this study (--archive) holds at their "
                            "end, so that they are skipped (a study folder lost with its machine); never over a "
                            "run folder that exists; runs the archive holds in progress start again")
    study.add_argument("--adopt", nargs="+", metavar="ARCHIVE",
                       help="first copy into --out the runs another study's archive holds at their end where this "
                            "study has a run of the same name, case and bed, so that they count here as they are (a "
                            "later stage reusing an earlier one's runs); never over a run folder that exists")
    study.add_argument("--supersede", action="store_true",
                       help="move bed and run folders that were started with other physics than the study file now "
                            "sets (a changed setting) to --out's superseded/ and run them again; without it such "
                            "folders are refused before anything runs, each named with the keys that differ; also "
                            "moves there the folders of runs the study file no longer lists that have not ended "
                            "(listed 'not planned' by --status)")
    study.add_argument("--only", nargs="+", metavar="RUN", help="run only these runs (and the beds they need)")
    study.add_argument("--until", type=deadline, metavar="TIME",
                       help="stop at TIME (HH:MM, an ISO date and time, or +DURATION: +150m, +2h, +2:30:00): "
                            "the running runs checkpoint and the same command continues; until then a free "
                            "worker takes first the runs expected to end by TIME (their family's CPU seconds per "
                            "simulated second so far, and where their point's ended replicas ended)")
    study.add_argument("--status", action="store_true",
                       help="where a study folder (or an archive of one) stands, read without writing: whether a "
                            "study runs there now, each run's state, simulated seconds, t95 and mixing entropy, "
                            "CPU seconds per simulated second and memory per family, and the core-hours left")
    study.add_argument("--stop", action="store_true",
                       help="ask the study running in this folder to stop (its runs checkpoint first)")
    study.add_argument("--json", action="store_true", help="the result as one JSON line")
    study.set_defaults(func=cmd_study)
    sub.add_parser("info", help="versions and threads").set_defaults(func=cmd_info)
    compile_ = sub.add_parser("compile", help="compile the kernels into numba's cache before a first run, study or "
                                              "job array (a few seconds when they are cached)")
    compile_.add_argument("--jobs", type=positive_count, default=min(2, os.cpu_count() or 1),
                          help="processes at a time (default: 2, or 1 on one CPU)")
    compile_.add_argument("--json", action="store_true", help="the scenes' times and compiled kernels as one JSON line")
    compile_.set_defaults(func=cmd_compile)
    schema = sub.add_parser("schema", help="print the case-file reference (Markdown)")
    schema.add_argument("--docs", action="store_true", help="the form of docs/case-reference.md (registries by name)")
    schema.add_argument("--json-schema", choices=("case", "study"),
                        help="a JSON Schema of case files or study files, for an editor's TOML checks "
                             "(docs/schema/ holds copies)")
    schema.set_defaults(func=cmd_schema)
    laws = sub.add_parser("laws", help="list the registered closures, voidage methods, stochastic forces, scenes, DEM "
                                       "backends, stop conditions and study reports")
    laws.add_argument("kind", nargs="?", choices=("drag", "lift", "torque", "voidage", "stochastic_force", "scenes",
                                                  "dem_backend", "stop_condition", "report"),
                      help="only this registry (default: all)")
    laws.add_argument("--json", action="store_true", help="one JSON object")
    laws.set_defaults(func=cmd_laws)
    return parser


def _show_warning(message, category, filename, lineno, file=None, line=None):
    """A warning on standard error as one readable line (not Python's file:line and source line)."""
    from .io.run_log import warning_line
    try:
        print(f"fvdem: {warning_line(message, category)}", file=sys.stderr, flush=True)
    except (OSError, ValueError):  # standard error closed
        pass


def _quiet_after_broken_pipe() -> int:
    """The reader of standard output went away (``fvdem schema | head``): end quietly with exit 0, with
    standard output pointed at /dev/null so the interpreter's last flush does not complain."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass
    return 0


def main(argv=None) -> int:
    from .errors import OutputError
    from .errors import SimulationError
    args = make_parser().parse_args(argv)
    warnings.showwarning = _show_warning
    try:
        return args.func(args)
    except BrokenPipeError:
        return _quiet_after_broken_pipe()
    except CaseError as exc:
        if len(exc.problems) == 1:
            return _fail(f"invalid case: {exc.problems[0]}")
        return _fail("invalid case:\n  " + "\n  ".join(exc.problems))
    except OutputError as exc:
        return _fail(str(exc))
    except SimulationError as exc:
        return _fail(f"simulation stopped: {exc}", 3)
    except OSError as exc:  # a file the command reads or writes outside the case and run folders
        return _fail(f"{exc.filename or ''}: {exc.strerror or exc}")


if __name__ == "__main__":
    sys.exit(main())

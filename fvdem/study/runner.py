"""The Dask runner: a study's beds and runs as tasks (runs in progress first, then first replicas, longest
first), their progress, stop requests, walltime pauses and resubmissions, and ``study.json``; ``map_tasks`` for the
sweeps that are not studies of case files. Nothing here knows what a run measures: the study's report
(``reports``) gives each finished run's progress detail."""
from __future__ import annotations

import json
import math
import signal
import sys
import time
from pathlib import Path

from ..case import CaseError, load_case
from ..io.locks import FolderLock
from ..io.run_folder import write_text_atomic
from .cluster import close_client, make_client, worker_count
from .records import Outcome, ended_early, entry_folder, read_summary, run_at_end, simulated_so_far
from .registry import report_for
from .specs import BedSpec, RunSpec, Study
from .status import clock, study_status
from .tasks import STOP_FILE, StudyStopped, prepare_bed, run_finished, run_task


MAX_STALLS = 3  # paused attempts in a row that started and made no progress: the walltime is too short


def progress_line(done: int, total: int, name: str, status: str, detail: str, started: float,
                  work_done: float | None = None, work_total: float | None = None, unit: str = "",
                  work_start: float = 0.0) -> str:
    """One line of a sweep's progress view: tasks done, the work done (e.g. simulated seconds) and an ETA
    from the rate so far (the work done since ``started``: beyond ``work_start``, what was done before)."""
    elapsed = time.perf_counter() - started
    done_work, total_work = (done, total) if work_done is None else (work_done, work_total)
    rate = (done_work - work_start) / elapsed if elapsed > 0 and done_work > work_start else 0.0
    eta = (total_work - done_work) / rate if rate else math.nan
    work = f"{done_work:.4g} of {total_work:.4g}{unit} done, " if work_done is not None else ""
    if eta != eta:
        left = "?"
    else:  # a campaign's, an hour or more: hours too
        left = f"{eta:.0f} s" + (f" ({_hours_minutes(eta)})" if eta >= 3600.0 else "")
    return (f"[{done}/{total}] {name}: {status}" + (f" ({detail})" if detail else "")
            + f"; {work}{elapsed:.0f} s wall, ETA {left}")


def _hours_minutes(seconds: float) -> str:
    """``seconds`` as "H h MM min" (rounded to the minute)."""
    minutes = max(0, round(seconds / 60.0))
    return f"{minutes // 60} h {minutes % 60:02d} min"


def _guarded(function, item, threads):
    """A sweep task: ``function(item, threads)``, its failure returned with the cause instead of raised."""
    started = time.perf_counter()
    try:
        value = function(item, threads)
    except Exception as exc:  # noqa: BLE001  (one failed point is reported, the others go on)
        return {"status": Outcome.FAILED, "error": f"{type(exc).__name__}: {exc}", "value": None,
                "wall_seconds": time.perf_counter() - started}
    return {"status": Outcome.FINISHED, "error": None, "value": value, "wall_seconds": time.perf_counter() - started}


def map_tasks(function, items, names, *, threads=1, scheduler=None, workers=None, cluster=None, log=print) -> list:
    """The engine under every sweep that is not a study of case files (the tools' fractions, variants
    and ramps): ``function(item, threads)`` for each item, each a task on the same Dask clients as
    ``fvdem study`` (``scheduler``, a dask-jobqueue ``cluster`` table, or a LocalCluster of ``workers``),
    one progress line per finished task. Returns, in the items' order, ``{"name", "status"
    ("finished" or "failed"), "value", "error", "wall_seconds"}``: a failure does not stop the others.
    ``function`` must be importable or picklable (a tool's module-level function is)."""
    from distributed import as_completed
    names = [str(n) for n in names]
    if len(set(names)) != len(names):
        raise ValueError("map_tasks: task names must be distinct")
    started = time.perf_counter()
    client, description = make_client(cluster, scheduler, workers, threads)
    log(f"{len(names)} tasks on {description}")
    results = {}
    try:
        futures = {client.submit(_guarded, function, item, threads, key=f"task-{name}", pure=False): name
                   for item, name in zip(items, names)}
        for done, future in enumerate(as_completed(list(futures)), 1):
            name = futures[future]
            result = dict(future.result(), name=name)
            results[name] = result
            log(progress_line(done, len(names), name, result["status"], result["error"] or "", started))
    finally:
        close_client(client)
    return [results[name] for name in names]


def request_stop(out) -> Path:
    """Ask the study running in ``out`` to stop: its runs checkpoint and end, queued runs do not start."""
    path = Path(out) / STOP_FILE
    path.write_text("stop requested\n")
    return path


# a replica's rank in the queue: every first replica before any second one, and so on (far more than a
# run's DEM steps, 2e7 for 20 s at 1e-6 s); the beds come before the runs of their replica
REPLICA_RANK = 10**10


BED_RANK = 10**12

# a run in progress (a checkpoint, not at its end) before every run not started, the nearest its end first:
# a campaign stopped and continued finishes what it began instead of beginning more (a machine handed back
# bare loses the runs in progress, compact results of finished ones are archived)
IN_PROGRESS_RANK = 10**11


def _priority(run: RunSpec) -> int:
    """Runs in progress first (``IN_PROGRESS_RANK``), the nearest their end first; then first replicas
    first, longest first: DEM steps left (duration minus what the folder holds, over the DEM step), less
    ``REPLICA_RANK`` per replica after the first. A campaign cut short has every point of the study once
    before it has any twice."""
    return _standing(run)[1]


def _standing(run: RunSpec) -> tuple[bool, int]:
    """Whether ``run`` is at its end (``run_finished``) and its ``_priority``, from one read of its case and
    folder."""
    rank = -(run.replica - 1) * REPLICA_RANK
    try:
        case = load_case(run.case, {**run.overrides, "output.progress": False})
    except CaseError:
        return False, rank
    so_far = simulated_so_far(Path(run.folder))
    steps_left = int(round(max(0.0, run.duration - so_far) / float(case.time.dem_step)))
    finished = run_at_end(Path(run.folder), case)
    if so_far > 0 and not finished:
        return False, IN_PROGRESS_RANK - steps_left
    return finished, rank + steps_left


def _bed_priority(bed: BedSpec) -> int:
    """A bed's rank among the tasks Dask holds: it goes to Dask with the first run the queue hands on that
    starts from it (``_run_study``), so that a later replica's bed settles only once the runs before its
    replica have started; ranked above that run and the runs of its replica (``_priority``), below those of
    the replica before."""
    return BED_RANK if bed.replica == 1 else -(bed.replica - 1) * REPLICA_RANK + REPLICA_RANK // 2


def _expected_wall(out: Path, threads: int, status: dict | None = None) -> dict:
    """Each run's expected wall seconds to its end, by name: the simulated seconds it is likely to run yet
    (``study_status``'s ``expected_left``: where its point's ended replicas ended, where a stop condition whose
    mark it has reached ends it, else its duration) at its family's CPU seconds per simulated second so far (the
    slowest family's where its own has none measured) over its ``threads`` (at one thread per run, as the campaign runs, its wall time; a
    lower bound where threads do not scale). Runs of a study that has measured no rate yet are missing."""
    return {r["name"]: r["expected_cpu_seconds_left"] / threads for r in (status or study_status(out))["runs"]
            if r["expected_cpu_seconds_left"] is not None}


def _bed_wall(beds, states: list, threads: int) -> dict:
    """Each of ``beds`` (``BedSpec``) not settled yet: its expected wall seconds to settle, by name: the mean CPU
    seconds of the settled beds among them of its case file (of all the settled ones where none of its case has
    settled), over ``threads``; ``states``: ``study_status``'s ``beds`` (a bed without a folder has not begun).
    Missing where no bed has settled yet (the shipped cases' beds settle in 60-180 CPU s)."""
    state_of = {state["name"]: state for state in states}
    settled, waiting = {}, []
    for bed in beds:
        state = state_of.get(bed.name, {"state": "begun"})
        if state["state"] == "settled" and state.get("cpu_seconds"):
            settled.setdefault(bed.case, []).append(float(state["cpu_seconds"]))
        elif state["state"] != "settled":
            waiting.append(bed)
    every = [cpu for cpus in settled.values() for cpu in cpus]
    wall = {}
    for bed in waiting if every else ():
        cpus = settled.get(bed.case, every)
        wall[bed.name] = sum(cpus) / len(cpus) / threads
    return wall


def _fitting(out: Path, runs, until: float, threads: int, beds=()) -> set:
    """The names of ``runs`` expected to end (``_expected_wall``, and the settling of a bed of ``beds`` they start
    from that has not settled yet, ``_bed_wall``) before ``until`` (epoch seconds)."""
    status = study_status(out)  # one read of the folder for both
    wall, settling = _expected_wall(out, threads, status), _bed_wall(beds, status["beds"], threads)
    left = until - time.time()
    return {r.name for r in runs if r.name in wall and wall[r.name] + settling.get(r.bed, 0.0) <= left}


class _Queue:
    """The study's runs not yet handed to Dask, handed on in ``_priority`` order as read from their folders
    when a slot frees, never more than ``slots`` at a time (runs at their end, which are only skipped, at
    once). Dask itself orders tasks by priority only among those on one worker: runs submitted all at once go
    to the worker that settled their bed, so a worker could begin a new run while a run in progress waited
    behind the other (2026-12-03). With ``fits`` (runs -> the names of those expected to end in the time left:
    ``_fitting``, the study's ``until``) the runs that fit go first, in ``_priority`` order among themselves, then
    the others: a slot is never left idle, and a run that cannot end stops at its checkpoint at the deadline.
    Above both, the runs' ``priority`` (the study file's, of a family or ``[[points]]``): a tier below another
    starts only once that one's runs have all started (a later tranche waits for the runs queued before it,
    even where it fits and they do not); a run in progress counts in the top tier, so that without priorities
    the order is as before."""

    def __init__(self, runs, slots, fits=None):
        self.runs, self.slots = list(runs), slots  # slots: a number, or a callable (the live cluster's size)
        self.fits = fits
        self.top = max((r.priority for r in self.runs), default=0)

    def __len__(self) -> int:
        return len(self.runs)

    def take(self, in_flight: int) -> tuple[list, list]:
        """The runs to submit now: those at their end (skipped at once: they only read their summary), and, first
        first, as many others as free the slots left by ``in_flight`` runs. Each run's case and folder are
        read once."""
        standing = {r.name: _standing(r) for r in self.runs}
        ended = [r for r in self.runs if standing[r.name][0]]
        self.runs = [r for r in self.runs if not standing[r.name][0]]
        free = (self.slots() if callable(self.slots) else self.slots) - in_flight - len(ended)
        if free <= 0 or not self.runs:
            return ended, []
        fitting = self.fits(self.runs) if self.fits else set()

        def tier(run):  # a run in progress (ranked above every replica's runs not started) is in the top tier
            return self.top if standing[run.name][1] > IN_PROGRESS_RANK - REPLICA_RANK else run.priority
        self.runs.sort(key=lambda r: (tier(r), r.name in fitting, standing[r.name][1]), reverse=True)
        taken, self.runs = self.runs[:free], self.runs[free:]
        return ended, taken

    def drain(self) -> list:
        """The runs never handed on (the study is stopping)."""
        taken, self.runs = self.runs, []
        return taken


class _StudyProgress:
    """The study's progress view: simulated seconds done over all runs (read from the run folders every
    ``poll`` seconds), runs done and the time left, as a tqdm bar on a terminal or a line every 2 % in a
    log (``fvdem.io.progress``); per-run lines go above it."""

    def __init__(self, study: Study, started: float, log):
        from ..io.progress import progress_bar
        self.study, self.log = study, log
        self.total = sum(r.duration for r in study.runs)
        self.initial = self._simulated()  # what the run folders held when the study started
        self.bar = progress_bar(self.total, self.initial, f"study {study.name} (simulated s)")
        if hasattr(self.bar, "step"):
            self.bar.step = 2.0
            self.bar.final_postfix = True  # the last line says how many runs ended, even after the 100 % line
        self.is_tqdm = not hasattr(self.bar, "step")

    def _simulated(self) -> float:
        """Simulated seconds done: a run that ended early (a stop condition its case sets) counts whole."""
        return sum(r.duration if ended_early(read_summary(Path(r.folder)))
                   else min(r.duration, simulated_so_far(Path(r.folder), live=True)) for r in self.study.runs)

    def update(self, runs_done: int) -> None:
        now = self._simulated()
        self.bar.set_postfix_str(f"{runs_done}/{len(self.study.runs)} runs done", refresh=False)
        if now > self.bar.n:
            self.bar.update(now - self.bar.n)

    def message(self, line: str) -> None:
        if self.is_tqdm:
            self.bar.write(line, file=sys.stderr)
        else:
            self.log(line)

    def close(self) -> None:
        self.bar.close()


def _retire(client, address: str, seconds: float = 10.0) -> bool:
    """Retire and close the worker at ``address`` (its job is at its walltime); tried again for up to
    ``seconds`` while Dask declines because a key released just before (the paused run's, its bed's) still
    lives only there. Returns whether it left; if it did not, ``PAUSED_RETURN_DELAY`` paces the run's
    returns to it until its lifetime ends it."""
    deadline = time.time() + seconds
    while True:
        try:
            if address in client.retire_workers(workers=[address], close_workers=True):
                return True
            if address not in client.scheduler_info().get("workers", {}):
                return True
        except Exception:  # noqa: BLE001  (already gone: its job ended)
            return True
        if time.time() >= deadline:
            return False
        time.sleep(0.25)


def run_study(study: Study, out, *, scheduler=None, workers=None, threads=1, log=print, poll: float = 30.0,
              until: float | None = None) -> dict:
    """Run every bed and run of ``study`` on Dask; returns the study's result (see ``fvdem study``).
    SIGINT/SIGTERM (main thread) or ``request_stop(out)`` stop it with every running run checkpointed.
    ``until`` (epoch seconds: a machine's or an allocation's end) stops it so at that time, and until then a
    freed slot goes first to the runs expected to end before it (``_Queue``, ``_fitting``).
    Progress: the run folders are read every ``poll`` seconds (``_StudyProgress``). One study at a time runs
    in ``out``: a second is refused (``FolderInUse``, naming the first) before it touches anything."""
    with study_lock(study, out):
        return _run_study(study, Path(out), scheduler, workers, threads, log, poll, until)


def study_lock(study: Study, out) -> FolderLock:
    """The lock of the study folder ``out`` (``fvdem.io.locks``), held while a study runs there; taken again by
    the process that holds it (the command line takes it before it moves superseded folders)."""
    return FolderLock(out, "study", {"study": study.name, "file": str(study.path)})


def _run_study(study: Study, out: Path, scheduler, workers, threads, log, poll, until=None) -> dict:
    from distributed import wait
    out.mkdir(parents=True, exist_ok=True)
    (out / "study.toml").write_text(Path(study.path).read_text())
    (out / STOP_FILE).unlink(missing_ok=True)  # a stop request belongs to the invocation it stopped
    stop_requested = []

    def on_signal(signum, _frame):
        if not stop_requested:
            log(f"stopping (signal {signum}): each running run checkpoints at its next chunk; the same command "
                "continues the study")
        stop_requested.append(signum)
        request_stop(out)

    handlers = {}
    try:
        handlers = {sig: signal.signal(sig, on_signal) for sig in (signal.SIGINT, signal.SIGTERM)}
    except ValueError:  # not the main thread: request_stop(out) still stops the study
        pass
    started = time.perf_counter()
    client, description = make_client(study.cluster, scheduler, workers, threads)
    log(f"{description}; Dask dashboard at {getattr(client, 'dashboard_link', None) or 'none'}")
    if until is not None:
        log(f"stops at {clock(until, 'seconds')} (--until), in {_hours_minutes(until - time.time())}; until then a "
            "free worker takes first the runs expected to end by then")
    tag = task_tag(study, out)
    chosen = report_for(study.report)
    try:
        # a bed settles only for runs not at their end (a study restored from its archive settles none
        # for the runs it holds finished: a run at its end is skipped without its bed's state), and only once
        # the queue hands on the first run that starts from it: submitted at once, a later replica's bed took
        # the free workers ahead of the runs in progress (Dask's priorities order only the tasks it holds,
        # and the queue holds the runs back)
        starting = {r.bed for r in study.runs if r.bed and not run_finished(r)}
        needed = {b.name: b for b in study.beds if b.name in starting}
        beds: dict = {}  # bed name -> its future (its state's path once a paused run let the future go)

        def bed_of(run):
            if run.bed not in needed:
                return None
            if run.bed not in beds:
                bed = needed[run.bed]
                beds[run.bed] = client.submit(prepare_bed, bed, threads, key=f"{tag}bed-{bed.name}", pure=False,
                                              priority=_bed_priority(bed))
            return beds[run.bed]

        def submit(run, key, ended=False):
            return client.submit(run_task, run, threads, None if ended else bed_of(run), key=key, pure=False,
                                 priority=_priority(run))

        run_of, pending = {}, set()  # the futures live in ``pending`` only (a finished one is let go)
        fits = None if until is None else (lambda runs: _fitting(out, runs, until, threads, study.beds))
        if scheduler:  # a running cluster: as many runs as it has threads now
            queue = _Queue(study.runs, lambda: max(1, sum(client.nthreads().values())), fits)
        else:  # a LocalCluster's workers, or a dask-jobqueue cluster's jobs at most (adaptive: one per run)
            queue = _Queue(study.runs, worker_count(study.cluster, workers, threads), fits)

        def top_up():
            ended, taken = queue.take(len(pending))
            if (out / STOP_FILE).exists():  # runs not started do not start; runs at their end still say so
                for run in taken + queue.drain():
                    results.append({"name": run.name, "family": run.family, "status": Outcome.STOPPED,
                                    "folder": run.folder, "simulated_seconds": simulated_so_far(Path(run.folder)),
                                    "point": run.point})
                taken = []
            for run in ended + taken:
                future = submit(run, f"{tag}run-{run.name}", ended=run in ended)
                run_of[future.key] = run
                pending.add(future)
        attempts = {r.name: 1 for r in study.runs}
        stalls: dict[str, tuple] = {}  # run -> (paused attempts in a row without progress, time reached)

        def resubmit(run, result, future):
            """A run paused before its job's walltime goes back into the queue under a new key, however many
            jobs it takes; None after ``MAX_STALLS`` started attempts in a row without progress (or when
            the study is stopping)."""
            count, reached = stalls.get(run.name, (0, -1.0))
            if result.get("started", True):
                count = count + 1 if result["simulated_seconds"] <= reached else 0
            stalls[run.name] = (count, max(reached, result["simulated_seconds"]))
            if result.get("worker"):
                # the job is at its end: its worker takes no further run (retired before the resubmission,
                # or the scheduler could hand the run straight back to it), and adaptive scaling starts a
                # fresh job. Dask retires a worker only when no key lives on it alone, so the paused run's
                # result and its bed's state (now passed by value) are released first.
                if run.bed in beds and not isinstance(beds[run.bed], str):
                    beds[run.bed] = beds[run.bed].result()
                client.cancel([future])
                _retire(client, result["worker"])
            if count >= MAX_STALLS or (out / STOP_FILE).exists():
                return None
            attempts[run.name] += 1
            bar.message(f"{run.name}: paused at t = {result['simulated_seconds']:.4g} s before its job's walltime; "
                        f"resubmitted (attempt {attempts[run.name]})")
            retry = submit(run, f"{tag}run-{run.name}-{attempts[run.name]}")
            run_of[retry.key] = run
            return retry

        total = sum(r.duration for r in study.runs)
        results = []
        write_index(out, study, description=description)
        bar = _StudyProgress(study, started, log)
        reached = []  # the --until deadline, once reached
        while pending or len(queue):
            if until is not None and not reached and time.time() >= until:
                reached.append(time.time())
                bar.message(f"--until {clock(until, 'seconds')} reached: stopping; each running run checkpoints at "
                            "its next chunk; the same command continues the study")
                request_stop(out)
            top_up()
            if not pending:
                continue
            waiting = poll if until is None or reached else min(poll, max(1.0, until - time.time()))
            try:
                finished, pending = wait(pending, timeout=waiting, return_when="FIRST_COMPLETED")
            except TimeoutError:  # Dask's wait raises when nothing finished within the poll: show progress
                finished = set()
            for future in finished:
                try:
                    result = future.result()
                except Exception as exc:  # noqa: BLE001  (a bed failed or was stopped: its runs cannot start)
                    run = run_of[future.key]
                    name = run.name
                    stopped = isinstance(exc, StudyStopped) or (out / STOP_FILE).exists()
                    result = {"name": name, "family": run.family,
                              "status": Outcome.STOPPED if stopped else Outcome.FAILED,
                              "folder": run.folder, "simulated_seconds": 0.0, "point": run.point,
                              **({} if stopped else {"error": f"{type(exc).__name__}: {exc}"})}
                if result["status"] == Outcome.PAUSED:
                    retry = resubmit(run_of[future.key], result, future)
                    if retry is not None:
                        pending.add(retry)
                        write_index(out, study, [*results, result], description)
                        continue
                    if (out / STOP_FILE).exists():  # paused at its job's walltime as the study stops: its checkpoint
                        result = {**result, "status": Outcome.STOPPED}  # holds it, the next invocation continues it
                    else:
                        result = {**result, "status": Outcome.FAILED, "error": (
                            f"paused {MAX_STALLS} times in a row at t = {result['simulated_seconds']:.6g} s without "
                            "a step: its job's walltime less stop_before_walltime leaves no time for one chunk of "
                            "it; raise the cluster's walltime or lower stop_before_walltime")}
                results.append(result)
                detail = result.get("error") or (chosen.headline(result) if chosen.headline else "")
                bar.update(len(results))  # the ETA from what this invocation simulated (not runs skipped, restored)
                bar.message(progress_line(len(results), len(study.runs), result["name"], result["status"], detail,
                                          started, bar.bar.n, total, " simulated s", work_start=bar.initial))
                write_index(out, study, results, description)
            bar.update(len(results))
        bar.close()
    finally:
        close_client(client)
        for sig, handler in handlers.items():
            signal.signal(sig, handler)
    index = write_index(out, study, results, description)
    summary = {"study": study.name, "report": study.report, **({"design": study.design} if study.design else {}),
               "scheduler": description, "runs": index["runs"], "wall_seconds": time.perf_counter() - started}
    if (out / STOP_FILE).exists():
        summary["stopped"] = True
    if until is not None:
        summary["until"] = clock(until, "seconds")
        if reached:
            summary["until_reached"] = True
    write_text_atomic(out / "study.json", json.dumps(summary, indent=1) + "\n")
    return summary


def task_tag(study: Study, out) -> str:
    """The prefix of a study's Dask task keys: its name and a digest of its folder, so that two studies
    (or one study in two folders) on one shared scheduler never share a task (Dask keeps the first task
    of a key and hands its result to the second: another study's bed, settled at other settings)."""
    import hashlib
    digest = hashlib.sha1(str(Path(out).resolve()).encode()).hexdigest()[:10]
    return f"{study.name}-{digest}-"


def _pending(run: RunSpec) -> dict:
    return {"name": run.name, "family": run.family, "status": Outcome.PENDING, "folder": run.folder,
            "point": run.point, "simulated_seconds": simulated_so_far(Path(run.folder))}


def _holds(out: Path, entry: dict) -> bool:
    """Whether an index entry's run folder (``entry_folder``) exists."""
    return bool(entry.get("folder")) and entry_folder(out, entry).is_dir()


def write_index(out, study: Study, results=(), description: str | None = None) -> dict:
    """``study.json``: every run of ``study`` with its latest result (``results``, else the one on
    record, else ``pending`` with the simulated seconds its folder holds), so that ``--report`` works
    while a study runs; of the runs on record that ``study`` does not list, those ``--only`` left out
    (``study.left_out``) and those whose folder exists stay (flagged ``"planned": false``), a run taken out of
    the study file before it started goes; a run ``--only`` left out that the index has never listed (one new in
    the study file) joins it pending, so that ``--status`` counts what the study file plans. Returns the index
    written."""
    out = Path(out)
    path = out / "study.json"
    record = {}
    if path.exists():
        try:
            record = json.loads(path.read_text())
        except (OSError, json.JSONDecodeError):
            record = {}
    latest = {r["name"]: r for r in record.get("runs", [])}
    latest.update({r["name"]: r for r in results})
    names = [r.name for r in study.runs]
    planned = set(names) | {r.name for r in study.left_out}

    def unflagged(entry):  # an entry without its "planned" flag (a run the file plans, again)
        return {k: v for k, v in entry.items() if k != "planned"}

    def listed(run, result=None):  # the run's latest result (else pending) with what the study file says of it
        return {**unflagged(result or _pending(run)), "replica": run.replica, "duration": run.duration,
                "physics": run.physics, **dict(run.stops), "priority": run.priority}

    # the index keeps the runs ``--only`` left out, and a run the study file no longer plans while its folder
    # holds something (nothing on disk goes unlisted), flagged ``"planned": false`` (``--status`` and the report
    # neither count nor wait for it where it has not ended; ``--supersede`` moves its folder aside); one it no
    # longer plans that never started (a replica or point taken out of the file) leaves it
    runs = ([listed(r, latest.get(r.name)) for r in study.runs]
            + [unflagged(r) if n in planned else {**r, "planned": False}
               for n, r in latest.items() if n not in names and (n in planned or _holds(out, r))]
            + [listed(r) for r in study.left_out if r.name not in latest])
    index = {**{k: v for k, v in record.items() if k not in ("runs", "design")}, "study": study.name,
             "file": study.path, "report": study.report, **({"design": study.design} if study.design else {}),
             **({"scheduler": description} if description else {}), "runs": runs}
    write_text_atomic(path, json.dumps(index, indent=1) + "\n")
    return index

"""Studies: a sweep of runs over families of cases and axes of settings, run as tasks on Dask.

A study file (TOML) names its families (a base case and its own settings), the settled beds some of
them start from, the axes to vary, exclusions, the duration and replicas::

    name = "smoke"
    duration = 0.04                    # simulated seconds of every run (time.end)
    replicas = 1                       # repeats, each from its own bed (insertion seed + k - 1)
    report = "table"                   # its table, figures and findings: a registered report ("table" by default)
    [settings]                         # for every run and bed
    "output.vtk" = false
    [beds.small]                       # prepared once, before the runs that start from it
    case = "../cases/bed_ar1.toml"
    set = {"particles.count" = 300}
    [families.spheres]
    case = "../cases/ar1.toml"
    bed = "small"                      # particles.initial_state = the bed's final state
    set = {"particles.count" = 300}
    duration = 0.08                    # optional: this family's own duration
    [axes]
    "gas.u_over_umf" = [2.0, 2.9]
    [[exclude]]                        # drop the runs that match every key given (each one value or a list)
    family = "spheres"
    "gas.u_over_umf" = 2.9
    [cluster]                          # optional: where the tasks run
    kind = "local"                     # or "slurm", "pbs", "sge", "lsf" (dask-jobqueue), with its options
    workers = 2

Every run and every bed is one task on Dask distributed: a ``LocalCluster`` sized to the machine by
default, the ``--scheduler`` of a running cluster, or a dask-jobqueue cluster from ``[cluster]``. A
run's folder is ``OUT/runs/<name>``, a bed's ``OUT/beds/<name>``. A finished run (its summary
reached the duration) is skipped, an interrupted one resumed from its checkpoint (also when Dask
retries a task whose worker died), and a failed one reported with its cause without stopping the
others. Every case is checked before anything runs. Runs in progress go first (the nearest its end
first), then first replicas before second ones, longest first (most DEM steps left), so the last to
finish is not a long one begun late. A bed settles only for runs not at their end. A study folder lost
with its machine comes back from its archive (``--restore``: the runs it holds at their end are skipped).

Stopping: Ctrl-C or SIGTERM to ``fvdem study``, or ``fvdem study OUT --stop`` from anywhere, writes
``OUT/STOP``; each running run then checkpoints at its next chunk and returns ``stopped``, runs not
started do not start, and the same command continues later. ``--only NAME ...`` runs some of the
runs; ``study.json`` keeps the others' last results. ``study.json`` lists every run from the start
(``pending`` until its result comes), so ``fvdem study DIR --report`` works while a study runs.

The package, one module per job: ``sweep`` (the study file read and checked into beds and runs),
``cluster`` (where the runs go: the ``[cluster]`` table and the Dask client), ``tasks`` (what runs on a
worker), ``runner`` (the Dask runner, ``study.json``, ``map_tasks``), ``reports`` (the table, the figures
and the archive of the registered report), the leaves ``records``, ``registry`` and ``specs``, and the
designed experiments (``design``, ``designed``, ``screening``). A published study's report is a package of
its own (``fvdem.reports``), registered by name; what ends a run early (and when a study may skip it) comes from
the scenes' stop conditions (``fvdem.scenes.stops``).
"""
from .checks import read_toml
from .cluster import (CLUSTER_KINDS, CLUSTER_TYPES, DEFAULT_STOP_BEFORE_WALLTIME, JOB_END_ENV, STOP_MARGIN_ENV,
                      check_cluster, close_client, cluster_keys, job_deadline, jobqueue_options, load_cluster,
                      make_client, walltime_seconds)
from .reports import REPORTS, StudyReport, archive, register_report, report, report_for, restore, results
from .runner import map_tasks, progress_line, request_stop, run_study, task_tag, write_index
from .sweep import STUDY_KEYS, BedSpec, RunSpec, Study, load_study, select_runs, study_from_table
from .tasks import STOP_FILE, StudyStopped, prepare_bed, run_task

__all__ = ["CLUSTER_KINDS", "CLUSTER_TYPES", "DEFAULT_STOP_BEFORE_WALLTIME", "JOB_END_ENV", "REPORTS", "STOP_FILE",
           "STOP_MARGIN_ENV", "STUDY_KEYS", "BedSpec", "RunSpec", "Study", "StudyReport", "StudyStopped", "archive",
           "check_cluster", "close_client", "cluster_keys", "job_deadline", "jobqueue_options", "load_cluster",
           "load_study", "make_client", "map_tasks", "prepare_bed", "progress_line", "read_toml", "register_report",
           "report", "report_for", "request_stop", "restore", "results", "run_study", "run_task", "select_runs",
           "study_from_table", "task_tag", "walltime_seconds", "write_index"]

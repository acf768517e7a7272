"""Progress in a log file: one plain line every few per cent, no carriage returns (issue 19)."""
import io

from fvdem.io.progress import LineProgress, progress_bar


def test_line_progress_prints_a_line_every_five_percent_and_no_carriage_returns():
    stream = io.StringIO()
    bar = progress_bar(2.0, 0.0, "run", stream=stream)  # not a terminal
    assert isinstance(bar, LineProgress)
    for _ in range(400):  # 400 updates of 0.005 s
        bar.update(0.005)
        bar.set_postfix_str("90 steps/s")
    bar.close()
    text = stream.getvalue()
    lines = text.splitlines()
    assert "\r" not in text
    assert len(lines) == 20  # 5 %, 10 %, ..., 100 %
    assert lines[0].startswith("run:   5% 0.1000/2.0000 s, 90 steps/s, elapsed")
    assert lines[-1].startswith("run: 100% 2.0000/2.0000 s") and "left 0:00:00" in lines[-1]


def test_a_stopped_run_ends_its_log_with_where_it_stopped():
    stream = io.StringIO()
    bar = LineProgress(1.0, 0.25, "run", stream=stream)  # resumed at 25 %
    bar.update(0.28)  # one step across several 5 % marks: one line
    bar.update(0.01)  # stopped at 54 %: close() writes where
    bar.close()
    lines = stream.getvalue().splitlines()
    assert [line.split()[1] for line in lines] == ["53%", "54%"]


def test_fvdem_prefers_the_openmp_threading_layer_unless_the_user_chose_one():
    """With libtbb installed numba picks TBB, whose kernel launches made small systems up to 250 x
    slower; fvdem asks for OpenMP first, and leaves a user's NUMBA_THREADING_LAYER(_PRIORITY) alone."""
    import os
    import subprocess
    import sys
    code = ("import fvdem, numba, numpy\n"
            "from numba import njit, prange\n"
            "@njit(parallel=True)\n"
            "def f(a):\n"
            "    for i in prange(a.shape[0]):\n"
            "        a[i] += 1\n"
            "f(numpy.zeros(2))\n"
            "print(numba.config.THREADING_LAYER_PRIORITY[0], numba.threading_layer())\n")
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_THREADING_LAYER")}
    first, used = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                                 timeout=120, check=True).stdout.split()
    assert first == "omp" and used in ("omp", "tbb", "workqueue")
    env["NUMBA_THREADING_LAYER"] = "workqueue"
    _, used = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                             timeout=120, check=True).stdout.split()
    assert used == "workqueue"


def test_a_log_progress_ends_on_its_last_postfix_when_asked():
    """A study's progress in a log: its 100 % line may come while a run's result is still on its way (the
    run folders are read, not the results); with ``final_postfix`` the closing line says how many runs
    ended, without it (a run's steps per second) no line is repeated."""
    import io

    from fvdem.io.progress import LineProgress
    for final, lines in ((True, 2), (False, 1)):
        stream = io.StringIO()
        bar = LineProgress(1.0, desc="study", step_percent=2.0, stream=stream)
        bar.final_postfix = final
        bar.set_postfix_str("1/2 runs done")
        bar.update(1.0)
        bar.set_postfix_str("2/2 runs done")
        bar.close()
        printed = stream.getvalue().splitlines()
        assert len(printed) == lines and "100%" in printed[-1]
        assert ("2/2 runs done" in printed[-1]) == final

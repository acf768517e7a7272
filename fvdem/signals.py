"""SIGINT and SIGTERM while a run with an output folder runs: they ask it to stop at its next chunk
(checkpoint written) instead of killing it; outside the main thread (a study's worker) they cannot be
caught, and the study's stop file does the same."""
from __future__ import annotations

import contextlib
import signal


@contextlib.contextmanager
def stop_on_signals(request_stop, enabled: bool = True):
    """While the block runs, SIGINT and SIGTERM call ``request_stop`` (the previous handlers after)."""
    handlers = {}
    if enabled:
        try:
            handlers = {s: signal.signal(s, request_stop) for s in (signal.SIGINT, signal.SIGTERM)}
        except ValueError:  # not in the main thread
            handlers = {}
    try:
        yield
    finally:
        for sig, handler in handlers.items():
            signal.signal(sig, handler)

"""``timeseries.csv``: one row of scalar diagnostics per output interval."""
from __future__ import annotations

import csv
from pathlib import Path


class TimeseriesWriter:
    """Append rows to a CSV file; on resume, rows later than the checkpoint are dropped."""

    def __init__(self, path, columns):
        self.path = Path(path)
        self.columns = list(columns)

    def start(self, resume_time: float | None = None) -> None:
        if resume_time is None or not self.path.exists():
            with open(self.path, "w", newline="") as fh:
                csv.writer(fh).writerow(self.columns)
            return
        with open(self.path, newline="") as fh:
            rows = list(csv.reader(fh))
        kept = [r for r in rows[1:] if r and float(r[0]) <= resume_time * (1 + 1e-12)]
        if rows[0] != self.columns:  # written by another version: its columns kept by name, new ones nan
            where = {name: k for k, name in enumerate(rows[0])}
            kept = [[r[where[c]] if c in where else "nan" for c in self.columns] for r in kept]
        kept = [self.columns] + kept
        with open(self.path, "w", newline="") as fh:
            csv.writer(fh).writerows(kept)

    def append(self, values: dict) -> None:
        with open(self.path, "a", newline="") as fh:
            csv.writer(fh).writerow([repr(float(values[c])) for c in self.columns])

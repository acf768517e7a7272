"""The run table's columns of seed 000's study (``table_columns``): t95, the bed's pressure drop, height and
expansion over one window, the dense bed, the outlet's share, the channels, the entropy at fixed times, the void
fractions' binarity and the overlaps; what a run in progress holds (``live_values``), its progress line
(``headline``) and what an archive keeps of its snapshots (``archive_extra``: the void-fraction, channel and
colour-by-layer records)."""
from __future__ import annotations

import json
import math
from pathlib import Path

from ...analysis.plots import COLOUR_LAYERS
from ...scenes.observables import colour_layer_record
from ...study.records import folder_case
from .families import row_ended, row_failed


# s: the window of the bed's height and of its channels, the same in every run whatever its length (8 s,
# 20 s, or ended 2 s past t95: ``time.stop_after_mixed``): from this long after the inlet reached its velocity,
# for ``WINDOW``
WINDOW_START, WINDOW = 1.0, 3.0


def _window_mean(series, column: str, ramp: float | None = None):
    """The mean of a time-series column from ``WINDOW_START`` after the inlet ramp (``ramp`` [s]) for ``WINDOW``
    (to the run's end if sooner); without a ramp known, or before the run reaches that window, over the second
    half of its time series. One window for all runs: AR-1's first replicas' beds stood 1-5 % higher over their
    second halves (4-8 s) than over 2.75-5.5 s, enough to decide AR-1 against AR-4 by run length. None without
    the column. ``series``: ``_series``'s (None, or at least one row)."""
    import numpy as np
    if series is None or column not in series:
        return None
    times = series["time"]
    start = None if ramp is None else ramp + WINDOW_START
    if start is None or times[-1] <= start:
        return float(np.mean(series[column][times >= 0.5 * times[-1]]))
    return float(np.mean(series[column][(times >= start) & (times <= start + WINDOW)]))


def _bed_surface(series, ramp: float | None = None):
    """The bed's height [m] as the table gives it: ``bed_top`` (the height below which 99 % of the particle tops
    lie) over the window (``_window_mean``). The summary's ``bed_height`` is a packed bed's (solid volume over
    area and core solids fraction): in a fluidized bed it exceeds the column (1.37 m in the 1.05 m column for
    AR-1 at 2.9 Umf)."""
    return _window_mean(series, "bed_top", ramp)


def _bed_expansion(series, ramp: float | None = None):
    """The bed's expansion: its height (``_bed_surface``) over ``bed_top`` at the run's start (the settled bed
    it started from); None without it."""
    surface = _bed_surface(series, ramp)
    return None if surface is None or series["bed_top"][0] <= 0 else surface / float(series["bed_top"][0])


DENSE = 0.9  # the dense bed: the height under this share of the particle centres (``_dense_bed_expansion``)


def _centre_quantile(count, z_lower: float, layer_height: float, share: float = DENSE) -> float | None:
    """The height [m] under which ``share`` of the particle centres lie, from their counts in horizontal layers
    from ``z_lower`` up (``colour_layer_record``), the centres spread evenly within the layer it falls in. None
    without particles."""
    cumulative, total = [], 0
    for n in count:
        total += n
        cumulative.append(total)
    if total <= 0:
        return None
    target = share * total
    layer = next(i for i, c in enumerate(cumulative) if c >= target)
    below = cumulative[layer - 1] if layer else 0
    return z_lower + layer_height * (layer + (target - below) / count[layer])


def _dense_bed_expansion(record: dict | None, ramp: float | None = None) -> float | None:
    """The dense bed's expansion: the height under 90 % (``DENSE``) of the particle centres (``_centre_quantile``)
    over the window (``_window_mean``, at the particle snapshots: every 0.5 s) over its value at the first
    snapshot (the settled bed). Beside ``_bed_expansion`` (99 % of the tops), which the few particles thrown above
    the bed set: at 1.6-1.7 Umf AR-4 MP's 99 % height stood 1.6-2.6 times its settled value by the chance of a
    spout (1 % of the rods thrown to 0.6-0.9 m) while its 90 % height stood 1.2-1.4 times, below AR-1's 1.5-1.8
    (2026-12-05). ``record``: ``colour_layer_record``'s (None for a run without snapshots or an archived record:
    those archived before 2026-12-04 have none); None without it or its first snapshot's height."""
    import numpy as np
    if record is None or not record.get("count"):
        return None
    heights = [_centre_quantile(c, record["z_lower"], record["layer_height"]) for c in record["count"]]
    if heights[0] is None or heights[0] <= 0 or None in heights:
        return None
    window = _window_mean({"time": np.asarray(record["times"], float), "dense": np.asarray(heights)}, "dense", ramp)
    return window / heights[0]


ROOF_MARGIN = 0.01  # m: a bed top within this of the column's outlet is the outlet's


def _at_roof(series, roof: float | None, ramp: float | None = None):
    """The share of the window's samples (``_window_mean``) at which ``bed_top`` stands at the column's outlet
    (within ``ROOF_MARGIN`` of ``roof`` [m]): rods or spheres thrown up and pinned against the outlet by the gas
    leaving through them (AR-4 MP at 2.9 Umf: 1,055-1,095 rods, 3.3 %, from 1.5 s), so that the height below
    which 99 % of the tops lie is the outlet's, not the bed's. None without the column or the roof."""
    if roof is None or series is None or "bed_top" not in series:
        return None
    at_roof = {**series, "bed_top": (series["bed_top"] >= roof - ROOF_MARGIN).astype(float)}
    return _window_mean(at_roof, "bed_top", ramp)


def _reaches_roof(series, roof: float | None) -> bool:
    """Whether a run's bed top (``bed_top`` of its series) ever stood at the column's outlet (within
    ``ROOF_MARGIN`` of ``roof`` [m]); False without the column, the series or its bed top."""
    if roof is None or series is None or "bed_top" not in series or not len(series["bed_top"]):
        return False
    return float(series["bed_top"].max()) >= roof - ROOF_MARGIN


def _roof_share(series, roof: float | None, record: dict | None):
    """The share of the particles in the column's top layer of the mixing grid (0.03 m under the outlet on the
    paper's grid) at the run's last particle snapshot, from ``record`` (``colour_layer_record``'s): those pinned
    at the outlet (AR-4 MP at 2.9 Umf: 3.3 % of the rods at 3 s, 4.7 % at 6 s; SP at 2.6: 10 % from 1.5 s on).
    0 where the bed's top never reached the outlet (``_reaches_roof``: the record need not be read then); None
    without the column, the series or the record."""
    if roof is None or series is None or "bed_top" not in series:
        return None
    if not _reaches_roof(series, roof):
        return 0.0
    if record is None or not record["count"]:
        return None
    last = record["count"][-1]
    reaches = record["z_lower"] + record["layer_height"] * len(last)  # the record stops at the highest layer reached
    if not sum(last) or reaches < roof - 1e-9:
        return 0.0
    return last[-1] / sum(last)


def _gas(folder: Path):
    """The gas settings of a run's case.toml; None without a readable one."""
    case = folder_case(folder)
    return None if case is None else case.gas


def _inlet_passes_umf(gas) -> float | None:
    """When [s] a run's inlet velocity reaches the Umf its ``u_over_umf`` refers to: ``inlet_ramp / u_over_umf``
    for a linear ramp from 0 (0 for a full-speed start); None without the case's gas settings or a U/Umf."""
    if gas is None or not gas.u_over_umf:
        return None
    return gas.inlet_ramp / gas.u_over_umf if gas.u_over_umf >= 1.0 else None


def void_fraction_samples(folder, below=0.3):
    """Cell void fractions of the cells whose centres are below ``below`` [m], over the second half of
    a run's gas snapshots (the fluidized state, not the start-up), pooled; empty without snapshots."""
    import meshio
    import numpy as np
    snapshots = sorted(Path(folder).glob("gas_*.vtu"))
    values = []
    for snapshot in snapshots[len(snapshots) // 2:] if len(snapshots) > 1 else []:
        grid = meshio.read(snapshot)
        centres = grid.points[grid.cells[0].data].mean(axis=1)
        values.append(np.asarray(grid.cell_data["voidage"][0])[centres[:, 2] < below])
    return np.concatenate(values) if values else np.zeros(0)


VOID_FRACTION = "void_fraction.json"  # an archived run's void-fraction record (its gas snapshots are not kept)


def void_fraction_record(folder, below=0.3) -> dict | None:
    """A run's cell void fractions below ``below`` [m] over the second half of its gas snapshots, as a
    20-bin density histogram on [0, 1], their binarity (``void_fraction_binarity``) and count; from the
    snapshots, else from an archived run's ``void_fraction.json``; None without either."""
    import numpy as np
    from ...analysis.mixing import void_fraction_binarity
    values = void_fraction_samples(folder, below)
    if values.size:
        counts, edges = np.histogram(values, bins=20, range=(0.0, 1.0), density=True)
        binarity = void_fraction_binarity(values)
        return {"below": below, "edges": edges.tolist(), "density": counts.tolist(), "cells": int(values.size),
                "binarity": None if math.isnan(binarity) else binarity}
    stored = Path(folder) / VOID_FRACTION
    return json.loads(stored.read_text()) if stored.exists() else None


WINDOW_TIMES = tuple(1.0 + 0.5 * k for k in range(15))  # s: 1.0, 1.5, ..., 8.0: the entropy curve's window
ENTROPY_TIMES = (2.0, 4.0, 6.0, 8.0)  # s: the entropy at fixed times the table shows beside its window mean


def entropy_columns(series, ended_mixed: bool) -> dict:
    """A run's mixing entropy at ``ENTROPY_TIMES`` (``mixing_entropy_at_<t>``) and averaged over ``WINDOW_TIMES``
    (``mixing_entropy_window``), from its time series; a time past the series' end holds the last value where
    the run ended mixed, else None (not reached yet)."""
    import numpy as np
    keys = [f"mixing_entropy_at_{t:g}" for t in ENTROPY_TIMES] + ["mixing_entropy_window"]
    if series is None or "mixing_entropy" not in series or not len(series["time"]):
        return dict.fromkeys(keys)
    time, entropy = np.asarray(series["time"], float), np.asarray(series["mixing_entropy"], float)

    def at(t):
        if t > time[-1] + 1e-9 and not ended_mixed:
            return None
        return float(np.interp(t, time, entropy))

    values = {f"mixing_entropy_at_{t:g}": at(t) for t in ENTROPY_TIMES}
    window = [at(t) for t in WINDOW_TIMES]
    values["mixing_entropy_window"] = None if None in window else float(sum(window) / len(window))
    return values


def live_values(series) -> dict:
    """A run in progress from its time series: t95 (None if not yet mixed), and the bed pressure drop over
    W/A and its fluctuation over the second half of what it holds."""
    import numpy as np
    from ...analysis.plots import series_t95
    times = series["time"]
    out = {"t95": series_t95(series)}
    if "pressure_drop_over_weight" in series and len(times) > 1:
        half = series["pressure_drop_over_weight"][times >= 0.5 * times[-1]]
        out["pressure_drop_over_weight"] = float(np.mean(half))
        out["pressure_drop_std_over_weight"] = float(np.std(half))
    return out


def table_columns(r: dict, folder: Path, data: dict, series) -> dict:
    """t95 and t95 counted from when the inlet passes Umf, the column's height (its outlet), the bed's pressure
    drop over W/A and its fluctuation, the bed height and expansion, the largest cell gas speed over the inlet
    velocity over the same window (a channel's mark: 3.1-3.5 in AR-1's beds at 1.6-2.9 Umf, 5.5-5.8 in AR-4 MP's
    at 1.6, 8 there from 8 s on, where corner and wall channels of void fraction 0.9-1 carry the gas up the bed),
    over the same window the share of its samples with the bed's top at the outlet (``_at_roof``) and, at its last
    snapshot, the share of its particles pinned there (``_roof_share``), the share of the rising gas in the corner
    and wall columns of the lower bed and the rods' mean |a_z| inside and in the corners (``channel_record``),
    the mixing entropy at the end and the one its bed would
    have with its colours shuffled at random (the grid's ceiling; runs that ended from 2026-12-04 on), the
    void fractions' binarity and the largest overlap's median, 99th percentile and maximum (``_overlaps``)."""
    record = void_fraction_record(folder) if not row_failed(r) else None
    case = folder_case(folder)
    gas, roof = (None, None) if case is None else (case.gas, case.domain.upper[2])
    passes, ramp = _inlet_passes_umf(gas), None if gas is None else gas.inlet_ramp
    fastest = _window_mean(series, "gas_max_speed", ramp)
    t95 = r.get("t95")
    # the colour-by-layer record (snapshots read unless archived), once: for the dense bed of an ended run and
    # the share pinned at the outlet of one whose top reached it
    layers = colour_layer_record(folder) if row_ended(r) or _reaches_roof(series, roof) else None
    return {"t95": t95, "inlet_passes_umf": passes, "column_height": roof, "cpu_seconds": data.get("cpu_seconds"),
            "t95_from_inlet_at_umf": None if t95 is None or passes is None else t95 - passes,
            "pressure_drop_over_weight": data.get("pressure_drop_over_weight"),
            "pressure_drop_std_over_weight": (data["bed_pressure_drop_std_second_half"] / data["bed_weight_per_area"]
                                              if "bed_pressure_drop_std_second_half" in data
                                              else data.get("pressure_drop_std_over_weight")),
            "bed_height": _bed_surface(series, ramp), "bed_expansion": _bed_expansion(series, ramp),
            "dense_bed_expansion": _dense_bed_expansion(layers, ramp) if row_ended(r) else None,
            "bed_at_roof": _at_roof(series, roof, ramp), "roof_share": _roof_share(series, roof, layers),
            "gas_max_speed_over_inlet": (None if fastest is None or gas is None or not gas.inlet_velocity
                                         else fastest / gas.inlet_velocity),
            **(_channel_means(folder, ramp) if not row_failed(r) else {}),
            "final_mixing_entropy": (float(series["mixing_entropy"][-1])
                                     if series is not None and "mixing_entropy" in series else None),
            "mixing_entropy_random": data.get("mixing_entropy_random"),
            "void_fraction_binarity": None if record is None else record["binarity"], **_overlaps(series),
            **entropy_columns(series, t95 is not None)}


def _overlaps(series) -> dict:
    """The contacts' depth over the whole run, from the largest overlap in the bed at each sample (fraction of
    a diameter): its median, 99th percentile and largest (``overlap_median``, ``overlap_p99``, ``overlap_max``;
    None without the column). The spring's softness at a glance: the defaults were chosen on 5.4 % (AR-1) and
    7.2 % (AR-4) in 2,000-particle beds (docs/speed-accuracy.md); single samples far above them are impacts."""
    import numpy as np
    keys = ("overlap_median", "overlap_p99", "overlap_max")
    if series is None or "max_overlap_over_diameter" not in series:
        return dict.fromkeys(keys)
    values = np.asarray(series["max_overlap_over_diameter"], float)
    return dict(zip(keys, (float(np.median(values)), float(np.percentile(values, 99)), float(values.max()))))


CHANNELS = "channels.json"  # an archived run's channel record (``channel_record``)
CHANNEL_LAYERS = (0.05, 0.2)  # m: the lower bed, where AR-4 MP's corner channels were found (2026-12-03)


def channel_record(folder, window: tuple | None = None) -> dict | None:
    """Per gas snapshot of a run (those at times in ``window`` [s], all without one): the share of the rising
    gas in the corner, wall and inside columns over ``CHANNEL_LAYERS`` and, for rods, their mean |a_z| there by
    the same classes (``fvdem.analysis.channels``). From the snapshots, else from an archived ``channels.json``;
    None without either. ``{"z_range", "cells", "rows": [{"time", "gas_corner", ..., "alignment_inside"}]}``."""
    import meshio
    import numpy as np

    from ...analysis.channels import gas_shares, rod_alignment
    from ...io.vtk import read_pvd
    folder = Path(folder)
    wanted = (lambda t: True) if window is None else (lambda t: window[0] - 1e-9 <= t <= window[1] + 1e-9)
    snapshots = [(t, name) for t, name in read_pvd(folder / "gas.pvd") if wanted(t)]
    if not snapshots:
        stored = folder / CHANNELS
        if not stored.exists():
            return None
        record = json.loads(stored.read_text())
        return {**record, "rows": [r for r in record["rows"] if wanted(r["time"])]}
    case = folder_case(folder)
    if case is None:
        return None
    lower, upper, cells = case.domain.lower, case.domain.upper, tuple(case.gas.cells)
    rods = case.particles.shape == "spherocylinder"
    particles = dict(read_pvd(folder / "particles.pvd")) if rods else {}
    rows = []
    for t, name in snapshots:
        grid = meshio.read(folder / name)
        centres = grid.points[grid.cells[0].data].mean(axis=1)
        if "superficial_velocity" not in grid.cell_data:  # not a gas snapshot fvdem wrote
            continue
        flux = np.asarray(grid.cell_data["superficial_velocity"][0])[:, 2]
        row = {"time": t, **{f"gas_{k}": v for k, v in
                             gas_shares(centres, flux, lower, upper, cells, CHANNEL_LAYERS).items()}}
        if t in particles and (folder / particles[t]).exists():
            state = meshio.read(folder / particles[t])
            row.update({f"alignment_{k}": v for k, v in rod_alignment(
                state.points, state.point_data["axis"], lower, upper, cells, CHANNEL_LAYERS).items()})
        rows.append(row)
    return {"z_range": list(CHANNEL_LAYERS), "cells": list(cells), "rows": rows}


def _channel_means(folder: Path, ramp: float | None) -> dict:
    """The channel record's means over the window of ``_window_mean`` (``WINDOW_START`` after the ramp, for
    ``WINDOW``): ``corner_gas_share``, ``wall_gas_share``, ``rod_alignment_inside`` and ``rod_alignment_corner``
    (None where the run has no snapshots in it, or no rods)."""
    keys = {"corner_gas_share": "gas_corner", "wall_gas_share": "gas_wall", "rod_alignment_inside": "alignment_inside",
            "rod_alignment_corner": "alignment_corner"}
    start = (ramp or 0.0) + WINDOW_START
    record = channel_record(folder, (start, start + WINDOW))
    rows = [] if record is None else record["rows"]
    means = {}
    for column, key in keys.items():
        values = [r[key] for r in rows if r.get(key) is not None]
        means[column] = float(sum(values) / len(values)) if values else None
    return means


def archive_extra(folder: Path, target: Path) -> None:
    """What an archived run keeps of its snapshots: the void-fraction record, the channel record and the colour
    by layer (``fvdem report`` on the archived run draws ``colour_layers.png`` from it)."""
    record = void_fraction_record(folder)
    if record is not None:
        (target / VOID_FRACTION).write_text(json.dumps(record) + "\n")
    channels = channel_record(folder)
    if channels is not None:
        (target / CHANNELS).write_text(json.dumps(channels) + "\n")
    layers = colour_layer_record(folder)
    if layers is not None:
        (target / COLOUR_LAYERS).write_text(json.dumps(layers) + "\n")


def headline(result: dict) -> str:
    return f"t95 {result['t95']:.3g} s" if result.get("t95") is not None else "t95 -"

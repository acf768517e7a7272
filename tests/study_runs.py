"""Shared by the study tests: the repository's study files, and run folders and studies of a few steps."""
import json
from pathlib import Path

from fvdem.study import RunSpec

from paths import ROOT

SMOKE = ROOT / "studies" / "smoke.toml"


def synthetic_text() -> str:
    """The engine's synthetic study: the smoke study's bed, family and two velocities (150 spheres, 0.02 s), its
    cases by absolute path and the generic report ("table"), as text to write anywhere."""
    return (SMOKE.read_text().replace('"../cases/', f'"{ROOT / "cases"}/')
            .replace('report = "mema2020"', 'report = "table"'))


def synthetic_study(folder) -> Path:
    """``synthetic_text`` written to ``folder/synthetic.toml``."""
    path = Path(folder) / "synthetic.toml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(synthetic_text())
    return path


def one_run_study(tmp_path, name, checkpoint_interval):
    """A study of one 0.3 s run of the 150-sphere demo bed at 2 Umf (run small_u_over_umf2)."""
    study = tmp_path / f"{name}.toml"
    study.write_text(f'''name = "{name}"
duration = 0.3
[settings]
"output.vtk" = false
"output.checkpoint_interval" = {checkpoint_interval}
"output.timeseries_interval" = 0.005
[families.small]
case = "{ROOT / 'cases' / 'demo.toml'}"
[families.small.set]
"particles.count" = 150
[axes]
"gas.u_over_umf" = [2.0]
''')
    return study


def small_run(tmp_path, end):
    """A study folder and one run of the 150-sphere demo bed to ``end`` [s] (checkpoints every 2 ms)."""
    bed_case = ROOT / "cases" / "demo.toml"
    out = tmp_path / "study"
    folder = out / "runs" / "demo"
    return out, RunSpec("demo", "demo", str(bed_case), {"time.end": end, "output.vtk": False,
                                                       "output.checkpoint_interval": 0.002,
                                                       "output.timeseries_interval": 0.001,
                                                       "particles.count": 150}, str(folder), None, {}, end)


def fake_run(folder, family, ratio, entropy_rate, voidage):
    """A finished run folder as a study leaves it: case, time series, summary, log, gas snapshots, a state."""
    import meshio
    import numpy as np
    folder.mkdir(parents=True)
    (folder / "case.toml").write_text(f'name = "{family}"\n[gas]\nenabled = true\numf = 1.58\nu_over_umf = {ratio}\n')
    t = np.linspace(0.0, 4.0, 401)
    columns = {"time": t, "kinetic_energy": 1e-3 + 0 * t, "mixing_entropy": 1 - np.exp(-entropy_rate * t),
               "pressure_drop_over_weight": 1.0 + 0.2 * np.sin(7 * t), "bed_top": 0.4 + 0.02 * np.sin(3 * t)}
    (folder / "timeseries.csv").write_text(",".join(columns) + "\n" + "".join(
        ",".join(repr(float(c[k])) for c in columns.values()) + "\n" for k in range(len(t))))
    (folder / "summary.json").write_text(json.dumps({"simulated_time": 4.0, "wall_seconds": 100.0, "t95": None,
                                                     "cpu_seconds": 90.0, "peak_memory_mb": 350.0, "threads": 1,
                                                     "bed_pressure_drop_std_second_half": 150.0,
                                                     "bed_weight_per_area": 1000.0, "pressure_drop_over_weight": 1.0,
                                                     "provenance": {"fvdem": "x", "host": "vm", "threads": 1,
                                                                    "cpu": "AMD EPYC (family 26, model 2), 2 CPUs"},
                                                     "timings": {"total": 100.0}}))
    (folder / "run.log").write_text("started\nreached its end\n")
    (folder / "checkpoint.npz").write_bytes(b"not small in a real run")
    x, y, z = np.meshgrid(np.linspace(0, 0.15, 3), np.linspace(0, 0.15, 3), np.linspace(0, 0.6, 5), indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    index = np.arange(points.shape[0]).reshape(x.shape)
    cells = [[index[i, j, k], index[i + 1, j, k], index[i + 1, j + 1, k], index[i, j + 1, k], index[i, j, k + 1],
              index[i + 1, j, k + 1], index[i + 1, j + 1, k + 1], index[i, j + 1, k + 1]]
             for i in range(2) for j in range(2) for k in range(4)]
    from fvdem.io.vtk import write_pvd
    for snapshot in range(4):
        values = np.asarray(voidage, float)[(np.arange(16) + snapshot) % len(voidage)]
        rising = np.column_stack([np.zeros(16), np.zeros(16), 1.0 + np.arange(16) % 3])
        meshio.write(folder / f"gas_{snapshot:05d}.vtu", meshio.Mesh(points, [("hexahedron", cells)], cell_data={
            "voidage": [values], "superficial_velocity": [rising]}))
    write_pvd(folder / "gas.pvd", [(1.0 * k, f"gas_{k:05d}.vtu") for k in range(4)])

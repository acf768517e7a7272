"""fvdem's DEM against LIGGGHTS on the same settled bed, in the same run (issue 16, point 4).

    python tools/compare_liggghts.py --json
    python tools/compare_liggghts.py --steps 2000 --ranks 1 2 --json

Writes fvdem's settled 32,500-sphere bed (``runs/bed_ar1/final_state.npz``: run ``fvdem run
cases/bed_ar1.toml --out runs/bed_ar1`` first) as a LIGGGHTS data file with an input script of the
same contact model: linear spring-dashpot (``hooke/stiffness``, the force never attractive), a linear
tangential spring-dashpot with history and Coulomb limit (k_t / k_n and the dashpot ratio of the case),
constant-directional-torque rolling friction, the case's walls, gravity and time step, and the
neighbour skin fvdem uses. The normal dashpot is fvdem's calibrated one for a pair (LIGGGHTS applies
the same to walls, where fvdem calibrates separately). Runs LIGGGHTS (``liggghts``, Debian/Ubuntu
``apt-get install liggghts``; ``mpirun`` for several ranks) for ``--steps`` steps after a warm-up and
takes its "Loop time"; runs fvdem's DEM on the same state for the same steps at 1 and 2 threads
(``tools/bench_dem.py``'s measurement). Prints one JSON object as the last line, with both costs in
ns per particle-step and their ratios per core count. Without LIGGGHTS it says so and reports fvdem.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
from _beds import settled_beds, settled_dem  # noqa: E402


def write_data(path: Path, particles, lower, upper) -> None:
    """A LIGGGHTS ``read_data`` file for ``atom_style granular``: id type diameter density x y z, and
    the velocities (v, omega)."""
    n = particles.count
    lines = ["LIGGGHTS data file written by fvdem tools/compare_liggghts.py", "", f"{n} atoms", "1 atom types", "",
             f"{lower[0]:.9g} {upper[0]:.9g} xlo xhi", f"{lower[1]:.9g} {upper[1]:.9g} ylo yhi",
             f"{lower[2]:.9g} {upper[2]:.9g} zlo zhi", "", "Atoms", ""]
    density = particles.mass / (4.0 / 3.0 * np.pi * particles.radius ** 3)
    for k in range(n):
        x, y, z = particles.position[k]
        lines.append(f"{k + 1} 1 {2 * particles.radius[k]:.12g} {density[k]:.12g} {x:.12g} {y:.12g} {z:.12g}")
    lines += ["", "Velocities", ""]
    for k in range(n):
        v, w = particles.velocity[k], particles.angular_velocity[k]
        lines.append(f"{k + 1} {v[0]:.12g} {v[1]:.12g} {v[2]:.12g} {w[0]:.12g} {w[1]:.12g} {w[2]:.12g}")
    path.write_text("\n".join(lines) + "\n")


def input_script(case, dem, data: str, steps: int, warmup: int) -> str:
    """The LIGGGHTS input of the same contact model, walls, gravity, step and skin."""
    from fvdem.dem.contact_law import K_N, K_T, ZETA_N, normal_damping
    p = dem.particles
    m_eff = 0.5 * float(p.mass[0])
    k_n, k_t = float(dem.params[K_N]), float(dem.params[K_T])
    eta_n = normal_damping(float(dem.params[ZETA_N]), m_eff, k_n)
    gamma_n = eta_n / m_eff  # hooke/stiffness without absolute damping multiplies by the effective mass
    gamma_t = gamma_n * case.contact.tangential_damping_ratio
    lo, hi = case.domain.lower, case.domain.upper
    model = "model hooke/stiffness tangential history rolling_friction cdt"
    walls = "\n".join(f"fix w{k} all wall/gran {model} primitive type 1 {axis}plane {value:.9g}"
                      for k, (axis, value) in enumerate((("x", lo[0]), ("x", hi[0]), ("y", lo[1]), ("y", hi[1]),
                                                         ("z", lo[2]), ("z", hi[2]))))
    g = np.asarray(case.domain.gravity, float)
    gnorm = float(np.linalg.norm(g))
    return f"""# written by fvdem tools/compare_liggghts.py: the settled bed of cases/bed_ar1.toml
atom_style granular
atom_modify map array
boundary f f f
# the bed fills the bottom fifth of the column: split the ranks across its section, not its height
processors * * 1
newton off
communicate single vel yes
units si
read_data {data}
neighbor {dem.skin:.9g} bin
neigh_modify delay 0
fix m1 all property/global kn peratomtypepair 1 {k_n:.12g}
fix m2 all property/global kt peratomtypepair 1 {k_t:.12g}
fix m3 all property/global gamman peratomtypepair 1 {gamma_n:.12g}
fix m4 all property/global gammat peratomtypepair 1 {gamma_t:.12g}
fix m5 all property/global coefficientFriction peratomtypepair 1 {case.contact.friction:.12g}
fix m6 all property/global coefficientRollingFriction peratomtypepair 1 {case.contact.rolling_friction:.12g}
pair_style gran {model} limitForce on tangential_damping on
pair_coeff * *
timestep {case.time.dem_step:.12g}
fix gravi all gravity {gnorm:.9g} vector {g[0] / gnorm:.9g} {g[1] / gnorm:.9g} {g[2] / gnorm:.9g}
{walls}
fix integr all nve/sphere
thermo_style custom step atoms ke
thermo {max(steps, warmup)}
run {warmup}
run {steps}
"""


LOOP = re.compile(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms")


def run_liggghts(executable: str, folder: Path, ranks: int, timeout: float) -> dict:
    command = [executable, "-in", "in.bench", "-log", f"log.{ranks}", "-echo", "none", "-screen", "none"]
    if ranks > 1:
        mpirun = shutil.which("mpirun")
        if mpirun is None:
            return {"error": "mpirun not found (needed for more than one rank)"}
        command = [mpirun, "--allow-run-as-root", "--oversubscribe", "-np", str(ranks)] + command
    wall = time.perf_counter()
    proc = subprocess.run(command, cwd=folder, capture_output=True, text=True, timeout=timeout)
    wall = time.perf_counter() - wall
    log = (folder / f"log.{ranks}").read_text() if (folder / f"log.{ranks}").exists() else proc.stdout
    loops = LOOP.findall(log)
    if proc.returncode != 0 or not loops:
        tail = (proc.stderr or log).strip().splitlines()[-5:]
        return {"error": f"liggghts exited {proc.returncode}: " + " | ".join(tail)}
    seconds, procs, steps, atoms = loops[-1]
    seconds, steps, atoms = float(seconds), int(steps), int(atoms)
    return {"ranks": int(procs), "steps": steps, "atoms": atoms, "loop_seconds": seconds,
            "ns_per_particle_step": 1e9 * seconds / (steps * atoms), "process_wall_seconds": wall}


def liggghts_version(executable: str, folder: Path) -> str | None:
    try:  # in the work folder: LIGGGHTS writes log.liggghts where it starts
        out = subprocess.run([executable, "-h", "-log", "none"], capture_output=True, text=True, timeout=30,
                             cwd=folder).stdout
    except (OSError, subprocess.TimeoutExpired):
        return None
    match = re.search(r"LIGGGHTS[^\n]*", out)
    return match.group(0).strip() if match else None


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--state", type=Path, help="a settled sphere bed (default: runs/bed_ar1's, settled first "
                                                   "when missing)")
    parser.add_argument("--steps", type=int, default=1000, help="measured steps (after a warm-up)")
    parser.add_argument("--ranks", type=int, nargs="+", default=[1, 2], help="LIGGGHTS MPI ranks (and fvdem threads)")
    parser.add_argument("--liggghts", default="liggghts", help="the LIGGGHTS executable")
    parser.add_argument("--keep", type=Path, help="write the LIGGGHTS data, input and logs here")
    parser.add_argument("--quick", action="store_true", help="a 1,500-sphere bed, 20 steps, 1 rank (seconds)")
    parser.add_argument("--json", action="store_true", help="the result as one JSON line")
    args = parser.parse_args(argv)
    if shutil.which(args.liggghts) is None:  # before anything is settled or measured
        print(f"compare_liggghts: LIGGGHTS ({args.liggghts!r}) not found: apt-get install liggghts, or --liggghts PATH",
              file=sys.stderr)
        return 2
    if args.quick:
        args.steps, args.ranks = 20, [1]
    if args.state is None:
        args.state = settled_beds(["ar1"], "compare_liggghts", args.quick)["ar1"]
    elif not args.state.exists():
        print(f"compare_liggghts: --state {args.state}: no such file", file=sys.stderr)
        return 2
    case, dem = settled_dem("ar1", args.state)
    particles = dem.particles
    result = {"bed": str(args.state), "particles": particles.count, "steps": args.steps,
              "dem_step": case.time.dem_step, "normal_stiffness": case.contact.normal_stiffness}
    executable = shutil.which(args.liggghts)
    liggghts = {}
    if executable is None:
        result["liggghts"] = {"error": f"{args.liggghts!r} not found: apt-get install liggghts"}
    else:
        folder = args.keep or Path(tempfile.mkdtemp(prefix="fvdem_liggghts_"))
        folder.mkdir(parents=True, exist_ok=True)
        write_data(folder / "bed.data", particles, case.domain.lower, case.domain.upper)
        (folder / "in.bench").write_text(input_script(case, dem, "bed.data", args.steps, warmup=50))
        for ranks in args.ranks:
            liggghts[f"ranks_{ranks}"] = run_liggghts(executable, folder, ranks, timeout=3600)
            print(f"LIGGGHTS, {ranks} rank(s): {json.dumps(liggghts[f'ranks_{ranks}'])}", file=sys.stderr)
        liggghts["version"] = liggghts_version(executable, folder)
        liggghts["folder"] = str(folder)
        result["liggghts"] = liggghts
    from bench_dem import worker
    fv = worker("sphere", args.state, args.steps)
    result["fvdem"] = fv
    ratios = {}
    for ranks in args.ranks:
        ours, theirs = fv.get(f"threads_{ranks}"), liggghts.get(f"ranks_{ranks}", {})
        if ours and "ns_per_particle_step" in theirs:
            ratios[f"cores_{ranks}"] = theirs["ns_per_particle_step"] / ours["ns_per_particle_step"]
    result["liggghts_over_fvdem"] = ratios
    result["machine"] = {"date": time.strftime("%Y-%m-%d %H:%M"), "cpu": platform.processor() or platform.machine(),
                         "cores": os.cpu_count(), "load_average": os.getloadavg()}
    for key, value in ratios.items():
        print(f"{key.replace('_', ' ')}: LIGGGHTS {liggghts[f'ranks_{key[6:]}']['ns_per_particle_step']:.0f} ns, "
              f"fvdem {fv[f'threads_{key[6:]}']['ns_per_particle_step']:.0f} ns per particle-step: fvdem {value:.2f} x faster",
              file=sys.stderr)
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())

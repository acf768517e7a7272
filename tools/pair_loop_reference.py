#!/usr/bin/env python
"""fvdem's sphere pair loop beside two C ports of it, on the same settled bed and the same lists (issue 16).

    python tools/pair_loop_reference.py [--json] [--calls 20] [--rounds 10]

What a compiled language would buy on the DEM's largest part, measured rather than guessed. On the
settled 32,500-sphere bed of ``cases/bed_ar1.toml`` (``runs/bed_ar1/final_state.npz``), one thread:

- ``numba``: ``fvdem.dem.forces.contact_forces`` with the walls switched off (every listed pair: the
  contact test, the normal, the lever arms, the contact law with its history, both sides added to the
  particles);
- ``c_scalar``: the same loop in C, pair after pair, compiled with ``cc -O3 -march=native``;
- ``c_batched``: the same loop in C with the contact law taken out of it: a row's touching pairs are
  gathered into a batch (struct of arrays), the law runs branch-free over the batch, so the compiler
  vectorizes it across pairs (``-ffast-math``, ``#pragma omp simd``), and the results are scattered
  back. One pair's law is a long dependent chain (three square roots, four divisions); across pairs it
  runs in SIMD lanes.

Each is checked against the numba kernel (largest force and torque difference relative to the largest
value) before it is timed; the three run alternately, ``--rounds`` times ``--calls`` calls each, and
the minimum and median ns per particle are reported. Needs a C compiler (``cc``); without one only the
numba figure is printed. The last line of output is one JSON object.
"""
from __future__ import annotations

import argparse
import ctypes
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
from _beds import settled_beds, settled_dem  # noqa: E402

# Row i's pairs, as fvdem/dem/forces.py (_sphere_row) and fvdem/dem/contact_law.py (contact_force) compute
# them for identical spheres (the pair constants precomputed) in a box without periodic axes.
# Both ports' signature (the arrays of fvdem's kernel, C order) and the contact law's constants.
PROLOGUE = r"""
#include <math.h>
#include <stdint.h>
#define PAIR_LOOP void pair_loop(int64_t n, const double *restrict pos, const double *restrict vel, \
    const double *restrict w, const double *restrict radius, const int64_t *restrict row_start, \
    const int32_t *restrict nb, double *restrict hist, double *restrict force, double *restrict torque, \
    const double *restrict law, const double *restrict uni)
#define LAW_CONSTANTS double k_n = law[0], k_t = law[1], inv_k_t = law[2], eta_t_ratio = law[3], mu = law[4], \
    mu_r = law[5], dt = law[6], inv_dt = law[7], eta_n = uni[0], r_eff = uni[1], inertia_eff = uni[2];
"""

SCALAR = PROLOGUE + r"""
PAIR_LOOP
{
    LAW_CONSTANTS
    for (int64_t i = 0; i < 3 * n; i++) { force[i] = 0.0; torque[i] = 0.0; }
    for (int64_t i = 0; i < n; i++) {
        double px = pos[3*i], py = pos[3*i+1], pz = pos[3*i+2], ri = radius[i];
        double vix = vel[3*i], viy = vel[3*i+1], viz = vel[3*i+2], wi0 = w[3*i], wi1 = w[3*i+1], wi2 = w[3*i+2];
        double sfx = 0, sfy = 0, sfz = 0, stx = 0, sty = 0, stz = 0;
        for (int64_t slot = row_start[i]; slot < row_start[i+1]; slot++) {
            int64_t j = nb[slot];
            double dx = px - pos[3*j], dy = py - pos[3*j+1], dz = pz - pos[3*j+2];
            double dist2 = dx*dx + dy*dy + dz*dz, rj = radius[j], rs = ri + rj;
            double *h = hist + 4*slot;
            if (dist2 >= rs*rs) { if (h[3] != 0.0) { h[0] = h[1] = h[2] = h[3] = 0.0; } continue; }
            double dist = sqrt(dist2), inv = 1.0/dist;
            double nx = dx*inv, ny = dy*inv, nz = dz*inv, overlap = rs - dist;
            double li = ri - 0.5*overlap, lj = rj - 0.5*overlap;
            double wj0 = w[3*j], wj1 = w[3*j+1], wj2 = w[3*j+2];
            double sx = li*wi0 + lj*wj0, sy = li*wi1 + lj*wj1, sz = li*wi2 + lj*wj2;
            double vx = vix - vel[3*j] - (sy*nz - sz*ny);
            double vy = viy - vel[3*j+1] - (sz*nx - sx*nz);
            double vz = viz - vel[3*j+2] - (sx*ny - sy*nx);
            double v_n = vx*nx + vy*ny + vz*nz, onset = 1.0;
            if (h[3] == 0.0) { h[3] = 1.0; if (v_n < 0.0) { double q = overlap/(-v_n*dt); onset = 0.5 + (q < 1.0 ? q : 1.0); } }
            double f_n = k_n*overlap - eta_n*onset*v_n; if (f_n < 0.0) f_n = 0.0;
            double vtx = vx - v_n*nx, vty = vy - v_n*ny, vtz = vz - v_n*nz;
            double hx = h[0], hy = h[1], hz = h[2], hl2 = hx*hx + hy*hy + hz*hz;
            if (hl2 > 0.0) { double hn = hx*nx + hy*ny + hz*nz; hx -= hn*nx; hy -= hn*ny; hz -= hn*nz;
                double nl2 = hx*hx + hy*hy + hz*hz; if (nl2 > 0.0) { double s = sqrt(hl2/nl2); hx *= s; hy *= s; hz *= s; } }
            hx += vtx*dt; hy += vty*dt; hz += vtz*dt;
            double eta_t = eta_n*eta_t_ratio;
            double ftx = -k_t*hx - eta_t*vtx, fty = -k_t*hy - eta_t*vty, ftz = -k_t*hz - eta_t*vtz;
            double ft2 = ftx*ftx + fty*fty + ftz*ftz, fmax = mu*f_n;
            if (ft2 > fmax*fmax) { double s = fmax/sqrt(ft2); ftx *= s; fty *= s; ftz *= s;
                hx = -(ftx + eta_t*vtx)*inv_k_t; hy = -(fty + eta_t*vty)*inv_k_t; hz = -(ftz + eta_t*vtz)*inv_k_t; }
            h[0] = hx; h[1] = hy; h[2] = hz;
            double wx = wi0 - wj0, wy = wi1 - wj1, wz = wi2 - wj2, wn = wx*nx + wy*ny + wz*nz;
            double rx = wx - wn*nx, ry = wy - wn*ny, rz = wz - wn*nz, wr2 = rx*rx + ry*ry + rz*rz;
            double trx = 0, tr_y = 0, trz = 0;
            if (wr2 != 0.0 && mu_r != 0.0) { double a = mu_r*r_eff*f_n/sqrt(wr2), b = inertia_eff*inv_dt;
                double s = -(a < b ? a : b); trx = s*rx; tr_y = s*ry; trz = s*rz; }
            double fx = f_n*nx + ftx, fy = f_n*ny + fty, fz = f_n*nz + ftz;
            double cx = ny*fz - nz*fy, cy = nz*fx - nx*fz, cz = nx*fy - ny*fx;
            sfx += fx; sfy += fy; sfz += fz; stx += trx - li*cx; sty += tr_y - li*cy; stz += trz - li*cz;
            force[3*j] -= fx; force[3*j+1] -= fy; force[3*j+2] -= fz;
            torque[3*j] += -lj*cx - trx; torque[3*j+1] += -lj*cy - tr_y; torque[3*j+2] += -lj*cz - trz;
        }
        force[3*i] += sfx; force[3*i+1] += sfy; force[3*i+2] += sfz;
        torque[3*i] += stx; torque[3*i+1] += sty; torque[3*i+2] += stz;
    }
}
"""

# The same pairs, with the law over batches of gathered pairs (branch-free: every branch computed, then
# selected), so that it vectorizes across pairs.
BATCHED = PROLOGUE + r"""
#define B 256
#define L (B + 40)  /* not a power of two: the batch's arrays must not share their low address bits (4K aliasing) */
#define SEL(c, a, b) ((c) ? (a) : (b))
static double dx_[L], dy_[L], dz_[L], d2_[L], ri_[L], rj_[L], vx_[L], vy_[L], vz_[L], a0_[L], a1_[L], a2_[L];
static double b0_[L], b1_[L], b2_[L], h0_[L], h1_[L], h2_[L], h3_[L], fx_[L], fy_[L], fz_[L];
static double ti0_[L], ti1_[L], ti2_[L], tj0_[L], tj1_[L], tj2_[L];
static int64_t sl_[L], ii_[L], jj_[L];
PAIR_LOOP
{
    LAW_CONSTANTS
    double eta_t = eta_n*eta_t_ratio, cap = inertia_eff*inv_dt;
    for (int64_t i = 0; i < 3 * n; i++) { force[i] = 0.0; torque[i] = 0.0; }
    int64_t i = 0;
    while (i < n) {
        int m = 0;
        for (; i < n && m + (row_start[i+1] - row_start[i]) <= B; i++) {
            double px = pos[3*i], py = pos[3*i+1], pz = pos[3*i+2], ri = radius[i];
            for (int64_t slot = row_start[i]; slot < row_start[i+1]; slot++) {
                int64_t j = nb[slot];
                double dx = px - pos[3*j], dy = py - pos[3*j+1], dz = pz - pos[3*j+2];
                double dist2 = dx*dx + dy*dy + dz*dz, rs = ri + radius[j];
                double *h = hist + 4*slot;
                if (dist2 >= rs*rs) { if (h[3] != 0.0) { h[0] = h[1] = h[2] = h[3] = 0.0; } continue; }
                dx_[m] = dx; dy_[m] = dy; dz_[m] = dz; d2_[m] = dist2; ri_[m] = ri; rj_[m] = radius[j];
                vx_[m] = vel[3*i] - vel[3*j]; vy_[m] = vel[3*i+1] - vel[3*j+1]; vz_[m] = vel[3*i+2] - vel[3*j+2];
                a0_[m] = w[3*i]; a1_[m] = w[3*i+1]; a2_[m] = w[3*i+2]; b0_[m] = w[3*j]; b1_[m] = w[3*j+1]; b2_[m] = w[3*j+2];
                h0_[m] = h[0]; h1_[m] = h[1]; h2_[m] = h[2]; h3_[m] = h[3]; sl_[m] = slot; ii_[m] = i; jj_[m] = j; m++;
            }
        }
        #pragma omp simd
        for (int k = 0; k < m; k++) {
            double dist = sqrt(d2_[k]), inv = 1.0/dist;
            double nx = dx_[k]*inv, ny = dy_[k]*inv, nz = dz_[k]*inv, overlap = ri_[k] + rj_[k] - dist;
            double li = ri_[k] - 0.5*overlap, lj = rj_[k] - 0.5*overlap;
            double wi0 = a0_[k], wi1 = a1_[k], wi2 = a2_[k], wj0 = b0_[k], wj1 = b1_[k], wj2 = b2_[k];
            double sx = li*wi0 + lj*wj0, sy = li*wi1 + lj*wj1, sz = li*wi2 + lj*wj2;
            double vx = vx_[k] - (sy*nz - sz*ny), vy = vy_[k] - (sz*nx - sx*nz), vz = vz_[k] - (sx*ny - sy*nx);
            double v_n = vx*nx + vy*ny + vz*nz;
            double onset = SEL((h3_[k] == 0.0) & (v_n < 0.0), 0.5 + fmin(overlap/fmax(-v_n*dt, 1e-300), 1.0), 1.0);
            double f_n = fmax(k_n*overlap - eta_n*onset*v_n, 0.0);
            double vtx = vx - v_n*nx, vty = vy - v_n*ny, vtz = vz - v_n*nz;
            double hx = h0_[k], hy = h1_[k], hz = h2_[k], hl2 = hx*hx + hy*hy + hz*hz, hn = hx*nx + hy*ny + hz*nz;
            hx -= hn*nx; hy -= hn*ny; hz -= hn*nz;
            double nl2 = hx*hx + hy*hy + hz*hz, s = SEL(nl2 > 0.0, sqrt(hl2/fmax(nl2, 1e-300)), 1.0);
            hx = hx*s + vtx*dt; hy = hy*s + vty*dt; hz = hz*s + vtz*dt;
            double ftx = -k_t*hx - eta_t*vtx, fty = -k_t*hy - eta_t*vty, ftz = -k_t*hz - eta_t*vtz;
            double ft2 = ftx*ftx + fty*fty + ftz*ftz, fm = mu*f_n;
            double c = SEL(ft2 > fm*fm, fm/sqrt(fmax(ft2, 1e-300)), 1.0);
            h0_[k] = SEL(ft2 > fm*fm, -(c*ftx + eta_t*vtx)*inv_k_t, hx);
            h1_[k] = SEL(ft2 > fm*fm, -(c*fty + eta_t*vty)*inv_k_t, hy);
            h2_[k] = SEL(ft2 > fm*fm, -(c*ftz + eta_t*vtz)*inv_k_t, hz);
            ftx *= c; fty *= c; ftz *= c;
            double wx = wi0 - wj0, wy = wi1 - wj1, wz = wi2 - wj2, wn = wx*nx + wy*ny + wz*nz;
            double rx = wx - wn*nx, ry = wy - wn*ny, rz = wz - wn*nz, wr2 = rx*rx + ry*ry + rz*rz;
            double sr = SEL(wr2 > 0.0, -fmin(mu_r*r_eff*f_n/sqrt(fmax(wr2, 1e-300)), cap), 0.0);
            double trx = sr*rx, tr_y = sr*ry, trz = sr*rz;
            double fx = f_n*nx + ftx, fy = f_n*ny + fty, fz = f_n*nz + ftz;
            double cx = ny*fz - nz*fy, cy = nz*fx - nx*fz, cz = nx*fy - ny*fx;
            fx_[k] = fx; fy_[k] = fy; fz_[k] = fz;
            ti0_[k] = trx - li*cx; ti1_[k] = tr_y - li*cy; ti2_[k] = trz - li*cz;
            tj0_[k] = -lj*cx - trx; tj1_[k] = -lj*cy - tr_y; tj2_[k] = -lj*cz - trz;
        }
        for (int k = 0; k < m; k++) {
            double *h = hist + 4*sl_[k]; h[0] = h0_[k]; h[1] = h1_[k]; h[2] = h2_[k]; h[3] = 1.0;
            int64_t a = ii_[k], b = jj_[k];
            force[3*a] += fx_[k]; force[3*a+1] += fy_[k]; force[3*a+2] += fz_[k];
            torque[3*a] += ti0_[k]; torque[3*a+1] += ti1_[k]; torque[3*a+2] += ti2_[k];
            force[3*b] -= fx_[k]; force[3*b+1] -= fy_[k]; force[3*b+2] -= fz_[k];
            torque[3*b] += tj0_[k]; torque[3*b+1] += tj1_[k]; torque[3*b+2] += tj2_[k];
        }
    }
}
"""

FLAGS = {"c_scalar": (SCALAR, ["-O3", "-march=native", "-fno-math-errno", "-ffp-contract=fast"]),
         "c_batched": (BATCHED, ["-O3", "-march=native", "-ffast-math", "-fopenmp-simd"])}


def compile_kernels(folder: Path) -> dict:
    """The C kernels as ctypes functions (empty without a C compiler)."""
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        return {}
    kernels = {}
    for name, (source, flags) in FLAGS.items():
        (folder / f"{name}.c").write_text(source)
        # compiled with the flags, linked without them: linking with -ffast-math adds crtfastmath.o, which
        # sets flush-to-zero for the whole process that loads the library (later tests then saw no subnormals)
        subprocess.run([cc, *flags, "-fPIC", "-c", "-o", str(folder / f"{name}.o"), str(folder / f"{name}.c")],
                       check=True)
        subprocess.run([cc, "-shared", "-o", str(folder / f"{name}.so"), str(folder / f"{name}.o")], check=True)
        kernels[name] = ctypes.CDLL(str(folder / f"{name}.so")).pair_loop
    return kernels


def measure(dem, calls: int, rounds: int) -> dict:
    """The numba pair loop and the C ports on ``dem``'s current state and lists (identical spheres, no
    periodic axis), one thread: per loop the min and median ns per particle and the largest force or
    torque difference to the numba kernel, relative to the largest value."""
    import numba

    from fvdem.dem.contact_law import kernel_constants
    from fvdem.dem.forces import contact_forces

    p, n = dem.particles, dem.particles.count
    if dem.track_orientation or dem._uniform[0] < 0.0 or dem._periodic.any():
        raise ValueError("the reference kernels are for identical spheres in a box without periodic axes")
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    history0 = dem.history.copy()
    no_walls = np.zeros(6, np.bool_)
    law = np.array(kernel_constants(dem.params))
    block_start, deferred, deferred_rows = dem._blocks

    def numba_loop():
        contact_forces(True, p.position, p.velocity, p.angular_velocity, p.axis, p.radius, p.half_length, p.mass,
                       p.inertia, dem.row_start, dem.neighbours, dem.history, block_start, deferred, deferred_rows,
                       no_walls, dem._box_lo, dem._box_hi, *scratch, dem._box_len, dem._periodic, dem.params,
                       dem._uniform, force_numba, torque_numba, *diagnostics)
        return force_numba, torque_numba

    # the kernel's wall histories and per-row diagnostics: copies, so the system's own stay as they are
    scratch = (dem.wall_history.copy(), dem.wall_mask.copy())
    diagnostics = (dem._row_max_overlap.copy(), dem._row_contacts.copy(), dem._row_wall_contacts.copy())

    force_numba, torque_numba = np.zeros((n, 3)), np.zeros((n, 3))
    force, torque = np.zeros((n, 3)), np.zeros((n, 3))
    pointer = [a.ctypes.data_as(ctypes.c_void_p) for a in (p.position, p.velocity, p.angular_velocity, p.radius,
                                                           dem.row_start, dem.neighbours, dem.history, force,
                                                           torque, law, dem._uniform)]

    def c_loop(kernel):
        def run():
            kernel(ctypes.c_int64(n), *pointer)
            return force, torque
        return run

    try:
        with tempfile.TemporaryDirectory() as folder:
            loops = {"numba": numba_loop}
            loops.update({name: c_loop(k) for name, k in compile_kernels(Path(folder)).items()})
            dem.history[:] = history0
            reference = [a.copy() for a in numba_loop()]
            difference = {}
            for name, loop in loops.items():
                dem.history[:] = history0
                out = loop()
                difference[name] = max(float(np.abs(out[k] - reference[k]).max() / np.abs(reference[k]).max())
                                       for k in range(2))
            times = {name: [] for name in loops}
            for _ in range(rounds):
                for name, loop in loops.items():
                    elapsed = 0.0
                    for _ in range(calls):
                        dem.history[:] = history0  # every call sees the same histories
                        t0 = time.perf_counter()
                        loop()
                        elapsed += time.perf_counter() - t0
                    times[name].append(1e9 * elapsed / (calls * n))
    finally:
        dem.history[:] = history0
        numba.set_num_threads(threads)
    result = {name: {"ns_per_particle_min": min(t), "ns_per_particle_median": float(np.median(t)),
                     "max_relative_difference_to_numba": difference[name]} for name, t in times.items()}
    base = result["numba"]["ns_per_particle_median"]
    for name in result:
        result[name]["median_over_numba"] = result[name]["ns_per_particle_median"] / base
    return result


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--json", action="store_true", help="print only the JSON line")
    parser.add_argument("--calls", type=int, default=20, help="kernel calls per round")
    parser.add_argument("--rounds", type=int, default=10, help="alternated rounds (min and median reported)")
    parser.add_argument("--state", type=Path, help="a settled sphere bed (default: runs/bed_ar1's, settled first "
                                                   "when missing)")
    parser.add_argument("--quick", action="store_true", help="a 1,500-sphere bed, 2 calls, 1 round (seconds)")
    args = parser.parse_args()
    if args.quick:
        args.calls, args.rounds = 2, 1
    if args.state is None:
        args.state = settled_beds(["ar1"], "pair_loop_reference", args.quick)["ar1"]
    elif not args.state.exists():
        print(f"pair_loop_reference: --state {args.state}: no such file", file=sys.stderr)
        return 2
    import numba

    dem = settled_dem("ar1", args.state)[1]
    dem.step(20)  # lists built, histories of a running bed
    result = measure(dem, args.calls, args.rounds)
    n = dem.particles.count
    if not args.json:
        for name, r in result.items():
            print(f"{name:10s} {r['ns_per_particle_min']:7.1f} / {r['ns_per_particle_median']:7.1f} ns per particle "
                  f"(min / median), {r['median_over_numba']:.2f} x numba, difference "
                  f"{r['max_relative_difference_to_numba']:.1e}", file=sys.stderr)
    result.update({"particles": n, "listed_pairs_per_particle": len(dem.neighbours) / n,
                   "touching_pairs_per_particle": float(dem._row_contacts.sum()) / n, "threads": 1,
                   "machine": {"cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
                               "load_average": os.getloadavg(), "numba": numba.__version__,
                               "date": time.strftime("%Y-%m-%d %H:%M")}})
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())

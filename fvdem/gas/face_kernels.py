"""Compiled face passes of the gas solver's pressure corrector on its structured grid: the Gauss
gradient, the Rhie-Chow predicted fluxes and the face pressures.

Every face normal of the grid is +-1 along one axis, so a face's contribution to a cell has one
component. The numpy and sparse-matrix forms stay in the solver (``GasSolver._*_reference``) as the
references the tests compare these kernels with.
"""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def gauss_gradient(face_values, first, second, axis, signed_area, volumes):
    """``(1 / V_c) sum_f phi_f A_f n_f`` over each cell's faces, outward (C, 3).

    ``first``/``second``: the face's two cells (second -1 on the boundary; the normal points from
    first to second, outward on the boundary); ``axis``: the normal's axis; ``signed_area``: ``A_f``
    times the normal's sign (zero on faces that carry nothing, such as a periodic face's unused
    copy); ``volumes`` (C,)."""
    n = len(volumes)
    out = np.zeros((n, 3))
    for f in range(len(face_values)):
        value = face_values[f] * signed_area[f]
        a = axis[f]
        out[first[f], a] += value
        if second[f] >= 0:
            out[second[f], a] -= value
    for c in range(n):
        out[c, 0] /= volumes[c]
        out[c, 1] /= volumes[c]
        out[c, 2] /= volumes[c]
    return out


# face kinds: interior (periodic faces included), a wall, the inlet, the outlet, and the unused copy
# FiPy keeps of a periodic face (no flux, no pressure)
INTERIOR, CLOSED, INLET, OUTLET, UNUSED = 0, 1, 2, 3, 4


@njit(cache=True)
def predicted_fluxes(kind, first, second, axis, sign, areas, distances, k_cell, d_cell, c, d_old, pressure,
                     old_face, rho_over_dt):
    """The drag-aware Rhie-Chow face fluxes before a pressure correction, one pass over the faces
    (``GasSolver._predicted_fluxes_reference`` is the same in numpy, term by term).

    Interior face P|N: weight ``w = k_N / (k_P + k_N)``, ``k_f = 2 k_P k_N / (k_P + k_N)``,
    ``phi = A [(w c_P + (1 - w) c_N) . n - k_f (p_N - p_P) / d + (rho / dt)(D_f u_old,f - (w D_P
    u_old,P + (1 - w) D_N u_old,N) . n)]``; outlet: ``A (c_P . n + k_P p_P / d_b)``; closed faces
    (walls) and unused copies 0; inlet faces 0 here (the caller sets their fixed flux).

    ``kind`` (F,): INTERIOR, CLOSED, INLET, OUTLET or UNUSED; ``c = eps u_hat`` and ``d_old = D eps_old u_old``
    (C, 3). Returns ``(flux, k_face, c_first, c_second)``: the flux, the face coefficient (the first
    cell's on the boundary) and the normal components of ``c`` at the first and second cell (0 on the
    boundary)."""
    nf = len(kind)
    flux = np.zeros(nf)
    k_face = np.empty(nf)
    c_first = np.empty(nf)
    c_second = np.zeros(nf)
    for f in range(nf):
        p = first[f]
        a = axis[f]
        s = sign[f]
        cp = c[p, a] * s
        c_first[f] = cp
        if kind[f] == INTERIOR:
            q = second[f]
            kp = k_cell[p]
            kq = k_cell[q]
            total = kp + kq
            w = kq / total
            kf = 2.0 * kp * kq / total
            k_face[f] = kf
            cq = c[q, a] * s
            c_second[f] = cq
            c_face = w * cp + (1.0 - w) * cq
            d_face = w * d_cell[p] + (1.0 - w) * d_cell[q]
            old_cell = w * (d_old[p, a] * s) + (1.0 - w) * (d_old[q, a] * s)
            old_term = rho_over_dt * (d_face * old_face[f] - old_cell)
            flux[f] = areas[f] * (c_face - kf * ((pressure[q] - pressure[p]) / distances[f]) + old_term)
        else:
            k_face[f] = k_cell[p]
            if kind[f] == OUTLET:
                flux[f] = areas[f] * (cp + k_cell[p] * (pressure[p] / distances[f]))
    return flux, k_face, c_first, c_second


@njit(cache=True)
def face_pressures(kind, first, second, areas, distances, k_cell, pressure, c_first, c_second, fixed_flux):
    """Face pressures consistent with the fluxes (``GasSolver._face_pressure``; its numpy form is
    ``_face_pressure_reference``): interior ``(k_P p_P + k_N p_N + (d / 2)(c_P - c_N) . n) / (k_P + k_N)``;
    inlet and wall faces ``p_P + d_b (c_P . n - phi / A) / k_P`` (``fixed_flux`` the face's flux);
    outlet and unused faces 0."""
    nf = len(kind)
    out = np.zeros(nf)
    for f in range(nf):
        p = first[f]
        if kind[f] == INTERIOR:
            q = second[f]
            kp = k_cell[p]
            kq = k_cell[q]
            out[f] = (kp * pressure[p] + kq * pressure[q] + 0.5 * distances[f] * (c_first[f] - c_second[f])) / (kp + kq)
        elif kind[f] == INLET or kind[f] == CLOSED:
            out[f] = pressure[p] + distances[f] * (c_first[f] - fixed_flux[f] / areas[f]) / k_cell[p]
    return out


@njit(cache=True)
def corrected_fluxes(kind, first, second, areas, distances, k_face, flux, correction):
    """The fluxes after a pressure correction ``p'`` (C,): ``phi - k_f A (p'_N - p'_P) / d`` on interior
    faces, ``phi - k_f A (0 - p'_P) / d`` on the outlet (``p' = 0`` beyond it), unchanged elsewhere (walls
    and the inlet carry fixed fluxes). The numpy form: ``flux - k_face A _face_difference(p')``."""
    out = flux.copy()
    for f in range(len(kind)):
        p = first[f]
        if kind[f] == INTERIOR:
            out[f] = flux[f] + (-k_face[f] * areas[f]) * ((correction[second[f]] - correction[p]) / distances[f])
        elif kind[f] == OUTLET:
            out[f] = flux[f] + (-k_face[f] * areas[f]) * (-correction[p] / distances[f])
    return out

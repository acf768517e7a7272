"""Particle insertion without overlap (random sequential addition).

Candidates are drawn uniformly in the insertion region (whole particle inside it) with the chosen
orientation, and accepted when their axis segment keeps at least ``r_i + r_j + gap`` from every
particle inserted before. A hash grid of accepted particles makes each test O(1).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .geometry import segment_parameters

ORIENTATIONS = ("random", "vertical", "horizontal")


@njit(cache=True)
def _insert(count, radius, half_length, lower, upper, orientation_code, gap, seed, max_attempts,
            position, axis):
    np.random.seed(seed)
    reach = 2.0 * (radius + half_length) + gap
    n_cells = np.empty(3, np.int64)
    for d in range(3):
        n_cells[d] = max(1, int((upper[d] - lower[d]) / reach))
    head = -np.ones(n_cells[0] * n_cells[1] * n_cells[2], np.int64)
    nxt = -np.ones(count, np.int64)
    inserted = 0
    attempts = 0
    while inserted < count and attempts < max_attempts:
        attempts += 1
        if orientation_code == 0:
            ax, ay, az = np.random.normal(), np.random.normal(), np.random.normal()
        elif orientation_code == 1:
            ax, ay, az = 0.0, 0.0, 1.0
        else:
            phi = 2.0 * np.pi * np.random.random()
            ax, ay, az = np.cos(phi), np.sin(phi), 0.0
        norm = np.sqrt(ax * ax + ay * ay + az * az)
        ax, ay, az = ax / norm, ay / norm, az / norm
        extent = (radius + half_length * abs(ax), radius + half_length * abs(ay), radius + half_length * abs(az))
        p = np.empty(3)
        ok = True
        for d in range(3):
            lo = lower[d] + extent[d]
            hi = upper[d] - extent[d]
            if hi < lo:
                ok = False
                break
            p[d] = lo + (hi - lo) * np.random.random()
        if not ok:
            continue
        c = np.empty(3, np.int64)
        for d in range(3):
            c[d] = min(n_cells[d] - 1, max(0, int((p[d] - lower[d]) / reach)))
        clear = True
        for oz in range(-1, 2):
            kz = c[2] + oz
            if kz < 0 or kz >= n_cells[2]:
                continue
            for oy in range(-1, 2):
                ky = c[1] + oy
                if ky < 0 or ky >= n_cells[1]:
                    continue
                for ox in range(-1, 2):
                    kx = c[0] + ox
                    if kx < 0 or kx >= n_cells[0]:
                        continue
                    j = head[(kz * n_cells[1] + ky) * n_cells[0] + kx]
                    while j >= 0 and clear:
                        rx = p[0] - position[j, 0]
                        ry = p[1] - position[j, 1]
                        rz = p[2] - position[j, 2]
                        s, t = segment_parameters(rx, ry, rz, ax, ay, az, half_length,
                                                  axis[j, 0], axis[j, 1], axis[j, 2], half_length)
                        dx = rx + s * ax - t * axis[j, 0]
                        dy = ry + s * ay - t * axis[j, 1]
                        dz = rz + s * az - t * axis[j, 2]
                        if dx * dx + dy * dy + dz * dz < (2.0 * radius + gap) ** 2:
                            clear = False
                        j = nxt[j]
        if not clear:
            continue
        position[inserted, 0], position[inserted, 1], position[inserted, 2] = p[0], p[1], p[2]
        axis[inserted, 0], axis[inserted, 1], axis[inserted, 2] = ax, ay, az
        cell = (c[2] * n_cells[1] + c[1]) * n_cells[0] + c[0]
        nxt[inserted] = head[cell]
        head[cell] = inserted
        inserted += 1
    return inserted


def insert_particles(count: int, radius: float, half_length: float, lower, upper, orientation="random",
                     gap: float = 0.0, seed: int = 1, max_attempts_per_particle: int = 2000):
    """Positions ``(count, 3)`` [m] and unit axes ``(count, 3)`` of non-overlapping particles.

    Raises ``ValueError`` naming the shortfall if the region cannot take ``count`` particles.
    """
    position = np.zeros((count, 3))
    axis = np.zeros((count, 3))
    code = ORIENTATIONS.index(orientation)
    got = _insert(count, float(radius), float(half_length), np.asarray(lower, float), np.asarray(upper, float),
                  code, float(gap), int(seed), int(max_attempts_per_particle) * count, position, axis)
    if got < count:
        region = np.prod(np.asarray(upper, float) - np.asarray(lower, float))
        raise ValueError(
            f"insertion placed only {got} of {count} particles in the region {list(lower)}-{list(upper)} m "
            f"({region:.4g} m^3); enlarge the insertion region or insert fewer particles")
    return position, axis

"""Correlations that more than one layer uses, in a leaf module (the gas must not import the coupling):

- ``ergun_beta_per_solids``: Ergun's (1952) interphase coefficient per solids fraction, for the gas's
  fixed porous zone (``gas.phase``) and the Gidaspow drag law (``coupling.closures``);
- ``ergun_umf``, ``wen_yu_umf`` and ``quadratic_crossing``: minimum fluidization velocities from a packed
  bed's voidage (Ergun) or from the Archimedes number alone (Wen & Yu), for the Umf tools and tests.
"""
from __future__ import annotations

import math


def ergun_beta_per_solids(voidage, speed, d, rho, mu):
    """Ergun's (1952) interphase coefficient divided by the solids fraction, ``beta / eps_s``
    [kg/(m^3 s)] = ``150 eps_s mu / (eps d^2) + 1.75 rho |u| / d`` at the interstitial slip speed ``|u|``
    [m/s] and diameter ``d`` [m]. In model A a uniform fixed bed then has Ergun's pressure gradient
    ``eps_s (beta / eps_s) |u| / eps``. Kept per solids fraction so that it stays finite at ``eps = 1``.
    Valid for packed beds (eps below about 0.8); numpy arrays or scalars."""
    return 150.0 * (1.0 - voidage) * mu / (voidage * d ** 2) + 1.75 * rho * speed / d


def quadratic_crossing(a, b, level) -> float:
    """The velocity [m/s] at which Ergun's form ``a U + b U^2`` (a, b >= 0) reaches ``level``: the positive root
    (``level / a`` where b vanishes)."""
    return float(level / a if abs(b) < 1e-12 else (-a + math.sqrt(a * a + 4 * b * level)) / (2 * b))


def ergun_umf(d_p, rho_p, voidage, sphericity, rho, mu, g=9.81) -> float:
    """Ergun's (1952) minimum fluidization velocity [m/s]: where the packed bed's pressure gradient
    ``150 (1-eps)^2 mu U / (eps^3 (phi d)^2) + 1.75 (1-eps) rho U^2 / (eps^3 phi d)`` equals its buoyant weight
    per volume ``(1-eps)(rho_p - rho) g``. ``d_p`` the volume-equivalent diameter [m], ``phi`` its sphericity,
    ``eps`` the packed voidage; gas density ``rho`` [kg/m^3] and viscosity ``mu`` [Pa s]."""
    weight = (1 - voidage) * (rho_p - rho) * g
    a = 150 * (1 - voidage) ** 2 * mu / (voidage ** 3 * (sphericity * d_p) ** 2)
    b = 1.75 * (1 - voidage) * rho / (voidage ** 3 * sphericity * d_p)
    return quadratic_crossing(a, b, weight)


def wen_yu_umf(d_p, rho_p, rho, mu, g=9.81) -> float:
    """Wen & Yu's (1966) minimum fluidization velocity [m/s] from the Archimedes number
    ``Ar = d^3 rho (rho_p - rho) g / mu^2``: ``Re_mf = sqrt(33.7^2 + 0.0408 Ar) - 33.7`` (no voidage needed;
    about +-30 % for spheres)."""
    archimedes = d_p ** 3 * rho * (rho_p - rho) * g / mu ** 2
    reynolds = math.sqrt(33.7 ** 2 + 0.0408 * archimedes) - 33.7
    return float(reynolds * mu / (rho * d_p))


__all__ = ["ergun_beta_per_solids", "ergun_umf", "quadratic_crossing", "wen_yu_umf"]

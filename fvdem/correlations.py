"""Correlations that more than one layer uses, in a leaf module (the gas must not import the coupling):

- ``ergun_beta_per_solids``: Ergun's (1952) interphase coefficient per solids fraction, for the gas's
  fixed porous zone (``gas.phase``) and the Gidaspow drag law (``coupling.closures``).
"""
from __future__ import annotations


def ergun_beta_per_solids(voidage, speed, d, rho, mu):
    """Ergun's (1952) interphase coefficient divided by the solids fraction, ``beta / eps_s``
    [kg/(m^3 s)] = ``150 eps_s mu / (eps d^2) + 1.75 rho |u| / d`` at the interstitial slip speed ``|u|``
    [m/s] and diameter ``d`` [m]. In model A a uniform fixed bed then has Ergun's pressure gradient
    ``eps_s (beta / eps_s) |u| / eps``. Kept per solids fraction so that it stays finite at ``eps = 1``.
    Valid for packed beds (eps below about 0.8); numpy arrays or scalars."""
    return 150.0 * (1.0 - voidage) * mu / (voidage * d ** 2) + 1.75 * rho * speed / d


__all__ = ["ergun_beta_per_solids"]

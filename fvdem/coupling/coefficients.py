"""The fitted coefficients of the hydrodynamic closures (a leaf: numpy only), as published and as the
compiled laws (``laws.py``) read them.

- ``SANJEEVI_PADDING_DRAG``: Sanjeevi & Padding (2020), AIChE J. 66, Table 2 (Mema et al. (2020) Table 2),
  each entry (incidence 0 deg, 90 deg); e = f = 11.12 at 90 degrees as extracted.
- ``SANJEEVI_PADDING_TORQUE``: their Table 4.
- ``ZASTAWNY_LIFT`` / ``ZASTAWNY_TORQUE``: b1..b10 and c1..c10 of Zastawny et al. (2012)'s form for AR-4
  spherocylinders (Mema et al. (2020) Table 3).
"""
import numpy as np

SANJEEVI_PADDING_DRAG = {  # Table 2: (phi = 0 deg, phi = 90 deg)
    "a": (2.0, 3.0), "b": (11.3, 17.2), "c": (0.69, 0.79), "d": (0.77, 3.0), "e": (0.42, 11.12),
    "f": (4.84, 11.12), "g": (0.0, 0.57),
    "a1": (24.48, 31.89), "a2": (3.965, 5.519), "a3": (0.41, 0.229), "a4": (0.0005, 0.0032), "a5": (0.15, 1.089),
}
SANJEEVI_PADDING_TORQUE = {"a": 0.82, "b": 1.44, "c": 1.07, "d": 5.48, "e": 0.223}  # Table 4
ZASTAWNY_LIFT = (1.884, 0.1324, 0.001668, -0.8159, 0.8562, 0.003624, 0.6598, -0.2621, 0.8021, 0.04384)  # b1..b10
ZASTAWNY_TORQUE = (-2.283, -0.01145, 4.09, -0.01395, 0.3406, 0.3609, 0.1355, 0.2356, 0.3612, 0.1358)  # c1..c10

GIDASPOW_SWITCH = 0.8  # voidage below which Ergun applies, above it Wen-Yu (Gidaspow 1994)
RE_FLOOR = 1e-12  # slip Reynolds numbers are floored here: finite coefficients (and zero force) at zero slip

# as the compiled laws read them: rows (0 deg, 90 deg) of a1..a5, a..g; a..e; b1..b10; c1..c10
SP_DRAG_ORDER = ("a1", "a2", "a3", "a4", "a5", "a", "b", "c", "d", "e", "f", "g")
SP_DRAG = np.array([[SANJEEVI_PADDING_DRAG[name][column] for name in SP_DRAG_ORDER] for column in (0, 1)])
SP_TORQUE = np.array([SANJEEVI_PADDING_TORQUE[name] for name in ("a", "b", "c", "d", "e")])
Z_LIFT = np.array(ZASTAWNY_LIFT)
Z_TORQUE = np.array(ZASTAWNY_TORQUE)

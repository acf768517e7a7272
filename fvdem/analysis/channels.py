"""Gas channels along a bed's walls and corners, and how its rods lie there (docs/validation.md, "Why AR-4 MP
stalls near its Umf: gas channels along the corners": AR-4 MP at 1.6 x its own Umf sends the gas up the column's
corners).

The column's gas cells are split into three classes of vertical columns: the 4 **corner** columns, the
**wall** columns along the side walls (corners excluded) and the columns **inside**. Over the layers whose
centres lie in ``z_range``:

    share_k = sum over layer cells of class k of U_z      / sum over all layer cells of U_z
              (superficial vertical velocity U_z = eps u_z; the cells of one layer have one area)

averaged over the layers: the share of the rising gas that class k carries. With the gas spread evenly it is
the class's share of the cross-section (on 10 x 10 cells: corners 0.04, walls 0.32, inside 0.64); a channel
raises it. Rods (spherocylinders) whose centres lie in ``z_range`` are classed by the column they are in:

    alignment_k = mean |a_z|     (a the unit axis: 1 all upright, 0 all flat, 1/2 for random orientations)

Units: shares and alignments are dimensionless; positions and ``z_range`` in m.
"""
from __future__ import annotations

import numpy as np

CLASSES = ("corner", "wall", "inside")


def column_classes(cells_x: int, cells_y: int) -> np.ndarray:
    """``(cells_x, cells_y)`` array of 0 (corner), 1 (wall) and 2 (inside) for the columns of a grid."""
    edge_x = np.zeros(cells_x, bool)
    edge_y = np.zeros(cells_y, bool)
    edge_x[[0, -1]] = True
    edge_y[[0, -1]] = True
    on_x, on_y = np.meshgrid(edge_x, edge_y, indexing="ij")
    return np.where(on_x & on_y, 0, np.where(on_x | on_y, 1, 2))


def _column_of(points, lower, upper, cells):
    """The (i, j) column of each point and its layer index k on a ``cells`` grid over [lower, upper]."""
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    index = np.floor((np.asarray(points, float) - lower) / ((upper - lower) / np.asarray(cells))).astype(int)
    return np.clip(index, 0, np.asarray(cells) - 1)


def gas_shares(centres, superficial_z, lower, upper, cells, z_range) -> dict:
    """``{"corner", "wall", "inside"}``: the share of the rising gas each class of columns carries, averaged over
    the layers whose cell centres lie in ``z_range`` (None where no layer does or no gas rises there)."""
    index = _column_of(centres, lower, upper, cells)
    kind = column_classes(cells[0], cells[1])[index[:, 0], index[:, 1]]
    flux = np.asarray(superficial_z, float)
    z = np.asarray(centres, float)[:, 2]
    layers = [k for k in np.unique(index[:, 2]) if z_range[0] <= z[index[:, 2] == k].mean() <= z_range[1]]
    shares = {name: [] for name in CLASSES}
    for k in layers:
        in_layer = index[:, 2] == k
        total = flux[in_layer].sum()
        if total <= 0.0:
            continue
        for c, name in enumerate(CLASSES):
            shares[name].append(flux[in_layer & (kind == c)].sum() / total)
    return {name: float(np.mean(v)) if v else None for name, v in shares.items()}


def rod_alignment(position, axis, lower, upper, cells, z_range) -> dict:
    """``{"corner", "wall", "inside"}``: the mean |a_z| of the particles whose centres lie in ``z_range``, by the
    class of the gas column they are in (None for a class without such particles)."""
    position, axis = np.asarray(position, float), np.asarray(axis, float)
    chosen = (position[:, 2] >= z_range[0]) & (position[:, 2] <= z_range[1])
    index = _column_of(position[chosen], lower, upper, cells)
    kind = column_classes(cells[0], cells[1])[index[:, 0], index[:, 1]]
    upright = np.abs(axis[chosen, 2])
    return {name: float(upright[kind == c].mean()) if np.any(kind == c) else None for c, name in enumerate(CLASSES)}

"""The depth column of the long-term stage: rows below the invert, layer by layer (§14).

The soil stage gives q_d on its depth grid d (below the ring–soil interface, the invert). The
long-term stage adds each layer boundary that falls inside the column **twice**: the upper row
carries the layer above, the lower row the layer below; the two rows share one depth (one
pore pressure in the consolidation solver, where u is continuous). Every row's trapezoidal cell
(:func:`trapezoid_thickness`) then lies in one layer, so Σ f Δz is the trapezoidal integral
taken layer by layer: it does not straddle a boundary, and a property that jumps there (ε_p,
m_v, k) is integrated to second order. The reported per-depth arrays keep each boundary depth
once, with the lower layer's values (docs/model.md §14: a depth on a boundary takes the lower
layer). At the two ends of the column a row takes the layer its half cell lies in.

Values the soil stage gives on its grid (q_d, cycles per train) are interpolated linearly onto
the rows; at the grid's own depths they are copied exactly, so a one-layer site reproduces the
homogeneous results to the last digit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SNAP_M = 1e-9  # a boundary closer than this to a grid depth is put on it (m)


def check_depths(depth: np.ndarray) -> None:
    """ValueError unless ``depth`` is a column: ≥ 2 finite non-decreasing depths, a depth given
    at most twice (a layer boundary), and the first and the last once."""
    if depth.ndim != 1 or depth.size < 2 or not np.all(np.isfinite(depth)):
        raise ValueError("depth_m must be a finite 1-D array of at least 2 depths")
    spacing = np.diff(depth)
    if np.any(spacing < 0.0):
        raise ValueError("depth_m must be non-decreasing")
    repeated = spacing == 0.0
    if repeated[0] or repeated[-1] or np.any(repeated[1:] & repeated[:-1]):
        raise ValueError(
            "a depth may repeat once, to mark a layer boundary, and not at the top or the base"
        )


def trapezoid_thickness(depth_m) -> np.ndarray:
    """Cell thickness Δz_i (m) of each depth: Σ f_i Δz_i is the trapezoidal ∫ f dz.

    Half the spacings to the neighbours. A depth given twice marks a layer boundary, where each
    of the two rows takes the half cell on its own side, so the sum is the trapezoidal integral
    layer by layer.

    Parameters
    ----------
    depth_m : array_like
        Non-decreasing depths (m), ≥ 2 of them; a depth at most twice, the first and the last
        once.

    Returns
    -------
    ndarray
        (nd,) thicknesses (m), ≥ 0.
    """
    depth = np.asarray(depth_m, dtype=float)
    check_depths(depth)
    spacing = np.diff(depth)
    return 0.5 * (np.concatenate([spacing, [0.0]]) + np.concatenate([[0.0], spacing]))


@dataclass(frozen=True)
class Column:
    """Rows of the long-term column: depths, the layer of each row, and which rows are reported."""

    depth_m: np.ndarray
    """(nr,) depth below the invert (m); an interior layer boundary appears twice."""
    layer_index: np.ndarray
    """(nr,) index into ``site.layers`` of each row's layer."""
    reported: np.ndarray
    """(nr,) False on the upper row of a boundary (the reported depth takes the lower layer)."""
    left: np.ndarray
    """(nr,) row of the coarser grid the row is interpolated from (see :meth:`interpolate`)."""
    weight: np.ndarray
    """(nr,) weight of the next row of the coarser grid; 0 where the row is a grid depth."""

    def interpolate(self, values: np.ndarray) -> np.ndarray:
        """Values on the coarser grid (..., n_coarse) → these rows (..., nr), linear in depth
        within a segment; exact copies at the coarser grid's own depths."""
        values = np.asarray(values, dtype=float)
        right = np.minimum(self.left + 1, values.shape[-1] - 1)
        lower = values[..., self.left]
        between = lower + self.weight * (values[..., right] - lower)
        return np.where(self.weight == 0.0, lower, between)

    @property
    def boundaries_m(self) -> np.ndarray:
        """Depths below the invert of the layer boundaries inside the column (m)."""
        return self.depth_m[1:][np.diff(self.depth_m) == 0.0]


def layered_column(grid_depth_m, bottoms_below_invert_m, layer_of_depth) -> Column:
    """Rows of the column: the soil stage's grid with each interior boundary added twice.

    Parameters
    ----------
    grid_depth_m : array_like
        (ng,) increasing depths below the invert of the soil stage's grid (m).
    bottoms_below_invert_m : array_like
        Depth below the invert of the bottom of each layer (m), increasing.
    layer_of_depth : callable
        ``layer_of_depth(d)``: index of the layer holding depth d below the invert, a boundary
        taking the lower layer.

    Returns
    -------
    Column
        ``left``/``weight`` interpolate from the soil stage's grid.
    """
    grid = np.asarray(grid_depth_m, dtype=float)
    top, base = grid[0], grid[-1]
    inside = np.array([b for b in bottoms_below_invert_m if top < b < base], dtype=float)
    # a boundary within rounding of a grid depth is on it (layer sums in depths below ground)
    if inside.size:
        nearest = grid[np.abs(grid[:, None] - inside[None, :]).argmin(axis=0)]
        inside = np.where(np.abs(nearest - inside) <= SNAP_M, nearest, inside)
    lower = np.union1d(grid, inside)  # a boundary on a grid depth is that depth's lower row
    depth = np.concatenate([lower, inside])
    upper = np.concatenate([np.zeros(lower.size, bool), np.ones(inside.size, bool)])
    order = np.lexsort((~upper, depth))  # at a repeated depth the upper row comes first
    depth, upper = depth[order], upper[order]
    layers = np.array([layer_of_depth(d) for d in depth]) - upper
    if grid.size > 1 and layer_of_depth(base) != layer_of_depth(np.nextafter(base, top)):
        layers[-1] -= 1  # the base on a boundary: its half cell lies in the layer above
    left = np.clip(np.searchsorted(grid, depth, side="right") - 1, 0, grid.size - 1)
    at_grid = grid[left] == depth
    spacing = np.diff(grid, append=grid[-1] + 1.0)[left]
    weight = np.where(at_grid, 0.0, (depth - grid[left]) / spacing)
    return Column(depth, layers.astype(int), ~upper, left, weight)


def refined_column(column: Column, max_spacing_m: float) -> tuple[Column, np.ndarray]:
    """Finer rows: every segment of ``column`` divided into equal parts ≤ ``max_spacing_m``.

    Returns
    -------
    (Column, ndarray)
        The fine rows (``left``/``weight`` interpolate from the rows of ``column``, never across
        a boundary), and the index of each row of ``column`` among them.
    """
    depth = column.depth_m
    spacing = np.diff(depth)
    parts = np.concatenate([np.maximum(1, np.ceil(spacing / max_spacing_m - 1e-9)), [1]])
    parts = parts.astype(int)
    left = np.repeat(np.arange(depth.size), parts)
    first = np.cumsum(parts) - parts  # the fine row of each coarse row
    weight = (np.arange(left.size) - first[left]) / parts[left]
    fine_depth = depth[left] + weight * np.concatenate([spacing, [0.0]])[left]
    fine = Column(
        depth_m=np.where(weight == 0.0, depth[left], fine_depth),
        layer_index=column.layer_index[left],
        reported=np.ones(left.size, bool),
        left=left,
        weight=weight,
    )
    return fine, first

"""Where the tunnel–soil kernel is evaluated on a record's frequency grid, and the interpolation
between (docs/tunnel_soil.md, soil stage step 4).

Outgoing waves at radius r vary as K_n(iωr/c), whose phase turns by ωr/c: the transfer functions
at r oscillate in f with period c₂/r (c₂ the S-wave speed, the slower wave). With
N = ``numerics.kernel_samples_per_cycle`` the kernel is evaluated with a stride of
s = ⌊c₂/(N r Δf)⌋ bins, and the bins between are 6-point Lagrange interpolants (degree 5: the
error of a sampled oscillation falls like (2π/N)⁶). Near f = 0 the 2D kernel grows like ln f,
which needs a step small against f: below N s bins the step at bin k is max(1, ⌊k/N⌋) (≤ f/N,
every bin up to 2N), a graded band that joins the stride s at bin N s. The DC bin and the last
bin are always evaluated; with s ≤ 1 or N = 0 every bin is.

Each output depth d is sampled for its own radius r = a + d (:func:`depth_sampled_transfer`):
the shallow depths, whose transfer functions turn slowly, take a longer stride than the deepest.
Depths are grouped so that a group's stride (that of its deepest depth) is within a factor
``DEPTH_GROUP_RATIO`` of each member's own: one kernel call per group.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import scipy.sparse

# Kernel samples in each interpolation stencil.
KERNEL_STENCIL = 6
# Depths share a kernel call while their own stride is less than this factor above the
# group's (a few calls, each sampling at most √2 more densely than its shallowest depth needs).
DEPTH_GROUP_RATIO = math.sqrt(2.0)


def kernel_stride(df_hz: float, samples_per_cycle: int, s_wave_speed: float, radius_m: float):
    """s = ⌊c₂/(N r Δf)⌋, the stride in bins for N samples per period c₂/r (0 when N = 0)."""
    if samples_per_cycle == 0:
        return 0
    return math.floor(s_wave_speed / (samples_per_cycle * radius_m * df_hz))


def kernel_sample_bins(
    n_freq: int, df_hz: float, samples_per_cycle: int, s_wave_speed: float, radius_m: float
) -> np.ndarray:
    """Bins of a record's frequency grid at which the tunnel–soil kernel is evaluated.

    Module docstring: with s = ⌊c₂/(N r Δf)⌋, the graded band below N s (step max(1, ⌊k/N⌋)),
    every s-th bin from there, and the last bin; every bin when s ≤ 1 or N = 0.

    Parameters
    ----------
    n_freq : int
        Bins of the grid, f_k = k Δf, k = 0 … n_freq − 1.
    df_hz : float
        Frequency step Δf (Hz), > 0.
    samples_per_cycle : int
        N ≥ 6, samples per period c₂/r of the transfer functions; 0 for every bin.
    s_wave_speed : float
        Soil shear-wave speed c₂ (m/s).
    radius_m : float
        Distance r from the tunnel axis to the output point (m), a + d.

    Returns
    -------
    ndarray
        Increasing bin indices, starting at 0 and ending at n_freq − 1.
    """
    stride = kernel_stride(df_hz, samples_per_cycle, s_wave_speed, radius_m)
    dense = samples_per_cycle * stride
    if stride <= 1 or dense + KERNEL_STENCIL * stride >= n_freq:
        return np.arange(n_freq)
    graded, k = [], 0
    while k < dense:
        graded.append(k)
        k += min(stride, max(1, k // samples_per_cycle))
    return np.concatenate([graded, np.arange(k, n_freq - 1, stride), [n_freq - 1]]).astype(int)


@numba.njit(cache=True)
def lagrange_stencils(nodes, n_freq, width):
    """(sample, first, weights) per bin: bin k is sample[k]'s value when sampled (≥ 0), else
    Σ_m weights[k, m] · value[first[k] + m], the Lagrange interpolant of the ``width`` samples
    centred on the interval that holds k, never sample 0 (the DC bin's band value)."""
    n_nodes = nodes.size
    sample = np.full(n_freq, -1, np.int64)
    first = np.zeros(n_freq, np.int64)
    weights = np.zeros((n_freq, width))
    for i in range(n_nodes):
        sample[nodes[i]] = i
    for i in range(n_nodes - 1):
        start = min(max(i - (width // 2 - 1), 1), n_nodes - width)
        for k in range(nodes[i] + 1, nodes[i + 1]):
            first[k] = start
            x = float(k)
            for m in range(width):
                xm = float(nodes[start + m])
                w = 1.0
                for o in range(width):
                    if o != m:
                        xo = float(nodes[start + o])
                        w *= (x - xo) / (xm - xo)
                weights[k, m] = w
    return sample, first, weights


@numba.njit(cache=True)
def apply_stencils(sample, first, weights, values, out):
    """Fill (n_freq, m) ``out`` from (n_samples, m) sampled rows by :func:`lagrange_stencils`'s
    weights (sampled rows copied as they are); each value written once."""
    n_freq, width = weights.shape
    n_columns = values.shape[1]
    for k in range(n_freq):
        if sample[k] >= 0:
            for c in range(n_columns):
                out[k, c] = values[sample[k], c]
            continue
        f = first[k]
        for c in range(n_columns):
            total = 0.0
            for m in range(width):
                total += weights[k, m] * values[f + m, c]
            out[k, c] = total


def kernel_interpolation_matrix(sample_bins, n_freq: int) -> scipy.sparse.csr_array:
    """Weights that give a transfer function at every bin from its values at the sample bins.

    Row k is 1 at bin k's own sample when k is sampled; otherwise the Lagrange weights of the
    ``KERNEL_STENCIL`` samples centred on the interval that holds k, never the DC bin (bin 0,
    a band value, not H(0)). The same weights as :func:`interpolate_samples` applies.

    Parameters
    ----------
    sample_bins : ndarray
        Increasing bins, from :func:`kernel_sample_bins` (at least ``KERNEL_STENCIL`` + 1).
    n_freq : int
        Bins of the grid.

    Returns
    -------
    scipy.sparse.csr_array
        (n_freq, n_samples) real weights.
    """
    nodes = np.asarray(sample_bins, dtype=np.int64)
    sample, first, weights = lagrange_stencils(nodes, n_freq, KERNEL_STENCIL)
    between = np.flatnonzero(sample < 0)
    rows = np.concatenate([nodes, np.repeat(between, KERNEL_STENCIL)])
    columns = np.concatenate(
        [np.arange(nodes.size), (first[between, None] + np.arange(KERNEL_STENCIL)).ravel()]
    )
    values = np.concatenate([np.ones(nodes.size), weights[between].ravel()])
    return scipy.sparse.csr_array((values, (rows, columns)), shape=(n_freq, nodes.size))


def interpolate_samples(sample_bins, n_freq: int, values: np.ndarray, out=None, stencils=None):
    """Complex (n_freq, m) transfer functions from their (n_samples, m) values at the sample
    bins (6-point Lagrange between them, real weights: real and imaginary parts alike), written
    into ``out`` (complex, (n_freq, m), e.g. a block of columns of a larger array) if given;
    ``stencils``: :func:`lagrange_stencils` of the bins, if already made."""
    if stencils is None:
        stencils = lagrange_stencils(np.asarray(sample_bins, np.int64), n_freq, KERNEL_STENCIL)
    pairs = np.ascontiguousarray(values).view(float)
    if out is None:
        out = np.empty((n_freq, values.shape[1]), dtype=complex)
    if out.strides[1] != out.itemsize:
        raise ValueError("out must hold whole complex values side by side in each row")
    # a complex array's float view: (n_freq, 2m), real and imaginary parts side by side
    floats = out.view(float) if out.flags.c_contiguous else _float_columns(out)
    apply_stencils(*stencils, pairs, floats)
    return out


def _float_columns(block: np.ndarray) -> np.ndarray:
    """The float view (n, 2m) of a block of columns of a C-ordered complex array."""
    return np.lib.stride_tricks.as_strided(
        block.real, shape=(block.shape[0], 2 * block.shape[1]), strides=(block.strides[0], 8)
    )


def _sampled_transfer(f_hz, bins, sampled, outs, columns) -> list[np.ndarray]:
    """Fill ``outs[i][:, columns]`` (allocated when None) from the values sampled at ``bins``:
    row 0 made real (the DC band value), the rest interpolated."""
    if outs is None:
        outs = [np.zeros((f_hz.size, values.shape[1]), dtype=complex) for values in sampled]
    stencils = None
    if bins.size < f_hz.size:
        stencils = lagrange_stencils(np.asarray(bins, np.int64), f_hz.size, KERNEL_STENCIL)
    for values, out in zip(sampled, outs, strict=True):
        values[0] = values[0].real
        if bins.size == f_hz.size:
            out[:, columns] = values
        elif not values.any():  # a component that vanishes under the invert: zeros
            continue
        elif isinstance(columns, slice):  # interpolated in place
            interpolate_samples(bins, f_hz.size, values, out[:, columns], stencils)
        else:
            out[:, columns] = interpolate_samples(bins, f_hz.size, values, stencils=stencils)
    return outs


def record_grid_transfer(f_hz, depth_m, evaluate, tunnel, soil, numerics) -> list[np.ndarray]:
    """Transfer functions at every frequency of a record grid, row 0 the DC band value.

    The kernel is evaluated at :func:`kernel_sample_bins` for the radius a + max(depth_m) and
    interpolated in between (module docstring); the DC bin holds Re of the value at Δf/(2e),
    the band average of A + B ln f (:func:`model.soil.response.dc_band_receptance`), evaluated
    in the same call.

    Parameters
    ----------
    f_hz : ndarray
        (nk,) the grid, f_k = k Δf (:func:`model.soil.response.padded_record_grid`).
    depth_m : ndarray
        (nd,) depths below the ring–soil interface (m), ≥ 0.
    evaluate : callable
        ``evaluate(freq_hz)`` → sequence of complex (n, nd) transfer functions at ``freq_hz``
        (Hz, > 0), fresh arrays.
    tunnel, soil : model.params.Tunnel, model.params.Soil
        Ring radius a and S-wave speed c₂, which set the sampling.
    numerics : model.params.Numerics
        Uses kernel_samples_per_cycle.

    Returns
    -------
    list of ndarray
        Complex (nk, nd) transfer functions, in the order ``evaluate`` gives them.
    """
    f_hz = np.asarray(f_hz, dtype=float)
    radius = tunnel.ring_radius + float(np.max(depth_m))
    bins = kernel_sample_bins(
        f_hz.size, f_hz[1], numerics.kernel_samples_per_cycle, soil.s_wave_speed, radius
    )
    freq = f_hz[bins]
    freq[0] = 0.5 * f_hz[1] / math.e
    return _sampled_transfer(f_hz, bins, evaluate(freq), None, slice(None))


def depth_groups(df_hz: float, depth_m, tunnel, soil, numerics) -> list[np.ndarray]:
    """Indices of the depths that share a kernel call, deepest group first (module docstring).

    Parameters
    ----------
    df_hz : float
        Frequency step of the grid (Hz).
    depth_m : ndarray
        (nd,) depths below the ring–soil interface (m).
    tunnel, soil, numerics
        Ring radius, S-wave speed and kernel_samples_per_cycle.

    Returns
    -------
    list of slice or ndarray
        Indices into ``depth_m`` (a slice where they are consecutive, as for increasing
        depths), covering every depth once.
    """
    depth = np.asarray(depth_m, dtype=float)
    order = np.argsort(-depth, kind="stable")
    strides = [
        kernel_stride(
            df_hz,
            numerics.kernel_samples_per_cycle,
            soil.s_wave_speed,
            tunnel.ring_radius + depth[j],
        )
        for j in order
    ]
    groups, start = [], 0
    for k in range(1, order.size + 1):
        if k == order.size or strides[k] >= DEPTH_GROUP_RATIO * max(strides[start], 1):
            members = np.sort(order[start:k])
            contiguous = members[-1] - members[0] == members.size - 1
            groups.append(slice(members[0], members[-1] + 1) if contiguous else members)
            start = k
    return groups


def depth_sample_bins(f_hz, depth_m, tunnel, soil, numerics) -> list[tuple[object, np.ndarray]]:
    """(depth indices, bins) of each kernel call of :func:`depth_sampled_transfer`: every depth
    in the indices is evaluated at exactly those bins of ``f_hz`` (bin 0 at Δf/(2e)).

    Parameters
    ----------
    f_hz : ndarray
        (nk,) the record grid (Hz).
    depth_m : ndarray
        (nd,) depths below the ring–soil interface (m).
    tunnel, soil, numerics
        Ring radius, S-wave speed and kernel_samples_per_cycle.

    Returns
    -------
    list of (slice or ndarray, ndarray)
    """
    depth = np.asarray(depth_m, dtype=float)
    calls = []
    for group in depth_groups(f_hz[1], depth, tunnel, soil, numerics):
        radius = tunnel.ring_radius + float(np.max(depth[group]))
        bins = kernel_sample_bins(
            len(f_hz), f_hz[1], numerics.kernel_samples_per_cycle, soil.s_wave_speed, radius
        )
        calls.append((group, bins))
    return calls


def depth_sampled_transfer(f_hz, depth_m, evaluate, tunnel, soil, numerics) -> list[np.ndarray]:
    """:func:`record_grid_transfer` with each group of depths sampled for its own radius.

    Parameters
    ----------
    f_hz, tunnel, soil, numerics
        As :func:`record_grid_transfer`.
    depth_m : ndarray
        (nd,) depths below the ring–soil interface (m), ≥ 0.
    evaluate : callable
        ``evaluate(freq_hz, depth_m)`` → sequence of complex (n, len(depth_m)) transfer
        functions at ``freq_hz`` (Hz, > 0) and those depths, fresh arrays.

    Returns
    -------
    list of ndarray
        Complex (nk, nd) transfer functions, in the order ``evaluate`` gives them.
    """
    depth = np.asarray(depth_m, dtype=float)
    f_hz = np.asarray(f_hz, dtype=float)
    transfers = None
    for group, bins in depth_sample_bins(f_hz, depth, tunnel, soil, numerics):
        freq = f_hz[bins]
        freq[0] = 0.5 * f_hz[1] / math.e
        sampled = evaluate(freq, depth[group])
        if transfers is None:
            transfers = [np.zeros((f_hz.size, depth.size), dtype=complex) for _ in sampled]
        transfers = _sampled_transfer(f_hz, bins, sampled, transfers, group)
    return transfers

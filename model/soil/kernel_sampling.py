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
the shallow depths, whose transfer functions turn slowly, take a longer stride than the deepest,
as a nested subset of the deepest depth's bins (:func:`depth_sample_bins`), so that one kernel
call at those bins, told which (frequency, depth) pairs to compute, serves every depth.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import scipy.sparse

# Kernel samples in each interpolation stencil.
KERNEL_STENCIL = 6


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


@numba.njit(cache=True, nogil=True)
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


@numba.njit(cache=True, nogil=True)
def apply_stencils(sample, first, weights, row_of, values, out):
    """Fill (n_freq, m) ``out`` from sampled rows by :func:`lagrange_stencils`'s weights
    (sampled rows copied as they are; each value written once): sample i is row row_of[i] of
    ``values``."""
    n_freq, width = weights.shape
    n_columns = values.shape[1]
    for k in range(n_freq):
        if sample[k] >= 0:
            row = row_of[sample[k]]
            for c in range(n_columns):
                out[k, c] = values[row, c]
            continue
        f = first[k]
        if width == 6:  # KERNEL_STENCIL written out: 8 times faster, the same sum in order
            r0, r1, r2 = row_of[f], row_of[f + 1], row_of[f + 2]
            r3, r4, r5 = row_of[f + 3], row_of[f + 4], row_of[f + 5]
            w0, w1, w2 = weights[k, 0], weights[k, 1], weights[k, 2]
            w3, w4, w5 = weights[k, 3], weights[k, 4], weights[k, 5]
            for c in range(n_columns):
                out[k, c] = (
                    w0 * values[r0, c]
                    + w1 * values[r1, c]
                    + w2 * values[r2, c]
                    + w3 * values[r3, c]
                    + w4 * values[r4, c]
                    + w5 * values[r5, c]
                )
            continue
        for c in range(n_columns):
            total = 0.0
            for m in range(width):
                total += weights[k, m] * values[row_of[f + m], c]
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


def interpolate_samples(
    sample_bins, n_freq: int, values: np.ndarray, out=None, stencils=None, rows=None
):
    """Complex (n_freq, m) transfer functions from their (n_samples, m) values at the sample
    bins (6-point Lagrange between them, real weights: real and imaginary parts alike), written
    into ``out`` (complex, (n_freq, m), e.g. a block of columns of a larger array) if given;
    ``stencils``: :func:`lagrange_stencils` of the bins, if already made; ``rows``: the rows of
    ``values`` that hold the samples (default its rows in order)."""
    if stencils is None:
        stencils = lagrange_stencils(np.asarray(sample_bins, np.int64), n_freq, KERNEL_STENCIL)
    if rows is None:
        rows = np.arange(len(sample_bins))
    if out is None:
        out = np.empty((n_freq, values.shape[1]), dtype=complex)
    apply_stencils(*stencils, rows, _float_view(values), _float_view(out))
    return out


def _float_view(block: np.ndarray) -> np.ndarray:
    """(n, 2m) floats, real and imaginary parts side by side, of a complex (n, m) array or of a
    block of columns of one."""
    if block.strides[1] != block.itemsize:
        raise ValueError("the complex values of a row must lie side by side")
    return block.view(float) if block.flags.c_contiguous else _float_columns(block)


def _float_columns(block: np.ndarray) -> np.ndarray:
    """The float view (n, 2m) of a block of columns of a C-ordered complex array."""
    return np.lib.stride_tricks.as_strided(
        block.real, shape=(block.shape[0], 2 * block.shape[1]), strides=(block.strides[0], 8)
    )


def _sampled_transfer(f_hz, bins, sampled, outs, columns, rows=None) -> list[np.ndarray]:
    """Fill ``outs[i][:, columns]`` (allocated when None) from the values sampled at ``bins``
    (rows ``rows`` of each ``sampled`` array, default all, and its ``columns``): row 0 made real
    (the DC band value), the rest interpolated."""
    if outs is None:
        outs = [np.zeros((f_hz.size, values.shape[1]), dtype=complex) for values in sampled]
    stencils = None
    if bins.size < f_hz.size:
        stencils = lagrange_stencils(np.asarray(bins, np.int64), f_hz.size, KERNEL_STENCIL)
    for values, out in zip(sampled, outs, strict=True):
        values[0] = values[0].real
        if bins.size == f_hz.size:
            out[:, columns] = values[:, columns] if rows is None else values[rows][:, columns]
        elif not values[:, columns].any():  # a component that vanishes under the invert
            continue
        elif isinstance(columns, slice):  # interpolated in place
            interpolate_samples(
                bins, f_hz.size, values[:, columns], out[:, columns], stencils, rows
            )
        else:
            block = np.ascontiguousarray(values[:, columns])
            out[:, columns] = interpolate_samples(
                bins, f_hz.size, block, stencils=stencils, rows=rows
            )
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


@numba.njit(cache=True, nogil=True)
def nested_subset(nodes, factor, base_stride, samples_per_cycle):
    """Indices into ``nodes`` (a :func:`kernel_sample_bins` sampling of stride s) of the coarser
    sampling of stride factor · s: from each kept bin k the next kept node is the farthest within
    min(factor · s, max(1, ⌊k/N⌋)) bins (the same graded rule); the first and last kept."""
    n = nodes.size
    keep = np.empty(n, np.int64)
    keep[0] = 0
    count = 1
    j = 0
    while True:
        k = nodes[keep[count - 1]]
        reach = k + min(factor * base_stride, max(1, k // samples_per_cycle))
        while j + 1 < n and nodes[j + 1] <= reach:
            j += 1
        if j >= n - 1:
            break
        keep[count] = j
        count += 1
    keep[count] = n - 1
    return keep[: count + 1]


def depth_sample_bins(f_hz, depth_m, tunnel, soil, numerics):
    """How :func:`depth_sampled_transfer` samples each depth (module docstring).

    The deepest depth takes :func:`kernel_sample_bins` for its radius, stride s₀; a depth whose
    own stride is s takes the nested subset of those bins with stride ⌊s/s₀⌋ s₀ (≤ s, so at least
    N samples per period c₂/r at its radius r), depths with equal factors forming one group.

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
    bins : ndarray
        The deepest depth's bins: the frequencies of the one kernel call.
    groups : list of (slice or ndarray, ndarray)
        Per group, its depths (indices into ``depth_m``; a slice where consecutive) and the
        indices into ``bins`` at which they are evaluated.
    """
    depth = np.asarray(depth_m, dtype=float)
    n_freq, df = len(f_hz), f_hz[1]
    count, speed, a = numerics.kernel_samples_per_cycle, soil.s_wave_speed, tunnel.ring_radius
    bins = kernel_sample_bins(n_freq, df, count, speed, a + float(np.max(depth)))
    base = kernel_stride(df, count, speed, a + float(np.max(depth)))
    if bins.size == n_freq:
        return bins, [(slice(0, depth.size), np.arange(bins.size))]
    factors = np.array([max(1, kernel_stride(df, count, speed, a + d) // base) for d in depth])
    groups = []
    for factor in np.unique(factors)[::-1]:
        members = np.flatnonzero(factors == factor)
        nodes = nested_subset(bins, int(factor), base, count)
        if nodes.size <= KERNEL_STENCIL:
            nodes = np.arange(bins.size)
        contiguous = members[-1] - members[0] == members.size - 1
        columns = slice(members[0], members[-1] + 1) if contiguous else members
        groups.append((columns, nodes))
    return bins, groups


def depth_sampled_transfer(f_hz, depth_m, evaluate, tunnel, soil, numerics) -> list[np.ndarray]:
    """:func:`record_grid_transfer` with each depth sampled for its own radius, one kernel call.

    Parameters
    ----------
    f_hz, tunnel, soil, numerics
        As :func:`record_grid_transfer`.
    depth_m : ndarray
        (nd,) depths below the ring–soil interface (m), ≥ 0.
    evaluate : callable
        ``evaluate(freq_hz, depth_m, mask)`` → sequence of complex (n, nd) transfer functions at
        ``freq_hz`` (Hz, > 0) and the depths, fresh arrays; ``mask`` (n, nd) bool marks the
        pairs that are used (the others may be left 0).

    Returns
    -------
    list of ndarray
        Complex (nk, nd) transfer functions, in the order ``evaluate`` gives them.
    """
    depth = np.asarray(depth_m, dtype=float)
    f_hz = np.asarray(f_hz, dtype=float)
    bins, groups = depth_sample_bins(f_hz, depth, tunnel, soil, numerics)
    mask = np.zeros((bins.size, depth.size), dtype=bool)
    for columns, nodes in groups:
        mask[np.ix_(nodes, np.arange(depth.size)[columns])] = True
    freq = f_hz[bins]
    freq[0] = 0.5 * f_hz[1] / math.e
    sampled = evaluate(freq, depth, mask)
    if len(groups) == 1:
        return _sampled_transfer(f_hz, bins, sampled, None, slice(None))
    if not all(isinstance(columns, slice) for columns, _ in groups):
        transfers = [np.zeros((f_hz.size, depth.size), dtype=complex) for _ in sampled]
        for columns, nodes in groups:
            _sampled_transfer(f_hz, bins[nodes], sampled, transfers, columns, nodes)
        return transfers
    # every column of a nonzero function is written below: no need to clear it first
    transfers = [
        (np.empty if values.any() else np.zeros)((f_hz.size, depth.size), dtype=complex)
        for values in sampled
    ]
    # Every group's columns consecutive (increasing depths): one stencil pass per transfer
    # function over whole C-ordered arrays, far faster than a pass per block of columns
    stencils = [
        (lagrange_stencils(bins[nodes].astype(np.int64), f_hz.size, KERNEL_STENCIL), nodes)
        for _, nodes in groups
    ]
    samples = np.stack([s[0] for s, _ in stencils])
    firsts = np.stack([s[1] for s, _ in stencils])
    weights = np.stack([s[2] for s, _ in stencils])
    rows = np.zeros((len(groups), bins.size), dtype=np.int64)
    for g, (_, nodes) in enumerate(stencils):
        rows[g, : nodes.size] = nodes
    spans = np.array([(2 * c.start, 2 * c.stop) for c, _ in groups], dtype=np.int64)
    for values, out in zip(sampled, transfers, strict=True):
        values[0] = values[0].real
        if values.any():  # else a component that vanishes under the invert: zeros
            values = np.ascontiguousarray(values)
            apply_grouped_stencils(
                samples, firsts, weights, rows, spans, values.view(float), out.view(float)
            )
    return transfers


@numba.njit(cache=True, nogil=True)
def apply_grouped_stencils(samples, firsts, weights, rows, spans, values, out):
    """:func:`apply_stencils` for several groups of columns at once: group g fills the (float)
    columns spans[g, 0] … spans[g, 1] − 1 of ``out`` from the rows rows[g] of ``values`` with
    the stencils samples[g], firsts[g], weights[g] (six weights; whole C-ordered arrays, which
    the compiler streams far better than blocks of columns)."""
    n_freq = samples.shape[1]
    for g in range(spans.shape[0]):
        c0, c1 = spans[g, 0], spans[g, 1]
        row_of = rows[g]
        for k in range(n_freq):
            if samples[g, k] >= 0:
                r = row_of[samples[g, k]]
                for c in range(c0, c1):
                    out[k, c] = values[r, c]
                continue
            f = firsts[g, k]
            r0, r1, r2 = row_of[f], row_of[f + 1], row_of[f + 2]
            r3, r4, r5 = row_of[f + 3], row_of[f + 4], row_of[f + 5]
            w0, w1, w2 = weights[g, k, 0], weights[g, k, 1], weights[g, k, 2]
            w3, w4, w5 = weights[g, k, 3], weights[g, k, 4], weights[g, k, 5]
            for c in range(c0, c1):
                out[k, c] = (
                    w0 * values[r0, c]
                    + w1 * values[r1, c]
                    + w2 * values[r2, c]
                    + w3 * values[r3, c]
                    + w4 * values[r4, c]
                    + w5 * values[r5, c]
                )

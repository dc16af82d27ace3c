"""Long logs made affordable: block means down to a bounded number of points.

A 2M-row log at 1 kHz carries far more samples than a fit of six parameters needs, and the fits'
cost (Jacobians n × p, several least-squares passes) grows with n. :func:`block_mean` replaces
each block of k consecutive samples by their mean, k chosen so that at most :data:`MAX_POINTS`
remain. For a model that is smooth over a block, the block mean of the data is the sufficient
statistic of that block (the mean of white noise over k samples has 1/k of its variance, and the
fits estimate the noise from the averaged residuals), so the estimates and their standard errors
lose next to nothing; the averaging also cancels encoder quantisation. The recording says what was
done in ``metadata["warnings"]`` and ``metadata["decimation"]``.
"""

from __future__ import annotations

import math

import numpy as np

from motorlab.recording import Recording

#: At most this many points enter a fit (a 50-s log at 1 kHz is not averaged at all).
MAX_POINTS = 50_000


def _blocks(values: np.ndarray, k: int) -> np.ndarray:
    """Means of consecutive blocks of ``k`` samples (the last block may be shorter)."""
    whole = values.size // k * k
    means = values[:whole].reshape(-1, k).mean(axis=1)
    if whole < values.size:
        means = np.append(means, values[whole:].mean())
    return means


def block_mean(recording: Recording, *, max_points: int = MAX_POINTS) -> Recording:
    """``recording`` with at most ``max_points`` samples, each the mean of a block of consecutive ones.

    Parameters
    ----------
    recording
        A time series (log); returned unchanged when it is short enough.
    max_points
        The most samples to keep.

    Returns
    -------
    Recording
        Block means of ``time`` and every signal; ``lines`` the first line of each block;
        segments and ``file_starts`` mapped to block indices.
    """
    n = len(recording)
    if n <= max_points:
        return recording
    k = math.ceil(n / max_points)
    signals = {name: _blocks(values, k) for name, values in recording.signals.items()}
    lines = None if recording.lines is None else recording.lines[::k].copy()
    metadata = dict(recording.metadata)
    metadata["decimation"] = {"block": k, "samples": n, "points": math.ceil(n / k)}
    metadata["warnings"] = [
        *(recording.metadata.get("warnings") or []),
        f"{recording.source or 'log'}: {n} samples averaged in blocks of {k} ({math.ceil(n / k)} points) "
        "to bound time and memory; the fit and its standard errors use the block means",
    ]
    if isinstance(metadata.get("file_starts"), list):
        metadata["file_starts"] = [int(s) // k for s in metadata["file_starts"]]
    out = Recording(time=_blocks(recording.time, k), signals=signals, metadata=metadata, source=recording.source,
                    lines=lines)
    out.segments = {key: (a // k, -(-b // k)) for key, (a, b) in recording.segments.items()}
    return out

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
from collections.abc import Callable

import numpy as np

from motorlab.recording import Recording

#: At most this many points enter a fit (a 50-s log at 1 kHz is not averaged at all).
MAX_POINTS = 50_000


def consecutive(x: np.ndarray, group: int, statistic: Callable[..., np.ndarray] = np.median) -> np.ndarray:
    """``statistic`` (median or mean) of ``group`` consecutive samples of ``x``, the last group shorter when
    the size is no multiple: how a log denser than its estimate needs is reduced (and the analysis says so)."""
    whole = x.size // group * group
    out = statistic(x[:whole].reshape(-1, group), axis=1)
    return np.append(out, statistic(x[whole:])) if whole < x.size else out


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
    signals = {name: consecutive(values, k, np.mean) for name, values in recording.signals.items()}
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
    out = Recording(time=consecutive(recording.time, k, np.mean), signals=signals, metadata=metadata,
                    source=recording.source, lines=lines)
    out.segments = {key: (a // k, -(-b // k)) for key, (a, b) in recording.segments.items()}
    return out


#: A block "holds" the voltage when its readings span at most this many noise standard deviations.
HOLD_SIGMAS = 8.0


def driven_log(recording: Recording, *, max_points: int = MAX_POINTS) -> Recording:
    """A long voltage-driven log made affordable without blurring its input.

    Block means (:func:`block_mean`) where the logged voltage holds over every block; otherwise the
    window of ``max_points`` consecutive samples over which the voltage changes most. A block mean of
    a voltage that switches inside its block is a level the motor never saw: simulated as held over
    the block, it biases a fit driven by the voltage (identify: b by −23 % and K, R by 8 standard
    errors on a 60 000-sample log averaged in pairs).

    Parameters
    ----------
    recording
        A log with ``voltage`` [V] (without one, :func:`block_mean`).
    max_points
        The most samples to keep.

    Returns
    -------
    Recording
        The recording itself when short enough, its block means, or a window of it, with a warning
        in ``metadata["warnings"]`` saying which and ``metadata["decimation"]``.
    """
    n = len(recording)
    if n <= max_points or "voltage" not in recording.signals:
        return block_mean(recording, max_points=max_points)
    v = np.asarray(recording.signals["voltage"], dtype=float)
    k = math.ceil(n / max_points)
    whole = n // k * k
    blocks = v[:whole].reshape(-1, k)
    spread = float(np.max(blocks.max(axis=1) - blocks.min(axis=1)))
    d = np.diff(v)
    noise = float(1.4826 * np.median(np.abs(d - np.median(d)))) / math.sqrt(2.0)
    if spread <= HOLD_SIGMAS * noise + 1e-9 * max(float(np.max(np.abs(v))), 1e-12):
        return block_mean(recording, max_points=max_points)
    change = np.concatenate([[0.0], np.cumsum(np.abs(d))])  # total variation up to each sample
    starts = np.arange(0, n - max_points + 1, max(1, max_points // 10))
    a = int(starts[np.argmax(change[starts + max_points - 1] - change[starts])])
    out = recording.select(slice(a, a + max_points))
    metadata = out.metadata
    if isinstance(metadata.get("file_starts"), list):
        metadata["file_starts"] = [int(s) - a for s in metadata["file_starts"] if a <= int(s) < a + max_points]
    metadata["decimation"] = {"window": [a, a + max_points], "samples": n, "points": max_points}
    t0, t1 = float(recording.time[a]), float(recording.time[a + max_points - 1])
    metadata["warnings"] = [
        *(recording.metadata.get("warnings") or []),
        f"{recording.source or 'log'}: {n} samples; the fit uses the {max_points} from {t0:.6g} s to {t1:.6g} s "
        "(where the voltage changes most): block means would blur the voltage's switches inside blocks and "
        "bias the fit; split the log to fit the rest",
    ]
    return out

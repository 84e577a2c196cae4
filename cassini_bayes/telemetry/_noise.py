"""The package's one white-noise estimator.
"""

from __future__ import annotations

import numpy as np

_MAD_TO_SD = 1.4826
RATE_NOISE_FLOORS = (1e-9, 1e-7)
"""rad/s: body-rate and wheel-rate noise levels are floored here, so that noise-free synthetic
data keep finite noise priors and thresholds (the noise priors and the input checks)."""


def white_noise_sd(x: np.ndarray, *, differenced: bool = False,
                   keep: np.ndarray | None = None) -> float:
    """Robust sd of white noise on a smooth signal ``x`` (n, ...) sampled along axis 0: the MAD
    of its second differences (all components pooled, non-finite values left out) ÷ √6.

    The one white-noise estimator of the package (noise priors, input checks). For white noise
    of sd ``σ`` second differences have sd ``√6 σ``; the median absolute deviation (× 1.4826,
    the normal's MAD-to-sd factor) ignores the few samples where the signal itself bends (a
    pulse, a wheel ramp, the slew profile).

    ``differenced``: ``x`` already holds the signal's first differences (e.g. attitude
    increments ``rotvec(q_{t+1} q_t⁻¹)``), so one more difference is taken. 0 when the signal
    has fewer than four samples or no finite difference.

    ``keep``: (n − 2,) bool (``n − 1`` when ``differenced``), the second differences to use;
    those a known input bends (a thruster pulse between their samples) are left out.
    """
    order = 1 if differenced else 2
    if x.shape[0] < 2 + order or x.size == 0:
        return 0.0
    d = np.diff(x, n=order, axis=0)
    if keep is not None:
        d = d[np.asarray(keep, bool)]
    d = d.ravel()
    d = d[np.isfinite(d)]
    if d.size == 0:
        return 0.0
    return float(_MAD_TO_SD * np.median(np.abs(d - np.median(d))) / np.sqrt(6.0))

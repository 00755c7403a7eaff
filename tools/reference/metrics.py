"""Image comparisons shared by check.py and ptracer.py: luminance, relative RMSE, the
caustic region, and block averages."""

import numpy as np


def lum(a):
    """Luminance as the mean of the RGB channels."""
    return a.mean(axis=-1)


def rel_rmse(a, b, mask=None):
    """sqrt(mean |a-b|^2) / mean((a+b)/2), over the mask (all channels)."""
    if mask is None:
        mask = np.ones(a.shape[:2], bool)
    d = (a - b)[mask]
    m = (0.5 * (a + b))[mask].mean()
    return float(np.sqrt((d ** 2).mean()) / m) if m > 0 else float("nan")


def caustic_mask(caustic, full):
    """Caustic region: lit pixels (luminance > 0) whose caustic part is >= 10 % of the
    pixel's luminance, as tests/accuracy.rs counts it. Black pixels (the background) are
    not in it: 0 >= 0.1 * 0 used to count them, which diluted the region's mean."""
    return (lum(full) > 0) & (lum(caustic) >= 0.1 * lum(full))


def binned(a, b):
    """Means over b x b pixel blocks (a trailing partial block is dropped)."""
    H, W = a.shape[:2]
    return a[: H // b * b, : W // b * b].reshape(H // b, b, W // b, b, -1).mean(axis=(1, 3))

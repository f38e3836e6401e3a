"""Residual vectors per point before and after the final model, as a PNG.

matplotlib is an optional extra (`pip install 'rapidcomp[plot]'`); without
it the plot is skipped with a note, never an error.
"""

from __future__ import annotations

import io

import numpy as np

MISSING = "matplotlib is not installed (pip install 'rapidcomp[plot]'); plot skipped"


def available() -> bool:
    import importlib.util
    return importlib.util.find_spec("matplotlib") is not None


def residual_plot(xyz_mm: np.ndarray, before: np.ndarray, after: np.ndarray,
                  title: str) -> bytes:
    """Two top views (x-y) of the measured points with their residual
    vectors drawn to one common scale, coloured by the z component."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    longest = max(float(np.max(np.linalg.norm(before, axis=1))), 1e-12)
    span = float(np.ptp(xyz_mm[:, :2], axis=0).max()) or 1.0
    gain = 0.15 * span / longest      # the longest arrow is 15 % of the point spread
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.5), sharex=True, sharey=True)
    vmax = max(float(np.abs(before[:, 2]).max()), 1e-12) * 1000
    for ax, res, name in ((axes[0], before, "before"), (axes[1], after, "after")):
        q = ax.quiver(xyz_mm[:, 0], xyz_mm[:, 1], res[:, 0] * gain, res[:, 1] * gain,
                      res[:, 2] * 1000, angles="xy", scale_units="xy", scale=1,
                      cmap="coolwarm", clim=(-vmax, vmax))
        ax.scatter(xyz_mm[:, 0], xyz_mm[:, 1], s=6, c="k")
        rms = float(np.sqrt(np.mean(np.sum(res ** 2, axis=1)))) * 1000
        ax.set_title(f"{name}: RMS {rms:.1f} um")
        ax.set_xlabel("x mm")
        ax.set_aspect("equal")
    # quiver does not widen the axes for its arrows: leave room for the longest.
    pad = longest * gain + 0.05 * span
    lo, hi = xyz_mm[:, :2].min(axis=0) - pad, xyz_mm[:, :2].max(axis=0) + pad
    axes[0].set_xlim(lo[0], hi[0])
    axes[0].set_ylim(lo[1], hi[1])
    axes[0].set_ylabel("y mm")
    fig.colorbar(q, ax=axes, label="residual z um")
    fig.suptitle(f"{title} (arrows x{gain:.0f}: {longest * 1000:.0f} um drawn as "
                 f"{longest * gain:.0f} mm)")
    buf = io.BytesIO()
    # No timestamp in the PNG metadata: the same input gives the same bytes.
    fig.savefig(buf, format="png", dpi=90, metadata={"Software": None})
    plt.close(fig)
    return buf.getvalue()

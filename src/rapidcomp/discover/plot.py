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


VIEWS = ((0, 1, "top (x-y)"), (0, 2, "front (x-z)"), (1, 2, "side (y-z)"))
COLORS = ("tab:blue", "tab:orange")
AXES = "xyz"


def residual_plot(xyz_mm: np.ndarray, before: np.ndarray, after: np.ndarray,
                  title: str, sigma_mm: float | None = None) -> bytes:
    """The measured points in three views (top, front, side) with their
    residual vectors, before (first row) and after the final model (second
    row), each row drawn to its own scale (the after-residuals are a tenth
    of the before ones: one scale would hide them) and coloured by the
    component out of the view's plane; below, the residual length of every
    point before and after, with the noise's expected length."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(15, 11))
    grid = fig.add_gridspec(3, 3, height_ratios=(1, 1, 0.7))
    for row, (res, name) in enumerate(((before, "before"), (after, "after"))):
        longest = max(float(np.max(np.linalg.norm(res, axis=1))), 1e-12)
        rms = float(np.sqrt(np.mean(np.sum(res ** 2, axis=1)))) * 1000
        for col, (i, j, view) in enumerate(VIEWS):
            ax = fig.add_subplot(grid[row, col])
            span = float(np.ptp(xyz_mm[:, [i, j]], axis=0).max()) or 1.0
            gain = 0.12 * span / longest      # the longest arrow: 12 % of the spread
            ax.quiver(xyz_mm[:, i], xyz_mm[:, j], res[:, i] * gain, res[:, j] * gain,
                      angles="xy", scale_units="xy", scale=1, color=COLORS[row], width=0.005)
            ax.scatter(xyz_mm[:, i], xyz_mm[:, j], s=5, c="k")
            # quiver does not widen the axes for its arrows: room for the longest.
            pad = longest * gain + 0.05 * span
            lo, hi = xyz_mm[:, [i, j]].min(axis=0) - pad, xyz_mm[:, [i, j]].max(axis=0) + pad
            ax.set_xlim(lo[0], hi[0])
            ax.set_ylim(lo[1], hi[1])
            ax.set_aspect("equal", adjustable="box")
            ax.set_xlabel(f"{AXES[i]} mm")
            ax.set_ylabel(f"{AXES[j]} mm")
            ax.set_title(f"{name}, {view}: RMS {rms:.1f} um; {longest * 1000:.0f} um drawn "
                         f"as {longest * gain:.0f} mm", fontsize=9)
    ax = fig.add_subplot(grid[2, :])
    idx = np.arange(1, len(xyz_mm) + 1)
    ax.plot(idx, np.linalg.norm(before, axis=1) * 1000, "o-", ms=3, lw=0.6, label="before",
            color=COLORS[0])
    ax.plot(idx, np.linalg.norm(after, axis=1) * 1000, "o-", ms=3, lw=0.6, label="after",
            color=COLORS[1])
    if sigma_mm:
        # The mean length of a 3-D Gaussian error of sigma per axis.
        ax.axhline(sigma_mm * 1000 * 1.596, color="k", ls="--", lw=0.8,
                   label=f"noise ({sigma_mm * 1000:.1f} um per axis: mean length)")
    ax.set_yscale("log")
    ax.set_xlabel("point (in file order)")
    ax.set_ylabel("residual length um")
    ax.legend(fontsize=8)
    ax.grid(True, which="both", lw=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    buf = io.BytesIO()
    # No timestamp in the PNG metadata: the same input gives the same bytes.
    fig.savefig(buf, format="png", dpi=80, metadata={"Software": None})
    plt.close(fig)
    return buf.getvalue()

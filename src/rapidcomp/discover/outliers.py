"""Gross measurement errors: points discover leaves out of the fit.

A broken beam, a reflector knocked, a mistyped row: one point far off
inflates the noise estimate and drags the fit. Each point's residual of
the whole-catalogue fit, scaled to the noise's covariance at that point
(standardized), is compared with a robust scale of all of them (1.4826 x
the median absolute deviation): a point whose squared standardized length
exceeds the chi-square(3) quantile at 0.001 / N (Bonferroni over the
points) is a gross error. It is reported with its deleted residual (what
it is off by, had it not been fitted), removed, and the test repeated.
At most a tenth of the points are removed: more than that is not a few
gross errors but data and model far apart.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .fit import CatalogueFit, catalogue_fit
from .noise import MIN_NOISE_DOF
from .stats import chi2_ppf

ALPHA = 0.001
MAX_SHARE = 0.1
MAX_ROUNDS = 5
MIN_SCALE_MM = 1e-6


@dataclass(frozen=True)
class Outlier:
    point: str
    line: int
    off_mm: float          # length of its deleted residual
    sigmas: float          # its standardized length in robust sigmas


@dataclass(frozen=True, eq=False)
class Screened:
    rows: np.ndarray                  # indices of the points kept
    outliers: tuple[Outlier, ...]
    full: CatalogueFit                # the whole-catalogue fit of the kept points
    note: str | None = None


def screen(model, data, effects) -> Screened:
    rows = np.arange(len(data))
    out: list[Outlier] = []
    note = None
    for _ in range(MAX_ROUNDS):
        full = catalogue_fit(model.subset(rows), data.xyz_mm[rows], effects)
        if 3 * len(rows) - full.rank < MIN_NOISE_DOF:
            break
        z = full.standardized
        scale = max(1.4826 * float(np.median(np.abs(z - np.median(z, axis=0)))), MIN_SCALE_MM)
        d2 = np.sum(z ** 2, axis=1) / scale ** 2
        bad = np.flatnonzero(d2 > chi2_ppf(1.0 - ALPHA / len(rows), 3))
        if not len(bad):
            break
        if len(out) + len(bad) > MAX_SHARE * len(data):
            note = (f"{len(out) + len(bad)} points lie far outside the rest: more than a tenth "
                    "of the data, so they are not treated as gross errors (none is left out)")
            # (Those an earlier round left out too: they are of the same
            # many, not a few gross errors.)
            if out:
                rows, out = np.arange(len(data)), []
                full = catalogue_fit(model, data.xyz_mm, effects)
            break
        for i in bad[np.argsort(-d2[bad], kind="stable")]:
            k = rows[i]
            out.append(Outlier(data.names[k], data.lines[k],
                               float(np.linalg.norm(full.deleted[i])), float(np.sqrt(d2[i]))))
        rows = np.delete(rows, bad)
    else:
        full = catalogue_fit(model.subset(rows), data.xyz_mm[rows], effects)
    return Screened(rows, tuple(out), full, note)

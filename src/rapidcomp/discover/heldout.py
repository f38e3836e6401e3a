"""Held-out proof: the final model on poses it was not fitted to
(`discover --test TEST.csv`), next to the nominal model's error there, and
whether what is left there is the measurement noise (a verdict that does
not hold where it was not fitted is not one: job.py)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .fit import Fit
from .measured import Measurements
from .model import ParamModel
from .stats import chi2_sf

# The held-out residuals refute the final model when their chi-square test
# against the noise fails at this level (a stricter one than the fit's: the
# fitted parameters' own uncertainty adds a little to every test pose).
HOLDS_QUANTILE = 0.999


@dataclass(frozen=True)
class HeldOut:
    source: str
    points: int
    rms_mm: float              # final model
    max_mm: float
    nominal_rms_mm: float      # the model without any named effect
    nominal_max_mm: float
    p: float                   # chi-square p of the final model's residuals against the noise

    @property
    def holds(self) -> bool:
        return self.p >= 1 - HOLDS_QUANTILE


def held_out(model: ParamModel, data: Measurements, final: Fit, sigma_mm: float) -> HeldOut:
    """model: the fitted model's robot, profile and measuring point at the
    test poses; sigma_mm: the noise per axis the discovery tested against."""
    X, _ = model.evaluate(final.effects, final.values, jacobian=False)
    X0, _ = model.evaluate((), (), jacobian=False)
    d = np.linalg.norm(data.xyz_mm - X, axis=1)
    d0 = np.linalg.norm(data.xyz_mm - X0, axis=1)
    p = chi2_sf(float(np.sum(d ** 2)) / sigma_mm ** 2, 3 * len(data))
    return HeldOut(data.source, len(data), float(np.sqrt(np.mean(d ** 2))), float(d.max()),
                   float(np.sqrt(np.mean(d0 ** 2))), float(d0.max()), p)

"""Held-out proof: the final model on poses it was not fitted to
(`discover --test TEST.csv`), next to the nominal model's error there."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .fit import Fit
from .measured import Measurements
from .model import ParamModel


@dataclass(frozen=True)
class HeldOut:
    source: str
    points: int
    rms_mm: float              # final model
    max_mm: float
    nominal_rms_mm: float      # the model without any named effect
    nominal_max_mm: float


def held_out(model: ParamModel, data: Measurements, final: Fit) -> HeldOut:
    """model: the fitted model's robot, profile and measuring point at the
    test poses."""
    X, _ = model.evaluate(final.effects, final.values, jacobian=False)
    X0, _ = model.evaluate((), (), jacobian=False)
    d = np.linalg.norm(data.xyz_mm - X, axis=1)
    d0 = np.linalg.norm(data.xyz_mm - X0, axis=1)
    return HeldOut(data.source, len(data), float(np.sqrt(np.mean(d ** 2))), float(d.max()),
                   float(np.sqrt(np.mean(d0 ** 2))), float(d0.max()))

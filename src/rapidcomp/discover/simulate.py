"""Measured-data files for planning a campaign, and what they can detect.

The generator is independent of the fitting code: the effects become an
extended profile (effects.to_profile), the profile a deformed Pinocchio
model (profile.deform), and positions come from Pinocchio's forward
kinematics with the joint map, then Gaussian noise per axis.

The detectability table asks, for every catalogue effect alone, how large
it must be for discover to name it with 90 % probability: the fitted RSS
drop of an effect of size delta is sigma^2 times a non-central chi2(k,
lambda) with lambda = |J delta|^2 / sigma^2, and discover names it when
that exceeds the larger of its two thresholds (select.py); it looks only
once the residuals fail its noise test, chi2(3N) at NOISE_QUANTILE, which
the same lambda must make them fail with that probability too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from ..errors import RapidcompError
from ..kinematics.frames import DEG
from ..kinematics.gravity import Payload
from ..kinematics.profile import FORCE_FACTOR, ThermalProfile, deform
from ..kinematics.robot import RobotModel
from .effects import Effect, find, to_profile
from .model import ZERO_COLUMN, ParamModel
from .plausible import FRAMES, implausible
from .select import ALPHA, NOISE_QUANTILE, STRONG_BIC
from .stats import chi2_ppf, ncx2_lambda_for_power

POWER = 0.9


def parse_effect_values(effects, specs, force: bool = False,
                        option: str = "--effect") -> dict[Effect, np.ndarray]:
    """`--effect ID=V[,V...]` options (`option`: the option's name, as the
    messages say it), values in the parameters' user units (within what a
    real robot has, plausible.py, unless force)."""
    out: dict[Effect, np.ndarray] = {}
    for spec in specs:
        if "=" not in spec:
            raise RapidcompError(f"{option} {spec}: expected ID=VALUE[,VALUE...]")
        eid, text = spec.split("=", 1)
        e = find(effects, eid.strip())
        try:
            vals = [float(v) for v in text.split(",")]
        except ValueError:
            vals = []
        if len(vals) != e.size or not all(math.isfinite(v) for v in vals):
            raise RapidcompError(f"{option} {spec}: {e.id} takes {e.size} number(s): "
                                 + ", ".join(e.params))
        if e.kind == "gravity_compliance" and vals[0] < 0:
            raise RapidcompError(f"{option} {spec}: a compliance is >= 0")
        # (A dead band's width: each joint lags behind the way it moved,
        # never ahead of it.)
        if e.kind == "backlash" and vals[0] < 0:
            raise RapidcompError(f"{option} {spec}: a backlash is >= 0 (the width of the gear's "
                                 "play)")
        user = dict(zip(e.params, vals))
        why = implausible(e, user, first=True)
        if why is not None and not force:
            raise RapidcompError(f"{option} {spec}: {why}; --force simulates it anyway")
        why = implausible(e, user, first=True, factor=FORCE_FACTOR) if force else None
        if why is not None:
            raise RapidcompError(f"{option} {spec}: {why.replace('a real robot', '--force')}; "
                                 f"--force allows {FORCE_FACTOR:g} times the bound of a real "
                                 "robot, no more")
        if e in out:
            raise RapidcompError(f"{option} {spec}: {e.id} given twice")
        out[e] = e.internal(vals)
    return out


def simulate_positions(robot: RobotModel, profile: ThermalProfile, values, q_deg: np.ndarray,
                       tool_mm, payload: Payload | None = None) -> np.ndarray:
    """Measuring point positions (N, 3) of the model robot + profile + effects
    (tool_mm: the measuring point in the flange frame, one or one per pose),
    the poses measured in the order given (backlash: each joint lags half
    of it behind the direction it last moved)."""
    if payload is not None:
        profile = replace(profile, payload=payload)
    model = deform(robot, to_profile(robot, profile, values))
    data = model.model.createData()
    q = np.asarray(q_deg, float) * DEG
    if model.joint_map is not None:
        q = model.joint_map.apply(q)
    gears = [(e.joint, e.harmonic, v) for e, v in values.items() if e.kind == "cyclic"]
    if gears:
        q = q.copy()
        for k, h, (a, b) in gears:
            angle = np.radians(np.asarray(q_deg, float)[:, k]) * h
            q[:, k] += a * np.sin(angle) + b * np.cos(angle)
    lash = [(e.joint, float(v[0])) for e, v in values.items() if e.kind == "backlash"]
    if lash:
        q = q.copy()
        for k, b in lash:
            q[:, k] += 0.5 * b * _last_direction(np.asarray(q_deg, float)[:, k])
    tool = np.broadcast_to(np.asarray(tool_mm, float), (len(q), 3))   # one per pose
    out = np.empty((len(q), 3))
    for i, qi in enumerate(q):
        pin.framesForwardKinematics(model.model, data, qi)
        out[i] = data.oMf[model.flange_frame].act(tool[i])
    return out


def _last_direction(angles: np.ndarray) -> np.ndarray:
    """Sign of the last change of one joint before each pose (0 before its
    first). Written apart from model.approach_directions on purpose: the
    simulator is the fitting code's independent check."""
    out = np.zeros(len(angles))
    for i in range(1, len(angles)):
        delta = angles[i] - angles[i - 1]
        out[i] = out[i - 1] if delta == 0 else (1.0 if delta > 0 else -1.0)
    return out


def add_noise(xyz: np.ndarray, sigma_mm: float, seed: int) -> np.ndarray:
    return xyz + np.random.default_rng(seed).normal(0.0, sigma_mm, xyz.shape)


@dataclass(frozen=True)
class Detectability:
    effect: str
    param: str
    smallest: float | None        # user units; None: cannot be detected
    tcp_um: float | None          # largest TCP shift at that size, um
    note: str


def detectability(model: ParamModel, effects, sigma_mm: float) -> tuple[Detectability, ...]:
    N = model.size
    n = 3 * N
    cols = {}
    for e in effects:
        _, J = model.evaluate((e,), (np.zeros(e.size),))
        cols[e] = J.reshape(n, e.size)
    live = [e for e in effects if np.all(np.linalg.norm(cols[e], axis=0) >= ZERO_COLUMN)]
    m = max(1, len(live))
    # Discover looks for an effect only once the residuals fail its noise
    # test (chi-square of 3N degrees of freedom at NOISE_QUANTILE): an effect
    # that test misses is never named, however its own test would judge it.
    noise_lam = ncx2_lambda_for_power(chi2_ppf(NOISE_QUANTILE, n), n, POWER)
    rows = []
    # The power's non-centrality depends on the effect's size alone; a
    # bisection over Poisson sums is 0.07 s, and the catalogue has ~60 effects.
    lams = {}
    for e in effects:
        A = cols[e]
        norms = np.linalg.norm(A, axis=0)
        k = e.size
        if k not in lams:
            threshold = max(chi2_ppf(1 - ALPHA / m, k), STRONG_BIC + k * math.log(n))
            lams[k] = max(ncx2_lambda_for_power(threshold, k, POWER), noise_lam)
        lam = lams[k]
        note = _same_as(e, A, cols)
        for j, name in enumerate(e.params):
            if norms[j] < ZERO_COLUMN:
                rows.append(Detectability(e.id, name, None, None,
                                          "does not move the measuring point at these poses"))
                continue
            size = sigma_mm * math.sqrt(lam) / norms[j]
            shift = float(np.max(np.linalg.norm(A[:, j].reshape(N, 3), axis=1)) * size)
            # (A size no real robot has: these points and this noise cannot
            # see the effect at all.)
            beyond = implausible(e, {name: size / e.to_internal[j]}, first=e.kind in FRAMES)
            said = note if beyond is None else "; ".join(
                x for x in (note, f"undetectable here: {beyond}") if x)
            rows.append(Detectability(e.id, name, size / e.to_internal[j], shift * 1000, said))
    return tuple(rows)


def _same_as(e: Effect, A: np.ndarray, cols) -> str:
    """Effects with no more parameters whose columns span e's: the data
    cannot tell them apart, discover names the one with fewer parameters."""
    scale = np.linalg.norm(A, axis=0)
    if np.any(scale < ZERO_COLUMN):
        return ""
    An = A / scale
    same = []
    for f, B in cols.items():
        if f is e or f.size > e.size or np.any(np.linalg.norm(B, axis=0) < ZERO_COLUMN):
            continue
        coef, *_ = np.linalg.lstsq(B, An, rcond=None)
        if np.max(np.linalg.norm(An - B @ coef, axis=0)) < 1e-6:
            same.append(f.id)
    return ("indistinguishable from " + ", ".join(same)) if same else ""

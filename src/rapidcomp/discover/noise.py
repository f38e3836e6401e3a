"""The noise discover tests its residuals against, and whether what is
left is noise at all.

Sigma per axis comes, in order, from `--sigma`; from poses measured more
than once (pure error: the scatter of each pose's measurements about their
mean, which no model error can inflate); else from the fit of the whole
catalogue at once, sigma^2 = RSS_full / (3N - rank). That last estimate
absorbs whatever systematic error the catalogue cannot express, so when it
is used the final residuals are also tested for structure: a smooth
function of one joint angle (harmonics 1..8; as an angle error of that
joint, or per axis of the residual) fitted to them and judged on points it
was not fitted to (5-fold cross-validation). If it predicts more than a
fifth of their sum of squares out of sample, they are not noise and the
verdict says so (a cyclic gear error, which no catalogue effect expresses,
shows there).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import RapidcompError
from .fit import CatalogueFit
from .stats import chi2_sf

MIN_NOISE_DOF = 10
# The repeats refute a --sigma whose chi-square test they fail at this level.
GIVEN_QUANTILE = 0.999
# The least noise a measurement of a robot's TCP has (mm): no instrument
# that measures one resolves 0.1 um. A scatter below it is the digits' (a
# pose written to the same last digit each time) or a simulation's without
# noise; tested against a smaller sigma, every rounding error of the fit
# would count as an effect (--sigma has the same floor).
MIN_SIGMA_MM = 1e-4
# Joint vectors closer than this (deg, every joint) are the same pose.
SAME_POSE_DEG = 1e-6
HARMONICS = 8
FOLDS = 5
# Out-of-sample share of the residual sum of squares a joint's harmonics
# must predict for the residuals to count as structured (for noise it is
# negative: a fit to noise predicts worse than nothing).
STRUCTURE_SHARE = 0.2


@dataclass(frozen=True)
class Noise:
    sigma_mm: float
    source: str
    kind: str         # "given", "replicates" or "estimated"
    floored: bool = False   # the estimate was below MIN_SIGMA_MM, which is taken


@dataclass(frozen=True)
class Structure:
    joint: str
    share: float      # of the residual sum of squares predicted out of sample


def replicate_groups(q_deg: np.ndarray, tool_mm: np.ndarray | None = None) -> list[np.ndarray]:
    """Row indices of the poses measured more than once (at the same
    measuring point: two reflectors on one pose are not a replicate)."""
    keys = np.round(np.asarray(q_deg, float) / SAME_POSE_DEG).astype(np.int64)
    if tool_mm is not None:
        keys = np.hstack([keys, np.round(np.asarray(tool_mm, float) / 1e-6).astype(np.int64)])
    _, inverse, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    return [np.flatnonzero(inverse == g) for g in np.flatnonzero(counts > 1)]


def noise(sigma_mm: float | None, q_deg: np.ndarray, xyz_mm: np.ndarray,
          full: CatalogueFit, tool_mm: np.ndarray | None = None,
          repeats: bool = True) -> Noise:
    """repeats: poses measured more than once are replicates (not in a
    warm-up campaign, where the same pose at another time has moved)."""
    groups = replicate_groups(q_deg, tool_mm) if repeats else []
    dof = 3 * sum(len(g) - 1 for g in groups)
    ss = (sum(float(np.sum((xyz_mm[g] - xyz_mm[g].mean(axis=0)) ** 2)) for g in groups)
          if dof >= MIN_NOISE_DOF else None)
    if sigma_mm is not None:
        # The pure error is evidence the given noise must survive: repeats
        # that scatter more than it allows would make every systematic
        # trace of that excess an effect.
        if ss is not None and chi2_sf(ss / sigma_mm ** 2, dof) < 1 - GIVEN_QUANTILE:
            raise RapidcompError(
                f"--sigma {sigma_mm:g}: the {len(groups)} poses measured more than once scatter "
                f"by {math.sqrt(ss / dof):.3g} mm per axis ({dof} degrees of freedom), more "
                f"than a noise of {sigma_mm:g} mm allows (chi-square p = "
                f"{chi2_sf(ss / sigma_mm ** 2, dof):.3g}); give the measuring system's noise, or "
                "leave --sigma out and the repeats tell it")
        return Noise(float(sigma_mm), "given (--sigma)", "given")
    if ss is not None:
        if ss == 0:
            raise RapidcompError(
                f"the {len(groups)} poses measured more than once have the very same "
                "coordinates each time: copied rows, or an instrument whose noise the digits "
                "written do not show; they cannot tell the noise. Give --sigma (the measuring "
                "system's standard deviation per axis, mm) or leave the copies out")
        return floored(math.sqrt(ss / dof),
                       f"from {len(groups)} poses measured more than once (pure error, {dof} "
                       "degrees of freedom)", "replicates")
    n = 3 * len(q_deg)
    dof = n - full.rank
    if dof < MIN_NOISE_DOF:
        raise RapidcompError(
            f"{len(q_deg)} points leave {dof} degrees of freedom after the whole catalogue "
            f"({full.rank} identifiable parameters): too few to estimate the noise; give "
            "--sigma (the measuring system's standard deviation per axis, mm), measure some "
            "poses more than once, or measure more points")
    return floored(math.sqrt(full.rss / dof),
                   f"estimated from the fit of the whole catalogue ({full.rank} identifiable "
                   f"parameters, {dof} degrees of freedom)", "estimated")


def floored(sigma_mm: float, source: str, kind: str) -> Noise:
    """The noise estimated, at least MIN_SIGMA_MM, which the source then says."""
    if sigma_mm >= MIN_SIGMA_MM:
        return Noise(sigma_mm, source, kind)
    return Noise(MIN_SIGMA_MM, f"taken as {MIN_SIGMA_MM * 1000:g} um, the least any instrument "
                 f"measuring a robot has (estimated {sigma_mm * 1000:.2g} um {source}: data "
                 "without noise, as a simulation makes them?)", kind, True)


def structure(q_deg: np.ndarray, residuals: np.ndarray, joint_names,
              columns: dict | None = None) -> Structure | None:
    """The joint whose angle best predicts the residuals out of sample, if
    it predicts more than STRUCTURE_SHARE of them; None otherwise (or with
    too few points to tell). Two families per joint: an angle error that is
    a function of the joint's own angle (harmonics times the joint's
    direction of motion at the measuring point, `columns`: joint index ->
    (N, 3)), and each axis of the residual as a function of the angle."""
    q = np.radians(np.asarray(q_deg, float))
    r = np.asarray(residuals, float)
    n = len(q)
    nfeat = 2 * HARMONICS + 1
    if n < 3 * nfeat:
        return None
    total = float(np.sum(r ** 2))
    if total <= 0:
        return None
    folds = np.arange(n) % FOLDS
    k = np.arange(1, HARMONICS + 1)
    best = None
    for j in range(q.shape[1]):
        H = np.hstack([np.ones((n, 1)), np.sin(np.outer(q[:, j], k)), np.cos(np.outer(q[:, j], k))])
        designs = [H]
        if columns is not None and j in columns:
            designs.append(columns[j][:, :, None] * H[:, None, :])    # (N, 3, nfeat)
        for X in designs:
            share = 1.0 - _cv_rss(X, r, folds) / total
            if best is None or share > best.share:
                best = Structure(joint_names[j], share)
    return best if best is not None and best.share > STRUCTURE_SHARE else None


def _cv_rss(X: np.ndarray, r: np.ndarray, folds: np.ndarray) -> float:
    """Residual sum of squares of a ridge fit of r on X, each fold predicted
    by the fit to the others. X: (N, F) one fit per axis, or (N, 3, F) one
    fit for all three."""
    pred = np.zeros_like(r)
    for f in range(FOLDS):
        tr, te = folds != f, folds == f
        if X.ndim == 2:
            A, b = X[tr], r[tr]
        else:
            A, b = X[tr].reshape(-1, X.shape[2]), r[tr].reshape(-1)
        G = A.T @ A
        B = np.linalg.solve(G + 1e-9 * np.trace(G) / len(G) * np.eye(len(G)), A.T @ b)
        pred[te] = X[te] @ B
    return float(np.sum((r - pred) ** 2))

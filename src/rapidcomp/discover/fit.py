"""Least-squares fit of effect parameters: Gauss-Newton with exact
Jacobians (model.py), column scaling, step halving, and the bound c >= 0
on gravity compliances (active set: a compliance that wants to go negative
is held at 0 and the rest refitted).

A fit is a result object: it says whether the parameters are identifiable
on these points (rank and condition number of the scaled Jacobian) and
why not, never returns bare arrays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .effects import Effect
from .model import ZERO_COLUMN, ParamModel

# Columns this much below the largest singular value are dependent: the
# data cannot tell the parameters apart (float64 round-off is ~1e-16).
RANK_TOL = 1e-9
MAX_ITERATIONS = 30
RSS_TOL = 1e-10
# 1 - leverage below this: the point is fitted by parameters of its own.
LEVERAGE_TOL = 1e-9
# For the whole catalogue at once: directions this weak are left out of the
# noise estimate's reference fit rather than fitted to the noise.
FULL_RANK_TOL = 1e-6


@dataclass(frozen=True, eq=False)
class Fit:
    effects: tuple[Effect, ...]
    values: tuple[np.ndarray, ...]   # internal units
    success: bool
    reason: str | None
    residuals: np.ndarray            # (N, 3) measured - model, mm
    jac: np.ndarray                  # (3N, P) at the solution
    free: np.ndarray                 # (P,) parameters not held at a bound
    cond: float
    iterations: int

    @property
    def rss(self) -> float:
        return float(np.sum(self.residuals ** 2))

    @property
    def rms_mm(self) -> float:
        """Root mean square of the 3-D residual lengths."""
        return float(np.sqrt(np.mean(np.sum(self.residuals ** 2, axis=1))))

    @property
    def nparams(self) -> int:
        return int(self.free.sum())

    def _basis(self):
        A = self.jac[:, self.free]
        scale = np.linalg.norm(A, axis=0)
        U, S, Vt = np.linalg.svd(A / scale, full_matrices=False)
        return U, S, Vt, scale

    def stderr(self, sigma_mm: float, held: np.ndarray | None = None) -> tuple[np.ndarray, ...]:
        """Standard error of every parameter (internal units) for noise
        sigma_mm per axis; 0 for a parameter held at its bound. held:
        columns (3N, m) of the positions' derivatives by parameters
        estimated from the same data but held in this fit (a warm-up's time
        constants): their uncertainty goes into every error, where the
        data can tell them from the fitted ones (else left out)."""
        out = np.zeros(self.jac.shape[1])
        if self.nparams:
            _, S, Vt, scale = self._basis()
            if held is not None:
                A = np.column_stack([self.jac[:, self.free], held])
                wide = np.linalg.norm(A, axis=0)
                wide[wide == 0] = 1.0
                _, S2, Vt2 = np.linalg.svd(A / wide, full_matrices=False)
                if S2[-1] >= RANK_TOL * S2[0]:
                    S, Vt, scale = S2, Vt2[:, :self.nparams], wide[:self.nparams]
            out[self.free] = sigma_mm * np.sqrt(np.sum((Vt.T / S) ** 2, axis=1)) / scale
        return _split(out, self.effects)

    def heldout_rms_mm(self) -> float:
        """Leave-one-point-out RMS: each point's residual had the fit been
        made without it, from the hat matrix of the (linearized) fit,
        e_i = (I - H_ii)^-1 r_i with H_ii the point's 3x3 block."""
        r = self.residuals
        if not self.nparams:
            return self.rms_mm
        U = self._basis()[0].reshape(len(r), 3, -1)
        H = U @ np.swapaxes(U, 1, 2)
        w, V = np.linalg.eigh(np.eye(3) - H)
        if np.min(w) < LEVERAGE_TOL:
            # A point the fit passes through on its own (leverage 1): the
            # others do not predict it at all.
            return float("inf")
        local = np.einsum("nji,nj->ni", V, r)
        e = np.einsum("nij,nj->ni", V, local / w)
        return float(np.sqrt(np.mean(np.sum(e ** 2, axis=1))))


def _split(x: np.ndarray, effects) -> tuple[np.ndarray, ...]:
    cuts = np.cumsum([e.size for e in effects])[:-1]
    return tuple(np.array(v) for v in np.split(x, cuts)) if effects else ()


def fit(model: ParamModel, measured: np.ndarray, effects: tuple[Effect, ...],
        start=None) -> Fit:
    effects = tuple(effects)
    P = sum(e.size for e in effects)
    x = np.concatenate([np.asarray(v, float) for v in start]) if start else np.zeros(P)
    bounded = np.concatenate([[e.kind == "gravity_compliance"] * e.size for e in effects]) \
        if effects else np.zeros(0, bool)
    free = np.ones(P, bool)
    it_total = 0
    cond = 1.0
    while True:
        X, J = model.evaluate(effects, _split(x, effects))
        r = (measured - X).ravel()
        for it in range(MAX_ITERATIONS):
            if not P or not free.any():
                break
            A = J.reshape(len(r), P)[:, free]
            scale = np.linalg.norm(A, axis=0)
            if np.any(scale < ZERO_COLUMN):
                dead = _names(effects, free, scale < ZERO_COLUMN)
                return _failed(effects, x, X, measured, J, free, np.inf, it_total,
                               f"{dead} does not move the measuring point at these poses")
            # The SVD of the scaled Jacobian through a QR of [A r]: the same
            # singular values and step as its own SVD, a third of the work
            # on thousands of rows.
            m = A.shape[1]
            R = np.linalg.qr(np.column_stack([A / scale, r]), mode="r")
            U, S, Vt = np.linalg.svd(R[:m, :m])
            cond = float(S[0] / S[-1]) if S[-1] > 0 else np.inf
            if S[-1] < RANK_TOL * S[0]:
                return _failed(effects, x, X, measured, J, free, cond, it_total,
                               "parameters not identifiable on these points (the Jacobian "
                               f"has rank {int(np.sum(S >= RANK_TOL * S[0]))} of {len(S)})")
            dx = (Vt.T @ ((U.T @ R[:m, m]) / S)) / scale
            rss = r @ r
            step = 1.0
            for _ in range(30):
                x_try = x.copy()
                x_try[free] += step * dx
                X_try, J_try = model.evaluate(effects, _split(x_try, effects))
                r_try = (measured - X_try).ravel()
                if r_try @ r_try <= rss * (1 + 1e-12):
                    break
                step /= 2
            x, X, J, r = x_try, X_try, J_try, r_try
            it_total += 1
            # Converged when the step changes the fitted positions by less
            # than a nanometre in total, or the residual sum of squares by
            # less than a part in 1e10 (a real robot's data: the last
            # digits of a large residual, far below any test's resolution).
            if np.linalg.norm(A @ (step * dx * scale)) < 1e-6 or \
                    rss - float(r @ r) <= RSS_TOL * rss:
                break
        negative = bounded & free & (x < 0)
        if not negative.any():
            break
        worst = int(np.argmin(np.where(negative, x, np.inf)))
        free[worst] = False
        x[worst] = 0.0
    return Fit(effects, _split(x, effects), True, None, measured - X,
               J.reshape(len(r), P), free, cond, it_total)


def _names(effects, free, mask) -> str:
    labels = [f"{e.id}.{p}" for e in effects for p in e.params]
    picked = [lab for lab, f in zip(labels, free) if f]
    return ", ".join(lab for lab, m in zip(picked, mask) if m)


def _failed(effects, x, X, measured, J, free, cond, iterations, reason) -> Fit:
    return Fit(effects, _split(x, effects), False, reason, measured - X,
               J.reshape(-1, J.shape[-1]), free, cond, iterations)


@dataclass(frozen=True, eq=False)
class CatalogueFit:
    """The fit of every effect at once (dependent directions dropped)."""

    rss: float
    rank: int
    residuals: np.ndarray    # (N, 3) mm
    deleted: np.ndarray      # (N, 3) each point's residual had it not been fitted
    standardized: np.ndarray  # (N, 3) residuals scaled to the noise's covariance


def catalogue_fit(model: ParamModel, measured: np.ndarray, effects) -> CatalogueFit:
    """The fit of all `effects` at once, dependent directions dropped
    (truncated SVD): the reference of the noise estimate and of gross
    errors.

    One linearized step from zero, and the residuals of the linear model:
    with ~70 parameters some directions are barely determined, and
    evaluating the chain at their large values would measure the
    nonlinearity of the model, not the noise. Effects are microns on a
    metre-sized arm, so the linearization error (~L theta^2) is far below
    any tracker's noise. Deleted residuals e_i = (I - H_ii)^-1 r_i (H the
    hat matrix, H_ii a point's 3x3 block): a gross error the many
    parameters would partly absorb shows at its full size.
    """
    effects = tuple(effects)
    # Save the base frame, centimetres and degrees off where a tracker's
    # frame was set by hand (a few degrees leave ~L theta^2, a millimetre,
    # of its own nonlinearity in a step from zero, taken for noise and for
    # gross errors). It is fitted alone to convergence first, and the
    # catalogue linearized there.
    values = [np.zeros(e.size) for e in effects]
    base = next((k for k, e in enumerate(effects) if e.kind == "base_frame" and not e.thermal),
                None)
    if base is not None:
        alone = fit(model, measured, (effects[base],))
        if alone.success:
            values[base] = alone.values[0]
    X, J = model.evaluate(effects, tuple(values))
    r = (measured - X).ravel()
    A = J.reshape(len(r), -1)
    scale = np.linalg.norm(A, axis=0)
    A = A[:, scale >= ZERO_COLUMN] / scale[scale >= ZERO_COLUMN]
    U, S, _ = np.linalg.svd(A, full_matrices=False)
    keep = S >= FULL_RANK_TOL * S[0]
    Uk = U[:, keep]
    res = (r - Uk @ (Uk.T @ r)).reshape(-1, 3)
    Up = Uk.reshape(len(res), 3, -1)
    H = Up @ np.swapaxes(Up, 1, 2)
    # A point the fit passes through exactly (H_ii = I) has no deleted
    # residual to speak of: those directions are left at 0.
    w, V = np.linalg.eigh(np.eye(3) - H)
    ok = w > 1e-9
    inv = np.where(ok, 1.0 / np.where(ok, w, 1.0), 0.0)
    local = np.einsum("nji,nj->ni", V, res)
    deleted = np.einsum("nij,nj->ni", V, local * inv)
    # Cov(r_i) = sigma^2 (I - H_ii): (I - H_ii)^-1/2 r_i has sigma^2 I.
    standardized = np.einsum("nij,nj->ni", V, local * np.sqrt(inv))
    return CatalogueFit(float(np.sum(res ** 2)), int(keep.sum()), res, deleted, standardized)

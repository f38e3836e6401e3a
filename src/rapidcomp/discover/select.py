"""Forward selection: name the effect the model misses, add it, repeat
until what is left is noise.

Statistics (README "How discover decides"):

- Noise sigma per axis: `--sigma`, else estimated from the fit of the whole
  catalogue at once (dependent directions dropped): sigma^2 = RSS_full /
  (3N - rank). An effect outside the catalogue inflates that estimate, so
  the report says which was used and recommends --sigma.
- Noise test: RSS / sigma^2 against chi2(3N - p). Above its 99 % quantile
  the residuals are not noise.
- Each candidate is fitted together with the effects already named. Its
  evidence: the drop in RSS, which for an absent effect is sigma^2 chi2(k)
  (k its parameters). Named only when all hold: p-value below 0.001 divided
  by the number of candidates (Bonferroni), BIC (RSS / sigma^2 + p ln 3N)
  lower by at least 10 ("very strong", Kass & Raftery), and the
  leave-one-point-out RMS lower too.
- Candidates whose RSS differs from the best's by less than the 99 %
  quantile of chi2(max(1, |k - k_best|)) explain the data equally: the one
  with the fewest parameters is named and the others are its
  `alternatives`; a tie in parameters is broken by the smaller RSS and the
  report says the data cannot tell them apart.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from itertools import combinations

import numpy as np

from . import warmup
from .effects import THERMAL_PREFIX, Effect, thermal_variants
from .fit import LEVERAGE_TOL, RANK_TOL, Fit, fit
from .measured import Measurements
from .model import ZERO_COLUMN, ParamModel
from .noise import Structure, floored, noise, structure
from .outliers import Outlier, screen
from .points import random_points
from .plausible import bounds, implausible
from .residuals import Analysis, analyse
from .stats import chi2_ppf, chi2_sf

ALPHA = 0.001
STRONG_BIC = 10.0
NOISE_QUANTILE = 0.99
# A fit whose leave-one-point-out RMS is within this factor of its own RMS
# predicts the points it was not fitted to as well as those it was.
HELD_LIKE_FITTED = 1.1
EQUIVALENT_QUANTILE = 0.99
# An implausible fit leaving less than this share of what the best
# plausible one leaves (100x better) means the model and the data are far
# apart: nothing more is named.
FAR_APART = 0.01
# Residuals beyond this RMS (mm) are beyond every plausible effect at once.
FAR_APART_MM = 250.0
# A candidate whose parameter estimates correlate beyond this with those
# already named needs cancelling parameters: not named.
CORRELATION_LIMIT = 0.995
# Candidates per scoring that the exchange of two effects draws from, and
# the most fits one exchange pass makes.
EXCHANGE_POOL = 6
EXCHANGE_FITS = 400
# The share of the RSS a linearized prediction of a fit's RSS may be off by
# (second-order terms): within it, the fit is made.
NEAR_MARGIN = 0.02
# Candidates a later scoring fits at least (the best by a linearized step's
# prediction); the rest get the prediction.
FULL_FITS = 8
MAX_EFFECT_SIZE = 6     # base_frame
# The least range of a joint's angle over which its cyclic errors are
# candidates.
CYCLIC_SPAN_DEG = 330.0
# Poses over the whole workspace on which two effects the data cannot tell
# apart are checked for any difference at all, and the singular value
# (relative) below which a direction is none.
SEPARATE_POSES = 200
SEPARATE_TOL = 1e-7


@dataclass(frozen=True)
class Candidate:
    effect: str
    nparams: int
    rms_mm: float
    heldout_mm: float
    p_value: float
    delta_bic: float          # BIC(model + candidate) - BIC(model): negative is better
    implausible: str | None = None   # the fit needs values no real robot has
    cancelling: str | None = None    # its parameters cancel those already named
    estimated: bool = False          # not fitted: a linearized step's prediction, far from the best


@dataclass(frozen=True)
class Step:
    effect: Effect
    fit: Fit                  # the fit at this step
    params: dict              # final model's estimate, user units
    stderr: dict
    at_step: dict             # this step's own estimate
    rms_before_mm: float
    rms_after_mm: float
    heldout_before_mm: float
    heldout_after_mm: float
    p_value: float
    delta_bic: float
    alternatives: tuple[str, ...]
    note: str | None
    candidates: tuple[Candidate, ...]   # best first


@dataclass(frozen=True)
class Discovery:
    points: int
    sigma_mm: float
    sigma_source: str
    initial: Analysis
    final: Analysis
    initial_heldout_mm: float
    steps: tuple[Step, ...]
    verdict: str                 # explained | noise | unexplained
    verdict_text: str
    noise_p: float               # p-value of the final residuals as noise
    not_identifiable: tuple[tuple[str, str], ...]
    final_fit: Fit
    start_fit: Fit
    effects: tuple[Effect, ...]
    implausible: tuple[str, ...] = ()   # strong fits refused as values no robot has
    noise: Noise | None = None
    outliers: tuple[Outlier, ...] = ()  # left out of the fit
    structure: Structure | None = None  # what the joints predict of the final residuals
    notes: tuple[str, ...] = ()
    kept: np.ndarray | None = None      # rows of the measured data fitted (outliers left out)
    far_apart: bool = False             # only values no robot has would explain the data
    warmup: "warmup.Warmup | None" = None  # a warm-up campaign's tau (data with t_min)
    thermal_evidence: dict | None = None    # effect id -> static/thermal and why
    # Named effects these data do not determine (_undetermined): effect id,
    # its largest stated error in words.
    undetermined: tuple[tuple[str, str], ...] = ()

    @property
    def initial_rms_mm(self) -> float:
        return self.initial.rms_mm

    @property
    def final_rms_mm(self) -> float:
        return self.final.rms_mm

    @property
    def initial_residuals(self) -> np.ndarray:
        return self.start_fit.residuals

    def named_values(self) -> dict:
        """{Effect: internal values} of the final model."""
        return dict(zip(self.final_fit.effects, self.final_fit.values))


def _bic(f: Fit, sigma: float, n: int) -> float:
    return f.rss / sigma ** 2 + f.nparams * math.log(n)


def _noise_p(f: Fit, sigma: float, n: int) -> float:
    return chi2_sf(f.rss / sigma ** 2, max(1, n - f.nparams))


@dataclass(frozen=True, eq=False)
class _Scored:
    effect: Effect
    fit: Fit | None           # None: not fitted (Candidate.estimated)
    candidate: Candidate
    strong: bool
    order: int
    blocked: str | None = None      # strong evidence, but for values no robot has


def _implausible(f: Fit) -> str | None:
    """Why a fit's values are beyond a real robot (plausible.py), or None."""
    for i, (e, v) in enumerate(zip(f.effects, f.values)):
        why = implausible(e, e.user(v), first=(i == 0))
        if why is not None:
            return why
    return None


def _invisible(e: Effect, cols: np.ndarray, sigma: float) -> str | None:
    """Why an effect cannot be seen at the measuring point: at the largest
    value a real robot has, none of its parameters moves any measured point
    by the noise."""
    bound_mm, bound_deg, bound_plain = bounds(e)
    shifts = []
    for j, (name, to_internal) in enumerate(zip(e.params, e.to_internal)):
        bound = (bound_mm if name.endswith("_mm") else bound_deg if name.endswith("_deg")
                 else bound_plain) * abs(to_internal)
        shifts.append(float(np.max(np.linalg.norm(cols[:, j].reshape(-1, 3), axis=1))) * bound)
    largest = max(shifts)
    if largest >= sigma:
        return None
    return (f"at the largest value a real robot has it moves the measuring point by at most "
            f"{largest * 1000:.2g} um at these poses, below the noise ({sigma * 1000:.2g} um): "
            "its lever there is too small to see it")


def _cancelling(f: Fit, e: Effect) -> str | None:
    """The new effect's parameters cancelling named ones: a correlation of
    the estimates beyond CORRELATION_LIMIT (the data fix only their
    difference; both grow without bound together)."""
    if not f.nparams or len(f.effects) < 2:
        return None
    A = f.jac[:, f.free]
    scale = np.linalg.norm(A, axis=0)
    _, S, Vt = np.linalg.svd(A / scale, full_matrices=False)
    C = (Vt.T / S ** 2) @ Vt
    d = np.sqrt(np.diag(C))
    corr = C / np.outer(d, d)
    labels = [f"{x.id}.{p}" for x in f.effects for p in x.params]
    labels = [lab for lab, free in zip(labels, f.free) if free]
    mine = [i for i, lab in enumerate(labels) if lab.startswith(e.id + ".")]
    others = [i for i in range(len(labels)) if i not in mine]
    if not mine or not others:
        return None
    sub = np.abs(corr[np.ix_(mine, others)])
    i, j = np.unravel_index(int(np.argmax(sub)), sub.shape)
    if sub[i, j] <= CORRELATION_LIMIT:
        return None
    return (f"{labels[mine[i]]} and {labels[others[j]]} cancel each other (their estimates "
            f"correlate at r = {corr[mine[i], others[j]]:+.4f}, condition number {f.cond:.3g})")


class _Selector:
    """One discover run: the data, the noise, and the fits it makes."""

    def __init__(self, model: ParamModel, meas: np.ndarray, effects, sigma: float,
                 noise_known: bool = True):
        """noise_known: sigma is given or measured (replicates, a warm-up's
        scatter), not estimated from the catalogue's fit, which holds
        whatever it misses."""
        self.model, self.meas, self.effects, self.sigma = model, meas, tuple(effects), sigma
        self.noise_known = noise_known
        self.n = meas.size
        self.not_identifiable: dict[str, str] = {}
        # A cyclic error's own evidence rule: over less than (nearly) a
        # full turn the harmonics of an angle are not orthogonal to each
        # other, nor to an offset, a scale or a compliance of the joint, so
        # a 3-cycle error would be named as a 4-cycle one plus geometry.
        span = np.ptp(np.degrees(model.q_cmd), axis=0) if model.size else None
        for e in self.effects:
            if e.kind == "cyclic" and span is not None and span[e.joint] < CYCLIC_SPAN_DEG:
                name = model.robot.joint_names[e.joint]
                self.not_identifiable[e.id] = (
                    f"the poses turn {name} over {span[e.joint]:.0f} deg: a cyclic error is "
                    f"told from the others only over (nearly) a full turn, "
                    f">= {CYCLIC_SPAN_DEG:g} deg")
        # Scorings by the model fit they extend: the search and the replay
        # of its steps meet the same models, whose candidates need fitting once.
        self._scored: dict[int, tuple] = {}
        self._structure: dict[int, tuple] = {}
        self._generic: ParamModel | None = None    # poses over the whole workspace

    def fit(self, effects, start=None) -> Fit:
        return fit(self.model, self.meas, tuple(effects), start)

    def score(self, current: Fit) -> list[_Scored]:
        """Every candidate not in `current`, fitted with it, best BIC first.

        The first scoring fits every candidate (it finds those that cannot
        be identified). Later ones fit the best FULL_FITS by a linearized
        step's prediction and every candidate it puts within the
        equivalence band of the best and of the best with strong evidence;
        the others are scored by the prediction (Candidate.estimated): they
        cannot be named, nor be the alternative of what is."""
        hit = self._scored.get(id(current))
        if hit is not None and hit[0] is current:
            return hit[1]
        named = {e.id for e in current.effects}
        pending = [(order, e) for order, e in enumerate(self.effects)
                   if e.id not in named and e.id not in self.not_identifiable]
        lin = {}
        if current.effects:
            lin = self._linear(current.effects, current.values, [e for _, e in pending])
            logn = math.log(self.n)
            ranked = sorted(pending, key=lambda oe: (lin[oe[1].id][0] / self.sigma ** 2
                                                     + oe[1].size * logn, oe[0]))
            want = {e.id for _, e in ranked[:FULL_FITS]}
            want |= self._near(lin, min(v[0] for v in lin.values()))
        else:
            want = {e.id for _, e in pending}
        m = max(1, len(pending))
        fitted: dict[str, _Scored] = {}
        while True:
            for order, e in pending:
                if e.id not in want or e.id in fitted:
                    continue
                f = self.fit(current.effects + (e,), current.values + (np.zeros(e.size),))
                if not f.success:
                    if not current.effects:
                        self.not_identifiable[e.id] = f.reason
                    continue
                if not current.effects:
                    hidden = _invisible(e, f.jac[:, -e.size:], self.sigma)
                    if hidden is not None:
                        self.not_identifiable[e.id] = hidden
                        continue
                fitted[e.id] = self._judge(current, order, e, f, m)
            strong = [x for x in fitted.values() if x.strong]
            if not strong or not lin:
                break
            more = self._near(lin, min(x.fit.rss for x in strong)) - want
            if not more:
                break
            want |= more
        out = list(fitted.values())
        for order, e in pending:
            if e.id in fitted or e.id not in lin or e.id in want:
                continue
            rss, deleted = lin[e.id]
            drop = max(0.0, (current.rss - rss) / self.sigma ** 2)
            cand = Candidate(e.id, e.size, math.sqrt(rss / len(self.meas)),
                             float(np.sqrt(np.mean(np.sum(deleted ** 2, axis=1)))),
                             chi2_sf(drop, e.size), (rss - current.rss) / self.sigma ** 2
                             + e.size * math.log(self.n), estimated=True)
            out.append(_Scored(e, None, cand, False, order))
        out.sort(key=lambda s: (s.candidate.delta_bic, s.order))
        self._scored[id(current)] = (current, out, m, lin)
        return out

    def _judge(self, current: Fit, order: int, e: Effect, f: Fit, m: int) -> _Scored:
        """A candidate's fit against the model it extends (m: the number of
        candidates, Bonferroni)."""
        k = f.nparams - current.nparams
        drop = max(0.0, (current.rss - f.rss) / self.sigma ** 2)
        p = chi2_sf(drop, k) if k > 0 else 1.0
        cand = Candidate(e.id, e.size, f.rms_mm, f.heldout_rms_mm(), p,
                         _bic(f, self.sigma, self.n) - _bic(current, self.sigma, self.n))
        strong = (p < ALPHA / m and cand.delta_bic <= -STRONG_BIC
                  and cand.heldout_mm < current.heldout_rms_mm())
        why = _implausible(f)
        if why is not None:
            cand = replace(cand, implausible=why)
        cancel = _cancelling(f, e)
        if cancel is not None:
            cand = replace(cand, cancelling=cancel)
            strong = False
        return _Scored(e, f, cand, strong and why is None, order,
                       why if strong and why is not None else None)

    def fitted(self, current: Fit, wanted) -> list[_Scored]:
        """score(current) with the candidates in `wanted` fitted, and those a
        linearized step puts within the equivalence band of them (the
        replay of the final model's steps needs their fits and their
        alternatives)."""
        scored = self.score(current)
        _, _, m, lin = self._scored[id(current)]
        need = {s.effect.id for s in scored if s.effect in wanted}
        for s in scored:
            if s.effect in wanted and s.fit is not None:
                need |= self._near(lin, s.fit.rss)
        if all(s.fit is not None for s in scored if s.effect.id in need):
            return scored
        out = []
        for s in scored:
            if s.fit is None and s.effect.id in need:
                f = self.fit(current.effects + (s.effect,),
                             current.values + (np.zeros(s.effect.size),))
                if f.success:
                    s = self._judge(current, s.order, s.effect, f, m)
            out.append(s)
        out.sort(key=lambda s: (s.candidate.delta_bic, s.order))
        self._scored[id(current)] = (current, out, m, lin)
        return out

    def equivalents(self, scored: list[_Scored], best: _Scored) -> list[_Scored]:
        return [s for s in scored
                if s is best or (s.fit is not None and _equivalent(s.fit, best.fit, self.sigma))]

    def pick(self, scored: list[_Scored], current: Fit) -> _Scored | None:
        """The best candidate with strong evidence, or the simplest of those
        that explain the data equally well.

        A cyclic gear error has its own evidence rule: it is named only as
        the step's best candidate (with its free amplitude and phase it
        would stand in for a geometric effect as an equal alternative), and
        only when what is left is a function of that joint's angle more
        than of any other's (noise.structure, out of sample): otherwise a
        harmonic of some joint would soak up whatever the catalogue misses."""
        strong = [s for s in scored if s.strong]
        while strong and strong[0].effect.kind == "cyclic" and \
                not self._cyclic_evident(current, strong[0]):
            strong = strong[1:]
        if not strong:
            return None
        equal = [s for s in self.equivalents(scored, strong[0]) if s.strong
                 and (s.effect.kind != "cyclic" or s is strong[0])]
        return min(equal, key=lambda s: (s.fit.nparams, s.fit.rss, s.order))

    def _cyclic_evident(self, current: Fit, s: _Scored) -> bool:
        """Whether the step's best candidate, a cyclic error, is evidently
        one: what is left is a function of its joint's angle more than of
        any other's (noise.structure: it needs 3 x 17 points), or it alone
        leaves nothing but noise, on the points it was fitted to and on
        each left out, where the noise is known (a harmonic that soaks up
        what the catalogue misses leaves more than noise, or leaves it only
        where it was fitted)."""
        e = s.effect
        # (Against a noise estimated from the catalogue's fit, which holds
        # what the catalogue misses, "nothing but noise" says nothing: a
        # 6-cycle error would pass as a 2-cycle one.)
        if self.noise_known and s.fit is not None and s.fit.success:
            n = self.meas.size
            held = s.candidate.heldout_mm
            # (The held-out residuals as the fit's: within a tenth of them.)
            if (_noise_p(s.fit, self.sigma, n) >= 1 - NOISE_QUANTILE
                    and held <= HELD_LIKE_FITTED * s.fit.rms_mm):
                return True
        names = self.model.robot.joint_names
        if id(current) not in self._structure:
            offsets = tuple(x for x in self.effects if x.kind == "joint_offset")
            _, J = self.model.evaluate(offsets, tuple(np.zeros(1) for _ in offsets))
            self._structure[id(current)] = (current, structure(
                np.degrees(self.model.q_cmd), current.residuals, names,
                {x.joint: J[:, :, i] for i, x in enumerate(offsets)}))
        found = self._structure[id(current)][1]
        return found is not None and found.joint == names[e.joint]

    def _linear(self, rest, start, options) -> dict[str, tuple[float, np.ndarray]]:
        """For each of `options` added to `rest` (at its values `start`):
        the RSS and the residuals (N, 3) of one linearized step from there,
        and the deleted residuals of that linear fit (leave-one-point-out,
        as Fit.heldout_rms_mm). A fit would tell exactly, but the step
        predicts the fit's RSS to second order in the (small) change, and a
        nonlinear fit ends at or below it: a cheap screen of which fits are
        worth making."""
        if not options:
            return {}
        X, J = self.model.evaluate(tuple(rest) + tuple(options),
                                   tuple(start) + tuple(np.zeros(f.size) for f in options))
        r = (self.meas - X).ravel()
        N = len(self.meas)
        A = J.reshape(len(r), -1)
        scale = np.linalg.norm(A, axis=0)
        scale[scale < ZERO_COLUMN] = 1.0
        A = A / scale
        k = sum(e.size for e in rest)
        H = np.zeros((N, 3, 3))
        if k:
            U, S, _ = np.linalg.svd(A[:, :k], full_matrices=False)
            Q = U[:, S >= RANK_TOL * S[0]]
            r = r - Q @ (Q.T @ r)
            A = A[:, k:] - Q @ (Q.T @ A[:, k:])
            Qp = Q.reshape(N, 3, -1)
            H = Qp @ np.swapaxes(Qp, 1, 2)
        else:
            A = A[:, k:]
        out = {}
        col = 0
        for f in options:
            B = A[:, col:col + f.size]
            col += f.size
            Uf, Sf, _ = np.linalg.svd(B, full_matrices=False)
            Uf = Uf[:, Sf > RANK_TOL * max(1.0, Sf[0])]
            res = r - Uf @ (Uf.T @ r)
            Up = Uf.reshape(N, 3, -1)
            Hf = H + Up @ np.swapaxes(Up, 1, 2)
            res = res.reshape(N, 3)
            w, V = np.linalg.eigh(np.eye(3) - Hf)
            if np.min(w) < LEVERAGE_TOL:
                e = np.full_like(res, np.inf)    # a point fitted on its own
            else:
                e = np.einsum("nij,nj->ni", V, np.einsum("nji,nj->ni", V, res) / w)
            out[f.id] = (float(np.sum(res ** 2)), e)
        return out

    def _near(self, lin: dict, target_rss: float) -> set[str]:
        """The ids in `lin` whose predicted RSS is within the equivalence
        band of `target_rss` (that of the largest difference in parameters
        any two effects have) with a margin for the second-order terms."""
        band = chi2_ppf(EQUIVALENT_QUANTILE, MAX_EFFECT_SIZE) * self.sigma ** 2
        return {fid for fid, (rss, _) in lin.items()
                if rss <= target_rss + 2 * band + NEAR_MARGIN * target_rss}

    def simplify(self, current: Fit, swapped: dict[str, list[str]]) -> Fit:
        """With a new effect in the model, an earlier one may be standing in
        for a simpler effect (a J4 origin shift doing a forearm elongation's
        and part of a J2 offset's work) or no longer be needed: swap it for
        the simplest equivalent, or drop it, until nothing changes."""
        changed = True
        while changed and len(current.effects) > 1:
            changed = False
            for i, e in enumerate(current.effects):
                rest = current.effects[:i] + current.effects[i + 1:]
                start = current.values[:i] + current.values[i + 1:]
                named = {x.id for x in current.effects}
                smaller = [f for f in self.effects if f.id not in named and f.size < e.size
                           and f.kind != "cyclic"]
                near = self._near(self._linear(rest, start, smaller), current.rss)
                options = []
                for order, f in enumerate(self.effects):
                    if f.id not in near:
                        continue
                    g = self.fit(rest + (f,), start + (np.zeros(f.size),))
                    if g.success and _equivalent(g, current, self.sigma) and \
                            _implausible(g) is None and _cancelling(g, f) is None:
                        options.append((f.size, g.rss, order, f, g))
                if options:
                    _, _, _, f, g = min(options, key=lambda o: o[:3])
                    swapped.setdefault(f.id, []).extend([e.id, *swapped.pop(e.id, [])])
                    current, changed = g, True
                    break
                without = self.fit(rest, start)
                k = current.nparams - without.nparams
                drop = max(0.0, (without.rss - current.rss) / self.sigma ** 2)
                needed = (k <= 0 or (chi2_sf(drop, k) < ALPHA and
                                     _bic(current, self.sigma, self.n)
                                     <= _bic(without, self.sigma, self.n) - STRONG_BIC))
                if without.success and not needed:
                    current, changed = without, True
                    break
        return current

    def exchange_two(self, current: Fit, swapped: dict[str, list[str]]) -> Fit:
        """Two named effects may together stand in for two others with fewer
        parameters (a J3 origin shift and a J2 offset doing an upper-arm
        elongation's and a J3 offset's work): swap them for the smallest
        such pair that explains the data equally, until none is left. The
        pairs tried are made of the candidates that scored best at any step
        of the search (their top EXCHANGE_POOL), at most EXCHANGE_FITS fits
        a pass."""
        pool: dict[str, Effect] = {}
        for _, scored, _, _ in self._scored.values():
            for x in [x for x in scored if x.effect.kind != "cyclic"][:EXCHANGE_POOL]:
                pool.setdefault(x.effect.id, x.effect)
        changed = True
        while changed and len(current.effects) > 1:
            changed = False
            named = {e.id for e in current.effects}
            options = []
            budget = EXCHANGE_FITS
            for i, j in combinations(range(len(current.effects)), 2):
                a, b = current.effects[i], current.effects[j]
                keep = [k for k in range(len(current.effects)) if k not in (i, j)]
                rest = tuple(current.effects[k] for k in keep)
                start = tuple(current.values[k] for k in keep)
                for f, g in combinations(pool.values(), 2):
                    if f.id in named or g.id in named or f.size + g.size >= a.size + b.size:
                        continue
                    budget -= 1
                    if budget < 0:
                        break
                    h = self.fit(rest + (f, g), start + (np.zeros(f.size), np.zeros(g.size)))
                    if h.success and _equivalent(h, current, self.sigma) and \
                            _implausible(h) is None and _cancelling(h, f) is None and \
                            _cancelling(h, g) is None:
                        options.append((f.size + g.size, h.rss, f.id, g.id, a, b, f, g, h))
            if options:
                *_, a, b, f, g, h = min(options, key=lambda o: o[:4])
                gone = [a.id, *swapped.pop(a.id, []), b.id, *swapped.pop(b.id, [])]
                swapped.setdefault(f.id, []).extend(gone)
                swapped.setdefault(g.id, []).extend(x for x in gone if x not in swapped[f.id])
                current, changed = h, True
        return current

    def separable(self, rest, a: Effect, b: Effect) -> bool:
        """Whether some poses tell `a` from `b` (with `rest` in the model):
        on poses spread over the whole workspace, does either add a
        direction the other does not? Same direction everywhere: no
        measurement separates them (a J6-flange elongation and a measuring
        point shifted along the flange axis)."""
        if self._generic is None:
            tool = np.mean(self.model.tool, axis=0) if self.model.size else np.zeros(3)
            _, q = random_points(self.model.robot, SEPARATE_POSES, 0)
            self._generic = ParamModel(self.model.robot, self.model.profile, q, tool)
            # Thermal effects: over every thermal state too.
            self._generic = self._generic.with_state(
                np.random.default_rng(0).uniform(0.0, 1.0, SEPARATE_POSES))
        effects = tuple(rest) + (a, b)
        _, J = self._generic.evaluate(effects, tuple(np.zeros(e.size) for e in effects))
        A = J.reshape(-1, J.shape[-1])
        scale = np.linalg.norm(A, axis=0)
        A = A / np.where(scale >= ZERO_COLUMN, scale, 1.0)
        k = sum(e.size for e in rest)

        def rank(cols) -> int:
            S = np.linalg.svd(A[:, cols], compute_uv=False)
            return int(np.sum(S >= SEPARATE_TOL * S[0])) if S.size and S[0] > 0 else 0
        both = rank(slice(None))
        # Separable: together they span more than one of them does.
        return both > rank(list(range(k + a.size))) or \
            both > rank(list(range(k)) + list(range(k + a.size, k + a.size + b.size)))

    def replay(self, start: Fit, chosen: tuple[Effect, ...], swapped) -> tuple[list[Step], Fit]:
        """The steps of the final model from `start` (no effects), in the
        order the data rank them: at each step the best-scoring remaining
        named effect is added."""
        current = start
        steps = []
        remaining = list(chosen)
        while remaining:
            scored = self.fitted(current, remaining)
            mine = [s for s in scored if s.effect in remaining and s.fit is not None]
            if not mine:
                break
            s = mine[0]
            equal = self.equivalents(scored, s)
            # An effect the final model names (at a later step) is not an
            # alternative to this one, nor replaced by it.
            final_ids = {e.id for e in chosen}
            alternatives = [x.effect.id for x in sorted(equal, key=lambda x: x.order)
                            if x is not s and x.effect.id not in final_ids]
            replaced = [a for a in swapped.get(s.effect.id, []) if a not in final_ids]
            alternatives += [a for a in replaced if a not in alternatives]
            ties = [x for x in equal if x is not s and x.fit.nparams == s.fit.nparams
                    and x.effect.id not in final_ids]
            note = None
            if ties:
                identical = all(abs(x.fit.rss - s.fit.rss) <= 1e-9 * max(s.fit.rss, 1e-30)
                                for x in ties)
                why = ("the fits are identical; it comes first in the catalogue" if identical
                       else "it leaves the smaller residual")
                same = [x.effect.id for x in ties
                        if not self.separable(current.effects, s.effect, x.effect)]
                advice = ("Measure poses that separate them to decide." if not same else
                          f"No pose separates {s.effect.id} from {', '.join(same)} on this "
                          "robot with this measuring point: they are the same effect here.")
                note = (f"the data cannot tell {s.effect.id} from "
                        f"{', '.join(x.effect.id for x in ties)} (same number of parameters, "
                        f"residuals within noise); named {s.effect.id} because {why}. {advice}")
            if replaced:
                extra = (f"replaces {', '.join(replaced)}, named earlier in the "
                         "search: with the other effects in the model it explains the same "
                         "with fewer parameters")
                note = f"{note} {extra}" if note else extra
            k = len(current.effects)
            f = s.fit
            steps.append(dict(effect=s.effect, fit=f, at_step=s.effect.user(f.values[k]),
                              rms_before_mm=current.rms_mm, rms_after_mm=f.rms_mm,
                              heldout_before_mm=current.heldout_rms_mm(),
                              heldout_after_mm=s.candidate.heldout_mm,
                              p_value=s.candidate.p_value, delta_bic=s.candidate.delta_bic,
                              alternatives=tuple(alternatives), note=note,
                              candidates=tuple(x.candidate for x in scored)))
            remaining.remove(s.effect)
            current = f
        # Parameters are reported as the final model estimates them (all
        # named effects fitted together); an early step's own fit is biased
        # by the effects not yet added.
        errors = current.stderr(self.sigma)
        final = {e.id: (e.user(v), e.user(err))
                 for e, v, err in zip(current.effects, current.values, errors)}
        return [Step(params=final[st["effect"].id][0], stderr=final[st["effect"].id][1], **st)
                for st in steps], current


def _with_time_constants(steps: list[Step], final: Fit, model: ParamModel, data: Measurements,
                         warm, sigma: float) -> list[Step]:
    """The steps' standard errors with the time constants' own uncertainty
    in them: tau (and tau_cool) were estimated from the same data and held
    while the effects were fitted, so the effects' errors alone come out too
    small (a thermal amplitude tracks its tau: ~3x in a campaign with
    stops). The final fit's Jacobian is widened by the positions' derivative
    with respect to each time constant (central differences of the states),
    and the errors read from its covariance."""
    t, stood = data.t_min, data.stood_min
    taus = [warm.tau_min] + ([warm.tau_cool_min] if warm.tau_cool_min is not None else [])
    cols = []
    for k, tau in enumerate(taus):
        h = 1e-3 * tau
        X = []
        for d in (h, -h):
            heat, cool = (tau + d, warm.tau_cool_min) if k == 0 else (warm.tau_min, tau + d)
            X.append(model.with_state(warmup.states(t, heat, stood, cool)).evaluate(
                final.effects, final.values, jacobian=False)[0])
        cols.append(((X[0] - X[1]) / (2 * h)).ravel())
    errors = {e.id: e.user(v) for e, v in zip(final.effects,
                                              final.stderr(sigma, np.column_stack(cols)))}
    return [replace(st, stderr=errors[st.effect.id]) for st in steps]


def discover(model: ParamModel, data: Measurements, effects: tuple[Effect, ...],
             sigma_mm: float | None = None, progress=None) -> Discovery:
    """progress: called with a short text at each stage (stderr on a
    terminal, job.py)."""
    say = progress or (lambda text: None)
    warm = None
    if data.t_min is not None:
        # A warm-up campaign: tau from the data alone (warmup.py); each
        # effect heat can change gets a thermal twin acting as s(t) times it.
        say("warm-up")
        warm = warmup.estimate(data.q_deg, data.xyz_mm, data.t_min, data.tool, sigma_mm,
                               data.temperatures, data.stood_min)
        if warm.tau_min is not None:
            model = model.with_state(warm.states(data.t_min, data.temperatures,
                                                 data.stood_min))
            effects = tuple(effects) + thermal_variants(effects)
    say("gross errors")
    # The reference fit for gross errors and the noise: every effect but
    # the cyclic ones, whose free amplitudes and phases would fit a small
    # data set's noise too.
    reference = tuple(e for e in effects if e.kind != "cyclic")
    screened = screen(model, data, reference)
    if screened.outliers:
        rows = screened.rows
        model = model.subset(rows)
        data = replace(data, names=tuple(data.names[i] for i in rows), q_deg=data.q_deg[rows],
                       xyz_mm=data.xyz_mm[rows], lines=tuple(data.lines[i] for i in rows),
                       approach=None if data.approach is None else data.approach[rows],
                       tool=None if data.tool is None else data.tool[rows],
                       t_min=None if data.t_min is None else data.t_min[rows],
                       temperatures=tuple((c, v[rows]) for c, v in data.temperatures),
                       stood_min=None if data.stood_min is None else data.stood_min[rows])
    n = 3 * len(data)
    meas = data.xyz_mm
    if warm is not None and sigma_mm is None:
        # The same pose at other times is no replicate (it moved): the
        # scatter about each pose's own warm-up curve is the pure error.
        nz = floored(warm.sigma_mm, f"from the warm-up fit of {warm.poses} poses measured "
                     f"at {warm.times} times (each pose's scatter about its own curve a + s(t) "
                     f"b, {warm.dof} degrees of freedom)", "replicates")
    else:
        nz = noise(sigma_mm, data.q_deg, meas, screened.full, model.tool, repeats=warm is None)
    sigma, source = nz.sigma_mm, nz.source
    sel = _Selector(model, meas, effects, sigma, nz.kind != "estimated")
    start = sel.fit(())
    current = start
    swapped: dict[str, list[str]] = {}
    blocked: list[str] = []
    far_apart = False
    far_notes: list[str] = []
    if start.rms_mm > FAR_APART_MM:
        # Beyond what every plausible effect together could do: any fit
        # would be an artefact of the distance.
        far_apart = True
        blocked = [f"the residuals (RMS {start.rms_mm:.4g} mm) are beyond what any effect a "
                   f"real robot has could explain (at most ~{FAR_APART_MM:g} mm at the "
                   "measuring point, a base frame registered 50 mm and 5 deg off included)"]
    while not far_apart and _noise_p(current, sigma, n) < 1 - NOISE_QUANTILE:
        say(f"step {len(current.effects) + 1}: fitting {len(effects)} candidates")
        scored = sel.score(current)
        # A fit that would take away most of what is left, with values no
        # robot has: the data and the model are far apart, and whatever
        # small plausible effect fits next would be an artefact of that.
        plausible = min([x.fit.rss for x in scored if x.strong] or [current.rss])
        far = [x.blocked for x in scored if x.blocked and x.fit.rss < FAR_APART * plausible]
        if far:
            blocked, far_apart = far[:3], True
            if current.effects:
                # What was named on the way is an artefact of that distance.
                dropped = ", ".join(e.id for e in current.effects)
                far_notes.append(f"{dropped} fitted before the data and the model showed far "
                                 "apart: not named (an artefact of the distance)")
                current = start
            break
        chosen = sel.pick(scored, current)
        if chosen is None:
            blocked = [s.blocked for s in scored if s.blocked][:3]
            break
        current = sel.simplify(chosen.fit, swapped)
    if _noise_p(current, sigma, n) >= 1 - NOISE_QUANTILE:
        # Only a model that explains the data is worth making smaller.
        say("looking for a smaller equivalent model")
        current = sel.exchange_two(current, swapped)
    say("report")
    sel.score(start)   # the not-identifiable list is made on the first scoring (cached)
    steps, current = sel.replay(start, current.effects, swapped)
    if (warm is not None and warm.tau_min is not None and warm.state_from is None
            and any(e.thermal for e in current.effects)):
        steps = _with_time_constants(steps, current, model, data, warm, sigma)
    noise_p = _noise_p(current, sigma, n)
    undetermined = _undetermined(steps)
    initial = analyse(data.names, data.q_deg, meas, start.residuals, model.robot.joint_names)
    final = analyse(data.names, data.q_deg, meas, current.residuals, model.robot.joint_names)
    found = None
    if nz.kind == "estimated":
        offsets = tuple(e for e in effects if e.kind == "joint_offset")
        _, J = model.evaluate(offsets, tuple(np.zeros(1) for _ in offsets))
        found = structure(data.q_deg, current.residuals, model.robot.joint_names,
                          {e.joint: J[:, :, i] for i, e in enumerate(offsets)})
    est = (" (the least an instrument has)" if nz.floored else
           " (estimated)" if nz.kind == "estimated" else "")
    verdict, text = _verdict(steps, current, sigma, noise_p, est, blocked,
                             far_apart, found, undetermined,
                             warm if warm is not None and warm.tau_min is not None else None,
                             nz.kind == "estimated" and not nz.floored)
    notes = ((screened.note,) if screened.note else ()) + tuple(far_notes)
    evidence = _thermal_evidence(sel, current, steps) if warm is not None else {}
    return Discovery(len(data), sigma, source, initial, final, start.heldout_rms_mm(),
                     tuple(steps), verdict, text, noise_p, tuple(sel.not_identifiable.items()),
                     current, start, effects, tuple(blocked), nz, screened.outliers, found, notes,
                     screened.rows, far_apart, warm, evidence, tuple(undetermined))


def _undetermined(steps) -> list[tuple[str, str]]:
    """The named effects whose stated error alone is beyond anything a real
    robot has (plausible.py's bounds, the errors read as values): the data
    do not bound the value within what a robot may have, so the fitted value
    is no measurement of the robot (a warm-up campaign of three rounds with
    a stop: the time constants and an effect's size trade off, and its
    error comes out at 1e5 mm). Each: effect id, its largest error."""
    out = []
    for i, st in enumerate(steps):
        errors = {k: abs(float(v)) for k, v in st.stderr.items()}
        if implausible(st.effect, errors, first=(i == 0)) is not None:
            name, err = max(errors.items(), key=lambda kv: kv[1])
            out.append((st.effect.id, f"{name} ±{err:.3g}"))
    return out


def _thermal_evidence(sel: _Selector, final: Fit, steps) -> dict[str, str]:
    """Per named effect: static or thermal, and what says so (the final
    model with the effect swapped for its twin of the other kind)."""
    out = {}
    named = {e.id for e in final.effects}
    twins = {e.id: e for e in sel.effects}
    for st in steps:
        e = st.effect
        kind = "thermal" if e.thermal else "static"
        other = e.base_id if e.thermal else THERMAL_PREFIX + e.id
        if other not in twins:
            out[e.id] = f"static: heat does not change a {e.kind.replace('_', ' ')}"
            continue
        if other in named:
            out[e.id] = (f"{kind}, and a {'static' if e.thermal else 'thermal'} part of it is "
                         "named too")
            continue
        i = final.effects.index(e)
        swapped = sel.fit(final.effects[:i] + (twins[other],) + final.effects[i + 1:],
                          final.values[:i] + (final.values[i],) + final.values[i + 1:])
        if not swapped.success:
            out[e.id] = f"{kind}: its {'static' if e.thermal else 'thermal'} twin does not fit"
            continue
        chi = (swapped.rss - final.rss) / sel.sigma ** 2
        tell = chi2_ppf(EQUIVALENT_QUANTILE, e.size)
        if chi > tell:
            out[e.id] = (f"{kind}: as a {'static' if e.thermal else 'thermal'} effect the fit is "
                         f"worse by chi-square {chi:.1f} (p = {chi2_sf(chi, e.size):.3g})")
        else:
            out[e.id] = (f"{kind}, but the data hardly tell: as a "
                         f"{'static' if e.thermal else 'thermal'} effect the fit is worse by "
                         f"chi-square {chi:.1f} only; measure over a longer warm-up")
    return out


def _equivalent(a: Fit, b: Fit, sigma: float) -> bool:
    dk = max(1, abs(a.nparams - b.nparams))
    return abs(a.rss - b.rss) / sigma ** 2 <= chi2_ppf(EQUIVALENT_QUANTILE, dk)


def _verdict(steps, current: Fit, sigma: float, noise_p: float, est: str,
             blocked=(), far_apart: bool = False, found: Structure | None = None,
             undetermined=(), warm=None, estimated: bool = False):
    """est: what the noise's figure is, said after it (" (estimated)").
    undetermined: _undetermined's; warm: a warm-up campaign's Warmup;
    estimated: the noise is the catalogue fit's estimate (est says so)."""
    s_um = sigma * 1000
    at_noise = noise_p >= 1 - NOISE_QUANTILE
    if at_noise and undetermined and not far_apart:
        # (Evidence over claims: a model whose size the data leave open
        # explains nothing about the robot.)
        names = ", ".join(s.effect.id for s in steps)
        ids = ", ".join(eid for eid, _ in undetermined)
        errs = "; ".join(err if len(undetermined) == 1 else f"{eid}: {err}"
                         for eid, err in undetermined)
        thermal = warm is not None and any(eid.startswith(THERMAL_PREFIX)
                                           for eid, _ in undetermined)
        why = (f": over the {warm.times} times of this warm-up campaign the warm-up's time "
               "constants and the effect's size trade off" if thermal else "")
        # (What the warm-up line advises where tau is poorly known; else more
        # of what the fit lacks.)
        more = (" and ".join(warm.advice) if thermal and warm.advice else
                "measure more rounds" if thermal
                else "measure more poses, spread over the workspace")
        return "unexplained", (
            f"With {names} added, the residuals (RMS {current.rms_mm * 1000:.1f} um) are "
            f"consistent with measurement noise of {s_um:.1f} um per axis{est}, but these data "
            f"do not determine {ids}: the stated error ({errs}) is beyond anything a real robot "
            f"has{why}. {more[0].upper()}{more[1:]}.")
    if at_noise and found is not None:
        named = (f"With {', '.join(s.effect.id for s in steps)} added, the" if steps
                 else "The")
        return "unexplained", (
            f"{named} residuals (RMS {current.rms_mm * 1000:.1f} um) match the noise estimated "
            f"from the catalogue's own fit ({s_um:.1f} um per axis), but they are not noise: "
            f"{found.joint}'s angle predicts {found.share:.0%} of them on points it was not "
            "fitted to (an effect outside the catalogue, such as a cyclic gear error, which "
            "also inflates that estimate). Give the measuring system's noise with --sigma or "
            "measure some poses more than once.")
    if not at_noise and far_apart:
        why = (blocked[0] if len(blocked) == 1 and blocked[0].startswith("the residuals (RMS")
               else f"the residuals (RMS {current.rms_mm * 1000:.1f} um) are explained only by "
                    f"values no real robot has ({'; '.join(blocked)})")
        return "unexplained", (
            f"The model and the data are far apart: {why}. Likely causes: the measuring point "
            "is not given (--tool X,Y,Z in the flange frame), the data are not in millimetres "
            "or not in the "
            "robot's base frame, or the robot model (--robot) is not the robot measured.")
    if at_noise and not steps:
        return "noise", (f"The residuals (RMS {current.rms_mm * 1000:.1f} um) are consistent with "
                         f"measurement noise of {s_um:.1f} um per axis{est} "
                         f"(chi-square p = {noise_p:.3g}): nothing to name.")
    if at_noise:
        names = ", ".join(s.effect.id for s in steps)
        cyclic = [s.effect.id for s in steps if s.effect.kind == "cyclic"]
        # (The noise estimate is the catalogue's fit without cyclic effects:
        # a cyclic error named is in it, and the residuals far below it.)
        inflated = ("" if not cyclic or not estimated or noise_p < 1 - 1e-3 else
                    f" The noise estimate holds what {', '.join(cyclic)} explains (it comes "
                    "from the fit of the catalogue without cyclic effects), so the residuals "
                    "are far below it: give the measuring system's noise with --sigma to test "
                    "them against it.")
        return "explained", (f"With {names} added, the residuals (RMS "
                             f"{current.rms_mm * 1000:.1f} um) are consistent with measurement "
                             f"noise of {s_um:.1f} um per axis{est} (chi-square p = "
                             f"{noise_p:.3g}).{inflated}")
    refused = ("" if not blocked else
               f" Fits that would need values no real robot has were not taken ({'; '.join(blocked)}).")
    if found is not None:
        refused += (f" {found.joint}'s angle predicts {found.share:.0%} of the residuals on "
                    "points it was not fitted to: look there first (a cyclic gear error "
                    f"of {found.joint} shows so).")
    return "unexplained", (f"The residuals (RMS {current.rms_mm * 1000:.1f} um) stay above "
                           f"measurement noise of {s_um:.1f} um per axis{est} (chi-square p = "
                           f"{noise_p:.3g}) and no catalogue effect explains more with strong "
                           "evidence: the missing effect is outside the catalogue. The residual "
                           f"analysis shows where it concentrates.{refused}")

"""Inverse kinematics with result objects: nominal (closed form) and
deformed (Newton on the deformed model, seeded from the nominal solution).

Every target gets a status and, when it fails, a reason with "by how much".
Nothing is silently put on another branch: the deformed solution must keep
the target's cfx (a flip of a bit whose boundary lies within the
singularity margin is reported as a warning, guarded by the joint-change
bound), and cf1/cf4/cf6 are recomputed from the result and reported when
they change.
"""

from __future__ import annotations

import contextvars
import dataclasses
import functools
import re
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from enum import IntEnum, IntFlag

import numpy as np

from ..cpus import side_by_side
from .analytic import ArmGeometry, solve_branches
from .chain import Chain
from .conf import confdata, quadrant_miss, wrap_pi
from .frames import DEG, rotation_log
from .robot import RobotModel


_DAMPING = 1e-12


class Status(IntEnum):
    OK = 0
    UNREACHABLE = 1
    NO_CONFIGURATION = 2
    JOINT_LIMIT = 3
    NOT_CONVERGED = 4
    JOINT_JUMP = 5
    BRANCH_CHANGED = 6


class Warn(IntFlag):
    NONE = 0
    WRIST_SINGULAR = 1      # J5 near 0
    SHOULDER_SINGULAR = 2   # wrist centre near axis 1
    ELBOW_SINGULAR = 4      # forearm stretched along the lower arm
    QUADRANT_CHANGED = 8    # cf1/cf4/cf6 of the result differ from the target's
    CFX_AT_SINGULARITY = 16  # cfx bit flipped across a singularity boundary
    ORIENTATION_LEFT = 32   # at the wrist singularity: position exact, orientation partly


WARN_TEXT = {
    Warn.WRIST_SINGULAR: "near wrist singularity (J5 ~ 0)",
    Warn.SHOULDER_SINGULAR: "near shoulder singularity (wrist centre near axis 1)",
    Warn.ELBOW_SINGULAR: "near elbow singularity (arm stretched)",
    Warn.QUADRANT_CHANGED: "joint quadrant changed (cf1/cf4/cf6 recomputed)",
    Warn.CFX_AT_SINGULARITY: "cfx changed across a singularity boundary",
    Warn.ORIENTATION_LEFT: ("at the wrist singularity the position is compensated exactly and "
                            "the orientation only as far as small J4/J6 changes allow "
                            "(what is left over is the row's residual in degrees)"),
}


# The largest flange rotation (rad) re-splitting J4/J6 near J5 = 0 may make
# (a quaternion written with 6 decimals is itself only good to ~2e-6 rad).
RESPLIT_RAD = 1e-5


@dataclass(frozen=True)
class IKOptions:
    singular_margin_deg: float = 0.5
    max_joint_change_deg: float = 1.0
    # A taught target whose J1, J4 or J6 is 0 deg sits on a quadrant
    # boundary; written with 3 decimals it solves a few 1e-5 deg on either
    # side. A solution this close to the programmed quadrant is in it (the
    # controller runs such targets every day).
    quadrant_tol_deg: float = 0.01
    tol_mm: float = 1e-9
    tol_rad: float = 1e-9
    # Newton from the nominal seed converges in 2-4 steps; more means the
    # warm robot cannot reach the pose (typically the arm fully stretched).
    max_iterations: int = 12
    # Within this distance of J5 = 0 a pose whose full compensation would
    # swing J4/J6 beyond the joint-change bound is compensated in position
    # exactly and in orientation as far as the bound allows.
    wrist_fallback_deg: float = 5.0
    # What the wrist fallback may leave over of the orientation (deg): the
    # thermal tilt is ~0.01 deg; more is not a thermal correction's leftover
    # but a wrong target, and the row fails.
    max_leftover_deg: float = 0.1


@dataclass(frozen=True, slots=True)
class IKResult:
    success: bool
    status: Status
    reason: str | None
    q_deg: tuple[float, ...] | None
    conf: tuple[int, int, int, int] | None
    residual_mm: float
    residual_rad: float
    iterations: int
    joint_change_deg: tuple[float, ...] | None
    warnings: tuple[str, ...]


# A solution beyond a joint's limit, in words; BEYOND_LIMIT reads them back
# (the note of a program that goes beyond the limits as written: rows.py).
LIMIT_REASON = "J{joint} beyond its limit by {by:.4f} deg"
MORE_LIMIT_REASON = ", J{joint} by {by:.4f} deg"
BEYOND_LIMIT = re.compile(r"J(\d+) beyond its limit by (\d+\.\d+) deg((?:, J\d+ by \d+\.\d+ deg)*)")
MORE_BEYOND = re.compile(r", J(\d+) by (\d+\.\d+) deg")
# A joint further than this beyond its limit is beyond it (deg).
LIMIT_SLACK_DEG = 1e-9
NO_SOLUTION_IN_LIMITS = "no solution within the joint limits"


def _near(bits: int) -> str:
    """Where a solve that did not converge was: the singularities near its
    last joints (at the elbow's, the arm stretched out, a pose moves the
    joints far for a small change of the arm: the deformed robot may reach
    it only by a large J2/J3 change, or not at all)."""
    near = [what for bit, what in ((Warn.SHOULDER_SINGULAR, "the shoulder singularity (the "
                                    "wrist centre near axis 1)"),
                                   (Warn.ELBOW_SINGULAR, "the elbow singularity (the arm "
                                    "stretched out)"),
                                   (Warn.WRIST_SINGULAR, "the wrist singularity (J5 ~ 0)"))
            if bits & bit]
    if not near:
        return ""
    return (": the pose is at " + " and ".join(near) + ", where a small change of the arm "
            "needs a large one of the joints")


@dataclass(frozen=True, eq=False)
class IKBatch:
    """Results of N targets as arrays; `result(i)` gives the i-th object."""

    q_deg: np.ndarray          # (N, 6), NaN where no solution
    status: np.ndarray         # (N,) Status
    detail: np.ndarray         # (N,) how much (mm or deg, see reason())
    detail_joint: np.ndarray   # (N,) joint index the detail refers to, -1 if none
    conf: np.ndarray           # (N, 4) cf1, cf4, cf6, cfx
    residual_mm: np.ndarray
    residual_rad: np.ndarray
    iterations: np.ndarray
    warnings: np.ndarray       # (N,) Warn bits
    joint_change_deg: np.ndarray | None = None
    # (N,) the bound on a joint's change from its seed (deg: the solver's
    # max_joint_change_deg), where the rows are a deformed robot's
    jump_bound_deg: np.ndarray | None = None
    # (N, 6) how far each joint of a JOINT_LIMIT row lies beyond its limit,
    # deg (0 within it): its reason names every such joint, not the worst
    # alone
    beyond_deg: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.status)

    @functools.cached_property
    def success(self) -> np.ndarray:
        # Once: the chooser asks per target (1e5 times on a CAM program).
        return self.status == Status.OK

    def reason(self, i: int) -> str | None:
        s = Status(int(self.status[i]))
        d = float(self.detail[i])
        j = int(self.detail_joint[i])
        if s == Status.OK:
            return None
        if s == Status.UNREACHABLE:
            if d < 0.0005:
                # (0.000 would read as in reach: a target on the edge of the
                # workspace, the arm stretched out, past it by rounding.)
                return (f"out of reach by {d:.2g} mm (on the edge of the workspace: the arm "
                        "stretched out)")
            return f"out of reach by {d:.3f} mm"
        if s == Status.NO_CONFIGURATION:
            if j < 0:
                return "confdata asks for a configuration (cfx) no solution has"
            return (f"confdata asks for a J{j + 1} quadrant no solution has "
                    f"(nearest solution {d:.4f} deg outside it)")
        if s == Status.JOINT_LIMIT:
            text = LIMIT_REASON.format(joint=j + 1, by=d)
            if self.beyond_deg is not None:
                # (The others beyond theirs, after the worst: one limit at a
                # time would be a user's round trip each.)
                over = self.beyond_deg[i]
                text += "".join(MORE_LIMIT_REASON.format(joint=k + 1, by=float(over[k]))
                                for k in np.argsort(-over, kind="stable").tolist()
                                if k != j and over[k] > LIMIT_SLACK_DEG)
            return text
        if s == Status.NOT_CONVERGED:
            return f"did not converge (residual {d:.3g} mm)" + _near(int(self.warnings[i]))
        if s == Status.JOINT_JUMP:
            near = (j in (3, 5) and self.q_deg is not None and not np.isnan(self.q_deg[i, 4])
                    and abs(self.q_deg[i, 4]) < 5.0)
            return (("near the wrist singularity (J5 ~ 0, where only J4 + J6 is defined): "
                     if near else "")
                    + f"J{j + 1} would move {d:.4f} deg from the nominal solution, more than "
                    + ("the allowed bound" if self.jump_bound_deg is None else
                       f"the {float(self.jump_bound_deg[i]):g} deg a thermal correction may "
                       "move a joint"))
        return "the solution is on another configuration branch (cfx changed)"

    def warning_texts(self, i: int) -> tuple[str, ...]:
        return warning_texts_of(int(self.warnings[i]))

    def result(self, i: int) -> IKResult:
        ok = bool(self.status[i] == Status.OK)
        q = self.q_deg[i]
        warn = Warn(int(self.warnings[i]))
        return IKResult(
            ok, Status(int(self.status[i])), self.reason(i),
            tuple(float(x) for x in q) if not np.isnan(q).any() else None,
            tuple(int(x) for x in self.conf[i]) if not np.isnan(q).any() else None,
            float(self.residual_mm[i]), float(self.residual_rad[i]), int(self.iterations[i]),
            tuple(float(x) for x in self.joint_change_deg[i])
            if self.joint_change_deg is not None and not np.isnan(q).any() else None,
            warning_texts_of(int(warn)))


@functools.lru_cache(maxsize=None)
def warning_texts_of(bits: int) -> tuple[str, ...]:
    """The texts of a warnings bit set (IKBatch.warnings holds them)."""
    warn = Warn(bits)
    return tuple(text for flag, text in WARN_TEXT.items() if flag in warn)


def _turns(theta_deg: np.ndarray, cf: np.ndarray, tol: float):
    """Shift angles by whole turns into quadrant cf. Returns angle, miss (deg)."""
    lo = 90.0 * cf
    k = np.ceil((lo - theta_deg) / 360.0)
    t1 = theta_deg + 360.0 * k           # in [lo, lo + 360)
    above = t1 - (lo + 90.0)             # > 0: outside, above the quadrant
    below = lo - (t1 - 360.0)            # > 0: the turn below misses by this
    exact = above < 0
    use_below = ~exact & (below < above)
    angle = np.where(use_below, t1 - 360.0, t1)
    miss = np.where(exact, 0.0, np.minimum(above, below))
    ok = miss <= tol
    return angle, miss, ok


# Rows per batch: every row is solved on its own (Newton steps stop per
# row), so a long program is solved in blocks that bound the temporaries
# (Jacobians, 8 branches per target) to a few MB, with the same results.
CHUNK = 8192


def _rows(a, sl: slice):
    if isinstance(a, IKBatch):
        return IKBatch(*(None if v is None else v[sl] for v in
                         (getattr(a, f.name) for f in dataclasses.fields(IKBatch))))
    if a is None or np.ndim(a) == 0:
        return a
    return a[sl]


def _join(parts: list):
    first = parts[0]
    if isinstance(first, tuple):
        return tuple(_join([p[k] for p in parts]) for k in range(len(first)))
    if isinstance(first, IKBatch):
        return IKBatch(*(None if getattr(first, f.name) is None else np.concatenate(
            [getattr(p, f.name) for p in parts]) for f in dataclasses.fields(IKBatch)))
    return np.concatenate(parts)


def _chunked(method):
    """method(self, rows, ...) over blocks of CHUNK rows: every array
    argument (and IKBatch) split along its first axis, results joined in
    block order. The blocks run on two threads where there are two cores:
    numpy releases the GIL inside its loops, and each block is computed
    alone, so the results are those of one thread, bit for bit; each block
    runs in a copy of the caller's context (numpy's errstate lives there).
    (A pool per call: one kept would not survive a fork of the process.)"""
    @functools.wraps(method)
    def run(self, *args, **kw):
        n = len(args[0])
        if n <= CHUNK:
            return method(self, *args, **kw)

        def block(i):
            return method(self, *(_rows(a, slice(i, i + CHUNK)) for a in args),
                          **{k: _rows(v, slice(i, i + CHUNK)) for k, v in kw.items()})
        threads = side_by_side()
        if threads == 1:
            return _join([block(i) for i in range(0, n, CHUNK)])
        with ThreadPoolExecutor(threads) as pool:
            futures = [pool.submit(contextvars.copy_context().run, block, i)
                       for i in range(0, n, CHUNK)]
            try:
                return _join([f.result() for f in futures])
            except BaseException:
                for f in futures:       # (the first block's error, as one thread raises it)
                    f.cancel()
                raise
    return run


def reusing(method, solver, args: tuple, known: tuple | None):
    """method(solver, *args) for a Solver method made @_chunked, with each
    block of rows it computes alone taken from `known` = (arguments,
    result) of an earlier call of it (a guess made ahead) where that
    block's arguments were the very same, byte for byte: the same block,
    the same result, bit for bit. The other blocks are computed; without
    `known` (or of another length) all of them, as the method does."""
    n = len(args[0])
    if known is None or len(known[0][0]) != n or len(known[0]) != len(args):
        return method(solver, *args)
    old_args, old = known
    blocks = [slice(i, i + CHUNK) for i in range(0, n, CHUNK)] if n > CHUNK else [slice(0, n)]
    parts = []
    for sl in blocks:
        if all(_same_rows(a, b, sl) for a, b in zip(args, old_args)):
            parts.append(tuple(_rows(r, sl) for r in old) if isinstance(old, tuple)
                         else _rows(old, sl))
        else:
            parts.append(method.__wrapped__(solver, *(_rows(a, sl) for a in args)))
    return parts[0] if len(parts) == 1 else _join(parts)


def _same_rows(a, b, sl: slice) -> bool:
    """a and b hold the same bytes in rows sl (IKBatch: each field)."""
    if isinstance(a, IKBatch) or isinstance(b, IKBatch):
        return (isinstance(a, IKBatch) and isinstance(b, IKBatch)
                and all(_same_rows(getattr(a, f.name), getattr(b, f.name), sl)
                        for f in dataclasses.fields(IKBatch)))
    if a is None or b is None:
        return a is None and b is None
    if not (isinstance(a, np.ndarray) and isinstance(b, np.ndarray)):
        return False
    a, b = a[sl], b[sl]
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


class Solver:
    """IK for one nominal robot and, optionally, its deformed copy."""

    def __init__(self, nominal: RobotModel, deformed: RobotModel | None = None,
                 options: IKOptions = IKOptions()):
        self.nominal_robot = nominal
        self.deformed_robot = deformed
        self.options = options
        self.nominal_chain = Chain.from_robot(nominal)
        self.geometry = ArmGeometry.from_chain(self.nominal_chain)
        self.deformed_chain = Chain.from_robot(deformed) if deformed is not None else None
        # Joint-space terms (offset, scale, compliance) of the deformed model:
        # Newton solves for the actual angles, the commanded ones are sent.
        self.joint_map = deformed.joint_map if deformed is not None else None
        self.lower = np.asarray(nominal.lower_deg)
        self.upper = np.asarray(nominal.upper_deg)

    # ------------------------------------------------------------ helpers
    def _singularity_warnings(self, q: np.ndarray, wrist: np.ndarray) -> np.ndarray:
        m = self.options.singular_margin_deg * DEG
        w = np.zeros(len(q), dtype=int)
        w |= np.where(np.abs(wrap_pi(q[:, 4])) < m, int(Warn.WRIST_SINGULAR), 0)
        rho = np.hypot(wrist[:, 0], wrist[:, 1])
        w |= np.where(rho < self.geometry.reach * np.sin(m), int(Warn.SHOULDER_SINGULAR), 0)
        w |= np.where(np.abs(wrap_pi(q[:, 2] - self.geometry.phi)) < m,
                      int(Warn.ELBOW_SINGULAR), 0)
        return w

    def _outside_quadrants(self, q_deg: np.ndarray, conf: np.ndarray) -> np.ndarray:
        """Rows whose J1, J4 or J6 lies beyond the quadrant tolerance outside
        the quadrant conf names (cf1, cf4, cf6)."""
        out = np.zeros(len(q_deg), dtype=bool)
        for col, cf in ((0, 0), (3, 1), (5, 2)):
            out |= quadrant_miss(q_deg[:, col], conf[:, cf]) > self.options.quadrant_tol_deg
        return out

    def _mark_limits(self, q_deg, status, detail, djoint) -> np.ndarray:
        """Mark rows still OK whose joints lie beyond a limit (in place),
        with the amount and the joint (the worst); returns how far each
        joint of those rows lies beyond (IKBatch.beyond_deg)."""
        over_all = np.maximum(self.lower - q_deg, q_deg - self.upper)  # > 0 beyond a limit
        j = np.argmax(over_all, axis=1)
        over = over_all[np.arange(len(q_deg)), j]
        lim = (over > LIMIT_SLACK_DEG) & (status == Status.OK)
        status[lim] = Status.JOINT_LIMIT
        detail[lim] = over[lim]
        djoint[lim] = j[lim]
        return np.where(lim[:, None] & (over_all > LIMIT_SLACK_DEG), over_all, 0.0)

    # ------------------------------------------------------------ nominal
    @_chunked
    def solve_nominal(self, R: np.ndarray, p: np.ndarray, conf: np.ndarray) -> IKBatch:
        """Closed-form IK of flange poses on the branch and turns of `conf`."""
        return self._nominal(R, p, conf)[0]

    @_chunked
    def nominal_and_candidates(self, R: np.ndarray, p: np.ndarray,
                               conf: np.ndarray) -> tuple[IKBatch, np.ndarray]:
        """(solve_nominal, candidates) of the same poses, their closed-form
        solutions computed once (the choice needs both, of every robtarget
        of a program)."""
        batch, br = self._nominal(R, p, conf)
        return batch, br.q / DEG

    def _nominal(self, R: np.ndarray, p: np.ndarray, conf: np.ndarray):
        R = np.asarray(R, float).reshape(-1, 3, 3)
        p = np.asarray(p, float).reshape(-1, 3)
        conf = np.asarray(conf, dtype=int).reshape(-1, 4)
        N = len(p)
        br = solve_branches(self.geometry, R, p)
        cfx = conf[:, 3]
        rows = np.arange(N)
        # Branch index = cfx by construction in solve_branches (front/back,
        # elbow, wrist); the computed cfx is checked rather than assumed.
        q = br.q[rows, np.clip(cfx, 0, 7)]
        status = np.zeros(N, dtype=int)
        detail = np.zeros(N)
        djoint = np.full(N, -1)
        bad_cfx = (cfx < 0) | (cfx > 7)
        unreachable = np.isnan(q).any(axis=1)
        status[unreachable] = Status.UNREACHABLE
        detail[unreachable] = br.reach_excess[rows, np.clip(cfx, 0, 7)][unreachable]
        got = br.cfx[rows, np.clip(cfx, 0, 7)]
        mismatch = ~unreachable & ((got != cfx) | bad_cfx)
        status[mismatch] = Status.NO_CONFIGURATION
        qd = np.nan_to_num(q) / DEG
        warnings = self._singularity_warnings(np.nan_to_num(q), br.wrist)
        # At the wrist singularity only q4 + q6 is defined: place q4 in the
        # programmed quadrant (nearest 0) and keep the sum, where that moves
        # the flange by less than RESPLIT_RAD (a target taught at J5 = 0 and
        # written with rounded quaternion digits lies a few 1e-4 deg off it,
        # with an arbitrary split; the controller runs it on its confdata).
        sing = (warnings & Warn.WRIST_SINGULAR).astype(bool)
        if sing.any():
            target4 = np.clip(0.0, 90.0 * conf[:, 1], 90.0 * conf[:, 1] + 89.999)
            shift = np.where(sing, target4 - qd[:, 3], 0.0)
            # Turning the split by d at J5 = q5 turns the flange by ~|q5 d|.
            shift = np.where(np.abs(q[:, 4] * shift * DEG) <= RESPLIT_RAD, shift, 0.0)
            qd[:, 3] += shift
            qd[:, 5] -= shift
        for col, cf_col in ((0, 0), (3, 1), (5, 2)):
            angle, miss, ok = _turns(qd[:, col], conf[:, cf_col], self.options.quadrant_tol_deg)
            qd[:, col] = angle
            fail = ~ok & (status == Status.OK)
            status[fail] = Status.NO_CONFIGURATION
            detail[fail] = miss[fail]
            djoint[fail] = col
        qd = self._uncounted_turns(qd)
        beyond = self._mark_limits(qd, status, detail, djoint)
        # Joint-limit failures keep their angles (the report shows them).
        has_q = (status == Status.OK) | (status == Status.JOINT_LIMIT)
        q_out = np.where(has_q[:, None], qd, np.nan)
        conf_out = confdata(np.nan_to_num(q_out) * DEG, br.wrist, self.geometry.phi)
        err_mm, err_rad = self.nominal_chain.pose_error(np.nan_to_num(q_out) * DEG, R, p)
        res_mm = np.where(has_q, err_mm, np.nan)
        res_rad = np.where(has_q, err_rad, np.nan)
        warnings = np.where(has_q, warnings, 0)
        return IKBatch(q_out, status, detail, djoint, conf_out, res_mm, res_rad,
                       np.zeros(N, dtype=int), warnings, beyond_deg=beyond), br

    @_chunked
    def nominal_pose_and_wrist(self, q: np.ndarray):
        """Nominal FK of joints q (N, 6) rad, R (N, 3, 3) and p (N, 3) mm,
        and the wrist centre (the origin of joint 5's frame, mm), which
        the confdata of those joints needs."""
        (R, p), (_, ps) = self.nominal_chain.fk_and_frames(q)
        return R, p, np.ascontiguousarray(ps[:, 4])

    # ------------------------------------------------------------ deformed
    @_chunked
    def deformed_pose_error(self, q_cmd: np.ndarray, R: np.ndarray, p: np.ndarray,
                            tcp: np.ndarray | None = None):
        """Error (mm, rad) of the deformed robot commanded q_cmd (rad)
        against the flange poses R, p: the distance of the TCP (tcp: its
        position in the flange frame, mm, per row; default the flange) and
        the rotation angle."""
        q = self.joint_map.apply(q_cmd) if self.joint_map is not None else q_cmd
        if tcp is None:
            return self.deformed_chain.pose_error(q, R, p)
        Rf, pf = self.deformed_chain.fk(q)
        t = np.asarray(tcp, float).reshape(-1, 3, 1)
        d = (p + (R @ t)[..., 0]) - (pf + (Rf @ t)[..., 0])
        return (np.linalg.norm(d, axis=1),
                np.linalg.norm(rotation_log(R @ np.swapaxes(Rf, 1, 2)), axis=1))

    @_chunked
    def solve_deformed(self, R: np.ndarray, p: np.ndarray, seed: IKBatch,
                       tcp: np.ndarray | None = None) -> IKBatch:
        """Joint angles with which the deformed robot reaches R, p.

        Newton's method on the deformed chain from the nominal solution,
        which is continuous with it: no turn jumps are possible. tcp: the
        tool centre point in the flange frame (mm) per row, which the wrist
        fallback keeps exact (default: the flange).
        """
        if self.deformed_chain is None:
            raise ValueError("Solver was built without a deformed model")
        opt = self.options
        R = np.asarray(R, float).reshape(-1, 3, 3)
        p = np.asarray(p, float).reshape(-1, 3)
        N = len(p)
        status = seed.status.copy()
        active = status == Status.OK
        q = np.where(active[:, None], np.nan_to_num(seed.q_deg) * DEG, 0.0)
        iters = np.zeros(N, dtype=int)
        res_mm = np.full(N, np.nan)
        res_rad = np.full(N, np.nan)
        idx = np.flatnonzero(active)
        prev = np.full(N, np.inf)
        chain = self.deformed_chain
        for it in range(opt.max_iterations + 1):
            if idx.size == 0:
                break
            Rc, pc, J = chain.fk_jacobian(q[idx])
            e_p = p[idx] - pc
            e_w = rotation_log(R[idx] @ np.swapaxes(Rc, 1, 2))
            n_p = np.linalg.norm(e_p, axis=1)
            n_w = np.linalg.norm(e_w, axis=1)
            res_mm[idx] = n_p
            res_rad[idx] = n_w
            # Stop below the acceptance tolerance, or once within it when a
            # step no longer halves the error (float64 round-off reached).
            within = (n_p <= opt.tol_mm) & (n_w <= opt.tol_rad)
            stalled = within & (n_p + opt.tol_mm * 1e-3 * n_w > 0.5 * prev[idx])
            done = ((n_p <= opt.tol_mm * 0.1) & (n_w <= opt.tol_rad * 0.1)) | stalled
            prev[idx] = n_p + opt.tol_mm * 1e-3 * n_w
            if it == opt.max_iterations:
                break
            idx_next = idx[~done]
            if idx_next.size == 0:
                break
            e = np.concatenate([e_p, e_w], axis=1)[~done]
            Jn = J[~done]
            # Damped least squares: identical to Newton where J is well
            # conditioned (the damping is 1e-12 of typical singular values
            # squared), bounded steps where it is singular (J5 = 0 exactly).
            Jt = np.swapaxes(Jn, 1, 2)
            dq = np.linalg.solve(Jt @ Jn + _DAMPING * np.eye(Jn.shape[2]),
                                 (Jt @ e[..., None]))[..., 0]
            q[idx_next] += dq
            iters[idx_next] += 1
            idx = idx_next
        q_ref = np.nan_to_num(seed.q_deg) * DEG
        if self.joint_map is not None:
            q_ref = np.where(active[:, None], self.joint_map.apply(q_ref), 0.0)
        tcp = np.zeros((N, 3)) if tcp is None else np.asarray(tcp, float).reshape(-1, 3)
        leftover = self._wrist_fallback(R, p, q, q_ref, seed, active, res_mm, res_rad, tcp)
        q_act = q
        if self.joint_map is not None:
            q = np.where(active[:, None], self.joint_map.invert(q_act), 0.0)
        qd = q / DEG
        detail = seed.detail.copy()
        djoint = seed.detail_joint.copy()
        conv = active & (res_mm <= opt.tol_mm) & ((res_rad <= opt.tol_rad) | leftover)
        nc = active & ~conv
        status[nc] = Status.NOT_CONVERGED
        detail[nc] = res_mm[nc]
        change = np.where(active[:, None], qd - np.nan_to_num(seed.q_deg), np.nan)
        big = np.nan_to_num(np.abs(change))
        jmax = np.argmax(big, axis=1)
        jump = (status == Status.OK) & (big[np.arange(N), jmax] > opt.max_joint_change_deg)
        status[jump] = Status.JOINT_JUMP
        detail[jump] = big[np.arange(N), jmax][jump]
        djoint[jump] = jmax[jump]
        # Configuration of the result, from the deformed robot's own wrist centre.
        _, ps = chain.joint_frames(q_act)
        conf = confdata(q, ps[:, 4], self.geometry.phi)
        warnings = seed.warnings | self._singularity_warnings(q, ps[:, 4])
        warnings |= np.where(leftover, int(Warn.ORIENTATION_LEFT), 0)
        flipped = (conf[:, 3] ^ seed.conf[:, 3]) & 7
        at_singularity = (
            ((flipped & 1) == 0) | ((warnings & Warn.WRIST_SINGULAR) > 0)) & (
            ((flipped & 2) == 0) | ((warnings & Warn.ELBOW_SINGULAR) > 0)) & (
            ((flipped & 4) == 0) | ((warnings & Warn.SHOULDER_SINGULAR) > 0))
        ok = status == Status.OK
        branch = ok & (flipped != 0) & ~at_singularity
        status[branch] = Status.BRANCH_CHANGED
        warnings |= np.where(ok & (flipped != 0) & at_singularity,
                             int(Warn.CFX_AT_SINGULARITY), 0)
        quad = self._outside_quadrants(qd, seed.conf)
        warnings |= np.where(ok & quad, int(Warn.QUADRANT_CHANGED), 0)
        beyond = self._mark_limits(qd, status, detail, djoint)
        q_out = np.where(active[:, None], qd, np.nan)
        return IKBatch(q_out, status, detail, djoint, conf, res_mm, res_rad, iters,
                       warnings, change, np.full(N, float(opt.max_joint_change_deg)), beyond)

    def _wrist_fallback(self, R, p, q, q_ref, seed: IKBatch, active, res_mm, res_rad, tcp):
        """Rows near J5 = 0 that the full solve left unconverged or moved
        J4/J6 beyond the bound: solve again with the TCP's position exact
        and the orientation as close as the joint-change bound allows (in
        place on q, res_mm, res_rad). Returns the mask of rows solved this
        way.

        At J5 = 0 the axes of J4 and J6 coincide: one direction of rotation
        is reached only by swinging J4 and J6 far. Its share of the thermal
        tilt (~0.01 deg) is left over rather than bought with that swing.
        """
        opt = self.options
        leftover = np.zeros(len(q), dtype=bool)
        near = active & (np.abs(wrap_pi(np.nan_to_num(seed.q_deg[:, 4]) * DEG))
                         < opt.wrist_fallback_deg * DEG)
        if not near.any():
            return leftover
        change = np.abs(q - q_ref).max(axis=1) / DEG
        need = near & ((res_mm > opt.tol_mm) | (res_rad > opt.tol_rad)
                       | (change > opt.max_joint_change_deg))
        bound = 0.95 * opt.max_joint_change_deg * DEG
        rows = np.flatnonzero(need)
        if not rows.size:
            return leftover
        got, q_got, mm_got, rad_got = self._position_exact(R[rows], p[rows], q_ref[rows], bound,
                                                           tcp[rows])
        # Holding the TCP exact, the tilt J4/J6 cannot follow may grow a
        # little over the uncompensated one; beyond the cap it is not a
        # thermal leftover but a wrong target: not taken.
        take = got & (rad_got <= opt.max_leftover_deg * DEG)
        at = rows[take]
        q[at], res_mm[at], res_rad[at] = q_got[take], mm_got[take], rad_got[take]
        leftover[at] = res_rad[at] > opt.tol_rad
        return leftover

    # The orientation's weight against the joints' change, stiff to soft.
    MUS = (1e2, 1.0, 1e-2, 1e-4, 1e-6, 1e-8)

    def _position_exact(self, R, p, q_ref, bound, tcp):
        """Per row: min |orientation error|^2 + mu |q - q_ref|^2 subject to
        the exact TCP position (tcp in the flange frame; Gauss-Newton on the
        KKT system, each row until its step is below 1e-13 rad, at most 40
        steps), for mu in decades from stiff to soft (MUS) while the
        joints stay within `bound` (rad) of q_ref. Of those, the stiffest
        whose orientation error is within 1e-4 deg of the best: a J4/J6
        swing that buys less than that is not made. Every row at once (a
        CAM program near J5 = 0 has thousands: ~8 ms each one by one).
        Returns (found (m,), q (m, n), residual mm (m,), residual rad (m,));
        a row not found keeps q_ref and NaN residuals."""
        opt = self.options
        chain = self.deformed_chain
        m, n = q_ref.shape
        want = p + np.einsum("mij,mj->mi", R, tcp)
        qs = np.empty((len(self.MUS), m, n))
        mm = np.full((len(self.MUS), m), np.nan)
        rad = np.full((len(self.MUS), m), np.inf)
        found = np.zeros((len(self.MUS), m), bool)
        alive = np.ones(m, bool)
        eye = np.eye(n)
        for k, mu in enumerate(self.MUS):
            rows = np.flatnonzero(alive)
            if not rows.size:
                break
            q = q_ref[rows].copy()
            go = np.arange(len(rows))
            for _ in range(40):
                if not go.size:
                    break
                at = rows[go]
                Rc, pc, J = chain.fk_jacobian(q[go])
                arm = np.einsum("mij,mj->mi", Rc, tcp[at])
                e_p = want[at] - (pc + arm)
                e_w = rotation_log(R[at] @ np.swapaxes(Rc, 1, 2))
                # The TCP moves with the flange and turns about it.
                Jw = J[:, 3:]
                Jp = J[:, :3] - np.cross(arm[:, :, None], Jw, axis=1)
                Jwt = np.swapaxes(Jw, 1, 2)
                K = np.zeros((len(go), n + 3, n + 3))
                K[:, :n, :n] = Jwt @ Jw + mu * eye
                K[:, :n, n:] = np.swapaxes(Jp, 1, 2)
                K[:, n:, :n] = Jp
                rhs = np.concatenate([np.einsum("mij,mj->mi", Jwt, e_w)
                                      - mu * (q[go] - q_ref[at]), e_p], axis=1)
                dq = np.linalg.solve(K, rhs[..., None])[:, :n, 0]
                q[go] += dq
                go = go[np.abs(dq).max(axis=1) >= 1e-13]
            Rc, pc = chain.fk(q)
            e_p = np.linalg.norm(want[rows] - (pc + np.einsum("mij,mj->mi", Rc, tcp[rows])),
                                 axis=1)
            e_w = np.linalg.norm(rotation_log(R[rows] @ np.swapaxes(Rc, 1, 2)), axis=1)
            # A row whose joints leave the bound tries no softer mu.
            out = np.abs(q - q_ref[rows]).max(axis=1) > bound
            alive[rows[out]] = False
            ok = ~out & (e_p <= opt.tol_mm)
            at = rows[ok]
            qs[k, at], mm[k, at], rad[k, at], found[k, at] = q[ok], e_p[ok], e_w[ok], True
        got = found.any(axis=0)
        best = np.where(found, rad, np.inf).min(axis=0)
        # (The first mu, stiff to soft, within 1e-4 deg of the best.)
        pick = np.argmax(found & (rad <= best + 1e-4 * DEG), axis=0)
        cols = np.arange(m)
        q_out = np.where(got[:, None], qs[pick, cols], q_ref)
        return (got, q_out, np.where(got, mm[pick, cols], np.nan),
                np.where(got, rad[pick, cols], np.nan))

    @_chunked
    def candidates(self, R: np.ndarray, p: np.ndarray) -> np.ndarray:
        """Every closed-form solution of the flange poses (N, 8, 6), degrees
        in (-180, 180], NaN on a branch that cannot reach. For the rule the
        controller follows without configuration supervision (closest)."""
        br = solve_branches(self.geometry, np.asarray(R, float).reshape(-1, 3, 3),
                            np.asarray(p, float).reshape(-1, 3))
        return br.q / DEG

    def _turned(self, c: np.ndarray, prev: np.ndarray) -> np.ndarray:
        """Candidates c (..., 6) with J1, J4, J6 turned by whole turns
        towards prev (then back inside the limits if that left them), and
        J2, J3, J5 shifted into their limits where a turn does that."""
        c = c.copy()
        lo, hi = self.lower, self.upper
        for col in (0, 3, 5):
            a = c[..., col] + 360.0 * np.round((prev[..., col] - c[..., col]) / 360.0)
            a = np.where(a > hi[col], a - 360.0, a)
            a = np.where(a < lo[col], a + 360.0, a)
            c[..., col] = a
        return self._uncounted_turns(c)

    def _uncounted_turns(self, c: np.ndarray) -> np.ndarray:
        """Axes without a turn counter in confdata (J2, J3, J5) take the
        turn that lies within their limits (J3 of the IRB 140 spans
        -230..+50): c (..., 6) deg, in place and returned."""
        lo, hi = self.lower, self.upper
        for col in (1, 2, 4):
            for shift in (-360.0, 360.0):
                moved = c[..., col] + shift
                out = (c[..., col] < lo[col]) | (c[..., col] > hi[col])
                c[..., col] = np.where(out & (moved >= lo[col]) & (moved <= hi[col]), moved,
                                       c[..., col])
        return c

    @_chunked
    def closest(self, cands_deg: np.ndarray, prev_deg: np.ndarray,
                with_branch: bool = False):
        """Per row, the solution nearest (Euclidean, degrees) to prev_deg
        (M, 6) among cands_deg (M, 8, 6) within the joint limits: J1, J4
        and J6 turned by whole turns towards the previous angles, J2, J3, J5
        within their limits. NaN rows where no candidate is within limits.
        At an exact wrist singularity (J5 = 0) only J4 + J6 is defined; it is
        split evenly around the previous J4, J6 (the nearest split).
        with_branch: also the index of the branch chosen (-1: none)."""
        c = np.array(cands_deg, float, copy=True)
        prev = np.asarray(prev_deg, float)[:, None, :]
        singular = np.abs(c[:, :, 4]) < 1e-7
        if singular.any():
            s = c[:, :, 3] + c[:, :, 5]
            target = prev[:, :, 3] + prev[:, :, 5]
            s = s + 360.0 * np.round((target - s) / 360.0)
            half = (s - target) / 2.0
            c[:, :, 3] = np.where(singular, prev[:, :, 3] + half, c[:, :, 3])
            c[:, :, 5] = np.where(singular, prev[:, :, 5] + half, c[:, :, 5])
        c = self._turned(c, prev)
        lo, hi = self.lower, self.upper
        inside = np.all((c >= lo - 1e-9) & (c <= hi + 1e-9), axis=2) & ~np.isnan(c).any(axis=2)
        dist = np.where(inside, np.linalg.norm(c - prev, axis=2), np.inf)
        best = np.argmin(dist, axis=1)
        rows = np.arange(len(c))
        out = c[rows, best]
        none = ~np.isfinite(dist[rows, best])
        out[none] = np.nan
        if with_branch:
            return out, np.where(none, -1, best)
        return out

    def follow(self, branch_deg: np.ndarray, start_deg: np.ndarray) -> np.ndarray:
        """The joints of a path that stays on one branch: each row of
        branch_deg (M, 6) turned towards the row before it (the first
        towards start_deg), in one vectorized pass. Equal to calling
        closest() row by row wherever that keeps the branch and no limit
        turns a joint back (the turn counts come from an unwrap of the
        sequence; the angles are then computed as closest() does)."""
        c = np.asarray(branch_deg, float)
        seq = np.vstack([np.asarray(start_deg, float)[None], c])
        prev = np.empty_like(c)
        prev[:] = np.nan
        unwrapped = seq.copy()
        for col in (0, 3, 5):
            unwrapped[:, col] = np.unwrap(seq[:, col], period=360.0)
        # Row i is turned towards row i - 1 of the unwrapped sequence.
        prev = unwrapped[:-1]
        return self._turned(c, prev)

    @_chunked
    def seed_from_joints(self, q_deg: np.ndarray):
        """Nominal flange poses of joint vectors (MoveAbsJ targets) and a seed
        IKBatch for solve_deformed: the intended pose is where the ideal
        robot puts the flange with these joints."""
        q_deg = np.asarray(q_deg, float).reshape(-1, 6)
        N = len(q_deg)
        q = q_deg * DEG
        (R, p), (_, ps) = self.nominal_chain.fk_and_frames(q)
        status = np.zeros(N, dtype=int)
        detail = np.zeros(N)
        djoint = np.full(N, -1)
        beyond = self._mark_limits(q_deg, status, detail, djoint)
        seed = IKBatch(q_deg.copy(), status, detail, djoint,
                       confdata(q, ps[:, 4], self.geometry.phi), np.zeros(N), np.zeros(N),
                       np.zeros(N, dtype=int), self._singularity_warnings(q, ps[:, 4]),
                       beyond_deg=beyond)
        return R, p, seed

    def compensate(self, R: np.ndarray, p: np.ndarray, conf: np.ndarray):
        """Nominal solution on the programmed branch, then the deformed one."""
        nominal = self.solve_nominal(R, p, conf)
        return nominal, self.solve_deformed(R, p, nominal)


def solve_deformed_pinocchio(robot: RobotModel, R: np.ndarray, p: np.ndarray,
                             q0_deg, options: IKOptions = IKOptions()):
    """Per-target Newton with Pinocchio's FK and Jacobians (the reference
    implementation for the batch kernel, and the benchmark's baseline).
    Returns (q_deg, residual_mm, residual_rad, iterations)."""
    import pinocchio as pin
    model = robot.model
    data = model.createData()
    fid = robot.flange_frame
    q = np.asarray(q0_deg, float) * DEG
    target = pin.SE3(np.asarray(R, float), np.asarray(p, float))
    it = 0
    for it in range(options.max_iterations + 1):
        pin.framesForwardKinematics(model, data, q)
        M = data.oMf[fid]
        e_p = target.translation - M.translation
        e_w = pin.log3(target.rotation @ M.rotation.T)
        if (np.linalg.norm(e_p) <= options.tol_mm * 0.1
                and np.linalg.norm(e_w) <= options.tol_rad * 0.1) or it == options.max_iterations:
            break
        J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
        q = q + np.linalg.solve(J, np.concatenate([e_p, e_w]))
    return q / DEG, float(np.linalg.norm(e_p)), float(np.linalg.norm(e_w)), it

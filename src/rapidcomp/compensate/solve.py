"""Stage 2 of `fix` and `check`: the joints of every resolved use.

First the nominal solution, the one the ideal controller takes for the
target as written, by the rule the controller follows there:

* configuration supervision on (ConfJ/ConfL \\On): the branch and quadrants
  of the target's confdata;
* supervision off: the solution closest to the joints of the move before
  (the previous move's solution); for the first move after an unknown
  position, its confdata where that is a valid solution, else the solution
  closest to the program's first jointtarget;
* supervision not known statically: both rules must agree, or the use is
  not compensated (the controller's choice cannot be known);
* MoveAbsJ: the joints as written.

Then the deformed robot's solution, Newton from the nominal one (no branch
or turn can change on the way). Solutions are chosen in the order the
controller reaches the moves, because each may depend on the one before.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..kinematics.conf import confdata
from ..kinematics.frames import DEG
from ..kinematics.ik import IKBatch, Solver, Status
from .flow import OFF, ON
from .plan import Plan, line_ranges
from .targets import TargetUse

# Two solutions closer than this (deg, Euclidean) are the same solution.
SAME_DEG = 1e-6


@dataclass(frozen=True, eq=False)
class Solved:
    """Row i of every array belongs to uses[i]."""

    uses: list                 # TargetUse
    row: dict                  # use key -> row
    R: np.ndarray              # intended base_M_flange
    p: np.ndarray
    nominal: IKBatch           # the ideal controller's joints (the uncompensated program)
    deformed: IKBatch          # the compensated joints
    err_p: np.ndarray          # uncompensated error on the warm robot, mm
    err_r: np.ndarray          # ... rad
    flange_R: np.ndarray       # nominal FK of the compensated joints
    flange_p: np.ndarray
    conf_after: np.ndarray     # confdata of the compensated joints
    picks: list                # Pick: how the nominal solution was chosen, or why none
    displacement_um_per_mm: np.ndarray  # extra error per mm of program displacement
    start: np.ndarray | None = None     # --start joints, deg

    def ok(self, i: int) -> bool:
        return self.picks[i].failure is None and bool(self.deformed.success[i])

    def reason(self, i: int) -> str | None:
        if self.picks[i].failure is not None:
            return self.picks[i].failure
        return self.deformed.reason(i)


def _flag(u: TargetUse) -> str:
    return "ConfJ" if u.motion.spec.interpolation == "joint" else "ConfL"


def _conf_text(c) -> str:
    return "[" + ",".join(str(int(x)) for x in c) + "]"


class Pick(NamedTuple):
    """A nominal solution and how it was chosen. kind: "joint" (as
    written), "conf" (by confdata), "closest" (closest to the joints of row
    `pred`); failure: why there is none."""

    q: np.ndarray | None
    rule: str | None
    failure: str | None
    kind: str | None = None
    pred: int | None = None   # "closest": the row it is closest to (None: --start)
    # The controller might choose otherwise (supervision not known): the
    # move stays a robtarget move, so its configuration stays the
    # controller's choice, and the report says what was assumed.
    caution: str | None = None


def _fail(why: str) -> Pick:
    return Pick(None, None, why)


class _Chooser:
    """The nominal solution of each robtarget use, in flow order."""

    def __init__(self, plan: Plan, solver: Solver, uses: list[TargetUse], rows: dict,
                 start: np.ndarray | None = None):
        self.start = start
        self.plan = plan
        self.solver = solver
        self.uses = uses
        self.rows = rows
        rob = [i for i, u in enumerate(uses) if u.kind == "robtarget"]
        R = np.array([uses[i].R for i in rob]).reshape(-1, 3, 3)
        p = np.array([uses[i].p for i in rob]).reshape(-1, 3)
        conf = np.array([uses[i].conf for i in rob], dtype=int).reshape(-1, 4)
        self.by_conf = solver.solve_nominal(R, p, conf) if rob else None
        self.cands = solver.candidates(R, p) if rob else None
        self.rob_row = {i: k for k, i in enumerate(rob)}
        n = len(uses)
        self.q = np.full((n, 6), np.nan)
        self.picks: list = [None] * n
        for i, u in enumerate(uses):
            if u.kind == "jointtarget":
                self.q[i] = u.joints_deg
                self.picks[i] = Pick(self.q[i], "as written (MoveAbsJ)", None, "joint")
        first = next((u for u in plan.order() if u.kind == "jointtarget" and u.reason is None),
                     None)
        self.first_joint = self.rows[first.key] if first is not None else None
        self.order = [self.rows[u.key] for u in plan.order() if u.key in self.rows]
        self._speculate()

    # ------------------------------------------------------------ speed
    def _speculate(self) -> None:
        """A guess of every row's joints and, in one batch, the solution of
        each row closest to its guessed predecessor. The choice in flow
        order (run) takes the batch result wherever the predecessor's real
        joints equal the guess, and computes it afresh elsewhere: the guess
        changes the speed, never the result. Guess: the confdata's solution
        where it is valid, MoveAbsJ joints as written, and along a chain of
        moves without supervision the branch of the chain's first move,
        followed turn by turn (Solver.follow)."""
        n = len(self.uses)
        self.spec = np.full((n, 6), np.nan)
        self.pred1 = np.full(n, -1)
        self.off_spec = np.full((n, 6), np.nan)
        if not self.rob_row:
            return
        for i, u in enumerate(self.uses):
            if u.kind == "jointtarget":
                self.spec[i] = self.q[i]
        ok = self.by_conf.success
        rob = np.array(list(self.rob_row))
        self.spec[rob[ok]] = self.by_conf.q_deg[ok]
        need = []
        for i in self.order:
            u = self.uses[i]
            if u.kind != "robtarget":
                continue
            st = self.plan.state(u)
            if OFF not in st.supervision(u.motion.spec.interpolation):
                continue
            if st.last is not None and len(st.last) == 1:
                (pk,) = st.last
                self.pred1[i] = self.rows.get(pk, -1)
            need.append(i)
        # Chains: consecutive rows each following the one before.
        run: list[int] = []
        for i in need + [-1]:
            j = self.pred1[i] if i >= 0 else -2
            if i >= 0 and np.isnan(self.spec[i]).any() and run and j == run[-1]:
                run.append(i)
                continue
            self._follow(run)
            run = [i] if i >= 0 and np.isnan(self.spec[i]).any() and j >= 0 else []
        sel = [i for i in need if self.pred1[i] >= 0 and not np.isnan(self.spec[self.pred1[i]]).any()]
        if sel:
            ks = [self.rob_row[i] for i in sel]
            self.off_spec[sel] = self.solver.closest(self.cands[ks], self.spec[self.pred1[sel]])

    def _follow(self, run: list[int]) -> None:
        if not run or np.isnan(self.spec[self.pred1[run[0]]]).any():
            return
        k0 = self.rob_row[run[0]]
        first, branch = self.solver.closest(self.cands[k0][None],
                                            self.spec[self.pred1[run[0]]][None], with_branch=True)
        if branch[0] < 0:
            return
        self.spec[run[0]] = first[0]
        if len(run) > 1:
            ks = [self.rob_row[i] for i in run[1:]]
            self.spec[run[1:]] = self.solver.follow(self.cands[ks, branch[0]], first[0])

    # ------------------------------------------------------------ rules
    def _by_conf(self, i: int, rule: str) -> Pick:
        k = self.rob_row[i]
        b = self.by_conf
        if b.success[k]:
            return Pick(b.q_deg[k], rule, None, "conf")
        return Pick(None, rule, f"nominal: {b.reason(k)}")

    def _closest_to(self, i: int, j: int, rule: str) -> Pick:
        if self.pred1[i] == j and np.array_equal(self.q[j], self.spec[j]):
            q = self.off_spec[i]      # computed in the batch from these very joints
        else:
            k = self.rob_row[i]
            q = self.solver.closest(self.cands[k][None], self.q[j][None])[0]
        if np.isnan(q).any():
            return _fail("nominal: no solution within the joint limits")
        return Pick(q, rule, None, "closest", j)

    def _unknown_start(self, i: int, flag: str) -> Pick:
        """The first move after an unknown position, supervision off."""
        u = self.uses[i]
        c = _conf_text(u.conf)
        pick = self._by_conf(i, f"confdata; position before unknown ({flag}\\Off)")
        if pick.q is not None:
            return pick
        if self.start is not None:
            k = self.rob_row[i]
            q = self.solver.closest(self.cands[k][None], self.start[None])[0]
            if np.isnan(q).any():
                return _fail("nominal: no solution within the joint limits")
            return Pick(q, f"closest to --start: position before unknown, confdata names no "
                           f"solution ({flag}\\Off)", None, "closest", None)
        j = self.first_joint
        if j is None:
            return _fail(f"{flag}\\Off and the position before it is unknown: its confdata {c} "
                         f"names no solution ({pick.failure}) and the program has no "
                         "jointtarget to start from (say where the robot starts with --start)")
        ju = self.uses[j]
        return self._closest_to(i, j, f"closest to {ju.label} (line {ju.line}), the first "
                                      "jointtarget: position before unknown, confdata names no "
                                      f"solution ({flag}\\Off)")

    def _off(self, i: int, preds, flag: str) -> Pick:
        """The pick with supervision off."""
        if preds is None:
            return self._unknown_start(i, flag)
        picks = []
        unknown = False
        for pk in sorted(preds):
            j = self.rows.get(pk)
            if j is None or np.isnan(self.q[j]).any():
                unknown = True        # not resolved, failed, or not chosen yet
                continue
            picks.append(self._closest_to(i, j, ""))
        if unknown:
            start = self._unknown_start(i, flag)
            if not picks:
                return start
            picks.append(start)
        fails = [p for p in picks if p.q is None]
        if fails:
            return fails[0]
        lines = sorted({self.uses[p.pred].line for p in picks if p.kind == "closest"})
        if any(np.linalg.norm(p.q - picks[0].q) > SAME_DEG for p in picks[1:]):
            return _fail(f"{flag}\\Off: the controller takes the solution closest to where the "
                         "robot is, and that depends on which move ran before it (lines "
                         f"{line_ranges(lines)})")
        where = f"line {line_ranges(lines)}" + (" or an unknown start" if unknown else "")
        return picks[0]._replace(rule=f"closest to {where} ({flag}\\Off)")

    def choose(self, i: int) -> Pick:
        u = self.uses[i]
        flag = _flag(u)
        st = self.plan.state(u)
        sup = st.supervision(u.motion.spec.interpolation)
        c = _conf_text(u.conf)
        if OFF not in sup:
            return self._by_conf(i, f"confdata ({flag}\\On)")
        off = self._off(i, st.last, flag)
        if ON not in sup:
            return off
        on = self._by_conf(i, f"confdata ({flag} on or off: the same solution)")
        if on.q is not None:
            if off.q is not None and np.linalg.norm(on.q - off.q) <= SAME_DEG:
                return on
            other = ("" if off.q is None else " (J" + ", J".join(
                f"{j + 1} {off.q[j]:.1f}" for j in range(6)) + ")")
            return on._replace(
                rule=f"confdata ({flag} may be on or off here)",
                caution=(f"{flag} may be on or off here (not known statically): compensated on "
                         "the solution of the programmed confdata and kept a robtarget move; if "
                         f"{flag} is off when it runs, the controller takes the solution closest "
                         f"to the previous position{other}, for which this correction is not "
                         "made"))
        if off.q is not None:
            return off._replace(rule=f"{off.rule}; its confdata names no solution, so {flag} "
                                     "is off here")
        return _fail(f"{flag} may be on or off here (not known statically): on, the confdata "
                     f"{c} names no solution ({on.failure}); off, {off.failure}")

    def run(self) -> None:
        order = self.order
        done = set()
        pending = []
        succ: dict[int, list[int]] = {}
        for i in order:
            u = self.uses[i]
            if u.kind != "robtarget":
                done.add(i)
                continue
            preds = self.plan.state(u).last or ()
            pred_rows = [self.rows[k] for k in preds if k in self.rows]
            for j in pred_rows:
                succ.setdefault(j, []).append(i)
            if any(j not in done for j in pred_rows):
                pending.append(i)
            self._set(i)
            done.add(i)
        # Loops: a move whose predecessor comes later in the flow (the last
        # move of a loop body before its first) is chosen again once that
        # one is known, and the change propagates.
        updates: dict[int, int] = {}
        work = list(dict.fromkeys(pending))
        while work:
            i = work.pop(0)
            before = self.q[i].copy()
            self._set(i)
            if not np.allclose(before, self.q[i], atol=SAME_DEG, equal_nan=True):
                updates[i] = updates.get(i, 0) + 1
                if updates[i] > 3:
                    self.q[i] = np.nan
                    self.picks[i] = _fail("the closest solution does not settle around the "
                                          "loop this move is in")
                    continue
                work.extend(j for j in succ.get(i, []) if j not in work)

    def _set(self, i: int) -> None:
        pick = self.choose(i)
        self.q[i] = pick.q if pick.q is not None else np.nan
        self.picks[i] = pick


def solve(plan: Plan, solver: Solver, start=None) -> Solved:
    """start: the joints (deg) the robot is at where the program leaves its
    position unknown (--start), for moves without supervision whose
    confdata names no solution; default: the program's first jointtarget."""
    uses = [u for u in plan.uses if u.reason is None]
    rows = {u.key: i for i, u in enumerate(uses)}
    n = len(uses)
    start = None if start is None else np.asarray(start, float)
    chooser = _Chooser(plan, solver, uses, rows, start)
    chooser.run()
    q_nom = chooser.q
    picks = chooser.picks
    R = np.empty((n, 3, 3))
    p = np.empty((n, 3))
    Rj, pj, seed = solver.seed_from_joints(np.nan_to_num(q_nom))
    for i, u in enumerate(uses):
        if u.kind == "robtarget":
            R[i], p[i] = u.R, u.p
        else:
            R[i], p[i] = Rj[i], pj[i]
    # Joint limits of the chosen joints (MoveAbsJ targets) are failures too.
    status = seed.status.copy()
    for i in range(n):
        if picks[i].failure is not None:
            status[i] = Status.NO_CONFIGURATION
        elif status[i] != Status.OK:
            picks[i] = _fail(f"nominal: {seed.reason(i)}")
    seed = IKBatch(np.where(np.isnan(q_nom), np.nan, seed.q_deg), status, seed.detail,
                   seed.detail_joint, seed.conf, seed.residual_mm, seed.residual_rad,
                   seed.iterations, seed.warnings)
    deformed = solver.solve_deformed(R, p, seed)
    err_p, err_r = solver.deformed_pose_error(np.nan_to_num(q_nom) * DEG, R, p)
    qc = np.nan_to_num(deformed.q_deg) * DEG
    Rn, pn = solver.nominal_chain.fk(qc)
    _, frames = solver.nominal_chain.joint_frames(qc)
    conf_after = confdata(qc, frames[:, 4], solver.geometry.phi)
    disp = np.full(n, np.nan)
    moved = [i for i, u in enumerate(uses) if u.kind == "robtarget" and plan.may_be_displaced(u)
             and picks[i].failure is None and deformed.success[i]]
    if moved:
        disp[moved] = _displacement_sensitivity(solver, deformed.q_deg[moved])
    return Solved(uses, rows, R, p, seed, deformed, err_p, err_r, Rn, pn, conf_after, picks,
                  disp, start)


def _displacement_sensitivity(solver: Solver, q_deg: np.ndarray) -> np.ndarray:
    """um of TCP error per mm of program displacement, per row.

    The written correction delta(x) = FK_nominal(q_comp(x)) - x was computed
    for the undisplaced pose x; displaced by d the robot needs delta(x + d).
    d delta / dx = J_nominal(q_comp) . J_deformed(q_comp)^-1 - I, whose
    translation block's largest singular value bounds the extra error per mm.
    """
    q = np.asarray(q_deg, float) * DEG
    _, _, Jn = solver.nominal_chain.fk_jacobian(q)
    qa = solver.joint_map.apply(q) if solver.joint_map is not None else q
    _, _, Jd = solver.deformed_chain.fk_jacobian(qa)
    M = Jn @ np.linalg.inv(Jd) - np.eye(6)
    return np.linalg.norm(M[:, :3, :3], ord=2, axis=(1, 2)) * 1000.0

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

import functools
import itertools
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .. import side
from ..kinematics.conf import confdata
from ..kinematics.frames import DEG
from ..kinematics.ik import NO_SOLUTION_IN_LIMITS, IKBatch, Solver, Status, Warn, reusing
from .flow import AFTER, OFF, ON, PROGRAM_START, State
from .plan import Plan, line_ranges
from .targets import (IDENTITY_POSE, UNKNOWN_TOOL, UNKNOWN_TOOL_MEANS, TargetUse, flange_stack,
                      stacked_poses)

# Two solutions closer than this (deg, Euclidean) are the same solution.
SAME_DEG = 1e-6
# How far the choice's batches follow chains of second solutions (each step
# one batch for every chain); past it the choice computes them one by one.
ALT_STEPS = 256


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
    picks: "Picks"             # Pick: how the nominal solution was chosen, or why none
    displacement_um_per_mm: np.ndarray  # extra error per mm of program displacement
    start: np.ndarray | None = None     # --start joints, deg

    def ok(self, i: int) -> bool:
        return self.picks.failure[i] is None and bool(self.deformed.success[i])

    def oks(self) -> list[bool]:
        """ok(i) of every row, as a list (1e5 rows asked at once)."""
        return [f is None and s for f, s in zip(self.picks.failure,
                                                self.deformed.success.tolist())]

    def reason(self, i: int) -> str | None:
        failure = self.picks.failure[i]
        return failure if failure is not None else self.deformed.reason(i)


def _in_text_order(keys) -> list:
    """The moves that may run before one (a set) in text order, the
    program start last: a set of keys holding strings iterates in an order
    that changes with every Python process (hash randomisation), and the
    first solution found names the rule a report shows."""
    if len(keys) < 2:
        return list(keys)
    return sorted(keys, key=lambda k: (0, k) if len(k) == 4 else (1, (0, 0, k[0], ())))


# The quick cases' rule where supervision may be on or off, by ConfJ/ConfL.
_SAME = {flag: f"confdata ({flag} on or off: the same solution)" for flag in ("ConfJ", "ConfL")}


def _flag(u: TargetUse) -> str:
    return "ConfJ" if u.motion.spec.interpolation == "joint" else "ConfL"


def _conf_text(c) -> str:
    return "[" + ",".join(str(int(x)) for x in c) + "]"


class Pick(NamedTuple):
    """A nominal solution and how it was chosen. kind: "joint" (as
    written), "conf" (by confdata), "closest" (closest to the joints
    `prev`); failure: why there is none."""

    q: np.ndarray | None
    rule: str | None
    failure: str | None
    kind: str | None = None
    prev: np.ndarray | None = None   # "closest": the joints it is closest to
    line: int | None = None          # "closest": the line of that move (None: --start)
    # The controller might choose otherwise than assumed (supervision or
    # position not known): the move stays a robtarget move, so its
    # configuration stays the controller's choice, and the report says what
    # was assumed.
    caution: str | None = None


class Picks:
    """Every row's Pick as columns, past the choice (a CAM program's 1e5: no
    tuple and joint array each, ~20 MB to the report); picks[i] makes row
    i's Pick when asked (its joints: the row of the nominal solutions as
    chosen)."""

    def __init__(self, picks: list, q: np.ndarray):
        self.q = q
        self.rule = [p.rule for p in picks]
        self.failure = [p.failure for p in picks]
        self.kind = [p.kind for p in picks]
        self.caution = [p.caution for p in picks]
        # ("closest": the joints and the line of the move it is closest to.)
        self.closest = {i: (p.prev, p.line) for i, p in enumerate(picks)
                        if p.prev is not None or p.line is not None}

    def __len__(self) -> int:
        return len(self.rule)

    def __getitem__(self, i: int) -> Pick:
        failure = self.failure[i]
        prev, line = self.closest.get(i, (None, None))
        return _pick((None if failure is not None else self.q[i], self.rule[i], failure,
                      self.kind[i], prev, line, self.caution[i]))


# (A Pick as its class makes it, every field given: run's quick cases make
# one or two for each of a CAM program's 1e5 moves.)
_pick = functools.partial(tuple.__new__, Pick)


def _follows(line: int, itself: bool) -> str:
    """The caution of a move whose solution follows one assumed (line: the
    move before it; itself: that move is this one, run before, as a loop or
    main runs again)."""
    before = "itself (its run before)" if itself else f"line {line}"
    return f"follows {before}, whose configuration is assumed: kept a robtarget move"


def _fail(why: str) -> Pick:
    return Pick(None, None, why)


# The squares of SAME_DEG 0.1 % below and above: a sum of squares beyond
# these decides as np.linalg.norm would (their rounding differs by ~1e-15).
_SAME_SQ_LO, _SAME_SQ_HI = (0.999 * SAME_DEG) ** 2, (1.001 * SAME_DEG) ** 2


def same_joints(a: np.ndarray, b: np.ndarray) -> bool:
    """Two solutions are the same one: np.linalg.norm(a - b) <= SAME_DEG,
    its verdict (asked of 1e4 pairs of joints in a CAM program; NaN:
    False): by the differences' sum of squares in
    Python where that is 0.1 % away from the bound, else (and for NaN) by
    the norm itself."""
    sq = sum([x * x for x in (a - b).tolist()])
    if sq <= _SAME_SQ_LO:
        return True
    if sq > _SAME_SQ_HI:
        return False
    return bool(np.linalg.norm(a - b) <= SAME_DEG)


def _apart(a: np.ndarray, b: np.ndarray) -> bool:
    """np.linalg.norm(a - b) > SAME_DEG, its verdict (NaN: False), as
    same_joints decides."""
    sq = sum([x * x for x in (a - b).tolist()])
    if sq > _SAME_SQ_HI:
        return True
    if sq <= _SAME_SQ_LO:
        return False
    return bool(np.linalg.norm(a - b) > SAME_DEG)


def _has_nan(q: np.ndarray) -> bool:
    return any(x != x for x in q.tolist())


def _distinct(picks: list[Pick]) -> list[Pick]:
    """One pick per solution; a solution reached by an assumption keeps
    its caution whichever way it came first."""
    out: list[Pick] = []
    for p in picks:
        k = next((n for n, o in enumerate(out) if same_joints(p.q, o.q)), None)
        if k is None:
            out.append(p)
        elif out[k].caution is None and p.caution is not None:
            out[k] = out[k]._replace(caution=p.caution)
    return out


class _Chooser:
    """The nominal solutions of each robtarget use, in flow order.

    A use reached from different places may be reached on different
    solutions: each use has the set of solutions it can take (solutions of
    its predecessors propagate), and one representative is compensated.
    Solutions that differ only by whole turns of J1/J4/J6 need the same
    correction; the move then stays a robtarget move (the controller keeps
    each run's turn). Other differences: not compensated, unless the
    confdata decides where supervision may be on (then with a caution)."""

    # run() takes the quick cases without the general rules (tests switch
    # it off to compare).
    QUICK = True

    def __init__(self, plan: Plan, solver: Solver, uses: list[TargetUse], rows: dict,
                 start: np.ndarray | None = None):
        self.start = start
        self.plan = plan
        self.solver = solver
        self.uses = uses
        self.rows = rows
        rob = [i for i, u in enumerate(uses) if u.kind == "robtarget"]
        self.rob_row = {i: k for k, i in enumerate(rob)}
        n = len(uses)
        self.q = np.full((n, 6), np.nan)
        self.picks: list = [None] * n
        self.sols: list = [[] for _ in range(n)]
        self.chosen: set[int] = set()   # rows whose solutions are set
        self.unsettled: set[int] = set()  # rows whose closest solution does not settle
        self.taken = [0, 0, 0, 0]       # how many rows run() took by each quick case
        for i, u in enumerate(uses):
            if u.kind == "jointtarget":
                self.q[i] = u.joints_deg
                self.picks[i] = Pick(self.q[i], "as written (MoveAbsJ)", None, "joint")
                self.sols[i] = [self.picks[i]]
                self.chosen.add(i)
        order = plan.order()
        first = next((u for u in order if u.kind == "jointtarget" and u.reason is None), None)
        self.first_joint = self.rows[first.key] if first is not None else None
        self.order = [self.rows[u.key] for u in order if u.key in self.rows]
        # Each robtarget row's state before it, once (_speculate, _quick_data
        # and run ask for it: a CAM program's 1e5 times each).
        self.states: list = [None] * n
        for i in self.order:
            if uses[i].kind == "robtarget":
                self.states[i] = plan.state_held(uses[i])
        scale = (solver.joint_map.scale if solver.joint_map is not None else np.zeros(6))
        self.scaled = [j for j in (0, 3, 5) if scale[j] != 0]
        need = self._needing_guess()
        # (Taken as late as this: the plan may have handed it off.)
        self.by_conf, self.cands, *self.flange = _nominal_of(plan, solver,
                                                             [uses[i] for i in rob])
        self.tcp = tcp_of(uses)
        self._speculate(need)
        self._quick_data()
        # The deformed robot's IK guessed from the solutions run() is expected
        # to choose, made by the job's helper while this process chooses
        # (see _guess_deformed). Not where more than 1 % of the robtargets
        # run without supervision: each follows the solution its move before
        # really took, and once one is off the guess, those after it are too
        # (a CAM program under ConfL\Off: ~1e4 of 1e5 rows, in every block,
        # and the helper would solve twice).
        off = np.flatnonzero(np.array(self.quick) == 1)
        self.guessed = (_guess_ahead(solver, self._expected(off), rob, *self.flange, self.tcp)
                        if len(off) * 100 <= len(rob) else None)

    # ------------------------------------------------------------ speed
    def _expected(self, off: np.ndarray) -> np.ndarray:
        """The joints run() is expected to choose (NaN: none): the guess
        (_speculate: the confdata's solution, MoveAbsJ joints as written,
        along a chain without supervision its first move's branch), and in
        the rows `off` (supervision off: run's first quick case) the
        solution closest to the guessed joints before."""
        q = self.spec.copy()
        q[off] = self.off_spec[off]
        return q

    def _needing_guess(self) -> list[int]:
        """The rows whose predecessor's joints decide their solution
        (supervision may be off, and circle points), in flow order; and
        pred1, each row's one predecessor (-1: none or several)."""
        n = len(self.uses)
        need = []
        pred1 = [-1] * n
        for i in self.order:
            st = self.states[i]
            if st is None:                   # (a MoveAbsJ)
                continue
            u = self.uses[i]
            if OFF not in st.supervision(u.motion.spec.interpolation) and u.role != "cir":
                continue
            pk = self.plan.one_before(u, st)
            if pk is not None:
                pred1[i] = self.rows.get(pk, -1)
            need.append(i)
        self.pred1 = np.array(pred1)
        return need

    def _speculate(self, need: list[int]) -> None:
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
        self.off_spec = np.full((n, 6), np.nan)
        self.more: dict[int, list] = {}   # row -> [(previous joints, closest)]
        if not self.rob_row:
            return
        for i, u in enumerate(self.uses):
            if u.kind == "jointtarget":
                self.spec[i] = self.q[i]
        ok = self.by_conf.success
        rob = np.array(list(self.rob_row))
        self.spec[rob[ok]] = self.by_conf.q_deg[ok]
        pred1 = self.pred1.tolist()
        # Chains: consecutive rows each following the one before (rows
        # without a guess yet: _follow_run sets only rows already passed).
        unguessed = np.isnan(self.spec).any(axis=1).tolist()
        run: list[int] = []
        for i in need + [-1]:
            j = pred1[i] if i >= 0 else -2
            if i >= 0 and unguessed[i] and run and j == run[-1]:
                run.append(i)
                continue
            if run:
                self._follow_run(run)
            run = [i] if i >= 0 and unguessed[i] and j >= 0 else []
        need = np.array(need, dtype=int)
        need = need[self.pred1[need] >= 0]
        pred = self.pred1[need]
        sel = need[~np.isnan(self.spec[pred]).any(axis=1)]
        if len(sel):
            # (Rows of the robtargets in order: rob is ascending. Every one,
            # in order, as a CAM program's: the candidates as they are.)
            ks = np.searchsorted(rob, sel)
            cands = (self.cands if len(ks) == len(self.cands)
                     and np.array_equal(ks, np.arange(len(ks))) else self.cands[ks])
            self.off_spec[sel] = self.solver.closest(cands, self.spec[self.pred1[sel]])
        self._alternatives(need)

    def _quick_data(self) -> None:
        """What run's quick cases ask of every row, as Python values at once: the
        predecessor, the guess as a list (exact floats: == is array_equal),
        whether the batch's closest solution is valid, and whether it is
        within SAME_DEG of the confdata's (decided here by a sum of squares
        where that is 0.1 % away from the bound, by np.linalg.norm as the
        choice computes it elsewhere)."""
        n = len(self.uses)
        self.pred1_l = self.pred1.tolist()
        self.spec_l = self.spec.tolist()
        self.off_ok = (~np.isnan(self.off_spec).any(axis=1)).tolist()
        self.near_conf = [None] * n
        # Which of the quick cases a row is, where it does not depend on
        # the solution its predecessor took (0: neither); whether the batch's
        # closest solution is the guess itself; whether a row's solution is
        # its guess (run and _set keep it; None: not known yet).
        self.quick = [0] * n
        self.off_is_spec = (self.off_spec == self.spec).all(axis=1).tolist()
        self.spec_hit: list = [None] * n
        if not self.rob_row:
            return
        rob = np.array(list(self.rob_row))
        d = self.off_spec[rob] - self.by_conf.q_deg
        sq = (d * d).sum(axis=1)
        near = np.where(sq <= _SAME_SQ_LO, 1, np.where(sq > _SAME_SQ_HI, 0, -1))
        for i, v in zip(rob.tolist(), near.tolist()):
            self.near_conf[i] = bool(v)
        for k in np.flatnonzero(near < 0).tolist():
            self.near_conf[int(rob[k])] = bool(np.linalg.norm(d[k]) <= SAME_DEG)
        ok = self.by_conf.success.tolist()
        for i, k in self.rob_row.items():
            st = self.states[i]
            # (pred1 is a row only where one move runs before: one_before.)
            if (st is None or self.pred1_l[i] < 0 or not self.off_ok[i]
                    or self.uses[i].role == "cir"):
                continue
            sup = st.supervision(self.uses[i].motion.spec.interpolation)
            if OFF not in sup:
                continue
            if ON not in sup:
                self.quick[i] = 1
            elif ok[k]:
                self.quick[i] = 2 if self.near_conf[i] else 3

    def _alternatives(self, need: np.ndarray) -> None:
        """Where supervision may be on or off, a move whose off solution is
        another than its confdata's has both, and the move after it follows
        from each: along such a chain the second solutions, one batch per
        step of all chains at once, while they stay apart (for at most
        ALT_STEPS steps; further on the choice computes them one by one)."""
        succ: dict[int, list[int]] = {}
        for i, j in zip(need.tolist(), self.pred1[need].tolist()):
            succ.setdefault(j, []).append(i)
        spec, off = self.spec[need], self.off_spec[need]
        apart = ~np.isnan(off).any(axis=1) & ~(off == spec).all(axis=1)
        rows, vals = need[apart].tolist(), off[apart]
        for _ in range(ALT_STEPS):
            pairs = [(i, n) for n, j in enumerate(rows) for i in succ.get(j, ())]
            if not pairs:
                return
            nxt, at = (np.array(c, dtype=int) for c in zip(*pairs))
            prev = vals[at]
            got = self.solver.closest(self.cands[[self.rob_row[i] for i in nxt.tolist()]], prev)
            for i, pv, q in zip(nxt.tolist(), prev, got):
                self.more.setdefault(i, []).append((pv, q))
            apart = ~np.isnan(got).any(axis=1) & ~(got == self.spec[nxt]).all(axis=1) & ~(
                got == self.off_spec[nxt]).all(axis=1)
            rows, vals = nxt[apart].tolist(), got[apart]

    def _follow_run(self, run: list[int]) -> None:
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

    def _closest_to(self, i: int, prev: np.ndarray, line: int | None, rule: str,
                    j: int = -1) -> Pick:
        # (Equal joints as np.array_equal sees them: the same length, each
        # == its own; as lists of floats, each made anew, so a NaN is
        # never equal.)
        at = np.asarray(prev, float).tolist()
        if j >= 0 and self.pred1_l[i] == j and at == self.spec_l[j]:
            q = self.off_spec[i]      # computed in the batch from these very joints
        else:
            q = next((q for pv, q in self.more.get(i, ()) if pv.tolist() == at), None)
            if q is None:
                k = self.rob_row[i]
                q = self.solver.closest(self.cands[k][None], prev[None])[0]
        if _has_nan(q):
            # (No branch with a solution at all is out of reach, as the
            # configuration's batch says with its distance: not a matter of
            # the limits.)
            k = self.rob_row[i]
            if np.isnan(self.cands[k]).any(axis=1).all() and \
                    self.by_conf.status[k] == Status.UNREACHABLE:
                return _fail(f"nominal: {self.by_conf.reason(k)}")
            return _fail(f"nominal: {NO_SOLUTION_IN_LIMITS}")
        return Pick(q, rule, None, "closest", prev, line)

    def _unknown_start(self, i: int, flag: str, at_start: bool, why: str | None = None) -> Pick:
        """The first move after an unknown position, supervision off: at
        program start, the solution closest to --start when it is given;
        else its confdata where that names a valid solution, else the
        solution closest to the program's first jointtarget, both assumed
        (with a caution). why: why the position is not known (a move before
        it that is not compensated), None where the flow cannot follow."""
        u = self.uses[i]
        c = _conf_text(u.conf)
        # (A circle point is passed on the way from the move before, with
        # supervision on or off: what is not known is where that leaves it.)
        off = "circle point" if u.role == "cir" else f"{flag}\\Off"
        if at_start and self.start is not None:
            return self._closest_to(i, self.start, None, f"closest to --start ({off})")
        where = ("the program starts here and where the robot stands is not known (--start "
                 "J1,...,J6 says where; so does a MoveAbsJ before it)" if at_start
                 else "the robot's position before this move is not known here")
        assumed = (f"{where}: {{what}} is assumed as a stand-in (the controller passes a "
                   "circle point on the way from where the robot is, whatever its confdata); "
                   "kept a robtarget move" if u.role == "cir" else
                   f"{off} and {where}: {{what}} is assumed (the controller takes the solution "
                   "closest to where the robot is); kept a robtarget move")
        pick = self._by_conf(i, f"confdata; position before unknown ({off})")
        if pick.q is not None:
            return pick._replace(caution=assumed.format(what="the solution of its confdata"))
        j = self.first_joint
        if j is None:
            hint = (" (say where the robot starts with --start)" if at_start else
                    f" ({why})" if why else
                    " (after a call, search or error the flow cannot follow)")
            return _fail(("the position before this circle point is unknown" if u.role == "cir"
                          else f"{off} and the position before it is unknown")
                         + f": its confdata {c} "
                         f"names no solution ({pick.failure}) and the program has no "
                         f"jointtarget to start from{hint}")
        ju = self.uses[j]
        return self._closest_to(
            i, self.q[j], ju.line, f"closest to {ju.label} (line {ju.line}), the first "
            f"jointtarget: position before unknown ({off})")._replace(
            caution=assumed.format(what=f"the solution closest to {ju.label}"))

    def _unknown_after(self, key, j: int | None) -> str | None:
        """Why the position after the use `key` (row j, None: not solved)
        is not known, where it is a move of the program's."""
        if j is not None:
            return (f"the move before it, line {self.uses[j].line}, is not compensated: where "
                    "the robot is after it is not known")
        u = (self.plan.by_key or {}).get(key)
        if u is None:
            return None
        return (f"the move before it, line {u.line}, is untouched (its target is not known "
                "statically): where the robot is after it is not known")

    def _follow(self, i: int, preds, flag: str) -> tuple[list[Pick], str | None]:
        """The solutions closest to every solution of every move that may
        run before (supervision off, and every circle point). A move not
        chosen yet (later in a loop) adds nothing now: it is chosen, and
        this one again, until nothing changes."""
        picks, unknown, start, pending = [], preds is None, False, False
        why = None
        for pk in _in_text_order(preds or ()):
            if pk == PROGRAM_START:
                start = True
                continue
            j = self.rows.get(pk)
            if j is None or (j in self.chosen and not self.sols[j]):
                unknown = True        # not resolved, failed, or where an error stopped it
                if why is None and len(preds) == 1:
                    why = self._unknown_after(pk, j)
                continue
            if j not in self.chosen:
                pending = True
                continue
            for s in self.sols[j]:
                p = self._closest_to(i, s.q, self.uses[j].line, "", j)
                if p.q is None:
                    return [], p.failure
                if s.caution is not None:
                    p = p._replace(caution=_follows(self.uses[j].line, j == i))
                picks.append(p)
        if pending and not (picks or unknown or start):
            start = True              # a loop entered from nowhere else: provisional
        for at_start, flag_on in ((True, start), (False, unknown)):
            if flag_on:
                p = self._unknown_start(i, flag, at_start, why)
                if p.q is None:
                    return [], p.failure
                picks.append(p)
        return _distinct(picks), None

    def _turns_only(self, sols: list[Pick]) -> bool:
        """Solutions on one configuration, J1/J4/J6 differing by whole turns
        only (the same correction, unless the profile scales those joints)."""
        # (In Python floats: the same differences, quotients and roundings
        # as numpy's, elementwise; a NaN or infinity fails no test, as a
        # comparison with numpy's NaN does not.)
        a = sols[0].q.tolist()
        for s in sols[1:]:
            d = [x - y for x, y in zip(s.q.tolist(), a)]
            if abs(d[1]) > SAME_DEG or abs(d[2]) > SAME_DEG or abs(d[4]) > SAME_DEG:
                return False
            for j in (0, 3, 5):
                turns = d[j] / 360.0
                if math.isfinite(turns) and abs(turns - round(turns)) > SAME_DEG:
                    return False
            if any(abs(d[j]) > SAME_DEG for j in self.scaled):
                return False
        return True

    def _one(self, sols: list[Pick], rule: str, flag: str) -> tuple[list[Pick], Pick]:
        """The representative of a use's solutions (closest rule)."""
        lines = sorted({p.line for p in sols if p.line is not None})
        where = line_ranges(lines) if lines else ""
        first = sols[0]
        if len(sols) == 1:
            if first.rule:
                return sols, first
            return sols, first._replace(rule=rule.format(where=f"line {where}"))
        if self._turns_only(sols):
            turns = ", ".join("J" + str(j + 1) for j in (0, 3, 5)
                              if np.ptp([p.q[j] for p in sols]) > SAME_DEG)
            rep = first._replace(rule=rule.format(where=f"lines {where}"), caution=(
                f"reached with {turns} whole turns apart in different runs (after lines "
                f"{where}): kept a robtarget move so the controller keeps each run's turn"))
            return sols, rep
        # Not compensated; its solutions still tell the moves after it where
        # the robot may be. (A circle point's solution is the closest one
        # whatever the supervision: the move before it may have left the
        # robot in more than one place.)
        what = ("the circle point is passed on the solution closest to where the robot is"
                if rule.startswith("circle point") else
                f"{flag}\\Off: the controller takes the solution closest to where the robot is")
        return sols, _fail(f"{what}, and that depends on which move ran before it, or on the "
                           f"solution it took ({'line' if len(lines) == 1 else 'lines'} "
                           f"{where})")

    def _on_or_off(self, on: Pick, off: list[Pick], flag: str) -> tuple[list[Pick], Pick]:
        """choose() where supervision may be on or off and the confdata
        names a solution (on): with the solutions supervision off gives."""
        sols = _distinct([on] + off)
        if len(sols) == 1:
            return sols, on._replace(caution=sols[0].caution)
        if self._turns_only(sols):
            return sols, on._replace(caution=(
                f"{flag} may be on or off here; the solutions it may take differ by whole "
                "turns only: kept a robtarget move so the controller keeps each run's turn"))
        other = next((p.q for p in off if _apart(p.q, on.q)), None)
        other = "" if other is None else " (J" + ", J".join(
            f"{j + 1} {x:.1f}" for j, x in enumerate(other.tolist())) + ")"
        return sols, on._replace(
            rule=f"confdata ({flag} may be on or off here)",
            caution=(f"{flag} may be on or off here (not known statically): compensated on "
                     "the solution of the programmed confdata and kept a robtarget move; if "
                     f"{flag} is off when it runs, the controller takes the solution closest "
                     f"to the previous position{other}, for which this correction is not "
                     "made"))

    def choose(self, i: int, st: State | None = None) -> tuple[list[Pick], Pick]:
        """(the solutions a use may take, the one compensated); st: the
        flow's state before the use, when the caller has it."""
        u = self.uses[i]
        flag = _flag(u)
        if st is None:
            st = self.plan.state_held(u)
        if u.role == "cir":
            # The circle point is passed on the way from the previous move:
            # its configuration follows from there, its confdata is not read.
            sols, why = self._follow(i, self.plan.last(u, st), flag)
            if not sols:
                return [], _fail(why)
            return self._one(sols, "circle point: closest to {where}", flag)
        sup = st.supervision(u.motion.spec.interpolation)
        if OFF not in sup:
            p = self._by_conf(i, f"confdata ({flag}\\On)")
            return ([p] if p.q is not None else []), p
        off, off_fail = self._follow(i, self.plan.last(u, st), flag)
        if ON not in sup:
            if not off:
                return [], _fail(off_fail)
            return self._one(off, f"closest to {{where}} ({flag}\\Off)", flag)
        on = self._by_conf(i, _SAME[flag])
        if on.q is not None:
            return self._on_or_off(on, off, flag)
        if off:
            sols, rep = self._one(off, f"closest to {{where}} ({flag}\\Off)", flag)
            if rep.q is None:
                return sols, rep
            return sols, rep._replace(rule=f"{rep.rule}; its confdata names no solution, so "
                                           f"{flag} is off here")
        return [], _fail(f"{flag} may be on or off here (not known statically): on, the "
                         f"confdata {_conf_text(u.conf)} names no solution ({on.failure}); "
                         f"off, {off_fail}")

    def run(self) -> None:
        pending = []
        edges = []                    # (predecessor, row) in the order met
        rows, chosen, states = self.rows, self.chosen, self.states
        # The quick cases (see _quick_data), taken here without choose()'s
        # general machinery, with its results (tested against it): one move
        # before, with one solution, the guess, whose closest solution here
        # came from the batch; supervision off (case 1), or on or off with
        # the confdata's solution that same one (case 2) or another (case 3).
        quick = self.quick if self.QUICK else [0] * len(self.uses)
        uses, sols, picks, spec_hit = self.uses, self.sols, self.picks, self.spec_hit
        pred1, spec_l, off_spec, off_is_spec = (self.pred1_l, self.spec_l, self.off_spec,
                                                self.off_is_spec)
        by_conf, rob_row, taken = self.by_conf, self.rob_row, self.taken
        previous = self.plan.flow.previous
        # (Their joints written into q after the loop, as _set writes them:
        # the supervision-off solution (case 1), the confdata's (2, 3).)
        off_rows: list[int] = []
        conf_rows: list[int] = []
        for i in self.order:
            st = states[i]
            if st is None:            # (a MoveAbsJ)
                continue
            last = st.last
            if last is AFTER or (last is not None and len(last) == 1):
                # (One move before: a CAM program's 1e5, each the one before
                # it in its run. Flow.one_before's, without a call per row.)
                j = rows.get(previous[uses[i].key] if last is AFTER else next(iter(last)))
                if j is not None:
                    edges.append((j, i))
                    if j not in chosen:
                        pending.append(i)
            elif last:
                pred_rows = [rows[k] for k in _in_text_order(last) if k in rows]
                edges.extend((j, i) for j in pred_rows)
                if any(j not in chosen for j in pred_rows):
                    pending.append(i)
            how = quick[i]
            if how:
                j = pred1[i]
                before = sols[j]
                if j in chosen and len(before) == 1:
                    s = before[0]
                    hit = spec_hit[j]
                    if hit is None:
                        hit = s.q is not None and s.q.tolist() == spec_l[j]
                    if hit:
                        line = uses[j].line
                        caution = None if s.caution is None else _follows(line, j == i)
                        flag = "ConfJ" if uses[i].motion.spec.interpolation == "joint" \
                            else "ConfL"
                        if how == 1:
                            q = off_spec[i]
                            spec_hit[i] = off_is_spec[i]
                            sols[i] = [_pick((q, "", None, "closest", s.q, line, caution))]
                            picks[i] = _pick((q, f"closest to line {line} ({flag}\\Off)", None,
                                              "closest", s.q, line, caution))
                            off_rows.append(i)
                        else:
                            # (The confdata's solution is the guess: _speculate
                            # guessed it.)
                            spec_hit[i] = True
                            q = by_conf.q_deg[rob_row[i]]
                            if how == 2:
                                picks[i] = on = _pick((q, _SAME[flag], None, "conf", None, None,
                                                       caution))
                                sols[i] = [on]
                            else:
                                sols[i], picks[i] = self._on_or_off(
                                    Pick(q, _SAME[flag], None, "conf"),
                                    [Pick(off_spec[i], "", None, "closest", s.q, line,
                                          caution)], flag)
                            conf_rows.append(i)
                        chosen.add(i)
                        taken[how] += 1
                        continue
            self._set(i, st)
        if off_rows:
            self.q[off_rows] = off_spec[off_rows]
        if conf_rows:
            self.q[conf_rows] = by_conf.q_deg[[rob_row[i] for i in conf_rows]]
        # Who follows whom, where a move is chosen again (below).
        succ: dict[int, list[int]] = {}
        if pending:
            for j, i in edges:
                succ.setdefault(j, []).append(i)
        # Loops: a move whose predecessor comes later in the flow (the last
        # move of a loop body before its first) is chosen again once that
        # one is known, and a change propagates.
        updates: dict[int, int] = {}
        work = list(dict.fromkeys(pending))
        while work:
            i = work.pop(0)
            before = [p.q for p in self.sols[i]], self.q[i].copy()
            self._set(i)
            after = [p.q for p in self.sols[i]]
            if len(after) != len(before[0]) or any(
                    np.linalg.norm(a - b) > SAME_DEG for a, b in zip(after, before[0])) or not \
                    np.allclose(before[1], self.q[i], atol=SAME_DEG, equal_nan=True):
                updates[i] = updates.get(i, 0) + 1
                if updates[i] > 3:
                    self.unsettled.add(i)
                    self.q[i] = np.nan
                    self.sols[i] = []
                    self.spec_hit[i] = None
                    self.picks[i] = _fail("the closest solution does not settle around the "
                                          "loop this move is in")
                    # Those after it now start from an unknown position.
                    work.extend(j for j in succ.get(i, []) if j not in work and j != i)
                    continue
                work.extend(j for j in succ.get(i, []) if j not in work)

    def _set(self, i: int, st: State | None = None) -> None:
        if i in self.unsettled:
            return
        self.spec_hit[i] = None              # (run's quick cases say it where they know)
        sols, pick = self.choose(i, st)
        if len(sols) > 8:
            sols, pick = [], _fail("reached on more than 8 configurations")
        self.sols[i] = sols
        self.q[i] = pick.q if pick.q is not None else np.nan
        self.picks[i] = pick
        self.chosen.add(i)


def nominal_ahead(solver: Solver):
    """Plan's `ahead` for solve() with this solver: the nominal IK of every
    robtarget use (the choice's first batch) handed to the job's helper
    (side.py) as soon as their flange poses are known, made there while
    this process analyses the flow (without a helper: made when solve()
    asks for it); with those flange poses, which the solve takes too."""
    def start(uses):
        rob = [u for u in uses if u.reason is None and u.kind == "robtarget"]
        R, p, conf = _ik_input(rob)
        return solver, len(rob), side.run(_nominal_and_candidates, solver, R, p, conf), R, p
    return start


def _ik_input(rob: list) -> tuple:
    """(R, p, conf) of robtarget uses, as the nominal IK takes them."""
    R, p = flange_stack(rob)
    return R, p, np.array([u.conf for u in rob], dtype=int).reshape(-1, 4)


def _nominal_and_candidates(solver: Solver, R, p, conf):
    return solver.nominal_and_candidates(R, p, conf) if len(p) else (None, None)


def _nominal_of(plan: Plan, solver: Solver, rob: list) -> tuple:
    """(solve_nominal, candidates, R, p) of the robtarget uses `rob` (those
    of plan.uses, solved, in order; R, p their flange poses): what the
    plan handed off for this solver, taken once; else made here."""
    ahead, plan.ahead = plan.ahead, None
    if ahead is not None and ahead[0] is solver and ahead[1] == len(rob):
        return (*ahead[2].get(), ahead[3], ahead[4])
    R, p, conf = _ik_input(rob)
    return (*_nominal_and_candidates(solver, R, p, conf), R, p)


def solve(plan: Plan, solver: Solver, start=None) -> Solved:
    """start: the joints (deg) the robot is at where the program leaves its
    position unknown (--start), for moves without supervision whose
    confdata names no solution; default: the program's first jointtarget."""
    return Solving(plan, solver, start).finish()


class Solving:
    """A solve whose nominal half is made (the choice of each use's nominal
    solution) and whose deformed robot's IK is under way: handed to the
    job's helper (side.py), made there while this process goes on with what
    needs the nominal half only (uses, row, R, p, nominal and picks, as
    Solved has them: place.grouping); finish() gives the Solved."""

    def __init__(self, plan: Plan, solver: Solver, start=None):
        uses = self.uses = [u for u in plan.uses if u.reason is None]
        self.row = rows = {u.key: i for i, u in enumerate(uses)}
        n = len(uses)
        self.start = None if start is None else np.asarray(start, float)
        chooser = _Chooser(plan, solver, uses, rows, self.start)
        chooser.run()
        q_nom = chooser.q
        self.picks = picks = chooser.picks
        rob = list(chooser.rob_row)
        flange, tcp, guessed = chooser.flange, chooser.tcp, chooser.guessed
        # The chooser's candidates, guesses and solutions (1e5 targets: ~100
        # MB) go before the deformed robot's batches are made.
        chooser = None
        failed = np.array([pick.failure is not None for pick in picks], dtype=bool)
        R, p, seed, self.nominal = _seed_of(solver, q_nom, rob, *flange, failed)
        # Joint limits of the chosen joints (MoveAbsJ targets) are failures too.
        bad = (seed.status != Status.OK).tolist()
        for i in range(n):
            if bad[i] and picks[i].failure is None:
                picks[i] = _fail(f"nominal: {seed.reason(i)}")
        # (Past the choice, as columns.)
        self.picks = picks = Picks(picks, q_nom)
        self.R, self.p = R, p
        self._deformed = side.run(_solve_deformed, guessed, solver, R, p, self.nominal, tcp,
                                  np.nan_to_num(q_nom) * DEG)
        self._plan, self._solver = plan, solver

    def finish(self) -> Solved:
        plan, solver, uses, picks = self._plan, self._solver, self.uses, self.picks
        deformed, self.err_p, self.err_r, Rn, pn, conf_after = self._deformed.get()
        # A MoveAbsJ whose tool is not known, at the wrist singularity: the
        # position held exact there is the flange's, not the tool's.
        left = np.flatnonzero(deformed.warnings & Warn.ORIENTATION_LEFT).tolist()
        for i in left:
            u = uses[i]
            if u.kind == "jointtarget" and u.tool is None and picks.failure[i] is None:
                why = next(n.removesuffix(UNKNOWN_TOOL_MEANS) for n in u.notes
                           if n.startswith(UNKNOWN_TOOL))
                picks.failure[i] = (f"at the wrist singularity (J5 {self.nominal.q_deg[i][4]:.2f}"
                                    " deg) only the tool centre point's position can be held "
                                    f"exact, and {why}")
        disp = np.full(len(uses), np.nan)
        moved = [i for i, u in enumerate(uses) if u.kind == "robtarget"
                 and plan.may_be_displaced(u) and picks.failure[i] is None
                 and deformed.success[i]]
        if moved:
            disp[moved] = _displacement_sensitivity(solver, deformed.q_deg[moved])
        return Solved(uses, self.row, self.R, self.p, self.nominal, deformed, self.err_p,
                      self.err_r, Rn, pn, conf_after, picks, disp, self.start)


def _seed_of(solver: Solver, q_nom: np.ndarray, rob: list, R_rob, p_rob, failed: np.ndarray):
    """(R, p, seed, nominal) of the chosen nominal joints q_nom (NaN: no
    solution; `failed`: the rows whose choice failed): the intended flange
    poses (a robtarget's as resolved, R_rob, p_rob of the rows `rob`; a
    MoveAbsJ's the nominal FK of its joints), seed_from_joints's batch,
    and the nominal batch the deformed robot's IK starts from (a failed
    row's status NO_CONFIGURATION)."""
    # (seed_from_joints's own arrays, written into.)
    R, p, seed = solver.seed_from_joints(np.nan_to_num(q_nom))
    R[rob], p[rob] = R_rob, p_rob
    status = seed.status.copy()
    status[failed] = Status.NO_CONFIGURATION
    nominal = IKBatch(np.where(np.isnan(q_nom), np.nan, seed.q_deg), status, seed.detail,
                      seed.detail_joint, seed.conf, seed.residual_mm, seed.residual_rad,
                      seed.iterations, seed.warnings, beyond_deg=seed.beyond_deg)
    return R, p, seed, nominal


def _solve_deformed(guessed, solver: Solver, R, p, nominal: IKBatch, tcp, q_cmd) -> tuple:
    """(deformed, err_p, err_r, Rn, pn, conf_after) as Solved has them: the
    deformed robot's IK of the flange poses R, p from the nominal batch,
    the uncompensated error of q_cmd (rad), the nominal FK of the
    compensated joints and their confdata. Each block of rows is taken
    from the guess made ahead (_guess_deformed) where its inputs are the
    guess's, byte for byte: the same results (ik.reusing)."""
    global _guessed
    known = _guessed[1] if _guessed is not None and _guessed[0] == guessed else {}
    _guessed = None
    work = _deformed_work(solver, R, p, nominal, tcp, q_cmd, known)
    (qc,), (Rn, pn, wrist) = work["fk"]
    return (work["ik"][1], *work["error"][1], Rn, pn,
            confdata(qc, wrist, solver.geometry.phi))


def _deformed_work(solver: Solver, R, p, nominal: IKBatch, tcp, q_cmd, known: dict) -> dict:
    """The IK, the error and the FK _solve_deformed computes, each as
    (its arguments, its result), each block taken from `known` (the same
    of a guess) where its arguments are the guess's (ik.reusing)."""
    ik_args, error_args = (R, p, nominal, tcp), (q_cmd, R, p, tcp)
    deformed = reusing(Solver.solve_deformed, solver, ik_args, known.get("ik"))
    error = reusing(Solver.deformed_pose_error, solver, error_args, known.get("error"))
    qc = np.nan_to_num(deformed.q_deg) * DEG
    fk = reusing(Solver.nominal_pose_and_wrist, solver, (qc,), known.get("fk"))
    return {"ik": (ik_args, deformed), "error": (error_args, error), "fk": ((qc,), fk)}


# The guess _guess_deformed made in the job's helper: (its number, what
# _solve_deformed may take of it), until _solve_deformed takes it.
_guessed: tuple | None = None
_guesses = itertools.count(1)


def _guess_ahead(solver: Solver, q: np.ndarray, rob: list, R_rob, p_rob, tcp) -> int | None:
    """Hand the helper (side.py) the deformed robot's IK from the nominal
    joints q the choice is expected to take (made there while this process
    chooses: _guess_deformed); its number, which _solve_deformed is given,
    or None (no helper, no robtarget)."""
    if not rob or not side.helps():
        return None
    rows = np.array(rob, dtype=np.intp)        # (pickled as one array, not 1e5 ints)
    number = next(_guesses)
    side.run(_guess_deformed, number, solver, q, rows, R_rob, p_rob, tcp)
    return number


def _guess_deformed(number: int, solver: Solver, q_nom, rob, R_rob, p_rob, tcp) -> None:
    """In the helper: _solve_deformed's work on the nominal joints guessed
    (q_nom; NaN: failed), kept as the guess numbered `number` for the
    _solve_deformed call that comes with that number; where the choice took
    other joints, their blocks are computed there again."""
    global _guessed
    _guessed = None
    failed = np.isnan(q_nom).any(axis=1)
    R, p, _, nominal = _seed_of(solver, q_nom, rob, R_rob, p_rob, failed)
    _guessed = (number, _deformed_work(solver, R, p, nominal, tcp,
                                       np.nan_to_num(q_nom) * DEG, {}))


class Slot(NamedTuple):
    q_deg: np.ndarray     # the joints written into the slot
    what: str             # what they are, for the report


def tcp_of(uses) -> np.ndarray:
    """The tool centre point of each use in the flange frame (mm): where
    errors are measured and what the wrist fallback holds exact."""
    # (stacked_poses: each tool converted once, a CAM program's 1e5 uses
    # share one.)
    return stacked_poses([u.tool[1] if u.tool is not None else IDENTITY_POSE
                          for u in uses])[1]


def solve_slots(solver: Solver, R, p, conf, valid) -> list[Slot]:
    """Joints for array slots no executed move reaches (they need some
    valid value): compensated where the slot's robtarget solves by its
    confdata, else its nominal joints, else the calibration position; with
    what each is."""
    nominal, deformed = solver.compensate(R, p, conf)
    out = []
    for i in range(len(valid)):
        if valid[i] and deformed.success[i]:
            out.append(Slot(deformed.q_deg[i], "the compensated joints of their robtargets"))
        elif valid[i] and nominal.success[i]:
            out.append(Slot(nominal.q_deg[i], "the nominal joints of their robtargets (these "
                                              "cannot be compensated)"))
        else:
            out.append(Slot(np.zeros(6), "[0,0,0,0,0,0], the calibration position (their "
                                         "robtargets have no solution)"))
    return out


def _displacement_sensitivity(solver: Solver, q_deg: np.ndarray) -> np.ndarray:
    """um of TCP error per mm of program displacement, per row.

    The written correction delta(x) = FK_nominal(q_comp(x)) - x was computed
    for the undisplaced pose x; displaced by d the robot needs delta(x + d).
    d delta / dx = J_nominal(q_comp) . J_deformed(q_comp)^-1 - I, whose
    translation block's largest singular value bounds the extra error per mm.
    """
    q = np.asarray(q_deg, float) * DEG
    _, _, Jn = solver.nominal_chain.fk_jacobian(q)
    jm = solver.joint_map
    qa = jm.apply(q) if jm is not None else q
    _, _, Jd = solver.deformed_chain.fk_jacobian(qa)
    if jm is not None:
        # The warm robot answers the commanded joints through the joint
        # map (offsets, scales, gravity compliance): J wrt the commands is
        # Jd(qa) . d qa / d q (central differences; the map is smooth).
        h = 1e-6
        D = np.empty(q.shape + (q.shape[1],))
        for j in range(q.shape[1]):
            dq = np.zeros(q.shape[1])
            dq[j] = h
            D[:, :, j] = (jm.apply(q + dq) - jm.apply(q - dq)) / (2 * h)
        Jd = Jd @ D
    M = Jn @ np.linalg.inv(Jd) - np.eye(6)
    return np.linalg.norm(M[:, :3, :3], ord=2, axis=(1, 2)) * 1000.0

"""One row per target use, the content of every report: what `check`
predicts and what `fix` did, in the same terms."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields

import numpy as np

from ..construct import maker
from ..kinematics.frames import DEG
from ..kinematics.ik import (BEYOND_LIMIT, MORE_BEYOND, NO_SOLUTION_IN_LIMITS, WARN_TEXT,
                              Warn, warning_texts_of)
from .place import Group, element_label
from .plan import Plan
from .solve import Solved
from .targets import EXTAX_UNUSED, TargetUse

LINEAR_WARNING = "MoveL -> MoveAbsJ: the path to this point is no longer a straight line"
# (One tuple: a row with no other warning holds this one, 1e5 rows in a CAM
# program converted by --emit absj.)
_LINEAR = (LINEAR_WARNING,)
COMPENSATED, NOT_COMPENSATED, UNTOUCHED = "compensated", "not compensated", "untouched"


@dataclass(frozen=True, slots=True)
class UseRow:
    file: str                        # the module file (display path)
    line: int
    instruction: str
    target: str
    status: str                      # compensated / not compensated / untouched (check: ...able)
    rule: str | None                 # how the controller's solution is determined
    action: str | None
    nominal_deg: tuple[float, ...] | None
    compensated_deg: tuple[float, ...] | None
    delta_deg: tuple[float, ...] | None
    error_um: float | None           # uncompensated program on the warm robot
    error_deg: float | None
    residual_um: float | None        # compensated (fix: the written values, float32)
    residual_deg: float | None
    conf_before: tuple[int, ...] | None
    conf_after: tuple[int, ...] | None
    warnings: tuple[str, ...]
    reason: str | None

    def as_dict(self) -> dict:
        """Field name -> value (what dataclasses.asdict gives a JSON
        encoder, without its deep copy: ~10x faster on 1e5 rows)."""
        return {name: getattr(self, name) for name in FIELDS}


FIELDS = tuple(f.name for f in fields(UseRow))
# (A CAM report's 1e5 rows, made as the class makes them: construct.py.)
_new_row = maker(UseRow)


def rounded_rows(a: np.ndarray) -> list[tuple[float, ...] | None]:
    """Each row of a (n, k) as a tuple of round(x, 6), None for a row with
    a NaN: the reports' joint columns (rounded_array's numbers)."""
    out, nan = rounded_array(a)
    # (Each row's tuple made from the columns' floats at once: no list per
    # row first.)
    rows = list(zip(*out.T.tolist())) if out.shape[1] else [()] * len(out)
    for i in np.flatnonzero(nan).tolist():
        rows[i] = None
    return rows


def rounded_array(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(round(x, 6) of every x of a (n, k), which rows hold a NaN): a CAM
    program has 1e5 rows, 3 arrays of 6 joints each. Bulk, with Python's
    round's results: round(x, 6) is the double nearest N / 1e6, N = x *
    10**6 rounded half to even exactly; rint of the product in floating
    point is that N wherever the product lies further than a few ulps from
    a half (the rest, ~1e-8 of random values, is rounded by round itself);
    N / 1e6, one correctly rounded division of exact numbers, is that
    nearest double (tested against round on ties, near-ties, signed zeros
    and large values)."""
    a = np.asarray(a, float)
    with np.errstate(over="ignore", invalid="ignore"):   # those go to round() below
        scaled = a * 1e6
        out = np.rint(scaled) / 1e6
        near_half = np.abs(scaled - np.floor(scaled) - 0.5) <= 4 * np.spacing(np.abs(scaled))
        odd = near_half | ~(np.abs(scaled) < 2.0 ** 52)    # NaN, inf, too large
    for i, j in zip(*np.nonzero(odd)):
        out[i, j] = round(float(a[i, j]), 6)
    return out, (np.isnan(a).any(axis=1) if a.shape[1] else np.zeros(len(a), bool))


def number_columns(qn_deg, qc_deg, err_p, err_r) -> tuple[list, ...]:
    """A row's numbers for every solved target (Solved's q_deg rows,
    err_p, err_r): its nominal, compensated and delta joints (rounded_rows
    of each) and its uncompensated error in um and deg. The rows take them
    (_Columns, as arrays), and so do the report's number cells made ahead
    (report.number_cells): one computation, the same numbers."""
    qn, qc = np.asarray(qn_deg, float), np.asarray(qc_deg, float)
    return (rounded_rows(qn), rounded_rows(qc), rounded_rows(qc - qn),
            *_errors(err_p, err_r))


def _errors(err_p, err_r) -> tuple[list, list]:
    return (np.asarray(err_p, float) * 1000).tolist(), (np.asarray(err_r, float) / DEG).tolist()


class _Columns:
    """The solved numbers of every row: the joints as rounded arrays (the
    rows read them: Rows), the others as Python lists, converted once (a
    CAM program has 1e5 rows; numpy scalars one by one cost ~10x more).
    Same values: elementwise, as for one row."""

    def __init__(self, solved: Solved):
        qn = np.asarray(solved.nominal.q_deg, float)
        qc = np.asarray(solved.deformed.q_deg, float)
        self.joints = (rounded_array(qn), rounded_array(qc), rounded_array(qc - qn))
        self.err_um, self.err_deg = _errors(solved.err_p, solved.err_r)
        self.res_mm = solved.deformed.residual_mm.tolist()
        self.res_rad = solved.deformed.residual_rad.tolist()
        self.disp = solved.displacement_um_per_mm.tolist()
        self.warn_bits = solved.deformed.warnings.tolist()
        self.ok = solved.oks()


# Rows made at once where many are asked for (their joints' tuples made
# from a block of the arrays).
_BLOCK = 4096
# UseRow's fields but its joints, in order; a row's joints are read from
# the solved numbers (Rows).
_JOINTS = ("nominal_deg", "compensated_deg", "delta_deg")
BASE_FIELDS = tuple(f for f in FIELDS if f not in _JOINTS)
_AT = {name: k for k, name in enumerate(BASE_FIELDS)}
assert FIELDS[7:10] == _JOINTS


class Rows(Sequence):
    """Every use's row, in text order, as a result holds them: its fields
    but the joints as columns (BASE_FIELDS, a list each), and where each
    row's joints are in the solved numbers' rounded arrays (one int: -1
    none, 2i the nominal joints of solved row i only, 2i + 1 all three).
    A row is a UseRow made when asked for; nothing is kept per row (a CAM
    program's 1e5 rows: no tuple of joints, ~75 MB, nor of fields, ~18
    MB), and the reports read the columns (column(), bases(), joints(),
    values()). A slice is a list of rows."""

    def __init__(self, base: list[tuple], codes: list[int], joints: tuple):
        """base: each row's fields but the joints (BASE_FIELDS), kept as
        columns."""
        self._cols = tuple(map(list, zip(*base))) if base else tuple([] for _ in BASE_FIELDS)
        self._codes, self._joints = codes, joints
        self._full: list[bool] | None = None

    def __len__(self) -> int:
        return len(self._codes)

    def __getitem__(self, k):
        if isinstance(k, slice):
            return self._rows(range(*k.indices(len(self))))
        if k < 0:
            k += len(self)
        if not 0 <= k < len(self):
            raise IndexError("row index out of range")
        return self._row(k)

    def __hash__(self) -> int:
        # (As the tuple of rows a result held before: equal rows, equal hash.)
        return hash(tuple(self))

    def __iter__(self):
        for at in range(0, len(self), _BLOCK):
            yield from self._rows(range(at, min(at + _BLOCK, len(self))))

    def _rows(self, ks) -> list[UseRow]:
        """The rows ks (UseRow)."""
        return [_new_row(*b[:7], *q, *b[7:]) for b, q in self.parts(ks)]

    def values(self, ks) -> list[tuple]:
        """The fields of rows ks, in FIELDS order."""
        return [(*b[:7], *q, *b[7:]) for b, q in self.parts(ks)]

    def parts(self, ks) -> list[tuple]:
        """(fields but the joints (BASE_FIELDS), (nominal, compensated,
        delta joints)) of rows ks, their joints' tuples made from a block
        of the arrays at once (the JSON report reads 1e5 rows so, no UseRow
        nor tuple of all fields made)."""
        codes = [self._codes[k] for k in ks]
        at = [c >> 1 if c >= 0 else 0 for c in codes]
        made = []
        for values, nan in self._joints:
            if not len(values) or not at:
                made.append(([None] * len(at), [True] * len(at)))
                continue
            block = values[at]
            made.append((list(zip(*block.T.tolist())) if block.shape[1] else [()] * len(at),
                         nan[at].tolist()))
        (qn, qn_nan), (qc, qc_nan), (dq, dq_nan) = made
        out = []
        for n, (b, code) in enumerate(zip(self.bases(ks), codes)):
            if code < 0:
                q = (None, None, None)
            elif code & 1:
                q = (None if qn_nan[n] else qn[n], None if qc_nan[n] else qc[n],
                     None if dq_nan[n] else dq[n])
            else:
                q = (None if qn_nan[n] else qn[n], None, None)
            out.append((b, q))
        return out

    def __eq__(self, other) -> bool:
        # (Equal to the rows it holds, as the tuple of rows a result held.)
        if not isinstance(other, (Rows, list, tuple)):
            return NotImplemented
        return len(self) == len(other) and all(a == b for a, b in zip(self, other))

    def __repr__(self) -> str:
        return f"Rows({len(self)} rows)"

    def _joint(self, which: int, i: int):
        values, nan = self._joints[which]
        return None if nan[i] else tuple(values[i].tolist())

    def joints(self, k: int) -> tuple:
        """Row k's (nominal, compensated, delta) joints, each a tuple or
        None."""
        code = self._codes[k]
        if code < 0:
            return None, None, None
        i = code >> 1
        if code & 1:
            return self._joint(0, i), self._joint(1, i), self._joint(2, i)
        return self._joint(0, i), None, None

    def _row(self, k: int) -> UseRow:
        b = self.base(k)
        return _new_row(b[0], b[1], b[2], b[3], b[4], b[5], b[6], *self.joints(k), b[7], b[8],
                        b[9], b[10], b[11], b[12], b[13], b[14])

    def column(self, name: str) -> list:
        """Every row's value of field `name` (not a joints field), as a
        list of its own."""
        return list(self._cols[_AT[name]])

    def code(self, k: int) -> int:
        """Where row k's joints are (-1: none; 2i: solved row i's nominal
        joints only; 2i + 1: all three)."""
        return self._codes[k]

    def base(self, k: int) -> tuple:
        """Row k's fields but its joints (BASE_FIELDS)."""
        return tuple([c[k] for c in self._cols])

    def bases(self, ks) -> list[tuple]:
        """base(k) of each of rows ks, made a column at a time (a
        contiguous range, as the reports ask for blocks, by slices)."""
        if type(ks) is not range:
            ks = list(ks)
            if ks and ks[0] >= 0 and ks[-1] - ks[0] + 1 == len(ks) and all(
                    a < b for a, b in zip(ks, ks[1:])):
                ks = range(ks[0], ks[-1] + 1)
        if type(ks) is range and ks.step == 1 and ks.start >= 0 and ks.stop >= 0:
            return list(zip(*[c[ks.start:ks.stop] for c in self._cols]))
        return list(zip(*[[c[k] for k in ks] for c in self._cols]))

    def full(self, k: int) -> bool:
        """Row k has all three joints, six each, none a NaN, and its error
        and residual: the report's fast row (report._full)."""
        if self._full is None:
            self._full = self._fulls()
        return self._full[k]

    def _fulls(self) -> list[bool]:
        """full() of every row, at once."""
        codes = np.array(self._codes, np.int64).reshape(-1)
        values = self._joints[0][0]
        ok = (codes >= 0) & (codes & 1 == 1)
        if values.ndim != 2 or values.shape[1] != 6 or not len(values):
            ok[:] = False
        else:
            at = np.where(ok, codes >> 1, 0)
            for _, nan in self._joints:
                ok &= ~nan[at]
        e, d, r = (self._cols[_AT[name]] for name in ("error_um", "error_deg", "residual_um"))
        return [bool(o) and x is not None and y is not None and z is not None
                for o, x, y, z in zip(ok.tolist(), e, d, r)]


def displacement_warning(um_per_mm: float, track: bool = False) -> str:
    """track: a track carries the robot, and an external axis offset
    (EOffsOn/EOffsSet) displaces it too."""
    what = ("program displacement (PDispOn/PDispSet) or an external axis offset "
            "(EOffsOn/EOffsSet)" if track else "program displacement (PDispOn/PDispSet)")
    return (f"may run under {what}: compensated for the "
            "undisplaced pose and kept a robtarget move (the controller does not displace "
            f"MoveAbsJ); each mm of displacement adds up to {um_per_mm:.2f} um of error")


def use_rows(plan: Plan, solved: Solved, *, group_of: dict | None = None,
             actions: dict | None = None, verified: dict | None = None,
             written_conf: dict | None = None,
             statuses=(COMPENSATED, NOT_COMPENSATED), at: list | None = None,
             pers_copies: set | None = None) -> Rows:
    """Rows in text order. Without group_of/verified (check): per use, the
    solve's own residual and the confdata of the compensated joints; with
    them (fix): the written values' residual and confdata
    (written_conf: use key -> the confdata written, absent where no robtarget
    is written). `at`, when given, receives each row's row of `solved`
    (None for a use not solved). pers_copies (a transient output's): the
    uses whose move reads a copy of its PERS declaration (else: those of a
    group placed anew)."""
    ok_label, fail_label = statuses
    tracked = {k for k, _ in plan.track}
    cols = _Columns(solved)
    out: list[tuple] = []
    codes: list[int] = []
    for u in plan.uses:
        # (file, line, instruction, target): a row's first fields.
        base = (u.file.source.display_path, u.line, u.motion.instruction, u.label)
        if u.reason is not None:
            out.append((*base, fail_label if u.blocked else UNTOUCHED, None, None, None, None,
                        None, None, None, None, (), u.reason))
            codes.append(-1)
            if at is not None:
                at.append(None)
            continue
        if at is not None:
            at.append(solved.row[u.key])
        row, code = _row(solved, cols, u, base, group_of, actions, verified,
                         written_conf, ok_label, fail_label, tracked, pers_copies)
        out.append(row)
        codes.append(code)
    return Rows(out, codes, cols.joints)


def _row(solved: Solved, cols: _Columns, u: TargetUse, base, group_of, actions, verified,
         written_conf, ok_label, fail_label, tracked, pers_copies=None) -> tuple[tuple, int]:
    """(the row's fields but its joints, where its joints are: Rows)."""
    i = solved.row[u.key]
    # (The pick's columns read where they are: no Pick made for each row.)
    picks = solved.picks
    rule, caution = picks.rule[i], picks.caution[i]
    has_q = picks.failure[i] is None
    error = (cols.err_um[i], cols.err_deg[i]) if has_q else (None, None)
    # confdata is a robtarget's: a MoveAbsJ has none. (A record's conf is
    # a tuple of ints already.)
    conf_before = u.conf
    bits = cols.warn_bits[i]
    g: Group | None = group_of.get(u.key) if group_of is not None else None
    why = None
    if not cols.ok[i]:
        why = solved.reason(i)
    elif g is not None and g.failure is not None:
        reason, fk = g.failure
        # (Another element or use of the value written with this one's:
        # that one is why this one is refused too.)
        why = reason if fk == u.source.element else (
            f"{element_label(g, fk)}{WITH_IT}"
            f"{'array' if g.array else 'value'}{g.one_because}, is not compensated: {reason}")
    # (Written as a jointtarget: a MoveAbsJ's, or a move turned into one.)
    joints = u.kind == "jointtarget" or (g is not None and g.mode == "absj")
    d_warnings = (_warnings(solved, i, joints, warning_texts_of(bits), why is not None)
                  if has_q and bits else ())
    if why is not None:
        why = _hint(why, u, tracked)
        return ((*base, fail_label, rule, None, error[0], error[1], None, None, conf_before,
                 None, d_warnings, why), 2 * i if has_q else -1)
    warnings = d_warnings
    if g is not None:
        if g.mode == "absj" and u.motion.spec.name == "MoveL":
            warnings = warnings + _LINEAR
        kept = g.why_kept.get(u.key) if g.why_kept else None
        if kept is not None:
            # What keeps a move --emit would turn into MoveAbsJ (an argument
            # MoveAbsJ has not, ToPoint:=, PERS data, external axes of named
            # data; place.kept_robtarget): said, not a MoveL left as it was
            # with no word why.
            warnings = warnings + (f"kept as {u.motion.instruction}: "
                                   + kept.removesuffix(": kept a robtarget move"),)
        if g.kept and u.key in g.kept:
            warnings = warnings + (f"kept as {u.motion.instruction}: in another iteration of its "
                                   "loop this statement must stay a robtarget move, and one "
                                   "statement cannot be both",)
        # (A transient output's moves read a copy where the editor made one,
        # a cold value with other confdata; placed anew or not: pers_copies.)
        if (u.key in pers_copies if pers_copies is not None else
                g.placement == "new" and g.decl is not None and g.decl.storage == "PERS"):
            # (The use's own declaration: of Singles, g has none.)
            warnings = warnings + (f"{u.source.decl.name}{PERS_COPY}, which changes to it at "
                                   "run time (ModPos, another task) no longer reach",)
    warnings = warnings + u.notes
    if caution is not None:
        warnings = warnings + (caution,)
    after = _conf_after(solved, i, u, written_conf)
    if written_conf is not None and after is not None and after != conf_before:
        changed = [f"{n} {a} -> {b}" for n, a, b in zip(("cf1", "cf4", "cf6", "cfx"),
                                                          conf_before, after) if a != b]
        warnings = warnings + ("confdata rewritten (" + ", ".join(changed) + "): the "
                               "compensated joints lie in another quadrant",)
    disp = cols.disp[i]
    if disp == disp:                 # not NaN
        warnings = warnings + (displacement_warning(disp, bool(tracked)),)
    if verified is not None:
        res = verified[u.key]
    else:
        res = (cols.res_mm[i] * 1000, cols.res_rad[i] / DEG)
    return ((*base, ok_label, rule, actions.get(u.key) if actions is not None else None,
             error[0], error[1], res[0], res[1], conf_before, after, warnings, None), 2 * i + 1)


def _conf_after(solved: Solved, i: int, u: TargetUse, written_conf):
    if written_conf is not None:
        return written_conf.get(u.key)       # ints (fix.py)
    if u.kind != "robtarget":
        return None
    return tuple(int(c) for c in solved.conf_after[i])


def _warnings(solved: Solved, i: int, joints: bool, texts,
              refused: bool = False) -> tuple[str, ...]:
    """The solver's warnings that matter for this use: not its quadrant
    change (a written confdata that changes is said by the row's confdata
    columns and a note of its own), nor a cfx change where a jointtarget
    is written (joints: it has no confdata); the
    orientation left over at the wrist singularity with its amount, but in
    a row refused (its reason says what it is: a solution not written is
    not "compensated exactly")."""
    left = WARN_TEXT[Warn.ORIENTATION_LEFT] in texts
    out = []
    for text in texts:
        if text == WARN_TEXT[Warn.QUADRANT_CHANGED]:
            continue
        if joints and text == WARN_TEXT[Warn.CFX_AT_SINGULARITY]:
            continue
        if left and text == WARN_TEXT[Warn.WRIST_SINGULAR]:
            continue
        if text == WARN_TEXT[Warn.ORIENTATION_LEFT]:
            if refused:
                continue
            text = (f"at the wrist singularity (J5 {solved.nominal.q_deg[i][4]:.2f} deg) the "
                    "position is compensated exactly, the orientation only as far as small "
                    "J4/J6 changes allow: "
                    f"{float(solved.deformed.residual_rad[i]) / DEG:.4f} deg left over")
        out.append(text)
    return tuple(out)


def _hint(reason: str, u: TargetUse, tracked) -> str:
    """A target out of reach that carries external axis values the tool
    assumes do not move the base: say what to check."""
    if reason.startswith("nominal: out of reach") and any(
            abs(v) < EXTAX_UNUSED for k, v in enumerate(u.ext) if k not in tracked):
        return (reason + " (its external axes are assumed not to move the robot's base; if "
                "one is a track, say so with --track)")
    return reason


# How a row's warning says its move reads a CONST copy of its PERS target,
# after the target's name (_row; fix's note counts them).
PERS_COPY = " is PERS: this move now reads a CONST copy"
# How a row refused with another element of its value says so (_row).
WITH_IT = ", written with it as one "


def limits_note(rows: "Rows", robot) -> str | None:
    """What joint-limit refusals mean, said once with where the limits come
    from. As written (the nominal robot's solution, before any
    compensation): the limits are not the controller's, which runs only
    programs within its own (a user's --limit narrower than them, or the
    model's own where the controller's differ: the IRB 140's J5 is +-115 or
    +-120 deg by variant). After compensation: the warm robot needs a joint
    beyond the limit, which the robot cannot do, unless the controller's
    limits are wider. None where no target is refused so."""
    over: dict[str, dict[int, tuple[int, float]]] = {"nominal": {}, "compensated": {}}
    none = 0
    for reason in rows.column("reason"):
        # (A row's own failure only: an array's other elements refused with
        # it name its reason after their own words.)
        if reason is None or WITH_IT in reason:
            continue
        # (Anywhere in the reason: "ConfL may be on or off here: on, ...
        # (nominal: J5 beyond ...); off, ..." names one for each.)
        mine: dict = {}
        for m in BEYOND_LIMIT.finditer(reason):
            kind = ("nominal" if reason.endswith("nominal: ", 0, m.start())
                    else "compensated")
            for joint, by in ((m.group(1), m.group(2)), *MORE_BEYOND.findall(m.group(3))):
                key = (kind, int(joint) - 1)
                mine[key] = max(mine.get(key, 0.0), float(by))
        for (kind, k), by in mine.items():
            n, worst = over[kind].get(k, (0, 0.0))
            over[kind][k] = (n + 1, max(worst, by))
        none += f"nominal: {NO_SOLUTION_IN_LIMITS}" in reason
    if not any(over.values()) and not none:
        return None

    def joints(seen: dict) -> list[str]:
        return [f"{robot.joint_names[k]} at {n} target{'s' if n != 1 else ''}, by up to "
                f"{worst:.4g} deg (its limits {robot.lower_deg[k]:g}..{robot.upper_deg[k]:g} "
                f"deg, {robot.limit_source(k)})" for k, (n, worst) in sorted(seen.items())]
    said = []
    if over["nominal"] or none:
        # (The --limit options among the limits crossed.)
        given = sorted({robot.limit_source(k) for k in over["nominal"]
                        if robot.limit_source(k).startswith("set by --limit ")})
        said.append(
            "the program as written goes beyond the joint limits rapidcomp uses: "
            + "; ".join(joints(over["nominal"]) + ([
                f"no solution within the limits at {none} target{'s' if none != 1 else ''}"]
                if none else []))
            + ". The controller runs only programs within its own limits: if this one runs, "
            + (f"{' and '.join(g.removeprefix('set by ') for g in given)} "
               f"{'is' if len(given) == 1 else 'are'} narrower than the controller's: "
               if given else "")
            + "give the controller's own limits with --limit JOINT=LOWER:UPPER (degrees; its "
            "MOC.cfg gives them as lower_joint_bound/upper_joint_bound, in radians)")
    if over["compensated"]:
        said.append(
            ("the" if not said else "The") + " compensation needs joints beyond their limits: "
            + "; ".join(joints(over["compensated"]))
            + ". The warm robot reaches those targets only there: refused; if the "
            "controller's limits are wider, give them with --limit JOINT=LOWER:UPPER")
    return " ".join(x + "." for x in said)


def summary(rows, ok_label: str = COMPENSATED, fail_label: str = NOT_COMPENSATED) -> dict:
    """rows: Rows (read by column), or UseRows."""
    if isinstance(rows, Rows):
        status, reason, error, residual, warns = (rows.column(name) for name in (
            "status", "reason", "error_um", "residual_um", "warnings"))
    else:
        status, reason, error, residual, warns = ([getattr(r, name) for r in rows] for name in (
            "status", "reason", "error_um", "residual_um", "warnings"))
    comp = [k for k, st in enumerate(status) if st == ok_label]
    untouched: dict[str, int] = {}
    for st, why in zip(status, reason):
        if st == UNTOUCHED:
            untouched[why] = untouched.get(why, 0) + 1
    errs = [error[k] for k in comp]
    res = [residual[k] for k in comp]
    return {
        "target_uses": len(status),
        ok_label: len(comp),
        fail_label.replace(" ", "_"): sum(st == fail_label for st in status),
        "untouched": dict(sorted(untouched.items())),
        "error_before_um": {"max": max(errs), "mean": float(np.mean(errs))} if errs else None,
        "residual_after_um": {"max": max(res), "mean": float(np.mean(res))} if res else None,
        "movel_to_moveabsj": sum(1 for k in comp if LINEAR_WARNING in warns[k]),
    }

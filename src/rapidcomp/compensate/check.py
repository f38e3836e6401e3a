"""`rapidcomp check`: predicted error of every target on the warm robot.

For each target use: the nominal joints (what the controller computes), the
TCP error those joints give on the deformed robot (the error of the
uncompensated program), and whether compensation succeeds, with its
residual. Nothing is rewritten.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kinematics.frames import DEG
from ..kinematics.ik import IKBatch, Solver
from ..rapid.model import ParsedFile
from .targets import TargetUse, target_uses


@dataclass(frozen=True)
class CheckRow:
    line: int
    instruction: str
    target: str
    status: str                      # "compensable", "not compensable", "untouched"
    error_um: float | None           # uncompensated TCP position error on the warm robot
    error_deg: float | None          # ... orientation error
    residual_um: float | None        # after compensation
    max_joint_change_deg: float | None
    conf_before: tuple[int, ...] | None
    conf_after: tuple[int, ...] | None
    reason: str | None
    warnings: tuple[str, ...]


def _errors(pose_error, q_deg: np.ndarray, R: np.ndarray, p: np.ndarray):
    pos, rot = pose_error(np.nan_to_num(q_deg) * DEG, R, p)
    return pos, rot / DEG


def check(files: list[ParsedFile], solver: Solver) -> list[CheckRow]:
    uses = target_uses(files)
    rows: list[CheckRow | None] = [None] * len(uses)
    for i, u in enumerate(uses):
        if u.reason is not None:
            rows[i] = CheckRow(u.line, u.motion.spec.name, u.label, "untouched", None, None,
                               None, None, None, None, u.reason, ())
    for kind in ("robtarget", "jointtarget"):
        idx = [i for i, u in enumerate(uses) if u.reason is None and u.kind == kind]
        if not idx:
            continue
        sel = [uses[i] for i in idx]
        if kind == "robtarget":
            R = np.array([u.R for u in sel])
            p = np.array([u.p for u in sel])
            nominal = solver.solve_nominal(R, p, np.array([u.conf for u in sel]))
        else:
            R, p, nominal = solver.seed_from_joints(np.array([u.joints_deg for u in sel]))
        deformed = solver.solve_deformed(R, p, nominal)
        err, err_rot = _errors(solver.deformed_pose_error, nominal.q_deg, R, p)
        res, _ = _errors(solver.deformed_pose_error, deformed.q_deg, R, p)
        for k, i in enumerate(idx):
            rows[i] = _row(sel[k], nominal, deformed, k, err[k], err_rot[k], res[k])
    return rows


def _row(u: TargetUse, nominal: IKBatch, deformed: IKBatch, k: int, err, err_rot, res) -> CheckRow:
    n = nominal.result(k)
    d = deformed.result(k)
    base = dict(line=u.line, instruction=u.motion.spec.name, target=u.label)
    if not n.success:
        return CheckRow(**base, status="not compensable", error_um=None, error_deg=None,
                        residual_um=None, max_joint_change_deg=None, conf_before=None,
                        conf_after=None, reason=f"nominal: {n.reason}", warnings=n.warnings)
    ok = d.success
    return CheckRow(
        **base, status="compensable" if ok else "not compensable",
        error_um=float(err) * 1000, error_deg=float(err_rot),
        residual_um=float(res) * 1000 if ok else None,
        max_joint_change_deg=float(np.max(np.abs(d.joint_change_deg))) if ok else None,
        conf_before=n.conf, conf_after=d.conf if ok else None,
        reason=None if ok else d.reason, warnings=d.warnings)


def summary(rows: list[CheckRow]) -> dict:
    comp = [r for r in rows if r.status == "compensable"]
    errs = [r.error_um for r in comp]
    untouched: dict[str, int] = {}
    for r in rows:
        if r.status == "untouched":
            untouched[r.reason] = untouched.get(r.reason, 0) + 1
    return {
        "targets": len(rows),
        "compensable": len(comp),
        "not_compensable": sum(r.status == "not compensable" for r in rows),
        "untouched": untouched,
        "error_before_um": {"max": max(errs), "mean": float(np.mean(errs))} if errs else None,
        "residual_after_um": {"max": max(r.residual_um for r in comp)} if comp else None,
    }


def render_text(rows: list[CheckRow], summ: dict, program: str) -> str:
    out = [f"{program}: predicted error on the warm robot, per target",
           f"{'line':>6}  {'instruction':<10} {'target':<28} {'error um':>9} {'error deg':>9} "
           f"{'after um':>9} {'max dq deg':>10}  status"]
    for r in rows:
        def f(x, fmt):
            return format(x, fmt) if x is not None else "-"
        note = r.reason or ("; ".join(r.warnings) if r.warnings else "")
        out.append(f"{r.line:>6}  {r.instruction:<10} {r.target[:28]:<28} {f(r.error_um, '9.1f')} "
                   f"{f(r.error_deg, '9.4f')} {f(r.residual_um, '9.1e')} "
                   f"{f(r.max_joint_change_deg, '10.4f')}  {r.status}"
                   + (f": {note}" if note else ""))
    s = summ
    out.append("")
    line = f"{s['compensable']} of {s['targets']} target uses compensable"
    if s["not_compensable"]:
        line += f", {s['not_compensable']} not compensable"
    if s["untouched"]:
        line += f", {sum(s['untouched'].values())} untouched"
    out.append(line)
    for reason, n in sorted(s["untouched"].items()):
        out.append(f"  untouched ({n}): {reason}")
    if s["error_before_um"]:
        out.append(f"predicted TCP error without compensation: max {s['error_before_um']['max']:.1f} um, "
                   f"mean {s['error_before_um']['mean']:.1f} um -> after: max "
                   f"{s['residual_after_um']['max']:.1e} um")
    return "\n".join(out) + "\n"

"""`rapidcomp check`: the plan of `fix`, solved, without the rewrite.

For each target use: the joints the controller computes (and by which
rule), the TCP error those joints give on the deformed robot (the error of
the uncompensated program), and whether compensation succeeds, with its
residual. The same plan, solve and rows as `fix`: what check predicts is
what fix does, up to the float32 rounding of the written numbers.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..collector import paused
from ..kinematics.ik import Solver
from .place import groups
from .plan import Plan, Task
from .rows import UNTOUCHED, Rows, limits_note, summary, use_rows
from .solve import solve

OK, FAILED = "compensable", "not compensable"


@dataclass(frozen=True)
class CheckResult:
    program: str
    rows: Rows
    notes: tuple[str, ...]
    modules: int = 1      # the task's: places name their module where it has several

    @property
    def failed(self) -> int:
        return self.rows.column("status").count(FAILED)

    def summary(self) -> dict:
        return summary(self.rows, OK, FAILED)


def check(task: Task, solver: Solver, track=(), start=None, base=None) -> CheckResult:
    with paused():   # millions of acyclic objects at CAM scale (collector.py)
        return _check(task, solver, track, start, base)


def _check(task, solver, track, start, base) -> CheckResult:
    plan = Plan(task, track, base)
    solved = solve(plan, solver, start)
    # fix's groups (with its default --emit): an array element that cannot
    # be compensated fails its array there, and check says so too.
    gs = groups(plan, solved, "auto", solver.options.wrist_fallback_deg)
    group_of = {u.key: g for g in gs for u in g.uses}
    rows = use_rows(plan, solved, group_of=group_of, statuses=(OK, FAILED))
    limits = limits_note(rows, solver.nominal_robot)
    return CheckResult(task.name, rows, tuple(plan.notes()) + ((limits,) if limits else ()),
                       len(task.files))


def render_text(result: CheckResult) -> str:
    rows = result.rows
    # (As fix says places: with the module's name where the task has several.)
    several = result.modules > 1
    places = [f"{r.file}:{r.line}" if several else str(r.line) for r in rows]
    w = max([6] + [len(p) for p in places])
    out = [f"{result.program}: predicted error on the warm robot, per target",
           f"{'line':>{w}}  {'instruction':<11} {'target':<28} {'error um':>9} {'error deg':>9} "
           f"{'after um':>9} {'after deg':>9}  status"]
    for r, where in zip(rows, places):
        def f(x, fmt):
            # (A cell with no number keeps the column's width: "-" under it.)
            return format(x, fmt) if x is not None else "-".rjust(int(fmt.split(".")[0]))
        note = r.reason or ("; ".join(r.warnings) if r.warnings else "")
        # (A longer target cut where the cut shows: Offs(pTab,0,0,100 is not
        # Offs(pTab,0,0,1000).)
        target = r.target if len(r.target) <= 28 else r.target[:25] + "..."
        out.append(f"{where:>{w}}  {r.instruction:<11} {target:<28} "
                   f"{f(r.error_um, '9.1f')} {f(r.error_deg, '9.4f')} {f(r.residual_um, '9.1e')} "
                   f"{f(r.residual_deg, '9.1e')}  {r.status}" + (f" [{r.rule}]" if r.rule else "")
                   + (f": {note}" if note else ""))
    s = result.summary()
    out.append("")
    line = f"{s[OK]} of {s['target_uses']} target uses compensable"
    if s[FAILED.replace(' ', '_')]:
        line += f", {s[FAILED.replace(' ', '_')]} not compensable"
    if s["untouched"]:
        line += f", {sum(s['untouched'].values())} untouched"
    out.append(line)
    # The untouched and the failures as fix's summary says them, with their
    # places; alike failures in one line (313 rows of one long reason: its
    # advice said once).
    from .report import failure_lines, untouched_lines  # (report.py imports fix.py)
    out += [f"  {line}" for line in untouched_lines(result.rows, s["untouched"], several)]
    out += [f"  {line}" for line in failure_lines(
        [r for r in rows if r.status == FAILED], several, FAILED)]
    for note in result.notes:
        out.append(f"note: {note}")
    if s["error_before_um"]:
        n = s["compensable"]
        of = "" if n == s["target_uses"] else f" (the {n} compensable uses)"
        out.append(f"predicted TCP error without compensation{of}: max "
                   f"{s['error_before_um']['max']:.1f} um, mean "
                   f"{s['error_before_um']['mean']:.1f} um -> after: max "
                   f"{s['residual_after_um']['max']:.1e} um")
    return "\n".join(out) + "\n"

"""`rapidcomp fix`: compensate every statically known target of a task and
splice the new values into its modules' text.

Pipeline, one module per stage: plan (resolve every target use, follow the
task's flow) -> solve (the controller's nominal solution, then the
deformed robot's) -> place (group uses by where their value is written)
-> edit (span edits per module) -> verify (parse the output again and
evaluate every written value with float32 numbers) -> rows and report.

Modes. auto (default): MoveJ becomes MoveAbsJ on a new jointtarget, every
other instruction keeps its kind (a MoveL keeps its straight line) and gets
a compensated robtarget. absj: MoveL becomes MoveAbsJ too. robtarget:
every instruction keeps its kind. A compensated robtarget is the pose the
ideal controller must be given so that its own IK lands on the compensated
joints. Never MoveAbsJ where program displacement may be active (MoveAbsJ
ignores it), where the controller may choose the configuration otherwise
than assumed, or for PERS targets (place.mode_of).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .. import side
from ..collector import paused
from ..edits import EditColumns, SpanEdit, apply_edits
from ..errors import InternalError
from ..kinematics.frames import DEG
from ..kinematics.ik import Solver
from ..process import release
from ..rapid import ast as A
from ..rewrite.diff import columns_diff, handed_off, unified_diff
from . import place as P
from .edit import Editor, Values
from .plan import Plan, Task, line_ranges
from .rows import (COMPENSATED, LINEAR_WARNING, NOT_COMPENSATED, PERS_COPY, Rows, limits_note,
                   summary, use_rows)
from .solve import Solving, nominal_ahead
from .takeback import take_back
from .targets import IDENTITY_POSE
from .verify import (VERIFY_DEG, VERIFY_UM, relex, relex_absj, relex_copies, relex_transient,
                     reparse, verify, verify_states, verify_states_relexed)

MODES = P.MODES


@dataclass(frozen=True)
class ModuleOutput:
    """One module of the task, as written (text == input when unedited)."""

    path: str                        # display path of the input module
    text: str
    # (A batch of plain literals' field edits as EditColumns: 7e5 of them
    # in a CAM program, no tuple each.)
    edits: tuple[SpanEdit, ...] | EditColumns
    diff: tuple[str, ...]


@dataclass(frozen=True)
class FixResult:
    mode: str
    program: str                     # display name of the task
    modules: tuple[ModuleOutput, ...]
    rows: Rows
    notes: tuple[str, ...]
    # Each row's number cells as the Markdown report writes them
    # (report.number_cells), made beside the job (side.py); None: made
    # when the report is written.
    cells: tuple[str | None, ...] | None = field(default=None, compare=False, repr=False)
    # Each row's JSON text from its nominal joints to its error
    # (report.json_cells), made beside the job where a JSON report is
    # wanted; None: made when the report is written.
    json_cells: tuple[str | None, ...] | None = field(default=None, compare=False, repr=False)

    @property
    def failed(self) -> int:
        return self.rows.column("status").count(NOT_COMPENSATED)

    @property
    def edits(self) -> tuple[SpanEdit, ...]:
        return tuple(e for m in self.modules for e in m.edits)

    def summary(self) -> dict:
        out = summary(self.rows, COMPENSATED, NOT_COMPENSATED)
        out["edits"] = sum(len(m.edits) for m in self.modules)   # (no tuple of 1e6 edits)
        out["modules_changed"] = sum(1 for m in self.modules if m.edits)
        return out


def fix(task: Task, solver: Solver, mode: str = "auto", timings: dict | None = None,
        track=(), output_names: dict | None = None, start=None, base=None,
        transient=None, json: bool = False) -> FixResult:
    """Compensate the modules of `task` (its context modules supply data
    only). Targets that cannot be compensated keep their text and are
    listed with the reason; whether to write such an output is the caller's
    decision (FixResult.failed). `timings`, when given, receives seconds per
    stage; output_names maps a module's display path to the name its diff
    shows for the output; base: world_M_base (R, p) of the robot, default
    the identity. transient: (Transient, {s: Solver of the robot deformed
    by s . profile}) writes the correction for the run-time thermal state
    (transient.py), verified at every s. json: a JSON report will be
    written (its numbers' texts are made beside the job, side.py)."""
    with paused():
        return _fix(task, solver, mode, timings, track, output_names or {}, start, base,
                    transient, json)


def _fix(task, solver, mode, timings, track, output_names, start, base,
         transient=None, json: bool = False) -> FixResult:
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}")
    clock = _Clock(timings)
    # (The nominal IK made beside the flow's analysis: solve.nominal_ahead.)
    plan = Plan(task, track, base, ahead=nominal_ahead(solver))
    clock("resolve")
    # The uses grouped as far as their nominal solutions decide, while the
    # deformed robot's IK is made beside (solve.Solving).
    solving = Solving(plan, solver, start)
    # (Inline literals and declarations read by one use alone are Singles,
    # not a Group each: a CAM program's 1e5.)
    gs = P.grouping(plan, solving, mode, solver.options.wrist_fallback_deg, singles=True)
    if transient is not None:
        # (A transient output's declared targets each make a new name: made
        # in the groups' order, as a Group each would make them.)
        for s in gs:
            if type(s) is P.Singles and s.declared:
                s.in_order = True
    # The plan's notes made meanwhile too: past the groups nothing reads the
    # flow (printing and verifying the values read the plan's uses and
    # resolver; the rows its uses and track).
    plan_notes = plan.notes()
    solved = solving.finish()
    solving = None
    P.settle(gs, solved, plan, mode)
    if not any(g.mode == "rob" for g in gs):
        # No robtarget is written (a CAM program entered from main: 1e5
        # MoveAbsJ): the nominal FK of the compensated joints, which a
        # robtarget's value is made of (edit.Values), is not needed (~10 MB
        # off the peak, which is the printing's and the verification's).
        solved = replace(solved, flange_R=None, flange_p=None)
    clock("solve")
    cells = jcells = None
    # The flow's per-use states go before the values are printed and
    # verified (1e5 targets: ~50 MB off the peak; a later use of them fails
    # loudly).
    plan.flow = plan.by_key = None
    values = Values(plan, solved, solver.options.quadrant_tol_deg)
    state_errors: dict = {}
    # A written value that does not reproduce its compensated joints (the
    # ideal controller's IK lands elsewhere) fails its group; its edits are
    # taken back (takeback.py), or the rest is placed, written and verified
    # again without it.
    for _ in range(4):
        values.prepare(gs, transient is not None)
        if cells is None and side.helps():
            # The report's number cells of every target, made beside the
            # job while it places, edits and splices (side.py; without a
            # helper the report makes them).
            from .report import number_cells         # (report.py imports this module)
            cells = side.run(number_cells, solved.nominal.q_deg, solved.deformed.q_deg,
                             solved.err_p, solved.err_r)
            if json:
                from .report import json_cells
                jcells = side.run(json_cells, solved.nominal.q_deg, solved.deformed.q_deg,
                                  solved.err_p, solved.err_r)
        P.place(plan, gs, solved)
        P.fill_slots(plan, solver, gs)
        editor = Editor(plan, values, transient is not None)
        # (In the groups' order: new names and declarations are made in it;
        # an element of Singles that makes one, at its place among them.)
        for g in P.apply_order(gs):
            if type(g) is tuple:
                editor.apply_new(*g)
            elif g.failure is None:
                editor.apply(g)
        file_edits = editor.file_edits()
        # The confdata written, as ints, for the rows (once per use here,
        # not per row later). Past this point the values, their texts and
        # the edits' index are not needed (1e5 targets: ~230 MB before
        # verification); a retry prepares them again.
        # (Only where a robtarget is written: a CAM program's 1e5 MoveAbsJ,
        # none; rows.use_rows reads a use not in it as none written.)
        done = [(g, n if type(g) is P.Singles else u.source.element, u)
                for g in gs if g.failure is None and g.mode == "rob"
                for n, u in enumerate(g.uses)]
        written_conf = dict(zip([u.key for _, _, u in done],
                                values.confs([(g, k) for g, k, _ in done])))
        done = None                   # (a tuple per use: not kept past here)
        values.forget()
        # Elements of Singles whose writing failed (a transient output's
        # confdata): each the Group of its own it is, which says why (past
        # the values keyed by element, which the split renumbers).
        by_singles: dict = {}
        for s, n, why in editor.failed:
            by_singles.setdefault(id(s), (s, [], []))
            by_singles[id(s)][1].append(n)
            by_singles[id(s)][2].append(why)
        for s, ns, whys in by_singles.values():
            for g, why in zip(P.split_off(gs, s, ns, plan.file_index, placed=True), whys):
                g.failure = why
        # (The new declarations are in the edits now, as texts of their own:
        # 1e5 MoveL turned into MoveAbsJ, ~18 MB of them twice.)
        editor.edits = editor.field_lists = None
        editor.inserts = None
        # (And the names taken: every word of the input and every new name,
        # 2e5 of them where each of 1e5 declared targets gets two, ~25 MB.)
        editor.names = None
        if transient is not None:
            release()
        texts = {fi: apply_edits(plan.files[fi].source.text, es)
                 for fi, es in file_edits.items()}
        clock("print")
        # Numbers edited, moves turned into MoveAbsJ on jointtargets of
        # their own, and targets some uses read as copies of their own: what
        # was written is read again where the output holds it; any other
        # structural edit: the output is parsed again.
        written = converted = calls = None
        if transient is None and not editor.others:
            written = relex(plan, editor.fields, file_edits, texts)
            if written is not None and editor.converted:
                converted = relex_absj(plan, editor.converted, file_edits, texts,
                                       bool(editor.copies))
                written = None if converted is None else written
            if written is not None and editor.copies:
                written = relex_copies(plan, editor.copies, file_edits, texts, written)
        elif (transient is not None and not editor.calls_other and editor.calls
              and not plan.track):
            # (Every target an rcTcR/rcTcJ of a value read again: those
            # statements and declarations read again. A track moves the
            # base with each target's own axes: verify_states_relexed does
            # not take one.)
            calls = relex_transient(plan, editor.calls, file_edits, texts)
        editor.fields = editor.converted = editor.calls = editor.copies = None
        lexed = written is not None or calls is not None
        out_files = reparse(plan, texts) if not lexed else {}
        clock("re-lex" if lexed else "re-parse")
        keys = [u.key for g in gs if g.failure is None for u in g.uses]
        if transient is None:
            verified = verify(plan, solved, keys, out_files, solver,
                              written, converted) if keys else {}
        else:
            verified, state_errors = _verify_states(plan, solved, keys, out_files,
                                                    transient[1], calls, texts)
        clock("verify")
        missed = _missed(solved, gs, verified, plan.file_index)
        if not missed:
            break
        split = False
        for g, (u, um, deg) in missed.items():
            split |= P.fail(gs, g, u, solved, (
                f"the written value would miss by {um:.3f} um / {deg:.2e} deg: the ideal "
                "controller's IK does not land on the compensated joints here",
                u.source.element))
        # Where each group that misses wrote its literals alone, its edits
        # are taken back and the rest stays as written and verified
        # (takeback.py); else every group is placed, written and verified
        # again.
        # (written: the output was read back by re-lexing it; never so in
        # transient mode.)
        taken = (take_back(plan, gs, list(missed), file_edits, texts)
                 if written is not None and not split else None)
        if taken is not None:
            file_edits, texts = taken
            gone = {u.key for g in missed for u in g.uses}
            verified = {k: v for k, v in verified.items() if k not in gone}
            written_conf = {k: c for k, c in written_conf.items() if k not in gone}
            for k in gone:
                editor.actions.pop(k, None)
            for g in missed:
                g.placement = None
            clock("print")
            break
    else:
        raise InternalError("the written values do not settle (verification keeps failing)")
    # The diff of the largest module edited, made beside the job while the
    # rows are made (side.py); the others' here.
    diffs = {}
    if side.helps() and file_edits:
        fi = max(file_edits, key=lambda fi: len(texts[fi]))
        pf = task.files[fi]
        name = pf.source.display_path
        diffs[fi] = side.run(columns_diff, pf.source.text, handed_off(file_edits[fi]), name,
                             output_names.get(name, name))
    group_of = {u.key: g for g in gs for u in g.uses}
    # What each stage made per target is not needed past it (1e5 targets:
    # hundreds of MB): the edited literals as written, the output parsed
    # again; of the editor the rows read what it did per use only.
    actions, cold = editor.actions, (editor.cold_moves, editor.cold_inline, editor.cold_copies)
    pers_copies = editor.pers_copies if transient is not None else None
    values = written = converted = calls = out_files = editor = keys = None
    # The rows read the plan's uses and track only: the resolver's caches
    # go before the rows are made (a later use of them fails loudly).
    plan.resolver = None
    # (What malloc holds free handed back before the rows' 1e5 tuples are
    # made: in the command's own process, process.py.)
    release()
    at: list | None = [] if cells is not None or jcells is not None else None
    rows = use_rows(plan, solved, group_of=group_of, actions=actions, verified=verified,
                    written_conf=written_conf, at=at, pers_copies=pers_copies)
    notes = plan_notes + _notes(rows, gs, transient is not None)
    limits = limits_note(rows, solver.nominal_robot)
    if limits:
        notes.append(limits)
    if transient is not None:
        notes += _transient_notes(transient[0], state_errors if any(
            r.status == COMPENSATED for r in rows) else {}, *cold)
    # Past the rows the plan, the solutions, the groups and the actions are
    # not needed (1e5 targets: some 300 MB the diffs and the report reuse
    # instead of growing the process further).
    plan = solved = gs = actions = group_of = written_conf = verified = None
    release()
    # (The cells taken from the helper into what those freed.)
    cells, jcells = (None if p is None else _by_row(p.get(), at) for p in (cells, jcells))
    at = None
    modules = []
    for fi, pf in enumerate(task.files):
        es = file_edits.get(fi, [])
        name = pf.source.display_path
        diff = (diffs[fi].get() if fi in diffs else
                unified_diff(pf.source.text, es, name, output_names.get(name, name),
                             new_text=texts.get(fi)))
        modules.append(ModuleOutput(name, texts.get(fi, pf.source.text),
                                    es if type(es) is EditColumns else tuple(es), tuple(diff)))
    clock("report")
    return FixResult(mode, task.name, tuple(modules), rows, tuple(notes), cells, jcells)


def _by_row(made: list, at: list) -> tuple:
    """Each report row's entry of `made` (one per solved row; at: each
    row's solved row, None for a use not solved)."""
    return tuple(None if i is None else made[i] for i in at)


def _verify_states(plan, solved, keys, out_files, solvers, calls=None,
                   texts=None) -> tuple[dict, dict]:
    """Transient: the written program (out_files: parsed again; or calls,
    what relex_transient read of it) at every thermal state s, each
    rcTcJ/rcTcR(cold, dq) evaluated as the controller does, verified on the
    robot deformed by s . profile. Per use the worst state's residual; per
    state the worst use's."""
    if keys and calls is not None:
        got = verify_states_relexed(plan, solved, keys, calls, solvers)
        if got is not None:
            return _worst(solved, solvers, *got)
        # (A use the numbers read do not serve: the output parsed again.)
        out_files = reparse(plan, texts)
    states = verify_states(plan, solved, keys, out_files, solvers) if keys else {}
    # (Every state's residuals of the same uses: as the arrays _worst takes.)
    order = list(states[next(iter(solvers))]) if states else []
    um, deg = (np.array([[states[s][k][n] for k in order] for s in solvers],
                        float).reshape(len(solvers), len(order)) for n in (0, 1))
    return _worst(solved, solvers, order, um, deg)


def _worst(solved, solvers, keys: list, um: np.ndarray, deg: np.ndarray) -> tuple[dict, dict]:
    """_verify_states' figures of residuals (row n of um, deg: state n's of
    every use of keys): per use the worst state's (Python's max(a, b): b
    where b > a, else a), per state the worst use's, a wrist-singular
    target's orientation left out (what the wrist can hold: its row says
    what is left)."""
    left = solved.deformed.residual_rad.tolist()
    row = solved.row
    held = np.array([left[row[k]] / DEG <= VERIFY_DEG for k in keys], bool).reshape(-1)
    by_state = {s: (max(um[n].tolist() or [0.0]), max(deg[n][held].tolist() or [0.0]))
                for n, s in enumerate(solvers)}
    worst_um, worst_deg = np.zeros(len(keys)), np.zeros(len(keys))
    for n in range(len(solvers)):
        worst_um = np.where(um[n] > worst_um, um[n], worst_um)
        worst_deg = np.where(deg[n] > worst_deg, deg[n], worst_deg)
    return dict(zip(keys, zip(worst_um.tolist(), worst_deg.tolist()))), by_state


def _transient_notes(tr, state_errors: dict, cold_moves: int = 0, cold_inline: int = 0,
                     cold_copies: list[str] = ()) -> list[str]:
    from .transient import FUNC_J, FUNC_R, MODULE_FILE
    figures = "; ".join(f"s={s:g}: {um:.3f} um / {deg:.1e} deg"
                        for s, (um, deg) in sorted(state_errors.items()))
    if not state_errors:
        # (Whether anything is written is the command's: without
        # --allow-partial nothing is, and the note must not say otherwise.)
        return [f"transient: no target compensated; where the output is written "
                f"(--allow-partial), {MODULE_FILE} is written with it (state law: {tr.law})."]
    other = []
    if cold_moves:
        # (A robtarget's confdata is one for every state: where the warm
        # robot needs another quadrant of J1, J4 or J6 and the cold joints
        # are within the quadrant tolerance of it too, the cold value takes
        # it.)
        where = []
        declared = cold_moves - cold_inline
        if declared:
            shown = ", ".join(cold_copies[:3]) + (", ..." if len(cold_copies) > 3 else "")
            where.append(f"{declared} read from {len(cold_copies)} "
                         f"cop{'ies' if len(cold_copies) != 1 else 'y'} of declared targets "
                         f"({shown})")
        if cold_inline:
            where.append(f"{cold_inline} inline")
        other.append(f"transient: {cold_moves} target use{'s' if cold_moves != 1 else ''} of "
                     f"robtarget moves carr{'y' if cold_moves != 1 else 'ies'} a cold value "
                     "with other confdata "
                     f"than written, the one every thermal state needs: {', '.join(where)}; "
                     "the warm robot needs another quadrant of J1, J4 or J6 and the cold robot's "
                     "joints are within the quadrant tolerance of it too (the rows say which).")
    return other + [
        f"transient: each compensated move goes to {FUNC_J}(cold, dq) (MoveAbsJ) or "
        f"{FUNC_R}(cold, dq) (a robtarget move, which keeps its kind) = the cold robot's "
        "target + s x the warm robot's correction; load "
        f"{MODULE_FILE} (written next to the output) into the same task. State law: "
        f"{tr.law}.",
        "transient: the written numbers evaluated as the controller computes them (float32) "
        "at every thermal state, on the robot deformed by s x profile, worst target: "
        f"{figures} (what is left beyond float32 rounding is the linearisation q_cold + "
        "s x dq, second order in the deformation; the orientation of a wrist-singular "
        "target is in its row)."]


def _missed(solved, gs, verified, file_index: dict) -> dict:
    """Groups with a use whose written value misses its pose beyond the
    bound (the orientation bound widened by what a wrist-singular MoveAbsJ
    leaves over): group -> (use, um, deg). An element of Singles that
    misses is taken out of it into gs as the Group of its own it is."""
    # A use misses only beyond both bounds' floors: where none does (a CAM
    # program's 1e5 uses), no group needs looking at.
    if not any(um > VERIFY_UM or deg > VERIFY_DEG for um, deg in verified.values()):
        return {}
    out = {}
    # (Each row's residual in degrees converted once, not a numpy scalar per
    # use: the same division of the same doubles.)
    lefts = (solved.deformed.residual_rad.astype(float) / DEG).tolist()
    row = solved.row

    def miss(u) -> tuple | None:
        um, deg = verified[u.key]
        if um > VERIFY_UM or deg > max(VERIFY_DEG, lefts[row[u.key]] + VERIFY_DEG):
            return u, um, deg
        return None
    for g in list(gs):
        if g.failure is not None:
            continue
        if type(g) is P.Singles:
            # (Each a Group of its own, as it would be: that one fails.)
            missed = [(n, got) for n, got in enumerate(map(miss, g.uses)) if got is not None]
            ones = P.split_off(gs, g, [n for n, _ in missed], file_index, placed=True)
            out.update(zip(ones, [got for _, got in missed]))
            continue
        got = next((x for x in map(miss, g.uses) if x is not None), None)
        if got is not None:
            out[g] = got
    return out


def _file_lines(by_file: dict[str, set]) -> str:
    """`a.mod: lines 3-7, 9; b.mod: lines 2` of lines by file."""
    return "; ".join(f"{f}: lines {line_ranges(sorted(by_file[f]))}" for f in sorted(by_file))


def _notes(rows: Rows, gs: list[P.Group], transient: bool = False) -> list[str]:
    notes = []
    # The lines of the moves turned into MoveAbsJ, by file (a set of ints
    # each: 1e5 of a CAM program, no tuple each to sort).
    absj: dict[str, set] = {}
    for file, line, warnings in zip(rows.column("file"), rows.column("line"),
                                    rows.column("warnings")):
        if LINEAR_WARNING in warnings:
            lines = absj.get(file)
            if lines is None:
                lines = absj[file] = set()
            lines.add(line)
    # (What keeps MoveL linear: --emit robtarget, which --transient does not
    # take; there --emit auto, a MoveL kept with rcTcR.)
    keep = "--emit auto" if transient else "--emit robtarget"
    if absj:
        notes.append("MoveL -> MoveAbsJ gives up the straight-line path between points "
                     f"({_file_lines(absj)}); use {keep} to keep MoveL linear.")
    # Moves --emit would turn into MoveAbsJ that stay robtarget moves for
    # what they are (PERS data, named external axes, an optional argument
    # MoveAbsJ has not, ...; a caution or program displacement has its own
    # word): the output's MoveL are meant, each row says why.
    kept: dict[str, set] = {}
    for g in gs:
        if g.why_kept and g.failure is None:
            for u in g.uses:
                if u.key in g.why_kept:
                    kept.setdefault(u.file.source.display_path, set()).add(u.line)
    if kept:
        n = sum(len(v) for v in kept.values())
        notes.append(f"kept robtarget moves, not turned into MoveAbsJ: {n} "
                     f"statement{'s' if n != 1 else ''} ({_file_lines(kept)}); the report's "
                     "rows say why (PERS data, named external axes, an argument MoveAbsJ has "
                     "not, ...)")
    # A move turned into MoveAbsJ goes to joints computed with its tool and
    # work object as declared; the robtarget move followed a change to them
    # (a TCP calibration, a user frame redefined on the FlexPendant).
    frames: dict[str, str] = {}         # (RAPID's names: one whatever their case)
    assigned = False                    # (some as a routine assigns them: RoboDK's)
    # (Moves lexed as one token name their tool and work object in their
    # shared tail: read once per tail, not made from the text of each of a
    # CAM program's 1e5 moves.)
    tails: set = set()
    # (In the order of a Group each: a name's first spelling is said.)
    for g, u in P.uses_in_order(gs):
        if g.mode == "absj" and g.failure is None and u.kind == "robtarget":
            m = u.motion
            # (The controller's own tool0 and wobj0, which nothing changes,
            # are not named; a module's own data of that name is. The
            # resolver gives the controller's as its one identity pose: the
            # uses here are the ones it made, in this process.)
            builtin = (u.tool[1] is IDENTITY_POSE, u.wobj[1] is IDENTITY_POSE)
            if type(m.args) is not A.TailArgs or (m.roles, m.args.tail, builtin) not in tails:
                if type(m.args) is A.TailArgs:
                    tails.add((m.roles, m.args.tail, builtin))
                for ref, controllers in zip((m.tool, m.wobj), builtin):
                    if type(ref) is A.Ref and not controllers:
                        frames.setdefault(ref.name.lower(), ref.name)
            assigned = assigned or any("@" in x[0] for x in (u.tool, u.wobj) if x)
    if frames:
        notes.append("the moves turned into MoveAbsJ go to joints computed with "
                     + ", ".join(frames[k] for k in sorted(frames))
                     + (" as the modules declare or assign them" if assigned
                        else " as the modules declare them")
                     + ": a MoveAbsJ does not follow a later change to a tool or work object "
                     "(a TCP calibration, a user frame redefined on the FlexPendant) as the "
                     "robtarget move did; after one, run rapidcomp again, or keep "
                     + ("MoveL robtarget moves with --emit auto." if transient
                        else "robtarget moves with --emit robtarget."))
    # Copies of declared targets (not the MoveAbsJ jointtargets, which the
    # note above and the rows say; nor a transient output's constants, which
    # its own note says): a target its uses need at other values
    # (Offs/RelTool of it, other tools or configurations), one copy per
    # value, or one that is not edited in place (place.place). An
    # Offs-relative CAM program gets 1e5: the module doubles.
    copies: dict[str, list[str]] = {}
    for g in () if transient else gs:
        # (names: none where no number changes, a copy made of nothing.)
        if type(g) is not P.Singles and g.failure is None and g.mode != "absj" \
                and g.placement == "new" and g.names:
            copies.setdefault("robtarget" if g.mode == "rob" else "jointtarget",
                              []).extend(g.names.values())
    if copies:
        kinds = sorted(copies.items())
        many = sum(len(v) for _, v in kinds) > 1
        notes.append(
            "new declarations: "
            + " and ".join(f"{len(v)} {k}{'s' if len(v) != 1 else ''}" for k, v in kinds)
            + (", compensated copies of declared targets (" if many
               else ", a compensated copy of a declared target (")
            + "; ".join(v[0] + (", ..." if len(v) > 1 else "") for _, v in kinds)
            + "): where a target itself cannot serve a use compensated (its other uses need "
            "it at another value: Offs/RelTool of it, another tool or configuration; or it is "
            "not edited in place: data of a --with module, PERS another task shares, a name "
            "read outside moves), the use reads a copy; the report's rows name it")
    # PERS targets some moves now read through a CONST copy (rows._row's
    # warning): said once here too, the ModPos it costs being the user's
    # business before the robot's.
    pers: dict[str, int] = {}
    for warnings in rows.column("warnings"):
        for w in warnings:
            if PERS_COPY in w:
                name = w.split(PERS_COPY, 1)[0]
                pers[name] = pers.get(name, 0) + 1
    if pers:
        n = sum(pers.values())
        notes.append(f"{n} move{'s' if n != 1 else ''} now read{'' if n != 1 else 's'} a CONST "
                     f"copy of PERS data ({', '.join(sorted(pers))}): a change to "
                     f"{'them' if len(pers) > 1 else 'it'} at run time (ModPos, another task) "
                     f"no longer reaches {'those moves' if n != 1 else 'the move'}; the "
                     "report's rows say which")
    for g in gs:
        if g.slots:
            name = g.names.get("array", "the new jointtarget array")
            by_what: dict[str, list[int]] = {}
            for k, slot in sorted(g.slots.items()):
                by_what.setdefault(slot.what, []).append(k)
            notes.append(f"{name}: elements no executed move reaches ("
                         + ", ".join(P.element_label(g, k) for k in sorted(g.slots))
                         + ") hold " + "; ".join(
                             f"{what} ({', '.join(P.element_label(g, k) for k in ks)})"
                             if len(by_what) > 1 else what for what, ks in by_what.items()))
    return notes


class _Clock:
    def __init__(self, timings: dict | None):
        import time
        self.now = time.perf_counter
        self.timings = timings
        self.last = self.now()

    def __call__(self, stage: str) -> None:
        if self.timings is not None:
            t = self.now()
            self.timings[stage] = self.timings.get(stage, 0.0) + t - self.last
            self.last = t

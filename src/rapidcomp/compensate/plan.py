"""Stage 1 of `fix` and `check`: what a task moves to, and in which motion
state the controller runs each move.

A plan holds every target use of the task's motions (resolved to a flange
pose, or the reason it is not), and for each the state the flow analysis
found before it: configuration supervision, program displacement and the
moves that may have run just before. `check` stops after solving the plan;
`fix` goes on to place, edit and verify.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path, PurePath

from ..rapid.model import ParsedFile
from .flow import Flow, State, analyse
from .targets import EXTAX_UNUSED, Resolver, TargetUse, assigned_name


@dataclass(frozen=True)
class Task:
    """The modules of one task (written) and --with modules (read only)."""

    name: str
    files: tuple[ParsedFile, ...]
    context: tuple[ParsedFile, ...] = ()
    # Modules of the controller's other tasks: their writes to PERS data
    # count (PERS are shared between tasks), nothing else of them does.
    observers: tuple[ParsedFile, ...] = ()
    # The unit that moves the robot's base (a backup's MOC.cfg), if any.
    base_moved_by: str | None = None
    # The name `fix` makes its output's from: a module's file, a folder's
    # or backup's folder, a program file's folder (PROGRAM_comp).
    origin: str | None = None
    # The routines a backup's SYSPAR/SYS.cfg runs at events (lower case).
    event_routines: tuple[str, ...] = ()
    # The routine the program starts at (a backup's SYS.cfg -Entry).
    entry: str = "main"
    # Modules of the task that cannot be read (encrypted): taken as not
    # given; their paths in the task (a backup's from its folder).
    unreadable: tuple[str, ...] = ()
    # Another task's modules that cannot be read (a backup's): their writes
    # to shared PERS data are unknown.
    others_unreadable: tuple[str, ...] = ()
    # A backup's module files its backinfo.txt does not list (not read).
    unlisted: tuple[str, ...] = ()

    @property
    def all_files(self) -> list[ParsedFile]:
        return list(self.files) + list(self.context)


class Plan:
    def __init__(self, task: Task, track=(), base=None, ahead=None):
        """ahead(uses), when given, is called once the uses are resolved
        (their flange poses known), before the flow is analysed: what it
        returns is kept as `ahead` (solve.py hands the nominal IK off there,
        to be computed meanwhile)."""
        self.task = task
        self.files = task.all_files
        self.n_written = len(task.files)
        self.resolver = Resolver(self.files, track=track, base=base,
                                 observers=task.observers, moved_by=task.base_moved_by,
                                 events=task.event_routines, entry=task.entry,
                                 unreadable=task.unreadable, unlisted=task.unlisted)
        self.track = tuple(track)
        self.uses: list[TargetUse] = []
        for fi, pf in enumerate(task.files):
            mi = 0
            for m in pf.modules:
                self.uses.extend(self.resolver.resolve_all(pf, m, m.motions, (fi, mi)))
                mi += len(m.motions)
        self.resolver.poses()
        self.ahead = ahead(self.uses) if ahead is not None else None
        self.by_key = {u.key: u for u in self.uses}
        self.file_index = {id(pf): i for i, pf in enumerate(self.files)}
        self.flow: Flow = analyse(self.files, self.n_written, self.resolver, bool(track))
        if self.flow.measured:
            self._leave_measured()

    def _leave_measured(self) -> None:
        """Robtarget moves that may run under a program displacement set at
        run time are left as written: if the robot measured it (a search,
        CRobT, PDispOn reading where the robot is), the warm robot's error
        is in the displacement already, and a compensated target would
        count it twice (a MoveAbsJ is not displaced: it is compensated);
        and so are the moves whose position such a displacement may read."""
        def listed(at: list[str]) -> str:
            return "; ".join(at[:3]) + (f"; and {len(at) - 3} more" if len(at) > 3 else "")

        before, entry, read_by = self.flow.before, self.flow.entry, self.flow.read_by
        anywhere = self.flow.anywhere

        def left(u: TargetUse) -> TargetUse:
            if u.reason is not None:
                return u
            if anywhere:
                return replace(u, reason=f"a program displacement set at run time ({anywhere}) "
                               "may read where "
                               "any move leaves the robot: compensated, the displacement "
                               "would change with it; left as written")
            if u.key in read_by:
                return replace(u, reason="a program displacement set at run time "
                               f"({read_by[u.key]}) may read where this move leaves the "
                               "robot (PDispOn without \\ExeP does; a frame or \\ExeP "
                               "made with CRobT(), CPos() or CJointT(), which a task "
                               "calls, may): "
                               "compensated, the displacement would change with it; left "
                               "as written")
            st = before.get(u.key, entry)
            if u.kind == "robtarget" and st.measured:
                at = st.measured_at() or self.flow.measured
                return replace(u, reason="may run under a program displacement set at run "
                               f"time ({listed(at)}): if the robot measured it, its thermal "
                               "error is in the displacement already, and compensating would "
                               "count it twice; left as written")
            return u
        self.uses = [left(u) for u in self.uses]
        self.by_key = {u.key: u for u in self.uses}

    def _compensated_before(self) -> list[str]:
        """Declarations named as rapidcomp names its new values (jt_<name> for
        a robtarget's jointtarget, <name>_c for a robtarget copy) next to
        the target they come from."""
        decls = [d for pf in self.task.files for m in pf.modules for d in m.declarations]
        rob = {d.name.lower() for d in decls if d.type == "robtarget"}

        def from_robtarget(rest: str) -> bool:
            # pA, pA_offs, pA_2: the robtarget's name, then suffixes.
            parts = rest.split("_")
            return any("_".join(parts[:k]) in rob for k in range(1, len(parts) + 1))

        out = []
        for d in decls:
            name = d.name.lower()
            head, _, tail = name.rpartition("_c")
            if (d.type == "jointtarget" and name.startswith("jt_") and from_robtarget(name[3:])) \
                    or (d.type == "robtarget" and head in rob and (tail == "" or tail.isdigit())):
                out.append(d.name)
        return sorted(out)

    def _named_as_output(self) -> list[str]:
        """The task's folder and module files named as `fix` names its
        output by default (PROGRAM_comp.mod, a folder PROGRAM_comp: a
        backup's, or the folder of a program file)."""
        names = [Path(self.task.name).name, self.task.origin or ""] + [
            part for pf in self.task.files for part in PurePath(pf.source.display_path).parts]
        return sorted({n for n in names if PurePath(n).stem.lower().endswith("_comp")})

    def state(self, u: TargetUse) -> State:
        """The motion state before a use (where the flow never reached it:
        as entered from outside)."""
        return self.flow.state(u.key)

    def state_held(self, u: TargetUse) -> State:
        """state(u) as the flow holds it: a run's moves share one, its last
        read by last() and one_before()."""
        return self.flow.before.get(u.key, self.flow.entry)

    def last(self, u: TargetUse, st: State) -> frozenset | None:
        """The uses that may have run last before u (st: state_held(u))."""
        return self.flow.last(u.key, st)

    def one_before(self, u: TargetUse, st: State):
        """The one key in last(u, st), or None."""
        return self.flow.one_before(u.key, st)

    def may_be_displaced(self, u: TargetUse) -> bool:
        # (state(u)'s, asked of every move: without the call.)
        return self.flow.before.get(u.key, self.flow.entry).may_be_displaced

    def order(self) -> list[TargetUse]:
        """Uses in the order the controller reaches them first; uses the
        flow never reached come last, in text order."""
        seen = set()
        out = []
        for key in self.flow.order:
            u = self.by_key.get(key)
            if u is not None and key not in seen:
                seen.add(key)
                out.append(u)
        out += [u for u in self.uses if u.key not in seen]
        return out

    def notes(self) -> list[str]:
        out = list(self.flow.notes)
        if self.task.unreadable:
            many = len(self.task.unreadable) > 1
            they, them, their = ("they", "them", "their") if many else ("it", "it", "its")
            out.append(f"{', '.join(self.task.unreadable)} {'are' if many else 'is'} encrypted: "
                       f"rapidcomp cannot read {them} and takes {them} as "
                       f"{'modules' if many else 'a module'} not given: names only {they} "
                       f"declare{'' if many else 's'} are not resolved (the moves that need "
                       f"them left as written), the state after a call of {their} routines is "
                       f"not known, and an assignment in {them} to a target this output "
                       "compensates would replace its compensated value at run time; written "
                       f"to the output as {'they were' if many else 'it was'}")
        if self.task.others_unreadable:
            many = len(self.task.others_unreadable) > 1
            out.append(f"{', '.join(self.task.others_unreadable)}, of another task, "
                       f"{'are' if many else 'is'} encrypted: a write of "
                       f"{'theirs' if many else 'its'} to PERS data this task shares is not "
                       "known (an assignment to a target this output compensates would "
                       "replace its compensated value at run time)")
        # Tools and work objects a routine assigns (resolver._sites): said
        # once, with where.
        taken = sorted({key.split("@")[0] for u in self.uses if u.reason is None
                        for key in (u.tool[0] if u.tool else "", u.wobj[0] if u.wobj else "")
                        if "@" in key})
        if taken:
            sites = self.resolver.site_map()
            # (Per name, each data of it that routines assign: {routine: Sites}.)
            datas = {n: [d for d in sites[n].values() if type(d) is dict]
                     for n in taken if n in sites}
            said = "; ".join(_assigned_at([a for d in ds for hit in d.values()
                                           for a in hit.assigns]) for ds in datas.values())
            parts = any(hit.parts for ds in datas.values() for d in ds for hit in d.values())
            # (Several routines: of one data, or each of its own data of one
            # name, LOCAL in two modules.)
            several = any(len(ds) > 1 or any(len(d) > 1 for d in ds) for ds in datas.values())
            out.append(("assigned by the routines: " if several else
                        "assigned by the routine that moves with them: ")
                       + f"{said}; each move "
                       + ("is solved with the value its own routine assigned last before it"
                          if several else
                          "there is solved with the value assigned last before it")
                       + (" (a component: with the rest of the value as declared, or as "
                          "assigned whole before it; " if parts else " (")
                       + ("moves before their routine's first assignment, and in routines "
                          "that assign none, run" if several else
                          "moves before the first assignment, and in other routines, run")
                       + " with a value not known here: left as written)")
        again = self._compensated_before()
        named = self._named_as_output()
        if again or named:
            why = []
            if again:
                why.append(", ".join(again[:3]) + (", ..." if len(again) > 3 else "")
                           + " are the names rapidcomp gives its values")
            if named:
                # (A program whose compensated values are all inline, as
                # RoboDK writes them, keeps every name: only its file's
                # name tells.)
                why.append(", ".join(named[:3]) + (", ..." if len(named) > 3 else "")
                           + " named as rapidcomp names its output")
            out.append("this program looks compensated already (" + "; ".join(why) + "): "
                       "compensating it again adds the correction twice; compensate the "
                       "original program")
        if self.task.base_moved_by and not self.track:
            out.append(f"SYSPAR/MOC.cfg says {self.task.base_moved_by} moves the robot's base: "
                       "robtarget moves are not compensated until --track AXIS:x|y|z names "
                       "its external axis and direction; MoveAbsJ targets (joints, relative "
                       "to the base) are, their external axis values copied as written")
            return out
        # (Each external axes' tuple looked at once: a CAM program's 1e5 uses
        # share a few.)
        used: dict = {}
        for u in self.uses:
            if u.reason is None and id(u.ext) not in used:
                used[id(u.ext)] = any(abs(v) < EXTAX_UNUSED for v in u.ext)
        active = [u for u in self.uses if u.reason is None and used[id(u.ext)]]
        if active:
            axes = sorted({"abcdef"[i] for u in active for i, v in enumerate(u.ext)
                           if abs(v) < EXTAX_UNUSED})
            tracked = {"abcdef"[k] for k, _ in self.track}
            free = [a for a in axes if a not in tracked]
            files = sorted({u.file.source.display_path for u in active})
            lines = "; ".join(f"{f} lines " + line_ranges(sorted(
                {u.line for u in active if u.file.source.display_path == f})) for f in files)
            if free:
                out.append(
                    f"{len(active)} target uses carry external axis values (eax_"
                    f"{', eax_'.join(free)}; {lines}): assumed not to move the robot's "
                    "base (as with a positioner); they are copied as written. If an axis "
                    "carries the robot, say so with --track AXIS:x|y|z.")
            if tracked & set(axes):
                out.append(
                    "track axes (--track " + ", ".join(sorted(tracked & set(axes))) + ") move "
                    "the robot's base: each target is solved relative to the base at its own "
                    "track position, and a MoveAbsJ keeps the track value.")
        return out


def _assigned_at(assigns: list) -> str:
    """What assignments ((ParsedFile, Assign)) assign, and where, by file:
    "rdkTool (a.mod lines 6, 12)"."""
    by_file: dict = {}
    for pf, a in assigns:
        by_file.setdefault(pf.source.display_path, []).append(pf.line(a.span))
    return (", ".join(dict.fromkeys(assigned_name(a) for _, a in assigns)) + " ("
            + "; ".join(f"{f} " + ("line " if len(ls) == 1 else "lines ")
                        + line_ranges(sorted(ls)) for f, ls in by_file.items()) + ")")


# Ranges a list of lines names; past them the count of the lines left (a
# CAM program's notes would name thousands, on one line of the output).
LISTED_RANGES = 10


def line_ranges(lines: list[int]) -> str:
    out = []
    counts = []
    start = prev = lines[0]
    for x in lines[1:] + [None]:
        if x is not None and x == prev + 1:
            prev = x
            continue
        out.append(str(start) if start == prev else f"{start}-{prev}")
        counts.append(prev - start + 1)
        if x is not None:
            start = prev = x
    if len(out) > LISTED_RANGES + 1:
        return (", ".join(out[:LISTED_RANGES])
                + f" and {sum(counts[LISTED_RANGES:])} more lines")
    return ", ".join(out)


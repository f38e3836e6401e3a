"""Stage 3 of `fix`: which uses share one written value, and where it goes.

A group is the set of target uses whose compensated value is written in
one place: the same literal (declaration, array or inline aggregate), the
same Offs/RelTool, tool and work object, and the same solution (a target
reached on two configurations needs two values). Placement:

* "inline": the inline aggregate itself (or, for MoveAbsJ, a new inline
  jointtarget);
* "in place": the declaration is edited, when every reference to it in the
  task is one of the group's uses and its module is written;
* "new": a new declaration next to the source one, referenced instead
  (LOCAL when every use is in its module), or in the using module when the
  source lies in a --with module.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType

import numpy as np

from ..errors import InputError
from ..kinematics.ik import IKOptions, Solver, Warn
from ..rapid import ast as A
from ..rapid.model import Declaration, Module
from ..rapid.refs import reference_starts
from .plan import Plan
from .solve import Solved, Solving, same_joints, solve_slots
from .targets import NO_ROTATION, Source, TargetUse, flange_pose, named_part

MODES = ("auto", "absj", "robtarget")
# Optional arguments MoveJ/MoveL share with MoveAbsJ (RAPID Instructions
# manual); anything else (\Corr) keeps the instruction as it is.
ABSJ_OPTIONALS = frozenset({"conc", "id", "v", "t", "z", "inpos", "wobj", "tload"})
TO_ABSJ = frozenset({"movej", "movel"})
# Which instructions each mode turns into MoveAbsJ.
ABSJ_FROM = {"auto": frozenset({"movej"}), "absj": TO_ABSJ, "robtarget": frozenset()}
# A J4/J6 split a robtarget cannot carry: the wrist fallback's (the
# orientation partly left over) where J5 is within the singularity margin,
# where the controller's IK, not the written pose, decides the split. Past
# the margin the pose decides it (its IK gives the compensated joints back;
# the output's verification checks the written numbers do).
# (Plain bits: an IntFlag's & costs ~3 us per group.)
_LEFT = int(Warn.ORIENTATION_LEFT | Warn.WRIST_SINGULAR)


# A group's names or slots before any is written (writable() gives a dict
# of its own to write).
NONE: Mapping = MappingProxyType({})


def writable(m: Mapping) -> dict:
    return {} if m is NONE else m


@dataclass(eq=False, slots=True)
class Group:
    mode: str                        # "absj", "rob" or "joint"
    src: Source
    tool: tuple | None
    wobj: tuple | None
    home: tuple                      # (file index, Module) where new declarations go
    uses: list[TargetUse] = field(default_factory=list)
    array: bool = False              # all elements of the array (FOR-loop index)
    elements: list = field(default_factory=list)  # element indices reached, or [None]
    rows: dict = field(default_factory=dict)      # element -> row in Solved
    failure: tuple | None = None     # (why, element)
    placement: str | None = None     # "inline", "in place", "new"
    # (names and slots: NONE until written, one shared empty mapping, not
    # two empty dicts per group: a CAM program's 1e5 groups write none.)
    names: Mapping = field(default_factory=lambda: NONE)   # element (or "array") -> new name
    local: bool = True               # a new declaration is LOCAL to its module
    slots: Mapping = field(default_factory=lambda: NONE)   # unreached element -> (joints, what)
    rows_seen: dict = field(default_factory=dict)  # element -> first solved row (grouping)
    # A FOR-walked array's elements that only uses by a literal index read
    # (pArr{1} before FOR i FROM 2 ...) -> where the first of them is among
    # the uses grouping() walks: such an element that fails goes to a
    # Group of its own (settle), not failing the array's.
    outside: Mapping = field(default_factory=lambda: NONE)
    # Uses kept robtarget moves because other iterations of their statement
    # must stay ones (_one_statement).
    kept: frozenset = frozenset()
    # Use key -> why a move --emit would turn into MoveAbsJ stays a
    # robtarget move (kept_robtarget), for the report to say.
    why_kept: Mapping = field(default_factory=lambda: NONE)
    # Where its first use is among the uses grouping() walks: the groups'
    # order, which the editor keeps (new names and declarations are made in
    # it).
    first: int = 0
    # Elements of this FOR-walked array refused alone (_leave_out; the
    # failure of the first, (why, element)): it must write the array in
    # place, which keeps them as written for their moves.
    left_out: tuple | None = None
    # Why an element's failure refuses the others (rows: "written with it
    # as one array<this>"), where it is not plain.
    one_because: str = ""
    # src.decl (asked of every group again and again: a field, not a
    # property).
    decl: Declaration | None = field(init=False)

    def __post_init__(self) -> None:
        self.decl = self.src.decl

    def refuse_as_one(self, because: str) -> None:
        """This array, which left elements out as written (_leave_out),
        cannot keep them so after all (because: what would move their moves
        too): it fails as one, for the first of them."""
        self.failure, self.left_out = self.left_out, None
        self.one_because = because

    @property
    def home_module(self) -> Module:
        return self.home[1]

    def source(self, k) -> Source:
        """Element k's source (the group's own, or an array element's)."""
        if k is None or k == self.src.element:
            return self.src
        return replace(self.src, record=self.decl.value[k], element=k)

    def frames(self, k) -> tuple:
        """(tool, wobj) element k is written for: the group's."""
        return self.tool, self.wobj


@dataclass(eq=False, slots=True)
class Singles:
    """Inline literals of numbers each read by one use alone, not in a FOR
    loop, nor in Offs/RelTool (a CAM program's 1e5 moves), that compensate
    without failing: what a Group of one use each would be, held as columns
    (issue #14: no Group per target). Element n is uses[n] (its row in
    Solved rows[n]); written inline like such a group (Editor.apply). A
    use that fails (its solve, the wrist singularity, its verification)
    becomes a Group of its own (settle, single), which says why as a Group
    does; `groups(singles=False)` makes every one a Group (check, and the
    tests that compare the two)."""

    mode: str                        # "absj" or "rob", as Group.mode
    uses: list = field(default_factory=list)
    rows: list = field(default_factory=list)
    at: list = field(default_factory=list)     # each one's Group.first
    # Declared targets each read by its one use (rob: edited in place;
    # absj: a new jointtarget, made in the groups' order), not inline
    # literals.
    declared: bool = False
    # Its elements written in the groups' order even where they are not
    # turned into MoveAbsJ: a transient output's each make a new name
    # (<name>_dq) and declaration (fix.py sets it).
    in_order: bool = False
    # As a Group placed inline (declared: in place), nothing failed, no
    # name or slot written.
    failure: None = None
    placement: str | None = "inline"
    names: Mapping = field(default_factory=lambda: NONE)
    slots: Mapping = field(default_factory=lambda: NONE)
    array: bool = False
    decl: None = None
    kept: frozenset = frozenset()
    why_kept: Mapping = field(default_factory=lambda: NONE)

    @property
    def elements(self) -> range:
        return range(len(self.uses))

    def source(self, n: int) -> Source:
        return self.uses[n].source

    def frames(self, n: int) -> tuple:
        u = self.uses[n]
        return u.tool, u.wobj

    def single(self, n: int, file_index: dict, placed: bool = False) -> Group:
        """Element n as the Group of its one use grouping() makes
        (file_index: Plan.file_index); placed: as settle() and place()
        leave it (it compensates: inline, or in place)."""
        u = self.uses[n]
        src = u.source
        home = ((file_index[id(src.home)], src.home_module) if self.declared
                else (u.key[0], u.module))
        g = Group(self.mode, src, u.tool, u.wobj, home, first=self.at[n])
        g.uses.append(u)
        g.rows_seen[None] = self.rows[n]
        if placed:
            g.elements, g.rows = [None], g.rows_seen
            g.placement = self.placement
            g.local = u.module is home[1]
        return g

    def drop(self, ns) -> None:
        """Without elements ns."""
        gone = set(ns)
        self.uses = [u for n, u in enumerate(self.uses) if n not in gone]
        self.rows = [r for n, r in enumerate(self.rows) if n not in gone]
        self.at = [a for n, a in enumerate(self.at) if n not in gone]

    @property
    def ordered(self) -> bool:
        """Its elements are written in the groups' order (Editor.apply, in
        apply_order): each makes a new name and declaration."""
        return self.declared and (self.mode == "absj" or self.in_order)


def _runs(gs: list, singles) -> list:
    """The Groups of gs by Group.first, each element of the Singles
    `singles` at its own place among them (Singles.at): the order of a
    Group each; the elements of one Singles that come one after the other
    as one (Singles, [n, ...]). As arrays (1e5 elements: no tuple each to
    sort): by place among the uses walked, a Group before an element at
    the same place (none is: each is a use's own)."""
    groups = [g for g in gs if type(g) is not Singles]
    places = np.concatenate([np.array([g.first for g in groups], np.int64),
                             *(np.array(s.at, np.int64) for s in singles)])
    if not len(places):
        return []
    which = np.concatenate([np.full(len(groups), -1, np.int64),
                            *(np.full(len(s.at), k, np.int64) for k, s in enumerate(singles))])
    index = np.concatenate([np.arange(len(groups)), *(np.arange(len(s.at)) for s in singles)])
    by = np.argsort(places, kind="stable")
    which, index = which[by], index[by]
    # Runs: a Group each, else the elements of one Singles one after the other.
    cuts = np.flatnonzero((which[1:] != which[:-1]) | (which[1:] < 0)) + 1
    out: list = []
    for a, b in zip([0, *cuts.tolist()], [*cuts.tolist(), len(which)]):
        k = int(which[a])
        if k < 0:
            out.append(groups[int(index[a])])
        else:
            out.append((singles[k], index[a:b].tolist()))
    return out


def uses_in_order(gs: list) -> list:
    """(group or Singles, use) of every use of gs, group by group as the
    groups come, each element of Singles at its own place among them: the
    order of a Group each (what is said first of them is what a Group
    each says first)."""
    out = []
    for x in _runs(gs, [s for s in gs if type(s) is Singles]):
        if type(x) is tuple:
            s, ns = x
            out += [(s, s.uses[n]) for n in ns]
        else:
            out += [(x, u) for u in x.uses]
    return out


def apply_order(gs: list) -> list:
    """gs as the editor writes them: the groups in order, each element of
    Singles that makes a new name and declaration among them at its place,
    the elements of one Singles that come one after the other as one
    (Singles, [n, ...]), the other Singles after them (what they write does
    not depend on the order)."""
    ordered = [s for s in gs if type(s) is Singles and s.ordered]
    rest = [g for g in gs if not (type(g) is Singles and g.ordered)]
    if not ordered:
        return rest
    return _runs(rest, ordered) + [g for g in rest if type(g) is Singles]


def split_off(gs: list, s: Singles, ns, file_index: dict, placed: bool = False) -> list[Group]:
    """Elements ns of s taken out of it into gs as the Groups of their own
    they are (Singles.single; a Singles left empty leaves gs); those
    Groups."""
    out = [s.single(n, file_index, placed) for n in ns]
    if out:
        gs += out
        s.drop(ns)
    if not s.uses:
        gs.remove(s)
    return out


def mode_of(u: TargetUse, mode: str, plan: Plan, solved: Solved, row: int,
            why: dict | None = None) -> str:
    """absj: the use becomes a MoveAbsJ; rob: a robtarget is written; joint:
    a jointtarget of a MoveAbsJ is written. auto converts MoveJ only (a
    MoveL keeps its straight line), absj MoveJ and MoveL. A move that
    program displacement may shift, whose configuration the controller may
    choose otherwise than assumed, or whose target is PERS data (changed
    at run time by ModPos or another task) stays a robtarget move:
    MoveAbsJ would fix all three. why, when given, receives use key -> why
    a move the mode turns into MoveAbsJ is kept (but for a caution of its
    pick or program displacement, which its row says anyway)."""
    if u.kind == "jointtarget":
        return "joint"
    m = u.motion
    name = m.spec.name.lower()
    # (row: the use's row in solved.)
    if name in ABSJ_FROM[mode]:
        kept = kept_robtarget(u, plan, solved, row)
        if kept is None:
            return "absj"
        if why is not None and kept is not solved.picks.caution[row] and kept != DISPLACED:
            # (A caution, or program displacement, is said with its row
            # and its note already.)
            why[u.key] = kept
    return "rob"


DISPLACED = ("program displacement may be active here (a MoveAbsJ would ignore it): kept a "
             "robtarget move")


def kept_robtarget(u: TargetUse, plan: Plan, solved: Solved, row: int) -> str | None:
    """Why a MoveJ/MoveL stays a robtarget move whatever --emit asks (None:
    nothing but the mode keeps it)."""
    m = u.motion
    # What the statement is written with (each of it; asked of its roles
    # first: a CAM move's only optional argument is \WObj, which
    # m.optional leaves out).
    if m.roles.optional or m.roles.to_point:
        odd = ", ".join("\\" + a.name for a in m.optional
                        if a.name.lower() not in ABSJ_OPTIONALS)
        why = [f"{odd} has no MoveAbsJ equivalent"] if odd else []
        if names_to_point(m):
            why.append("its target is passed by name (ToPoint:=), which rapidcomp does not "
                       "rewrite as MoveAbsJ's ToJointPos:=")
        if why:
            return "; ".join(why) + ": kept a robtarget move"
    if plan.may_be_displaced(u):
        return DISPLACED
    caution = solved.picks.caution[row]
    if caution is not None:
        return caution
    if u.source.decl is not None and u.source.decl.storage == "PERS":
        return (f"{u.source.decl.name} is PERS data (ModPos or another task may change it; a "
                "MoveAbsJ would not follow): kept a robtarget move")
    axes = named_part(u.source.expr, -1)
    if axes is not None:
        return (f"its external axes are the data {axes} (a MoveAbsJ would write their "
                "value, not follow the name): kept a robtarget move")
    if plan.task.unreadable:
        # (A module no one reads may change the tool or work object it
        # sees at run time, as a readable one that does leaves the move
        # untouched: the robtarget move follows that, a MoveAbsJ would not.)
        for what, ref in (("tool", m.tool), ("work object", m.wobj)):
            if type(ref) is not A.Ref:
                continue
            d = plan.resolver.lookup(ref.name, u.module, m.routine)
            if (type(d) is Declaration and d.storage in ("PERS", "VAR") and d.routine is None
                    and d.scope != "LOCAL"):
                return (f"its {what} {ref.name} is {d.storage} data "
                        f"{', '.join(plan.task.unreadable)}, which is encrypted, may change "
                        "(a MoveAbsJ would not follow): kept a robtarget move")
    return None


def absj_hint(g: Group, mode: str, plan: Plan, solved: Solved) -> str:
    """What a robtarget group's failure at the wrist singularity says of
    MoveAbsJ, which carries any J4/J6 split: per move of the group, why it
    is not one (the mode, or what keeps it a robtarget move); by line where
    its moves differ. Nothing for a move no MoveAbsJ replaces (MoveC)."""
    lines: dict[str, list[int]] = {}
    for u in g.uses:
        if u.motion.spec.name.lower() not in TO_ABSJ:
            continue
        if u.key in g.kept:
            said = ("a MoveAbsJ can, but not here: other runs of its statement (a FOR loop) "
                    "must stay robtarget moves")
        else:
            why = kept_robtarget(u, plan, solved, solved.row[u.key])
            said = (f"a MoveAbsJ can, but not here: {why}" if why is not None else
                    "a MoveAbsJ can (--emit absj" + (" for a MoveL)" if mode == "auto" else ")"))
        lines.setdefault(said, []).append(u.line)
    if not lines:
        return ""
    if len(lines) == 1 and len(next(iter(lines.values()))) == len(g.uses):
        return ": " + next(iter(lines))
    return ": " + "; ".join(f"line{'s' if len(set(ls)) > 1 else ''} "
                            f"{', '.join(map(str, sorted(set(ls))))}: {said}"
                            for said, ls in lines.items())


def names_to_point(m) -> bool:
    """The move names its target parameter (`MoveL ToPoint:=p10,...`):
    MoveAbsJ's is ToJointPos, so it stays a robtarget move."""
    return m.to_point


def _call_keys(uses: list[TargetUse]) -> list:
    """What each use's Offs/RelTool is, as a key (None for none): its name,
    displacement and rotation rounded (the numbers of all rounded at once:
    an Offs-relative program's 1e5)."""
    out: list = [None] * len(uses)
    at = [n for n, u in enumerate(uses) if u.source.call is not None]
    if not at:
        return out
    srcs = [uses[n].source for n in at]
    d = np.round(np.array([s.rel_d for s in srcs], float).reshape(-1, 3), 12).tolist()
    turned = [k for k, s in enumerate(srcs) if s.rel_R is not NO_ROTATION]
    R = [_IDENTITY_KEY] * len(srcs)
    if turned:
        rows = np.round(np.array([srcs[k].rel_R for k in turned], float).reshape(-1, 9), 12)
        for k, r in zip(turned, rows.tolist()):
            R[k] = tuple(r)
    for n, s, dd, rr in zip(at, srcs, d, R):
        out[n] = (s.call.name.lower(), tuple(dd), rr)
    return out


_IDENTITY_KEY = tuple(np.round(NO_ROTATION, 12).ravel().tolist())


def multi_index(flat: int, dims: tuple[int, ...]) -> tuple[int, ...]:
    out = []
    for dim in reversed(dims):
        out.append(flat % dim + 1)
        flat //= dim
    return tuple(reversed(out))


def element_label(g: Group, k) -> str:
    if k is None:
        return g.decl.name if g.decl is not None else "inline target"
    return f"{g.decl.name}{{{','.join(map(str, multi_index(k, g.decl.dims)))}}}"


def groups(plan: Plan, solved: Solved, mode: str,
           wrist_deg: float = IKOptions.wrist_fallback_deg,
           singles: bool = False) -> list[Group | Singles]:
    """Uses that share one written value. FOR-walked array uses form one
    group per array (one value per element); any other use joins it when
    its solution there is the same, else groups by its own solution (a
    target reached on two solutions needs two values). singles: the
    inline literals read by one use alone that compensate are Singles
    (one per mode), not a Group each."""
    gs = grouping(plan, solved, mode, wrist_deg, singles)
    settle(gs, solved, plan, mode)
    return gs


def grouping(plan: Plan, solved: Solved | Solving, mode: str,
             wrist_deg: float = IKOptions.wrist_fallback_deg,
             singles: bool = False) -> list[Group | Singles]:
    """groups() as far as the nominal solutions decide them (a Solving's
    uses, rows, nominal solutions and picks: made while the deformed
    robot's IK is under way); settle() completes them. wrist_deg: the
    solver's IKOptions.wrist_fallback_deg."""
    file_index = plan.file_index
    by_key: dict = {}
    out: list[Group] = []
    loop_first = sorted(solved.uses, key=lambda u: not u.source.by_loop)
    # Each use's solution, rounded, as a key (all rows at once: 1e5 uses):
    # the bytes of its six rounded doubles, equal where the numbers are
    # (+ 0.0 makes a -0.0 the 0.0 it equals; a row with a NaN has none).
    q_all = solved.nominal.q_deg
    rounded = np.ascontiguousarray(np.round(q_all, 3) + 0.0, dtype=float)
    q_keys = [None if bad else q for bad, q in zip(
        np.isnan(q_all).any(axis=1).tolist(),
        rounded.view(np.dtype((np.void, rounded.itemsize * 6))).ravel().tolist())]
    rows = [solved.row[u.key] for u in loop_first]
    why: dict = {}
    modes = [mode_of(u, mode, plan, solved, row, why) for u, row in zip(loop_first, rows)]
    # A jointtarget's compensation does not depend on the move's tool (its
    # joints reach the flange's whole pose), except near J5 = 0, where the
    # wrist fallback holds the tool's point exact: there the tool is part
    # of what one written value serves.
    wrist = np.abs(np.nan_to_num(q_all[:, 4], nan=180.0)) < wrist_deg
    kept = _one_statement(loop_first, modes)
    alone = ({"absj": Singles("absj"), "rob": Singles("rob"),
              "rob decl": Singles("rob", declared=True, placement="in place"),
              "absj decl": Singles("absj", declared=True, placement="new")}
             if singles else None)
    once = _read_once(plan) if singles else frozenset()
    call_keys = _call_keys(loop_first)
    for at, (u, row, m) in enumerate(zip(loop_first, rows, modes)):
        src = u.source
        if alone is not None and m != "joint" and src.call is None and not src.by_loop \
                and not u.env:
            if src.decl is None and type(src.ref) is A.NumAgg:
                # (Its own literal, which no other use reads: a Group of
                # its own, as a column of Singles.)
                s = alone[m]
            elif id(src.decl) in once and src.element is None:
                # (A declaration nothing else reads: edited in place, or
                # a new jointtarget next to it, as place() places a Group
                # of its one use.)
                s = alone[m + " decl"]
            else:
                s = None
            if s is not None:
                s.uses.append(u)
                s.rows.append(row)
                s.at.append(at)
                if u.key in why:
                    s.why_kept = writable(s.why_kept)
                    s.why_kept[u.key] = why[u.key]
                continue
        if src.decl is not None and file_index[id(src.home)] < plan.n_written:
            home = (file_index[id(src.home)], src.home_module)
        else:
            home = (u.key[0], u.module)
        where = (("decl", id(src.decl)) if src.decl is not None
                 else ("inline", u.key[0], src.ref.span))
        context = (((u.tool[0] if u.tool is not None else None) if wrist[row] else None,
                    None) if m == "joint" else (u.tool[0], u.wobj[0]))
        base = (m, where, call_keys[at], *context, home[0], id(home[1]))
        if src.by_loop or m == "joint":
            key = base + (None,)
        else:
            # (An element of a FOR-walked array: its group holds the array's
            # literal, so the element is written there where its value is
            # the one the group's uses of it have, or where none of them
            # reads it (pArr{1} before a FOR i FROM 2 ...): not a copy. The
            # FOR-walked uses come first: such a group's first use is one.)
            array = by_key.get(base + (None,))
            if array is not None and not array.uses[0].source.by_loop:
                array = None
            seen = None if array is None else array.rows_seen.get(src.element, -1)
            # (A circle point no loop use reads keeps a group of its own:
            # written as such, its confdata as written.)
            if seen is not None and (_same(solved, seen, row) if seen >= 0
                                     else q_keys[row] is not None and u.role != "cir"):
                key = base + (None,)
                if seen < 0:
                    array.outside = writable(array.outside)
                    array.outside[src.element] = at
            else:
                # (A use with no nominal solution is a group with the other
                # uses of its element that have none, not the array's,
                # whose key None also is.)
                key = base + ((q_keys[row] if q_keys[row] is not None
                               else ("no solution", src.element)),)
        g = by_key.get(key)
        if g is None:
            g = by_key[key] = Group(m, src, u.tool, u.wobj, home, first=at)
            out.append(g)
        g.uses.append(u)
        g.rows_seen.setdefault(src.element, row)
        if u.key in kept:
            g.kept = g.kept | {u.key}
        if u.key in why:
            g.why_kept = writable(g.why_kept)
            g.why_kept[u.key] = why[u.key]
    if alone is not None:
        out += [s for s in alone.values() if s.uses]
    return out


def _declarations(plan: Plan) -> dict[str, list]:
    """Every declaration of the task by lower-case name: (file index,
    Declaration) of each."""
    out: dict[str, list] = {}
    for fi, pf in enumerate(plan.files):
        for m in pf.modules:
            for d in m.declarations:
                out.setdefault(d.name.lower(), []).append((fi, d))
    return out


def _read_once(plan: Plan) -> frozenset:
    """id() of each robtarget declaration one reference in the task reads
    (the move's own), declared once, in a written module, not shared with
    another task: place() edits it in place for that move's group."""
    count: dict[str, int] = {}
    for pf in plan.files:
        for m in pf.modules:
            for name, rs in plan.resolver.usages[id(m)].refs.items():
                count[name] = count.get(name, 0) + len(reference_starts(rs))
    shared = plan.resolver.shared
    return frozenset(id(ds[0][1]) for name, ds in _declarations(plan).items()
                     if len(ds) == 1 and ds[0][0] < plan.n_written
                     and ds[0][1].type == "robtarget" and count.get(name) == 1
                     and name not in shared)


def settle(gs: list[Group], solved: Solved, plan: Plan, mode: str) -> None:
    """Each group's elements, rows and failure, and whether a new
    declaration of it is LOCAL (groups() past grouping()). An element of
    Singles that fails is taken out of it into gs as the Group of its own
    it is (gs changes: a Singles left empty goes); so is one of a
    FOR-walked robtarget array where the array can do without it
    (_leave_out: kept as written; in a transient output, its correction
    zero)."""
    # Whether each row is solved, and needs a J4/J6 split at the wrist
    # singularity (_elements, _wrist: as Python values at once).
    ok = solved.oks()
    left = ((solved.deformed.warnings.astype(np.int64) & _LEFT) == _LEFT).tolist()
    # A single that fails is a Group of its own, which says why.
    for s in [g for g in gs if type(g) is Singles]:
        split_off(gs, s, [n for n, i in enumerate(s.rows)
                          if not ok[i] or (left[i] and s.mode == "rob")], plan.file_index)
    for g in [g for g in gs if type(g) is Group and g.outside]:
        _let_outside_go(gs, g, solved, ok, left)
    # (FOR-walked robtarget arrays failed for some elements' sake: decided
    # once every group's failure is known, _leave_out.)
    arrays = []
    for g in list(gs):
        if type(g) is Singles:
            continue
        _elements(g, solved, ok, left)
        if g.failure is None and g.mode == "rob":
            _wrist(g, solved, left, plan, mode)
        if g.failure is not None and g.array and g.mode == "rob":
            arrays.append(g)
        elif g.failure is not None:
            if g.array and g.mode == "absj":
                g.one_because = (" (the moves turned into MoveAbsJ read a jointtarget array, "
                                 "which needs every element's joints)")
            free_outside(gs, g, solved)
        _local(g)
    for g in arrays:
        if not _leave_out(gs, g, solved, ok, left, plan, mode):
            g.one_because = _copied(g)
            free_outside(gs, g, solved)


def _local(g: Group) -> None:
    uses = g.uses
    g.local = (uses[0].module is g.home[1] if len(uses) == 1
               else all(u.module is g.home[1] for u in uses))


def _let_outside_go(gs: list, g: Group, solved: Solved, ok: list, left: list) -> None:
    """An element of FOR-walked array g that only uses by a literal index
    read (Group.outside), one of which fails, leaves g with those uses
    (split_outside)."""
    for k in list(g.outside):
        rows = [solved.row[u.key] for u in g.uses
                if not u.source.by_loop and u.source.element == k]
        if not all(ok[i] and not (left[i] and g.mode == "rob") for i in rows):
            split_outside(gs, g, k, solved)


def free_outside(gs: list, g: Group, solved: Solved) -> None:
    """FOR-walked array g fails (one of the loop's elements): the elements
    only literal indices read, which joined it, leave it as the Groups of
    their own they were (split_outside), not failing with it."""
    for k in list(g.outside):
        split_outside(gs, g, k, solved)


def fail(gs: list, g, u: TargetUse, solved: Solved, why: tuple) -> bool:
    """Group g (or Singles) fails for use u's sake (its written value
    would miss: fix's verification): where u is of an element only
    literal indices read (Group.outside), that element's uses alone, the
    array's group written again without them; else g, its elements outside
    the loop leaving it. Whether groups were split (gs changed)."""
    if type(g) is not Group or not g.outside:
        g.failure = why
        return False
    k = u.source.element
    if k in g.outside and not u.source.by_loop:
        split_outside(gs, g, k, solved).failure = why
    else:
        g.failure = why
        free_outside(gs, g, solved)
    return True


def split_outside(gs: list, g: Group, k, solved: Solved) -> Group:
    """The uses of element k of FOR-walked array g that only literal
    indices read (Group.outside) taken out of g into gs as the Group of
    their own grouping() made before such elements joined the array's:
    where one of them fails (its solve, the wrist split, its verification)
    or the loop's elements do, each fails alone, and the others are
    written. That Group."""
    return _split_elements(gs, g, [k], solved)[k]


def _one_statement(uses: list[TargetUse], modes: list[str]) -> frozenset:
    """A move in a FOR loop is one statement for every iteration: it
    becomes MoveAbsJ only where every iteration may (modes[i] of uses[i]
    "absj"); where one must stay a robtarget move (its configuration or
    displacement not known, ...), all stay one (modes set to "rob"). The
    keys of the uses so kept."""
    by_move: dict = {}
    for n, u in enumerate(uses):
        if u.env:                 # (only a loop's variable makes a move several uses)
            by_move.setdefault(u.key[:3], []).append(n)
    kept = set()
    for ns in by_move.values():
        if len({modes[n] for n in ns}) > 1 and any(modes[n] == "rob" for n in ns):
            for n in ns:
                if modes[n] == "absj":
                    modes[n] = "rob"
                    kept.add(uses[n].key)
    return frozenset(kept)


def _same(solved: Solved, a: int, b: int) -> bool:
    """Rows a and b have the same nominal solution."""
    return same_joints(solved.nominal.q_deg[a], solved.nominal.q_deg[b])


def _leave_out(gs: list, g: Group, solved: Solved, ok: list, left: list, plan: Plan,
               mode: str) -> bool:
    """FOR-walked robtarget array g failed for some elements' sake. Where
    g, without them, writes the array in place (_in_place), each element
    that fails (a use of it not solved, two uses of it on different
    configurations, the wrist split) goes into gs as a Group of its own that
    says why, the array keeps it as written, which its moves reach as
    before, and g, no longer failed, writes the others (a glue path of 50
    points, one at the wrist singularity: 49 compensated, not none). Where
    the loop's elements all fail, nothing of the array is written and each
    says its own reason. Otherwise (g would write a copy, which the refused
    elements' moves would then read: a PERS element cut off from its data,
    and a move the report would not say was renamed) g fails as it did.
    Whether g was split (else the caller fails it as before)."""
    rows: dict = {}
    loop = set()
    for u in g.uses:
        k = u.source.element
        rows.setdefault(k, []).append(solved.row[u.key])
        if u.source.by_loop:
            loop.add(k)
    # What fails each element, in the order _elements and _wrist say it:
    # two uses on different configurations, a use not solved (its row),
    # the wrist split.
    fails: dict = {}
    for k, rs in rows.items():
        first = rs[0]
        if any(ok[first] and ok[i] and not _same(solved, first, i) for i in rs[1:]):
            fails[k] = ("configurations", first)
        elif (i := next((i for i in rs if not ok[i]), None)) is not None:
            fails[k] = ("solve", i)
        elif left[first]:
            fails[k] = ("wrist", first)
    bad = list(fails)
    every = loop <= fails.keys()
    if not every and not _alone_in_place(gs, g, set(bad), plan):
        return False
    g.failure = None
    owns = _split_elements(gs, g, bad, solved)
    for k, own in owns.items():
        kind, i = fails[k]
        why = (_configurations(own, k) if kind == "configurations" else
               solved.reason(i) if kind == "solve" else
               _split_needed(own, k, i, solved, plan, mode))
        own.failure = (why, k)
    if every:
        # (What is left: elements only literal indices read, each written
        # on its own, as where the array fails.)
        free_outside(gs, g, solved)
        gs.remove(g)
    else:
        g.left_out = owns[bad[0]].failure
    return True


def _alone_in_place(gs: list, g: Group, bad: set, plan: Plan) -> bool:
    """Whether g, its elements `bad` taken out, can write its array in
    place (_in_place), first of its declaration's groups (place puts a
    group that left elements out first): not where another group of it
    has left elements out already."""
    decl_groups = [x for x in gs if type(x) is Group and x.decl is g.decl]
    if any(x.left_out for x in decl_groups):
        return False
    # (g, failed still, is the one _in_place asks of: its own failure aside.)
    return _in_place(plan, g, decl_groups, _references(plan, {g.decl.name.lower()}),
                     _declarations(plan), _consumed(gs), set(g.elements) - bad)


def _split_elements(gs: list, g: Group, ks: list, solved: Solved) -> dict:
    """The uses of each element of ks taken out of g into gs, the Group of
    its own each (in one pass over g's uses), first where its first use is
    among those grouping() walks (an element only literal indices read:
    Group.outside; one of the loop's, g's). {element: that Group}."""
    ks_set = set(ks)
    firsts = {k: g.outside.get(k, g.first) for k in ks}
    taken: dict = {k: [] for k in ks}
    rest = []
    for u in g.uses:
        (taken[u.source.element] if u.source.element in ks_set else rest).append(u)
    g.uses = rest
    g.elements = [e for e in g.elements if e not in ks_set]
    g.rows = {e: r for e, r in g.rows.items() if e not in ks_set}
    g.rows_seen = {e: r for e, r in g.rows_seen.items() if e not in ks_set}
    if g.outside:
        g.outside = {e: at for e, at in g.outside.items() if e not in ks_set}
    out = {}
    for k in ks:
        us = taken[k]
        keys = {u.key for u in us}
        row = solved.row[us[0].key]
        own = Group(g.mode, us[0].source, us[0].tool, us[0].wobj, g.home, uses=us,
                    first=firsts[k], rows_seen={k: row}, elements=[k], rows={k: row})
        own.kept = g.kept & keys
        if g.why_kept:
            own.why_kept = {key: why for key, why in g.why_kept.items() if key in keys}
        _local(own)
        gs.append(own)
        out[k] = own
    return out


def _configurations(g: Group, k) -> str:
    lines = sorted({x.line for x in g.uses if x.source.element == k})
    return (f"{element_label(g, k)} is reached on different configurations "
            f"(lines {', '.join(map(str, lines))}); one array element cannot hold both values")


def _split_needed(g: Group, k, i: int, solved: Solved, plan: Plan, mode: str) -> str:
    return (f"at the wrist singularity (J5 {solved.nominal.q_deg[i][4]:.2f} deg) the "
            "compensation needs a J4/J6 split a robtarget cannot carry (the controller's IK "
            "chooses the split itself)" + absj_hint(g, mode, plan, solved))


def _elements(g: Group, solved: Solved, ok: list, left: list) -> None:
    """A group's elements and their rows, and its failure: ok[row]
    (solved.ok), left[row] (the J4/J6 split at the wrist singularity)."""
    if len(g.uses) == 1:     # (most groups: one literal, one move)
        u = g.uses[0]
        k = u.source.element
        row = g.rows_seen[k]
        g.array = u.source.by_loop
        if not ok[row]:
            g.failure = (solved.reason(row), k)
        # (rows_seen is {k: row} already: one dict, not two, per group;
        # neither changes past the grouping. 1e5 groups: ~20 MB.)
        g.elements, g.rows = [k], g.rows_seen
        return
    g.array = any(u.source.by_loop for u in g.uses)
    seen: dict = {}
    for u in g.uses:
        k = u.source.element
        row = solved.row[u.key]
        first = seen.get(k)
        if first is None:
            seen[k] = row
            continue
        if g.failure is None and ok[first] and ok[row] and not _same(solved, first, row):
            g.failure = (_configurations(g, k), k)
    # Any use of the group that fails fails the group (its value is shared).
    bad = next((u for u in g.uses if not ok[solved.row[u.key]]), None)
    if g.failure is None and bad is not None:
        g.failure = (solved.reason(solved.row[bad.key]), bad.source.element)
    g.elements = sorted(seen) if g.array else list(seen)
    g.rows = seen


def _wrist(g: Group, solved: Solved, left: list, plan: Plan, mode: str) -> None:
    """A robtarget group fails where the compensation needs a J4/J6 split
    at the wrist singularity (left[row])."""
    for k in g.elements:
        i = g.rows[k]
        if left[i]:
            g.failure = (_split_needed(g, k, i, solved, plan, mode), k)
            break


def place(plan: Plan, gs: list[Group], solved: Solved | None = None) -> None:
    """Inline values are edited inline; MoveAbsJ targets are new
    declarations; a declaration is edited in place by the group (the one
    with most uses) when every reference to it belongs to its groups and
    none failed (a failed group keeps reading the old value) and no other
    task of the controller refers to it (a PERS is shared: the value would
    change for that task too); the other groups get new declarations. A
    PERS target is shared data: a copy would not follow changes to it,
    which the report says."""
    # Every reference to the names of the declarations groups may write
    # (not those of speed, zone, tool: a CAM program has 1e5 of each).
    refs = _references(plan, {g.decl.name.lower() for g in gs if g.decl is not None})
    declared = _declarations(plan)
    consumed = _consumed(gs)
    by_decl: dict[int, list[Group]] = {}
    for g in gs:
        if g.decl is not None:
            by_decl.setdefault(id(g.decl), []).append(g)
    for g in gs:
        if type(g) is Singles:
            continue          # (placed as made: inline, or in place)
        # (A new dict only where the round before wrote one: two empty dicts
        # per group, 1e5 groups, otherwise.)
        g.placement = None
        g.names = g.slots = NONE
        if g.failure is not None:
            continue
        if g.decl is None:
            g.placement = "inline"
        elif g.mode == "absj":
            g.placement = "new"
    for decl_groups in by_decl.values():
        writable = [g for g in decl_groups if g.failure is None and g.mode != "absj"]
        if not writable:
            continue
        kept = next((g for g in writable if g.left_out), None)
        if kept is not None and not _in_place(plan, kept, decl_groups, refs, declared, consumed,
                                              set(kept.elements)):
            # (Another group of the array failed since _leave_out (fix's
            # verification): the array would be a copy, which the refused
            # elements' moves would read too. It is refused as one.)
            refuse_as_one(gs, kept, solved)
            writable.remove(kept)
            if not writable:
                continue
        # (The most uses; of as many, one that reads it plainly, not in
        # Offs/RelTool: the declaration keeps the value its name is read
        # for, and the copy is named for the call.)
        # (An array whose refused elements it keeps as written first:
        # _leave_out made sure it can write in place.)
        writable.sort(key=lambda g: (not g.left_out, -len(g.uses), g.src.call is not None))
        top = writable[0]
        exclusive = _in_place(plan, top, decl_groups, refs, declared, consumed,
                              set(top.elements) if top.array else None)
        for n, g in enumerate(writable):
            g.placement = "in place" if exclusive and n == 0 else "new"


def refuse_as_one(gs: list, g: Group, solved: Solved | None) -> None:
    """FOR-walked array g, which left elements out (_leave_out), cannot
    keep them as written after all (a copy, a cold copy): it fails as one,
    for the first of them; its elements outside the loop leave it."""
    g.refuse_as_one(_copied(g))
    if solved is not None:
        free_outside(gs, g, solved)


def _copied(g: Group) -> str:
    """Group.one_because of an array that is not edited in place."""
    return (f" ({g.decl.name} is not edited in place here: its moves would read a copy, the "
            "refused point's too)")


def _references(plan: Plan, needed: set) -> dict[str, set]:
    """(file index, start) of every reference to each lower-case name of
    `needed` in the task."""
    refs: dict[str, set] = {}
    for fi, pf in enumerate(plan.files):
        for m in pf.modules:
            for name, rs in plan.resolver.usages[id(m)].refs.items():
                if name in needed:
                    refs.setdefault(name, set()).update(
                        (fi, start) for start in reference_starts(rs))
    return refs


def _consumed(gs: list) -> set:
    """The references the moves turned into MoveAbsJ read no more."""
    return {(u.key[0], u.source.ref.span.start)
            for g in gs if g.mode == "absj" and g.failure is None and g.decl is not None
            for u in g.uses}


def _in_place(plan: Plan, top: Group, decl_groups: list, refs: dict, declared: dict,
              consumed: set, kept: set | None) -> bool:
    """Whether top, of its declaration's writable groups the one of most
    uses, writes the declaration in place: declared once, in a written
    module, no other task's; every reference to it read by its groups;
    none failed, but for groups of elements of an array that top leaves
    as they are (kept: the elements top writes); top's own failure aside
    (_leave_out asks before it clears it)."""
    name = top.decl.name.lower()
    mine = {(u.key[0], u.source.ref.span.start) for g in decl_groups if g.mode != "absj"
            for u in g.uses}
    # A failed group keeps reading the value as written: only elements
    # of an array that the one written in place leaves as they are
    # (pGlue{1}, refused, before the loop's pGlue{2..8}).
    return (plan.file_index[id(top.src.home)] < plan.n_written
            and len(declared.get(name, ())) == 1
            and name not in plan.resolver.shared
            and all(g is top or g.failure is None
                    or (kept is not None and g.elements and kept.isdisjoint(g.elements))
                    for g in decl_groups)
            and refs.get(name, set()) - consumed == mine)


def fill_slots(plan: Plan, solver: Solver, gs: list[Group]) -> None:
    """A jointtarget array written for a FOR-walked robtarget array needs a
    value in every slot; slots no executed use reaches get the compensated
    joints of their own robtarget (by its confdata) where it solves, else
    its nominal joints, else the calibration position [0,0,0,0,0,0]."""
    want = [(g, k) for g in gs if g.failure is None and g.array and g.mode == "absj"
            for k in range(len(g.decl.value)) if k not in g.rows]
    if not want:
        return
    R = np.empty((len(want), 3, 3))
    p = np.empty((len(want), 3))
    conf = np.zeros((len(want), 4), dtype=int)
    valid = np.zeros(len(want), dtype=bool)
    for i, (g, k) in enumerate(want):
        record = g.decl.value[k]
        q = np.asarray(record.quat_wxyz, float)
        if not np.all(np.isfinite(record.values[:7])) or np.linalg.norm(q) < 1e-6:
            R[i], p[i] = np.eye(3), np.zeros(3)
            continue
        src = Source(record, g.decl, g.src.home, k, True, g.src.ref, g.src.expr, g.src.call,
                     g.src.rel_R, g.src.rel_d, g.src.home_module)
        base = plan.resolver.world_M_base(record)
        if not isinstance(base, tuple):
            R[i], p[i] = np.eye(3), np.zeros(3)
            continue
        try:
            target = plan.resolver.target_pose(src)
        except InputError:
            # A slot no move reaches holds a value no move could use (a
            # position beyond reach of reason): the calibration position.
            R[i], p[i] = np.eye(3), np.zeros(3)
            continue
        R[i], p[i] = flange_pose(base, g.wobj[1], target, g.tool[1])
        conf[i] = record.conf
        valid[i] = True
    for (g, k), slot in zip(want, solve_slots(solver, R, p, conf, valid)):
        g.slots = writable(g.slots)
        g.slots[k] = slot

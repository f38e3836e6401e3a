"""Stage 4 of `fix`: the span edits that write every group's values.

Each written file gets its own edits: numeric fields replaced in place,
MoveJ/MoveL renamed to MoveAbsJ with a new target, new declarations
inserted on the line after the one they come from (in that line's
indentation and line break). Nothing else of the text changes.
"""

from __future__ import annotations

import re
from contextlib import contextmanager

import numpy as np

from .. import side
from ..edits import (BY_SPAN, EditColumns, EditRun, SpanEdit, columns_of, sorted_columns,
                     span_edit)
from ..kinematics.conf import quadrant_miss
from ..kinematics.frames import matrix_to_quat_wxyz, row_dots
from ..errors import InternalError
from ..rapid import ast as A
from ..rapid.values import RobTarget
from ..rewrite import records
from ..rewrite.names import NameAllocator
from .place import Group, Singles, element_label, multi_index, writable
from .plan import Plan
from .solve import Solved
from .targets import Source, base_pose, named_part, stacked_poses, wobj_targets
from .transient import FUNC_J, FUNC_R


# A file's edits from this many on are kept as EditColumns (file_edits).
COLUMNS_FROM = 4096
# Robtarget values prepared at once (a CAM program's 1e5 in blocks: each
# value and text is its own, whatever the block).
PREPARE_BLOCK = 8192


class Values:
    """The compensated value of each group element, as numbers and text."""

    def __init__(self, plan: Plan, solved: Solved, quadrant_tol_deg: float):
        self.plan = plan
        self.solved = solved
        self.tol = quadrant_tol_deg
        self._values: dict = {}

    def source(self, g: Group | Singles, k) -> Source:
        # (A group's own source asked of it directly: asked several times
        # for each of 1e5 values.)
        if type(g) is Group and (k is None or k == g.src.element):
            return g.src
        return g.source(k)

    def absj_literal(self, s: Singles, n: int) -> str:
        """literal() of element n of s (absj) as of the Group of its one
        use (Singles.single), without that Group."""
        prepared = self._values.get(("absj", id(s), n))
        if prepared is not None:
            return prepared
        return _absj_literal(self.solved.deformed.q_deg[s.rows[n]], s.uses[n].source.record)

    @contextmanager
    def lent(self, s: Singles, n: int, g: Group):
        """Within: the MoveAbsJ literal prepared for element n of s is that
        of g, the Group of its one use made for the while (Singles.single;
        its key only while it lives: an id is reused once it is gone)."""
        # (A transient output's value and correction, too: prepare()'s of
        # the element.)
        keys = []
        for mine, its in ((("absj", id(g), None), ("absj", id(s), n)),
                          ((id(g), None), (id(s), n)),
                          (("pose dq", id(g), None), ("pose dq", id(s), n))):
            prepared = self._values.get(its)
            if prepared is not None:
                self._values[mine] = prepared
                keys.append(mine)
        try:
            yield
        finally:
            for key in keys:
                self._values.pop(key, None)

    def joints(self, g: Group, k) -> np.ndarray:
        if k in g.slots:
            return g.slots[k].q_deg
        return self.solved.deformed.q_deg[g.rows[k]]

    def cold(self, g: Group, k) -> np.ndarray:
        """Transient: the joints the cold robot needs, the ideal
        controller's own solution (the uncompensated program's joints)."""
        if k in g.slots:
            return g.slots[k].q_deg
        return self.solved.nominal.q_deg[g.rows[k]]

    def dq(self, g: Group, k) -> np.ndarray:
        """Transient: the warm robot's correction of those joints (zero for
        a slot no move reaches)."""
        if k in g.slots or k not in g.rows:
            return np.zeros(6)
        i = g.rows[k]
        return self.solved.deformed.q_deg[i] - self.solved.nominal.q_deg[i]

    def pose_dq(self, g: Group, k):
        """Transient, robtarget kept: the warm robot's compensated robtarget
        minus the written one, (trans mm, quaternion components, RAPID
        order, the warm one's sign nearest the written one), and the
        confdata the warm robot needs; zero for an element no move reaches."""
        key = ("pose dq", id(g), k)
        got = self._values.get(key)
        if got is not None:           # (asked for its confdata, then for its literal)
            # (Rows of the stacks made for a batch: no three arrays per element.)
            (d, dq, conf, _), j = got[:2]
            return d[j], dq[j], conf[j]
        record = self.source(g, k).record
        q0 = np.asarray(record.quat_wxyz, float)
        if k in g.slots or k not in g.rows:
            return np.zeros(3), np.zeros(4), np.array(record.conf)
        (R, p, conf), j = self._stacked(g, k)
        # (The quaternions of a stack's rotations at once: the same
        # arithmetic row by row, not a call per target.)
        quats = self._values.get(("quats", id(R)))
        if quats is None:
            quats = self._values[("quats", id(R))] = (R, matrix_to_quat_wxyz(R))
        q = quats[1][j]
        q0n = q0 / np.linalg.norm(q0)
        if float(q @ q0n) < 0:
            q = -q
        got = (p[j] - np.asarray(record.values[:3], float), q - q0n, np.asarray(conf[j]))
        self._values[key] = (tuple(a[None] for a in got)
                             + (np.array([np.array_equal(got[2], record.conf)]),), 0)
        return got

    def _pose_stacks(self, items: list, values) -> tuple:
        """pose_dq of each (group, element) of `items` (reached elements;
        values: their robtarget values' stacks, as _robtarget_values makes
        them), as arrays (d, dq, conf, whether each keeps its written
        confdata): the same arithmetic elementwise (a norm as
        np.linalg.norm takes one vector's, row_dots; a sign decided near 0
        by the one product itself)."""
        R, p, conf = values
        recs = [self.source(g, k).record for g, k in items]
        n = len(items)
        q = matrix_to_quat_wxyz(R)
        q0 = np.array([r.quat_wxyz for r in recs], float).reshape(n, 4)
        q0n = q0 / np.sqrt(row_dots(q0))[:, None]
        dots = np.matmul(q[:, None, :], q0n[:, :, None])[:, 0, 0]
        flip = dots < 0
        for j in np.flatnonzero(np.abs(dots) < 1e-9).tolist():
            flip[j] = float(q[j] @ q0n[j]) < 0
        q = np.where(flip[:, None], -q, q)
        d = p - np.array([r.values[:3] for r in recs], float).reshape(n, 3)
        dq = q - q0n
        # (Whether each keeps its written confdata: RobTarget.conf's ints.)
        kept = (conf == np.array([r.values[7:11] for r in recs], float).reshape(n, 4).astype(
            int)).all(axis=1)
        return d, dq, conf, kept

    def conf_kept(self, g: Group, k) -> bool:
        """Transient: pose_dq(g, k)'s confdata is the written one."""
        key = ("pose dq", id(g), k)
        got = self._values.get(key)
        if got is None:                  # (not prepared: made now)
            _, _, conf = self.pose_dq(g, k)
            got = self._values.get(key)
            if got is None:              # (an element no move reaches)
                return np.array_equal(conf, self.source(g, k).record.conf)
        stacks, j = got[:2]
        return bool(stacks[3][j])

    def kept_pose_literal(self, s: Singles, n: int) -> str | None:
        """Transient: the literal of element n's correction where prepare()
        made it and its confdata is the written one (conf_kept), as
        pose_literal gives it: one look-up for 1e5 targets; else None."""
        got = self._values.get(("pose dq", id(s), n))
        if got is None or len(got) != 3 or not got[0][3][got[1]]:
            return None
        return got[2]

    def pose_literal(self, g: Group, k) -> str:
        """Transient: the literal of pose_dq(g, k)'s correction."""
        got = self._values.get(("pose dq", id(g), k))
        if got is not None and len(got) == 3:
            return got[2]
        d, dq, _ = self.pose_dq(g, k)
        return records.pose_literals(d[None], dq[None])[0]

    def robtarget_value(self, g: Group, k):
        """(R, p, conf) of the literal the ideal controller must be given:
        nominal FK of the compensated joints, back in the tool and work
        object (and track position), with Offs/RelTool undone. confdata:
        the compensated joints', except where every use runs with
        supervision off (the controller does not read it: it stays as written)
        and for a J1/J4/J6 within the quadrant tolerance of the written
        quadrant (it stays as written)."""
        stacks, j = self._stacked(g, k)
        return stacks[0][j], stacks[1][j], stacks[2][j]

    def _stacked(self, g: Group, k):
        """(the stacks (R, p, conf) holding element k's value, its row)."""
        key = (id(g), k)
        if key not in self._values:
            self._values[key] = (self._robtarget_values([(g, k)]), 0)
        return self._values[key]

    def confs(self, items) -> list[tuple[int, ...]]:
        """The confdata of robtarget_value(g, k) of each (group, element),
        as tuples of ints (1e5 at once: each stack's rows converted once,
        not four numpy integers per row; equal ones one tuple: a CAM
        program's 1e5 have a few values)."""
        out = []
        as_ints: dict = {}
        same: dict = {}
        for g, k in items:
            stacks, j = self._stacked(g, k)
            rows = as_ints.get(id(stacks))
            if rows is None:
                rows = as_ints[id(stacks)] = [same.setdefault(t, t) for t in
                                              zip(*stacks[2].T.tolist())]
            out.append(rows[j])
        return out

    def _unsupervised(self, items: list) -> list[bool]:
        """Whether every use of each (group, element) runs without
        configuration supervision (once per group: an array group is given
        once per element; a single's one use, its element's)."""
        s = self.solved
        kind, row = s.picks.kind, s.row
        out = []
        seen: dict = {}
        for g, k in items:
            if type(g) is Singles:
                out.append(kind[g.rows[k]] == "closest")
                continue
            uses = g.uses
            if len(uses) == 1:
                # (One use: its row is the group's one row.)
                out.append(kind[next(iter(g.rows.values()))] == "closest")
                continue
            v = seen.get(id(g))
            if v is None:
                v = seen[id(g)] = all(kind[row[u.key]] == "closest" for u in uses)
            out.append(v)
        return out

    def prepare(self, gs: list[Group], transient: bool = False) -> None:
        """Every robtarget value and field texts of the groups, in batches: a
        CAM program has 1e5, and one batch of rotations costs what a few
        single ones do; PREPARE_BLOCK at a time, the batch's intermediate
        numbers and texts are alive for one block, not for all. transient:
        the values and each one's pose correction and its literal instead
        of texts (the robtarget stays as written: the cold value)."""
        if transient:
            items = [(g, k) for g in gs if g.failure is None and g.mode == "rob"
                     for k in g.elements if (id(g), k) not in self._values]
            made: list = []             # (block, its stacks), as their literals come

            def corrections():
                for at in range(0, len(items), PREPARE_BLOCK):
                    block = items[at:at + PREPARE_BLOCK]
                    values = self._robtarget_values(block)
                    for j, (g, k) in enumerate(block):
                        self._values[(id(g), k)] = (values, j)
                    stacks = self._pose_stacks(block, values)
                    made.append((block, stacks))
                    yield stacks[:2]
            # (Every other block's literals formatted by the job's helper:
            # side.py.)
            for literals in side.alternate(records.pose_literals, corrections()):
                block, stacks = made.pop(0)
                for j, (g, k) in enumerate(block):
                    self._values[("pose dq", id(g), k)] = (stacks, j, literals[j])
            # Moves turned into MoveAbsJ rcTcJ(cold, dq), each read alone (a
            # CAM program's 1e5): their cold values' and corrections'
            # literals, as batches (every other block's by the job's helper).
            self._in_blocks([(s, n) for s in gs if type(s) is Singles and s.mode == "absj"
                             for n in s.elements if ("absj dq", id(s), n) not in self._values],
                            "absj dq", records.transient_joint_literals, self._transient_inputs)
            return
        items = [(g, k) for g in gs if g.failure is None and g.mode == "rob"
                 for k in g.elements if ("texts", id(g), k) not in self._values]
        # Every other block's texts made by the job's helper (side.py) while
        # this process prepares the next block: taken once all are handed.
        handed: list | None = [] if side.helps() else None
        for at in range(0, len(items), PREPARE_BLOCK):
            self._prepare(items[at:at + PREPARE_BLOCK],
                          handed if (at // PREPARE_BLOCK) % 2 else None)
        for block in handed or ():
            self._store(*block[:-1], block[-1].get())
        # The jointtargets of moves turned into MoveAbsJ (a CAM program
        # entered from main: 1e5), their joints formatted as one batch.
        self._in_blocks([(g, k) for g in gs if g.failure is None and g.mode == "absj"
                         and not g.array for k in g.elements
                         if ("absj", id(g), k) not in self._values],
                        "absj", records.absj_literals_of, self._absj_inputs)

    def _in_blocks(self, items: list, key: str, fn, inputs) -> None:
        """fn(*inputs(block)) of (group, element) items PREPARE_BLOCK at a
        time (every other block's made by the job's helper: side.py), each
        item's value kept as (key, id(group), element)."""
        blocks = [items[at:at + PREPARE_BLOCK] for at in range(0, len(items), PREPARE_BLOCK)]
        for block, made in zip(blocks, side.alternate(fn, map(inputs, blocks))):
            for (g, k), value in zip(block, made):
                self._values[(key, id(g), k)] = value

    def _absj_inputs(self, block: list) -> tuple:
        """(joints, external axes' texts) of a block's MoveAbsJ literals."""
        if any(g.slots for g, _ in block):
            q = np.array([self.joints(g, k) for g, k in block], float).reshape(-1, 6)
        else:
            q = self.solved.deformed.q_deg[[g.rows[k] for g, k in block]]
        return q, records.absj_axes([self.source(g, k).record for g, k in block])

    def _transient_inputs(self, block: list) -> tuple:
        """(cold joints, their corrections, external axes' texts) of a
        block of Singles' elements turned into MoveAbsJ rcTcJ(cold, dq):
        cold() and dq() of each, as rows."""
        rows = [s.rows[n] for s, n in block]
        cold = self.solved.nominal.q_deg[rows]
        return (cold, self.solved.deformed.q_deg[rows] - cold,
                records.absj_axes([s.uses[n].source.record for s, n in block]))

    def transient_literals(self, s: Singles, n: int) -> tuple[str, str]:
        """Transient: the (cold value, correction) literals prepare() made
        for element n of Singles s turned into MoveAbsJ."""
        return self._values[("absj dq", id(s), n)]

    def _prepare(self, items: list, handed: list | None = None) -> None:
        """The values and texts of `items`; with `handed`, the texts'
        making is handed to the helper where it can be (plain literals),
        and the block appended to `handed`, for _store."""
        new = [(g, k) for g, k in items if (id(g), k) not in self._values]
        if new:
            values = self._robtarget_values(new)
            # (Each value as its place in the stacks: no three row views
            # per target.)
            for j, (g, k) in enumerate(new):
                self._values[(id(g), k)] = (values, j)
        if len(new) == len(items):       # (the first round: the stacks just made)
            R, p, conf = values
        else:
            got = [self.robtarget_value(g, k) for g, k in items]
            R, p, conf = (np.array([v[n] for v in got]) for n in range(3))
        # (The edits made here, with their why: as field_edits makes them.)
        recs = [self.source(g, k).record for g, k in items]
        whys = [_why(g, k) for g, k in items]
        read = records.plain_inputs(recs) if handed is not None else None
        if read is not None:
            handed.append((items, recs, R, p, conf, whys,
                           side.run(records.plain_block, *read, R, p, conf, whys)))
            return
        self._store(items, recs, R, p, conf, whys,
                    records.robtarget_block(recs, R, p, conf, whys))

    def _store(self, items, recs, R, p, conf, whys, block) -> None:
        """Each item's new literal text and edits (block: the batch's
        records.plain_block, None where a literal is not plain)."""
        if block is not None:
            # Plain literals: each one's new text and its edits in the batch's
            # columns.
            at = block.at
            for j, (g, k) in enumerate(items):
                self._values[("texts", id(g), k)] = (block.literals[j],
                                                     EditRun(block.edits, at[j], at[j + 1]))
            return
        texts = records.robtarget_texts_many(recs, R, p, conf, whys)
        for (g, k), t in zip(items, texts):
            self._values[("texts", id(g), k)] = t

    def forget(self) -> None:
        """The values and their field texts, once written and their
        confdata read (a retry prepares them again, each row as the first
        round did: the batch's rows are computed one by one)."""
        self._values.clear()

    def _robtarget_values(self, items):
        """(R (n, 3, 3), p (n, 3), conf (n, 4)) of robtarget_value for each
        (group, element)."""
        s = self.solved
        rows = [g.rows[k] for g, k in items]
        srcs = [self.source(g, k) for g, k in items]
        n = len(items)
        resolver = self.plan.resolver
        frames = [g.frames(k) for g, k in items]
        R, p = wobj_targets(stacked_poses([resolver.world_M_base(src.record) for src in srcs]),
                            stacked_poses([wobj[1] for _, wobj in frames]),
                            (s.flange_R[rows], s.flange_p[rows]),
                            stacked_poses([tool[1] for tool, _ in frames]))
        for j, src in enumerate(srcs):
            if src.call is not None:
                R[j], p[j] = base_pose(src, (R[j], p[j]))
        # (The records' confdata as their conf gives it: int() of each.)
        written = np.array([src.record.values[7:11] for src in srcs],
                           float).reshape(n, 4).astype(int)
        conf = np.array(s.conf_after[rows], dtype=int).reshape(n, 4)
        q = s.deformed.q_deg[rows]
        # A J1/J4/J6 within the quadrant tolerance of the written quadrant
        # keeps it; every use without supervision keeps all of it (the
        # controller does not read it).
        keep = quadrant_miss(q[:, [0, 3, 5]], written[:, :3]) <= self.tol
        conf[:, :3] = np.where(keep, written[:, :3], conf[:, :3])
        off = np.array(self._unsupervised(items), bool).reshape(n)
        conf[off] = written[off]
        return R, p, conf

    def field_texts(self, g: Group, k) -> list[str] | str:
        """Element k's new field texts, or (a plain literal prepared in a
        batch) its new literal text."""
        record = self.source(g, k).record
        if g.mode == "joint":
            return records.jointtarget_texts(record, self.joints(g, k))
        prepared = self._values.get(("texts", id(g), k))
        if prepared is not None:
            return prepared[0]
        R, p, conf = self.robtarget_value(g, k)
        return records.robtarget_texts(record, R, p, conf)

    def field_edits(self, g: Group, k) -> tuple[list[str], list[SpanEdit]]:
        """Element k's field texts and the edits that write them."""
        # (Taken: a literal is written once; its edits are what stays.)
        prepared = self._values.pop(("texts", id(g), k), None)
        if prepared is not None:
            return prepared
        texts = self.field_texts(g, k)
        return texts, records.field_edits(self.source(g, k).record, texts, _why(g, k))

    def literal(self, g: Group, k, texts: list[str] | None = None) -> str:
        """The new literal of element k (`texts`: its field texts, when the
        caller has them already)."""
        if g.mode == "absj":
            prepared = self._values.get(("absj", id(g), k))
            if prepared is not None:
                return prepared
            return _absj_literal(self.joints(g, k), self.source(g, k).record)
        record = self.source(g, k).record
        if k in g.slots or (g.array and k not in g.rows):
            return records.robtarget_literal(list(record.texts))  # unreached: as written
        texts = texts if texts is not None else self.field_texts(g, k)
        if type(texts) is str:
            return texts
        if g.mode == "joint":
            return records.jointtarget_literal(texts)
        return records.robtarget_literal(texts)


def _absj_literal(q_deg, record) -> str:
    """The jointtarget literal of a MoveAbsJ to joints q_deg, its external
    axes those of `record`."""
    return records.jointtarget_literal(records.absj_texts(q_deg, record))


def _as_literal(record, texts) -> str:
    """A literal's new text from its field texts (or as the text itself)."""
    if type(texts) is str:
        return texts
    if isinstance(record, RobTarget):
        return records.robtarget_literal(list(texts))
    return records.jointtarget_literal(list(texts))


def _named_conf(src: Source, texts) -> str | None:
    """Why a target whose confdata is named data (the Grasshopper plugin
    Robots: [[x,y,z],[q],conf,extj]) cannot be written with the confdata
    texts `texts`, or None: they are its own (a move without configuration
    supervision keeps its confdata as written)."""
    name = named_part(src.expr, 2)
    if name is None:
        return None
    old = [float(t) for t in src.record.texts[7:11]]
    new = [float(t) for t in texts]
    if new == old:
        return None
    return (f"its confdata is the data {name} ({_conf(old)}), which other moves "
            f"share: the compensated joints need {_conf(new)} here, under configuration "
            "supervision (a confdata of its own, written in the target, would serve)")


def _why(g: Group | Singles, k) -> str:
    """What an edit of element k's fields says it is for."""
    if type(g) is Singles:
        return (f"{g.uses[k].source.decl.name} compensated" if g.declared
                else "inline target compensated")
    return f"{element_label(g, k)} compensated"


def _style(word: str, like: str) -> str:
    """An inserted keyword in the letter case of the word it replaces."""
    if like.islower():
        return word.lower()
    if like.isupper():
        return word.upper()
    return word


def _line_end(text: str, pos: int) -> tuple[int, str]:
    """Offset of the end of the line holding `pos`, and its line break."""
    n = len(text)
    i = _REST_OF_LINE.match(text, pos).end()
    if i == n:
        return n, "\n"
    return i, "\r\n" if text.startswith("\r\n", i) else text[i]


def _indent(text: str, pos: int) -> str:
    # The line starts after the last line break before pos: a '\r' is looked
    # for after the last '\n' only (in a file without one, a search back to
    # its start for each of 5e4 new declarations took 2 s).
    nl = text.rfind("\n", 0, pos)
    start = max(nl, text.rfind("\r", nl + 1, pos)) + 1
    return _BLANKS.match(text, start).group()


_REST_OF_LINE = re.compile(r"[^\r\n]*")
# An array literal whose first row begins a line: that line's blanks.
_FIRST_ROW = re.compile(r"\[[ \t]*(?:\r\n|\r|\n)([ \t]*)\[")
_BLANKS = re.compile(r"[ \t]*")


class Editor:
    def __init__(self, plan: Plan, values: Values, transient: bool = False):
        self.plan = plan
        self.values = values
        # Transient compensation (transient.py): every target becomes
        # rcTcJ(<cold>, <cold>_dq), the correction applied at run time.
        self.transient = transient
        self.names = NameAllocator([pf.source.text for pf in plan.files],
                                   [pf.words for pf in plan.files])
        self.edits: dict[tuple[int, int, int], SpanEdit] = {}   # (file, start, end)
        # (file, offset) -> [line break, indent, declarations...]: one entry
        # per place (1e5 places where every target is declared, each moved
        # to once: 2 dicts of their own took ~20 MB more).
        self.inserts: dict[tuple[int, int], list[str]] = {}
        self.actions: dict = {}                                # use key -> what was done
        self._said_texts: dict = {}                            # (_said)
        # (file, record offset) -> (record, new field texts) of every
        # literal whose numeric fields are edited.
        self.fields: dict[tuple[int, int], tuple] = {}
        # The field edits of each of those literals, as lists: no index by
        # span per field (a CAM program has 7e5); a literal is written once.
        self.field_lists: list[tuple[int, list[SpanEdit]]] = []
        # Moves turned into MoveAbsJ on a jointtarget of their own, inline
        # or newly declared: use key -> (the use, that literal, the new
        # declaration's name or None, the instruction's name as written, the
        # file declaring it or None; an element of a new array: None, its
        # reference as written, ...);
        # the output is checked on them by reading those statements again
        # (verify.relex_absj). others: some structural edit is of another
        # kind (the output is parsed again).
        self.converted: dict = {}
        # Elements of Singles written one by one that failed: (the Singles,
        # the element, why), for the caller (fix.py: place.split_off).
        self.failed: list[tuple[Singles, int, tuple]] = []
        # A declared robtarget or jointtarget that some of its uses read as
        # a CONST copy <name>_c next to it: use key -> (the use, the copy's
        # literal, its name, its type, the file it is declared in); read
        # again likewise (verify.relex_copies).
        self.copies: dict = {}
        self.others = False
        # Transient: each move whose target became rcTcR/rcTcJ(<cold>, <dq>):
        # use key -> (the use, the cold value's text as written, the
        # correction's new name or None, its literal, the function, the
        # span replaced, the move's new instruction name (MoveAbsJ) or None,
        # the cold value's new literal or None (its target as written)); the
        # output is checked on them by reading those statements and
        # declarations again (verify.relex_transient). calls_other: a
        # transient edit of another kind (arrays, Offs/RelTool, a cold copy
        # with other confdata: the output is parsed again).
        self.calls: dict = {}
        self.calls_other = False
        # Transient: robtarget moves whose cold value carries the confdata
        # every state needs, not the written one (_apply_transient): how
        # many, how many of them inline, and the names of the copies the
        # others read (<name>_cold; an array's once) (a note says so:
        # fix._transient_notes).
        self.cold_moves = self.cold_inline = 0
        self.cold_copies: list[str] = []
        # Transient: the uses whose move reads a new copy (its cold value)
        # of a PERS declaration, not the PERS itself (their rows say what
        # that costs: rows._row).
        self.pers_copies: set = set()
        self._per_module: dict = {}
        # (_to_absj) instruction -> (MoveAbsJ as it, the why of its name's edit, of its
        # target's)
        self._renamed: dict = {}

    def text(self, fi: int) -> str:
        return self.plan.files[fi].source.text

    def edit(self, fi: int, span, text: str, why: str) -> None:
        """An edit of anything but a literal's numbers (those are
        field_lists): the output's structure changes."""
        self.others = True
        self._edit_at(fi, span.start, span.end, text, why)

    def _edit_at(self, fi: int, start: int, end: int, text: str, why: str) -> None:
        key = (fi, start, end)
        old = self.edits.get(key)
        if old is not None and old.replacement != text:
            raise InternalError(f"{self.plan.files[fi].source.display_path}: conflicting edits "
                                f"at offset {start}: {why}")
        # (SpanEdit as its class makes it: 2e5 of them turning a CAM program
        # into MoveAbsJ.)
        self.edits[key] = span_edit((start, end, text, why))

    # -------------------------------------------------------- declarations
    def _anchor(self, g: Group) -> tuple[int, int, str, str, bool]:
        """Where a new declaration goes: after the source declaration when
        it is in the home module, else after the home module's last data
        declaration (or its MODULE line): at the end of its line, or, where
        that line goes on with anything but declarations and a comment,
        right after the last declaration of the line.
        Returns (file, offset, line break, indentation, in a routine)."""
        return self._anchor_of(g.home, g.decl, g.src.home_module)

    def _anchor_of(self, home: tuple, decl, decl_module) -> tuple[int, int, str, str, bool]:
        """_anchor of a group of home `home` whose source is declaration
        decl (or None) of module decl_module."""
        fi, module = home
        if decl is not None and decl_module is module:
            span = decl.span
            return self._after(fi, module, span, decl.node,
                               _indent(self.text(fi), span.start), decl.routine is not None)
        # (After the module's last data declaration: one place per file and
        # module, found once; a CAM program's 5e4 inline targets turned
        # into MoveAbsJ each declare a jointtarget there.)
        key = ("anchor", fi, id(module))
        found = self._per_module.get(key)
        if found is None:
            last = None
            for item in module.node.items:
                if isinstance(item, A.DataDecl):
                    last = item
                elif isinstance(item, A.Routine):
                    break
            span = last.span if last is not None else module.node.name_span
            indent = _indent(self.text(fi), span.start) + ("" if last is not None else "    ")
            found = self._per_module[key] = self._after(fi, module, span, last, indent, False)
        return found

    def _after(self, fi: int, module, span, node, indent: str, in_routine: bool
               ) -> tuple[int, int, str, str, bool]:
        """_anchor's place at the end of the line of `span` (declaration
        `node`'s, or the MODULE line's where node is None)."""
        text = self.text(fi)
        end, nl = _line_end(text, span.end)
        if node is not None:
            # (`CONST robtarget p:=[...]; n:=1;` or `...; PROC main()`: after
            # the line, the new declaration would follow a statement or lie
            # in a routine; right after the line's declarations, the rest of
            # the line follows the new one.)
            after = self._line_decls_end(fi, module, node)
            if after > end:
                # (A declaration of the line goes on onto the next lines: the
                # line that matters is the one where the last of them ends.)
                end, nl = _line_end(text, after)
            rest = text[after:end].lstrip(" \t")
            if rest and not rest.startswith("!"):
                end = after
        return fi, end, nl, indent, in_routine

    def _line_decls_end(self, fi: int, module, node) -> int:
        """The end of declaration `node`, or of the last declaration that
        follows it on its line with nothing but blanks between."""
        key = ("next", id(module))
        following = self._per_module.get(key)
        if following is None:
            # Once per module: what follows each module item, and each
            # routine's declaration in its routine.
            following = self._per_module[key] = {
                id(a): b for items in (module.node.items, *(r.node.decls for r in module.routines))
                for a, b in zip(items, items[1:])}
        text = self.text(fi)
        end = node.span.end
        while True:
            b = following.get(id(node))
            if type(b) is not A.DataDecl or text[end:b.span.start].strip(" \t"):
                return end
            node, end = b, b.span.end

    def declare(self, g: Group, type_name: str, name: str, dims: str, value: str,
                converted: bool = False, anchor: tuple | None = None) -> None:
        """converted: a declaration the output is read again on (the
        jointtarget of moves turned into MoveAbsJ, a copy of a target);
        anchor: _anchor(g), when the caller has it."""
        self.others = self.others or not converted
        anchor = anchor or self._anchor(g)
        self._declare(anchor, g.local,
                      self._assign(anchor[0], g.decl, g.src.home_module, g.home_module),
                      type_name, name, dims, value)

    def _declare(self, anchor: tuple, local: bool, assign: str, type_name: str, name: str,
                 dims: str, value: str) -> None:
        """declare() at `anchor` (_anchor's), ':=' spaced `assign`."""
        fi, end, nl, indent, in_routine = anchor
        scope = "" if in_routine or not local else "LOCAL "
        decl = f"{scope}CONST {type_name} {name}{dims}{assign}{value};"
        at = self.inserts.get((fi, end))
        if at is None:
            self.inserts[(fi, end)] = [nl, indent, decl]
        else:
            at[0], at[1] = nl, indent
            at.append(decl)

    def _assign(self, fi: int, decl, decl_module, home_module) -> str:
        """':=' spaced as in the declaration `decl` (of module decl_module)
        the new one comes from, where it is in home_module, of file fi
        (else as in home_module's first declaration with a value)."""
        text = self.text(fi)
        if decl is not None and decl_module is home_module:
            node = decl.node
        else:
            # The module's first declaration with a value (once per module:
            # a CAM program asks for each of its 1e5 targets).
            key = ("first value", id(home_module))
            if key not in self._per_module:
                self._per_module[key] = next((it for it in home_module.node.items
                                          if isinstance(it, A.DataDecl) and it.init is not None),
                                         None)
            node = self._per_module[key]
        if node is None:
            return " := "
        head = text[node.span.start:node.init.span.start].rstrip("\t ")
        # The spaces either side of the ':=' as written (at most one each).
        before = " " if head[:-2].endswith(" ") else ""
        after = " " if text[node.init.span.start - 1] == " " else ""
        return before + ":=" + after

    def array_value(self, g: Group, nl: str, indent: str, texts: dict) -> str:
        return self._array_literal(g, nl, indent,
                                   lambda g, k: self.values.literal(g, k, texts.get(k)))

    # -------------------------------------------------------- per group
    def apply(self, g: Group | Singles) -> None:
        if type(g) is Singles:
            if not self.transient:
                self._apply_singles(g)
            else:
                self._transient_singles(g, g.elements)
            return
        if self.transient:
            self._apply_transient(g)
            return
        vals = self.values
        type_name = "jointtarget" if g.mode in ("absj", "joint") else "robtarget"
        texts: dict = {}
        changes: dict = {}
        if g.mode != "absj":
            for k in g.elements:
                texts[k], changes[k] = vals.field_edits(g, k)
                if g.mode == "rob" and type(texts[k]) is not str:
                    why = _named_conf(vals.source(g, k), texts[k][7:11])
                    if why is not None:
                        g.failure = (why, k)
                        return
        if g.mode != "absj" and not any(changes.values()):
            # Nothing moves beyond the precision a new text would carry: the
            # value stays as written (a zero profile changes no byte).
            for u in g.uses:
                self.actions[u.key] = "unchanged (the change is below the written precision)"
            return
        if g.placement == "in place" or (g.placement == "inline" and g.mode != "absj"):
            for k in g.elements:
                record = vals.source(g, k).record
                fi = (self.plan.file_index[id(g.src.home)] if g.decl is not None
                      else g.uses[0].key[0])
                key = (fi, record.span.start)
                old = self.fields.get(key)
                if old is not None:
                    if _as_literal(record, old[1]) != _as_literal(record, texts[k]):
                        raise InternalError(f"{self.plan.files[fi].source.display_path}: "
                                            f"conflicting edits of the literal at offset "
                                            f"{record.span.start}: {element_label(g, k)}")
                    continue
                self.fields[key] = (record, texts[k])
                if changes[k]:
                    self.field_lists.append((fi, changes[k]))
            what = (f"inline {type_name} rewritten" if g.decl is None
                    else f"{type_name} {g.decl.name} rewritten in place")
            for u in g.uses:
                self.actions[u.key] = what
            return
        if g.placement == "inline":  # absj of an inline robtarget: inline jointtarget
            for u in g.uses:
                literal = vals.literal(g, None)
                called = self._to_absj(u, literal)
                self.converted[u.key] = (u, literal, None, called, None)
                self.actions[u.key] = self._said(
                    f"{u.motion.instruction} -> MoveAbsJ, inline jointtarget")
            return
        # A new declaration next to the source one.
        if g.array:
            name = self.names.new(("jt_" + _stem(g)) if g.mode == "absj" else _stem(g) + "_c")
            _, _, nl, indent, _ = self._anchor(g)
            # (A jointtarget array of moves turned into MoveAbsJ is read
            # again with them: verify.relex_absj.)
            self.declare(g, type_name, name, _dims(g), self.array_value(g, nl, indent, texts),
                         converted=g.mode == "absj")
            g.names = writable(g.names)
            g.names["array"] = name
        else:
            literals = {}
            for k in g.elements:
                s = _stem(g, k)
                name = self.names.new(("jt_" + s) if g.mode == "absj" else s + "_c")
                literals[k] = vals.literal(g, k, texts.get(k))
                # (A copy of a declared target is read again where its uses
                # name it by a plain name: verify.relex_copies.)
                self.declare(g, type_name, name, "", literals[k], converted=g.mode == "absj"
                             or all(_plain_ref(u.source.ref) for u in g.uses))
                g.names = writable(g.names)
                g.names[k] = name
        for u in g.uses:
            src = u.source
            if g.array:
                ref_text = u.file.text(src.ref)
                new_ref = g.names["array"] + ref_text[len(src.ref.name):]
            else:
                new_ref = g.names[src.element]
            if g.mode == "absj":
                called = self._to_absj(u, new_ref)
                self.converted[u.key] = (u, None if g.array else literals[src.element],
                                         new_ref, called, g.home[0])
                self.actions[u.key] = f"{u.motion.instruction} -> MoveAbsJ {new_ref}"
            elif not g.array and _plain_ref(src.ref):
                self._edit_at(u.key[0], src.ref.span.start, src.ref.span.end, new_ref,
                              f"{u.label} -> {new_ref}")
                self.copies[u.key] = (u, literals[src.element], new_ref, type_name, g.home[0])
                self.actions[u.key] = f"new {type_name} {new_ref}"
            else:
                self.edit(u.key[0], src.ref.span, new_ref, f"{u.label} -> {new_ref}")
                self.actions[u.key] = f"new {type_name} {new_ref.split('{')[0]}"

    def apply_new(self, s: Singles, ns: list[int]) -> None:
        """apply() of elements ns of Singles whose elements each make a new
        name and declaration, one after the other (place.apply_order): each
        as the Group of its one use (its literal the one prepared for the
        element). A declared target's move turned into MoveAbsJ on a new
        jointtarget next to it (RobotStudio's way: every target declared,
        each moved to once; 1e5 of them), and a transient output's
        <name>_dq next to it, without making that Group."""
        if self.transient:
            self._transient_singles(s, ns)
            return
        if s.mode != "absj" or s.placement != "new":
            self._apply_one_by_one(s, ns)
            return
        names, vals = self.names, self.values
        converted, actions = self.converted, self.actions
        for n in ns:
            u = s.uses[n]
            # (As apply() names it: "jt_" and _stem of the group, which is
            # the declaration's name: Singles hold no Offs/RelTool.)
            name = names.new("jt_" + u.source.decl.name)
            literal = vals.absj_literal(s, n)
            home = self._declare_next_to(u, "jointtarget", name, literal)
            called = self._to_absj(u, name)
            converted[u.key] = (u, literal, name, called, home)
            actions[u.key] = f"{u.motion.instruction} -> MoveAbsJ {name}"

    def _declare_next_to(self, u, type_name: str, *named: str) -> int:
        """declare() of the Group of u alone, u's target a declaration of a
        given module (Singles.single's home: that module), of each name and
        value of `named` (name, value, name, value, ...), in that order:
        next to it, LOCAL unless another module's move reads it. Returns
        the index of the file they go in. (RobotStudio's way, 1e5 declared
        targets each getting its own: no anchor's search where the
        declaration ends its line.)"""
        src = u.source
        decl, module = src.decl, src.home_module
        fi = self.plan.file_index[id(src.home)]
        text = self.plan.files[fi].source.text
        span = decl.span
        end = span.end
        c = text[end:end + 1]
        if c == "\n" or c == "\r" or not c:
            # (The declaration ends its line, as RobotStudio writes every one
            # of 1e5: the place _anchor_of finds, at the end of that line,
            # without its search for declarations that follow on it.)
            nl = "\r\n" if text.startswith("\r\n", end) else c or "\n"
            anchor = (fi, end, nl, _indent(text, span.start), decl.routine is not None)
        else:
            anchor = self._anchor_of((fi, module), decl, module)
        local, assign = u.module is module, self._assign(fi, decl, module, module)
        for at in range(0, len(named), 2):
            self._declare(anchor, local, assign, type_name, named[at], "", named[at + 1])
        return anchor[0]

    def _apply_one_by_one(self, s: Singles, ns) -> None:
        """apply() of elements ns of s, each as the Group of its one use
        (Singles.single; its prepared values lent to it). One that fails
        (a transient output's confdata) goes to self.failed, for the caller
        to make it the Group of its own it is (place.split_off)."""
        file_index = self.plan.file_index
        for n in ns:
            g = s.single(n, file_index, placed=True)
            with self.values.lent(s, n, g):
                self.apply(g)
            if g.failure is not None:
                self.failed.append((s, n, g.failure))

    def _transient_singles(self, s: Singles, ns) -> None:
        """_apply_one_by_one of elements ns of s (in the groups' order where
        they make new names) in a transient output: what _apply_transient
        writes for the Group of each one's use, without that Group (a CAM
        program's 1e5 inline targets; RobotStudio's way, every target
        declared and moved to once, 1e5 of them):
        - turned into MoveAbsJ: rcTcJ(cold, dq), the cold value and its
          correction inline, or declared next to the target as
          jt_<name> and jt_<name>_dq;
        - kept a robtarget move, where the written confdata serves every
          state: rcTcR(<target as written>, dq), the correction inline, or
          declared next to the target as <name>_dq;
        any other element, in its turn, that Group's way."""
        vals, names = self.values, self.names
        actions, calls = self.actions, self.calls
        if s.mode == "absj":
            why = self._said(f"MoveAbsJ {FUNC_J}(cold, correction)")
            for n in ns:
                u = s.uses[n]
                src = u.source
                cold_lit, dq_lit = vals.transient_literals(s, n)
                if s.declared:
                    # (As _declare_transient names and declares them.)
                    cold = names.new("jt_" + src.decl.name)
                    dq = names.new(cold[:29] + "_dq")
                    self.others = True
                    self._declare_next_to(u, "jointtarget", cold, cold_lit, dq, dq_lit)
                    target = f"{FUNC_J}({cold}, {dq})"
                    called = self._to_absj(u, target)
                    actions[u.key] = f"{u.motion.instruction} -> MoveAbsJ {target}"
                    calls[u.key] = (u, cold, dq, dq_lit, FUNC_J, src.expr.span, called,
                                    cold_lit)
                else:
                    # (As _apply_transient writes an inline one.)
                    called = self._to_absj(u, f"{FUNC_J}({cold_lit}, {dq_lit})")
                    actions[u.key] = self._said(f"{u.motion.instruction} -> {why}")
                    calls[u.key] = (u, cold_lit, None, dq_lit, FUNC_J, src.expr.span, called,
                                    cold_lit)
            return
        kept_literal = vals.kept_pose_literal
        why = self._said(f"target -> {FUNC_R}")
        inline = self._said(f"inline robtarget -> {FUNC_R}(written, correction)")
        for n in ns:
            literal = kept_literal(s, n)
            if literal is None:
                self._apply_one_by_one(s, (n,))
                continue
            u = s.uses[n]
            src = u.source
            ref_text = u.file.text(src.ref)
            if s.declared:
                # (As _declare_transient names and declares it: no cold copy.)
                dq = names.new(src.decl.name[:29] + "_dq")
                self._declare_next_to(u, "pose", dq, literal)
                # (As _use_transient writes its target.)
                target = f"{FUNC_R}({ref_text}, {dq})"
                self.edit(u.key[0], src.ref.span, target, why)
                actions[u.key] = f"{ref_text} -> {target}"
                calls[u.key] = (u, ref_text, dq, literal, FUNC_R, src.ref.span, None, None)
            else:
                # (As _apply_transient_rob writes an inline one.)
                self.edit(u.key[0], src.ref.span, f"{FUNC_R}({ref_text}, {literal})", why)
                actions[u.key] = inline
                calls[u.key] = (u, ref_text, None, literal, FUNC_R, src.ref.span, None, None)

    def _apply_singles(self, s: Singles) -> None:
        """apply() of each element of s as of the Group of its one use: its
        inline literal's numbers rewritten (or left as written where no
        number changes), or its move turned into MoveAbsJ on an inline
        jointtarget. (Its literal is its use's alone, and a literal of
        numbers names no confdata: nothing here fails.)"""
        if s.ordered:
            # (Each element's new name and declaration come at its place
            # among the groups: place.apply_order gives it to apply_new.)
            raise InternalError("Singles making new declarations are written one by one, in "
                                "the groups' order")
        vals, actions = self.values, self.actions
        if s.mode == "absj":
            for n, u in enumerate(s.uses):
                literal = vals.literal(s, n)
                called = self._to_absj(u, literal)
                self.converted[u.key] = (u, literal, None, called, None)
                actions[u.key] = self._said(
                    f"{u.motion.instruction} -> MoveAbsJ, inline jointtarget")
            return
        fields, lists = self.fields, self.field_lists
        file_index = self.plan.file_index
        for n, u in enumerate(s.uses):
            texts, changes = vals.field_edits(s, n)
            if not changes:
                actions[u.key] = "unchanged (the change is below the written precision)"
                continue
            src = u.source
            record = src.record
            # (A declaration's literal is in its own file.)
            fi = file_index[id(src.home)] if s.declared else u.key[0]
            key = (fi, record.span.start)
            if key in fields:
                raise InternalError(f"{self.plan.files[fi].source.display_path}: a literal "
                                    f"read by one use is written twice (offset "
                                    f"{record.span.start})")
            fields[key] = (record, texts)
            lists.append((fi, changes))
            actions[u.key] = (f"robtarget {src.decl.name} rewritten in place" if s.declared
                              else "inline robtarget rewritten")

    # -------------------------------------------------------- transient
    def _dq_literal(self, g: Group, k) -> str:
        return records.correction_literals(self.values.dq(g, k)[None])[0]

    def _cold_literal(self, g: Group, k) -> str:
        if g.mode == "absj":
            return records.jointtarget_literal(
                records.absj_texts(self.values.cold(g, k), self.values.source(g, k).record))
        return records.jointtarget_literal(list(self.values.source(g, k).record.texts))

    def _array_literal(self, g: Group, nl: str, indent: str, literal) -> str:
        dims = g.decl.dims
        lits = [literal(g, k) for k in range(len(g.decl.value))]

        def nest(items, ds):
            if len(ds) == 1:
                return "[" + ",".join(items) + "]"
            step = len(items) // ds[0]
            return "[" + ",".join(nest(items[i * step:(i + 1) * step], ds[1:])
                                  for i in range(ds[0])) + "]"
        rows = len(lits) // dims[0]
        parts = [nest(lits[i * rows:(i + 1) * rows], dims[1:]) if len(dims) > 1 else lits[i]
                 for i in range(dims[0])]
        inner = self._rows_indent(g, indent)
        return "[" + nl + inner + ("," + nl + inner).join(parts) + "]"

    def _rows_indent(self, g: Group, indent: str) -> str:
        """The indentation of a new array's rows: that of the rows of the
        array it comes from, where they begin lines of their own; else one
        step past the declaration's `indent`: a tab in a module indented
        with tabs, four spaces otherwise."""
        init = g.decl.node.init
        text = self.text(self.plan.file_index[id(g.src.home)])
        m = _FIRST_ROW.match(text, init.span.start, init.span.end)
        if m is not None:
            return m.group(1)
        return indent + ("\t" if "\t" in indent else "    ")

    def _pose_literal(self, g: Group, k) -> str:
        return self.values.pose_literal(g, k)

    def _apply_transient(self, g: Group) -> None:
        """The cold value and the steady-state correction as named
        constants, each move's target computed from them by rcTcJ (MoveAbsJ)
        or rcTcR (robtarget moves). A jointtarget of the program stays as
        written (it is the cold value) and gets its <name>_dq; a robtarget
        of a move that becomes MoveAbsJ becomes jt_<name> and jt_<name>_dq."""
        if g.mode == "rob":
            # One confdata serves every state: the written one, or the warm
            # robot's where the cold joints are within the quadrant
            # tolerance of it too (a J4 at 0 deg that the warm robot needs
            # at -0.02 deg); then the cold value is a copy with that confdata.
            confs = {}
            for k in g.elements:
                if self.values.conf_kept(g, k):
                    continue
                _, _, conf = self.values.pose_dq(g, k)
                written = np.asarray(self.values.source(g, k).record.conf)
                q = self.values.cold(g, k)
                if all(quadrant_miss(q[col], conf[cf]) <= self.values.tol
                       for col, cf in ((0, 0), (3, 1), (5, 2))):
                    why = _named_conf(self.values.source(g, k), [str(int(c)) for c in conf])
                    if why is not None:
                        g.failure = (why, k)
                        for u in g.uses:
                            self.actions.pop(u.key, None)
                        return
                    confs[k] = conf
                    continue
                g.failure = (f"the warm robot needs confdata {_conf(conf)}, the cold one "
                             f"{_conf(written)}: one robtarget cannot carry both states "
                             "(--emit absj makes it a MoveAbsJ)", k)
                for u in g.uses:
                    self.actions.pop(u.key, None)
                return
            if confs and g.left_out:
                # (Its cold values would be a copy with the warm robot's
                # confdata, which the moves of the elements it left out as
                # written would read too: refused as one, for the first.)
                g.refuse_as_one(" (its cold values are a copy with the warm robot's "
                                "confdata, which the refused point's move would read too)")
                for u in g.uses:
                    self.actions.pop(u.key, None)
                return
            self._apply_transient_rob(g, FUNC_R, confs)
            return
        # (A MoveAbsJ's jointtarget as written, or a move turned into one,
        # not an array nor an Offs/RelTool: self.calls.)
        plain = not g.array and g.src.call is None
        self.calls_other = self.calls_other or not plain
        if g.placement == "inline" or g.decl is None:
            for u in g.uses:
                k = u.source.element
                cold = (u.file.text(u.source.expr) if g.mode == "joint"
                        else self._cold_literal(g, k))
                dq = self._dq_literal(g, k)
                target = f"{FUNC_J}({cold}, {dq})"
                if g.mode == "joint":
                    self.edit(u.key[0], u.source.expr.span, target, f"{u.label} -> {FUNC_J}")
                    self.actions[u.key] = f"inline jointtarget -> {FUNC_J}(cold, correction)"
                    if plain:
                        self.calls[u.key] = (u, cold, None, dq, FUNC_J, u.source.expr.span,
                                             None, None)
                else:
                    called = self._to_absj(u, target)
                    self.actions[u.key] = (f"{u.motion.instruction} -> MoveAbsJ "
                                           f"{FUNC_J}(cold, correction)")
                    if plain:
                        self.calls[u.key] = (u, cold, None, dq, FUNC_J, u.source.expr.span,
                                             called, cold)
            return
        absj = g.mode == "absj"
        literals: dict | None = {} if plain else None
        names = self._declare_transient(
            g, "jointtarget", (lambda s, k: "jt_" + s) if absj else (lambda s, k: None),
            self._cold_literal, "jointtarget", self._dq_literal, dq_after_cold=True,
            literals=literals)
        self._use_transient(g, names, FUNC_J, absj, literals)

    def _declare_transient(self, g: Group, cold_type: str, cold_name, cold_literal,
                           dq_type: str, dq_literal, dq_after_cold: bool,
                           literals: dict | None = None) -> dict:
        """The named constants of a declared group: per element (or
        "array") the cold value's name (None: the program's own data is
        the cold value; cold_name(stem, element) says) and the
        correction's, <cold>_dq or <stem>_dq. literals, when given,
        receives each element's correction literal and its new cold value's
        (or None) (not of an array)."""
        # (Where its declarations go, found once for all of them.)
        anchor = self._anchor(g)
        _, _, nl, indent, _ = anchor
        names: dict = {}
        items = [("array", None)] if g.array else [(k, k) for k in g.elements]
        for key, k in items:
            s = _stem(g, k)
            want = cold_name(s, key if g.array else k)
            cold = self.names.new(want) if want else None
            if cold is not None and cold_type == "robtarget":
                self.cold_copies.append(cold)
            dq = self.names.new(((cold if dq_after_cold and cold else s))[:29] + "_dq")
            if g.array:
                if cold is not None:
                    self.declare(g, cold_type, cold, _dims(g),
                                 self._array_literal(g, nl, indent, cold_literal),
                                 anchor=anchor)
                self.declare(g, dq_type, dq, _dims(g),
                             self._array_literal(g, nl, indent, dq_literal), anchor=anchor)
            else:
                cold_text = None
                if cold is not None:
                    cold_text = cold_literal(g, k)
                    self.declare(g, cold_type, cold, "", cold_text, anchor=anchor)
                literal = dq_literal(g, k)
                self.declare(g, dq_type, dq, "", literal, anchor=anchor)
                if literals is not None:
                    literals[k] = (literal, cold_text)
            names[key] = (cold, dq)
            if g.array:
                # (Read by the note on slots no move reaches, fix._notes:
                # not kept for each of 1e5 declared targets.)
                g.names = writable(g.names)
                g.names[key] = cold or g.decl.name
        return names

    def _use_transient(self, g: Group, names: dict, func: str, absj: bool,
                       literals: dict | None = None) -> None:
        """Each use's target becomes func(<cold>, <dq>) (with its index).
        literals: each element's correction literal and new cold value's,
        for self.calls."""
        pers = g.decl is not None and g.decl.storage == "PERS"
        for u in g.uses:
            src = u.source
            ref_text = u.file.text(src.ref)
            cold, dq = names["array"] if g.array else names[src.element]
            index = ref_text[len(src.ref.name):] if g.array else ""
            cold_ref = (cold + index) if cold is not None else ref_text
            if pers and cold is not None:
                self.pers_copies.add(u.key)
            target = f"{func}({cold_ref}, {dq}{index})"
            if absj:
                called = self._to_absj(u, target)
                self.actions[u.key] = f"{u.motion.instruction} -> MoveAbsJ {target}"
                if literals is not None:
                    dq_lit, cold_lit = literals[src.element]
                    self.calls[u.key] = (u, cold_ref, dq, dq_lit, func, src.expr.span, called,
                                         cold_lit)
            else:
                # (One why for 1e5 edits: it names an edit only in an
                # internal error.)
                self.edit(u.key[0], src.ref.span, target, self._said(f"target -> {func}"))
                self.actions[u.key] = f"{ref_text} -> {target}"
                if literals is not None:
                    dq_lit, cold_lit = literals[src.element]
                    self.calls[u.key] = (u, cold_ref, dq, dq_lit, func, src.ref.span, None,
                                         cold_lit)

    def _apply_transient_rob(self, g: Group, func: str, confs: dict) -> None:
        """A robtarget move keeps its kind (a MoveL its straight line): its
        target becomes func(<robtarget as written>, <name>_dq), the
        correction a pose (translation and quaternion difference). confs:
        element -> the confdata every state needs where the written one does
        not serve (the cold value is then a copy with it, <name>_cold)."""
        def cold_literal(g, k):
            src = self.values.source(g, k)
            texts = list(src.record.texts)
            if k in confs:
                texts[7:11] = [str(int(c)) for c in confs[k]]
            literal = records.robtarget_literal(texts)
            axes = named_part(src.expr, -1)
            if axes is not None:
                # (Its external axes named data, [[x,y,z],[q],[cf],extj]:
                # the name kept, as written.)
                literal = literal[:literal.rindex(",[")] + "," + axes + "]"
            return literal

        self.cold_moves += sum(u.source.element in confs for u in g.uses) if confs else 0
        # (Its cold value its target as written, a name or a literal, and no
        # Offs/RelTool around it: self.calls, read again as such.)
        plain = not confs and not g.array and g.src.call is None
        self.calls_other = self.calls_other or not plain
        if g.placement == "inline" or g.decl is None:
            for u in g.uses:
                k = u.source.element
                cold = cold_literal(g, k) if k in confs else u.file.text(u.source.ref)
                self.cold_inline += k in confs
                dq = self._pose_literal(g, k)
                target = f"{func}({cold}, {dq})"
                self.edit(u.key[0], u.source.ref.span, target, self._said(f"target -> {func}"))
                self.actions[u.key] = self._said(
                    f"inline robtarget -> {func}(written"
                    + (" with the confdata every state needs" if k in confs else "")
                    + ", correction)")
                if plain:
                    self.calls[u.key] = (u, cold, None, dq, func, u.source.ref.span, None,
                                         None)
            return
        literals: dict | None = {} if plain else None
        names = self._declare_transient(
            g, "robtarget",
            lambda s, k: s[:27] + "_cold" if (confs if k == "array" else k in confs) else None,
            cold_literal, "pose", self._pose_literal, dq_after_cold=False, literals=literals)
        self._use_transient(g, names, func, False, literals)

    def _said(self, text: str) -> str:
        """`text` as the one equal string this editor keeps (a CAM
        program's 1e5 moves say the same few things: ~15 MB)."""
        return self._said_texts.setdefault(text, text)

    def _to_absj(self, u, target_text: str) -> str:
        """The move turned into MoveAbsJ on target_text; returns its new
        instruction name as written."""
        m = u.motion
        fi = u.key[0]
        # (Its name and why once per instruction as written: a CAM program
        # turns 1e5 MoveL into MoveAbsJ.)
        named = self._renamed.get(m.instruction)
        if named is None:
            named = self._renamed[m.instruction] = (
                _style("MoveAbsJ", m.instruction), self._said(f"{m.instruction} -> MoveAbsJ"),
                self._said(f"{m.instruction} -> MoveAbsJ: its target"))
        called, why, why_target = named
        # (Its name's span as Motion.name_span gives it, without the Span.)
        start = m.span.start
        self._edit_at(fi, start, start + len(m.instruction), called, why)
        # (One why for 1e5 edits, as the name's: it names an edit only in an
        # internal error, which gives its place.)
        expr = u.source.expr.span
        self._edit_at(fi, expr.start, expr.end, target_text, why_target)
        return called

    def file_edits(self) -> dict[int, list[SpanEdit] | EditColumns]:
        """Each file's edits in the order BY_SPAN sorts them; as
        EditColumns where a batch of plain literals wrote its fields (their
        edits stay columns to the splice, the verification and the
        result)."""
        out: dict[int, list] = {}
        runs: set[int] = set()
        for (fi, _, _), e in self.edits.items():
            out.setdefault(fi, []).append(e)
        for fi, es in self.field_lists:
            if type(es) is EditRun:
                runs.add(fi)
                out.setdefault(fi, []).append(es)
            else:
                out.setdefault(fi, []).extend(es)
        for (fi, pos), (nl, indent, *decls) in self.inserts.items():
            out.setdefault(fi, []).append(SpanEdit(pos, pos, "".join(nl + indent + d
                                                                     for d in decls),
                                                   "new declarations"))
        # Many edits of other kinds (a CAM program turned into MoveAbsJ:
        # 2.5e5) are columns too, made once: the splice, the verification
        # and the diff read them as such (each made its own of a list). Their
        # texts stay str (packing them cost more than it saved: the peak is
        # elsewhere).
        return {fi: (sorted_columns(columns_of(es)) if fi in runs
                     else sorted_columns(EditColumns.of(es, pack=False)) if len(es) >= COLUMNS_FROM
                     else sorted(es, key=BY_SPAN)) for fi, es in out.items()}


def _conf(c) -> str:
    return "[" + ",".join(str(int(x)) for x in c) + "]"


def _plain_ref(ref) -> bool:
    """A reference that is a name alone (no component, no index)."""
    return type(ref) is A.Ref and not ref.selectors


def _stem(g: Group, k=None) -> str:
    """The name new data of a declared group are made from: the source
    declaration's (with its Offs/RelTool), and an element's index."""
    stem = g.decl.name
    if g.src.call is not None:
        stem += "_" + g.src.call.name.lower()
    return stem if k is None else stem + "_" + "_".join(map(str, multi_index(k, g.decl.dims)))


def _dims(g: Group) -> str:
    return "{" + ",".join(map(str, g.decl.dims)) + "}"


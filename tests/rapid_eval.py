"""A small evaluator for the RAPID subset rapidcomp's generated support
module uses (tests only): data declarations, PROC/FUNC with value and
INOUT parameters, assignments to record components, IF (compact too),
RETURN, procedure calls, arithmetic in float32 as the controller's num, and
the built-ins the module calls (CDate, CTime, StrPart, StrToVal, Exp,
NOrient, AInput, TPWrite), whose clock and I/O the test supplies.

Written from the RAPID semantics, separately from the code that generates
the module: the tests execute the generated text with it.
"""

from __future__ import annotations

import math

import numpy as np

from rapidcomp.rapid import ast as A
from rapidcomp.rapid.parse import parse_text

F32 = np.float32

RECORDS = {
    "pos": ("x", "y", "z"),
    "orient": ("q1", "q2", "q3", "q4"),
    "confdata": ("cf1", "cf4", "cf6", "cfx"),
    "robjoint": tuple(f"rax_{k}" for k in range(1, 7)),
    "extjoint": tuple(f"eax_{c}" for c in "abcdef"),
    "jointtarget": ("robax", "extax"),
    "robtarget": ("trans", "rot", "robconf", "extax"),
    "pose": ("trans", "rot"),
}
COMPONENT_TYPES = {
    ("jointtarget", "robax"): "robjoint", ("jointtarget", "extax"): "extjoint",
    ("robtarget", "trans"): "pos", ("robtarget", "rot"): "orient",
    ("robtarget", "robconf"): "confdata", ("robtarget", "extax"): "extjoint",
    ("pose", "trans"): "pos", ("pose", "rot"): "orient",
}


class Return(Exception):
    def __init__(self, value):
        self.value = value


def make(type_name: str, value):
    """A RAPID value of `type_name` from a Python/aggregate value."""
    t = type_name.lower()
    if t == "num":
        return F32(value)
    if t in RECORDS:
        names = RECORDS[t]
        if isinstance(value, dict):
            return {n: make(COMPONENT_TYPES.get((t, n), "num"), value[n]) for n in names}
        return {n: make(COMPONENT_TYPES.get((t, n), "num"), v) for n, v in zip(names, value)}
    return value


def copy(v):
    return {k: copy(x) for k, x in v.items()} if isinstance(v, dict) else v


class Machine:
    """One task: the module's data and routines; `clock` is a callable
    giving (CDate, CTime) strings per read, `inputs` analog input values."""

    def __init__(self, text: str, clock=None, inputs=None):
        pf = parse_text(text, "support.sys")
        self.module = pf.modules[0].node
        self.text = text
        self.clock = clock
        self.inputs = inputs or {}
        self.printed: list[str] = []
        self.data: dict[str, object] = {}
        self.types: dict[str, str] = {}
        self.routines = {}
        for item in self.module.items:
            if isinstance(item, A.DataDecl):
                self.types[item.name.lower()] = item.type_name
                self.data[item.name.lower()] = make(
                    item.type_name, self.eval(item.init, [self.data]) if item.init is not None
                    else _zero(item.type_name))
            elif isinstance(item, A.Routine):
                self.routines[item.name.lower()] = item

    # ------------------------------------------------------------ routines
    def call(self, name: str, *args):
        """Call a routine with Python values (INOUT: a one-element list)."""
        r = self.routines[name.lower()]
        return self._invoke(r, [("value", a) for a in args])

    def _invoke(self, r: A.Routine, args):
        frame: dict[str, object] = {}
        cells = {}
        for p, (how, a) in zip(r.params, args):
            if p.access == "INOUT":
                cells[p.name.lower()] = a          # (scope dict, name)
                scope, key = a
                frame[p.name.lower()] = scope[key]
            else:
                frame[p.name.lower()] = make(p.type_name, a)
        for d in r.decls:
            frame[d.name.lower()] = make(d.type_name, self.eval(d.init, [frame, self.data])
                                         if d.init is not None else _zero(d.type_name))
        try:
            self.run(r.body, [frame, self.data])
            result = None
        except Return as ret:
            result = ret.value
        for name, (scope, key) in cells.items():
            scope[key] = frame[name]
        return result

    def run(self, stmts, scopes) -> None:
        for s in stmts:
            if isinstance(s, A.Assign):
                self.assign(s.target, self.eval(s.value, scopes), scopes)
            elif isinstance(s, A.ProcCall):
                self.proc(s.name, s.args, scopes)
            elif isinstance(s, A.If):
                for cond, body in s.branches:
                    if self.eval(cond, scopes):
                        self.run(body, scopes)
                        break
                else:
                    self.run(s.orelse, scopes)
            elif isinstance(s, A.CompactIf):
                if self.eval(s.cond, scopes):
                    self.run((s.stmt,), scopes)
            elif isinstance(s, A.Simple) and s.kind.upper() == "RETURN":
                raise Return(self.eval(s.expr, scopes) if s.expr is not None else None)
            else:
                raise NotImplementedError(type(s).__name__)

    def proc(self, name: str, args, scopes) -> None:
        n = name.lower()
        if n == "tpwrite":
            text = self.eval(args[0].value, scopes)
            extra = [f"{float(self.eval(a.value, scopes)):g}" for a in args[1:]]
            self.printed.append(text + "".join(extra))
            return
        r = self.routines[n]
        self._invoke(r, [self._arg(p, a, scopes) for p, a in zip(r.params, args)])

    def _arg(self, p: A.Param, a: A.Arg, scopes):
        if p.access == "INOUT":
            if not isinstance(a.value, A.Ref) or a.value.selectors:
                raise NotImplementedError("INOUT of a component")
            return ("ref", self._scope_of(a.value.name, scopes))
        return ("value", copy(self.eval(a.value, scopes)))

    def _scope_of(self, name: str, scopes):
        for scope in scopes:
            if name.lower() in scope:
                return (scope, name.lower())
        raise NameError(name)

    # ------------------------------------------------------------ data
    def assign(self, target: A.Ref, value, scopes) -> None:
        scope, key = self._scope_of(target.name, scopes)
        if not target.selectors:
            old = scope[key]
            scope[key] = F32(value) if isinstance(old, np.floating) else copy(value)
            return
        node = scope[key]
        *path, last = target.selectors
        for sel in path:
            node = node[sel.name.lower()]
        old = node[last.name.lower()]
        node[last.name.lower()] = F32(value) if isinstance(old, np.floating) else copy(value)

    def eval(self, e, scopes):
        if isinstance(e, A.Num):
            return F32(e.value)
        if isinstance(e, A.Str):
            return e.value
        if isinstance(e, A.Bool):
            return e.value
        if isinstance(e, (A.Agg, A.NumAgg)):
            return [self.eval(x, scopes) for x in e.items]
        if isinstance(e, A.Paren):
            return self.eval(e.expr, scopes)
        if isinstance(e, A.Ref):
            scope, key = self._scope_of(e.name, scopes)
            v = scope[key]
            for sel in e.selectors:
                v = v[sel.name.lower()]
            return v
        if isinstance(e, A.Unary):
            v = self.eval(e.operand, scopes)
            if e.op.upper() == "NOT":
                return not v
            return F32(-v) if e.op == "-" else v
        if isinstance(e, A.Binary):
            return self.binary(e.op.upper(), self.eval(e.left, scopes),
                               self.eval(e.right, scopes))
        if isinstance(e, A.Call):
            return self.function(e, scopes)
        raise NotImplementedError(type(e).__name__)

    @staticmethod
    def binary(op, a, b):
        if op == "+":
            return a + b if isinstance(a, str) else F32(F32(a) + F32(b))
        if op == "-":
            return F32(F32(a) - F32(b))
        if op == "*":
            return F32(F32(a) * F32(b))
        if op == "/":
            return F32(F32(a) / F32(b))
        if op == "DIV":
            return F32(math.trunc(float(a) / float(b)))
        if op == "MOD":
            return F32(math.fmod(float(a), float(b)))
        if op in ("<", "<=", ">", ">=", "=", "<>"):
            return {"<": a < b, "<=": a <= b, ">": a > b, ">=": a >= b, "=": a == b,
                    "<>": a != b}[op]
        if op == "AND":
            return a and b
        if op == "OR":
            return a or b
        raise NotImplementedError(op)

    def function(self, e: A.Call, scopes):
        n = e.name.lower()
        args = e.args
        if n in ("cdate", "ctime"):
            date, time = self.clock()
            return date if n == "cdate" else time
        if n == "strpart":
            s, start, length = (self.eval(a.value, scopes) for a in args)
            return s[int(start) - 1:int(start) - 1 + int(length)]
        if n == "strtoval":
            text = self.eval(args[0].value, scopes)
            try:
                value = float(text)
            except ValueError:
                return False
            self.assign(args[1].value, F32(value), scopes)
            return True
        if n == "exp":
            return F32(math.exp(float(self.eval(args[0].value, scopes))))
        if n == "norient":
            q = self.eval(args[0].value, scopes)
            v = np.array([float(q[k]) for k in ("q1", "q2", "q3", "q4")])
            v = v / np.linalg.norm(v)
            return {k: F32(x) for k, x in zip(("q1", "q2", "q3", "q4"), v)}
        if n == "ainput":
            return F32(self.inputs[args[0].value.name])
        r = self.routines[n]
        return self._invoke(r, [self._arg(p, a, scopes) for p, a in zip(r.params, args)])


def _zero(type_name: str):
    t = type_name.lower()
    if t == "num":
        return 0.0
    if t == "string":
        return ""
    if t == "bool":
        return False
    return {n: _zero(COMPONENT_TYPES.get((t, n), "num")) for n in RECORDS[t]}

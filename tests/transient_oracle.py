"""The transient output's verification as it was first made, kept as the
oracle of verify.verify_states: every rcTcJ/rcTcR(cold, dq) of the written
program replaced by its value at state s (the controller's float32
arithmetic written out one state and one target at a time: state_joints,
state_pose), the text parsed again and verified as any output is. The
state's values come out of the text (9 significant digits: a float32
exactly), not out of the resolver's evaluation of the calls.

Its own lookup of the calls' arguments is by bare name among the written
modules' declarations (module data, then routine data): programs whose
names are all distinct and declared in the written modules, indices
literal numbers."""

from __future__ import annotations

import numpy as np

from rapidcomp.compensate.transient import FUNC_J, FUNC_R
from rapidcomp.compensate.verify import reparse, verify
from rapidcomp.edits import BY_SPAN, SpanEdit, apply_edits
from rapidcomp.errors import InternalError
from rapidcomp.rapid import ast as A
from rapidcomp.rapid.refs import nodes
from rapidcomp.rapid.values import DecodeIssue, decode_array
from rapidcomp.rewrite.names import NameAllocator


def f32(x) -> np.ndarray:
    return np.asarray(x, dtype=np.float32)


def state_joints(cold, dq, s: float) -> np.ndarray:
    """rcTcJ as the controller computes it: float32 numbers, float32
    arithmetic (cold + s * dq)."""
    return (f32(cold) + f32(f32(s) * f32(dq))).astype(np.float32)


def state_pose(trans, rot, d_trans, d_rot, s: float):
    """rcTcR as the controller computes it: translation and quaternion
    components cold + s * dq in float32, the quaternion normalized
    (NOrient)."""
    t = state_joints(trans, d_trans, s)
    q = state_joints(rot, d_rot, s).astype(float)
    norm = np.linalg.norm(q)
    return t, f32(q / norm if norm > 0 else q)


def verify_states(plan, solved, keys, texts, parsed, solvers) -> dict:
    """s -> residual (um, deg) by use key, of the written program
    materialized at s and parsed again."""
    return {s: verify(plan, solved, keys, reparse(plan, materialize(texts, parsed, s)), solver)
            for s, solver in solvers.items()}


def _records(kind: str, expr, dims: tuple[int, ...]) -> tuple:
    """The literal `expr` (of `dims`, an array) decoded, row-major."""
    try:
        return decode_array(kind, expr, dims, kind)
    except DecodeIssue as exc:
        raise InternalError(f"a transient value does not decode: {exc.reason}") from None


def _state_text(text: str, cold, dq, func: str, s: float, dims=()) -> str:
    """The cold value's text (a literal or an array of them) with every
    number the state changes replaced by its value at s."""
    joint = func == FUNC_J
    c = _records("jointtarget" if joint else "robtarget", cold, dims)
    d = _records("jointtarget" if joint else "pose", dq, dims)
    base = cold.span.start
    edits = []
    for cv, dv in zip(c, d):
        if joint:
            fields, new = cv.robax, state_joints(cv.joints, dv.joints, s)
        else:
            t, q = state_pose(cv.xyz, cv.quat_wxyz, dv.xyz, dv.quat_wxyz, s)
            fields, new = cv.trans + cv.rot, np.concatenate([t, q])
        edits += [SpanEdit(f.span.start - base, f.span.end - base, _text(v), "state value")
                  for f, v in zip(fields, new)]
    return apply_edits(text[cold.span.start:cold.span.end],
                       sorted(edits, key=BY_SPAN))


def _text(v) -> str:
    return f"{float(v):.9g}"


def materialize(texts: dict, parsed: dict, s: float) -> dict:
    """The written files (index -> text, and as parsed) with every
    rcTcJ/rcTcR(cold, dq) replaced by its value at state s, computed as the
    controller does (float32): the program a controller without the
    functions would run at that state. A call on declared data becomes a
    reference to a new constant holding that value, declared after the
    correction; a call on an array element with a literal index, or on an
    inline literal, becomes the literal. Only for verification: never
    written."""
    decls = {}
    for fi, pf in parsed.items():
        for m in pf.modules:
            for item in m.node.items:
                if isinstance(item, A.DataDecl):
                    decls[item.name.lower()] = (fi, item)
                elif isinstance(item, A.Routine):
                    for d in item.decls:
                        decls.setdefault(d.name.lower(), (fi, d))
    fresh = NameAllocator(list(texts.values()))
    edits: dict = {fi: [] for fi in texts}
    made: dict = {}
    funcs = {FUNC_J.lower(): FUNC_J, FUNC_R.lower(): FUNC_R}
    for fi, pf in parsed.items():
        text = texts[fi]
        for m in pf.modules:
            for node in nodes(m.node):
                if not (isinstance(node, A.Call) and node.name.lower() in funcs):
                    continue
                func = funcs[node.name.lower()]
                cold, dq = (a.value for a in node.args)
                if not isinstance(cold, A.Ref):
                    if isinstance(dq, A.Ref):
                        raise InternalError(f"{func}: an inline value with a declared correction")
                    new = _state_text(text, cold, dq, func, s)
                else:
                    (cfi, cold_decl), (dfi, dq_decl) = (_declared(decls, r, func)
                                                        for r in (cold, dq))
                    if cold.selectors and not dq.selectors:
                        # One element (a literal index) with its own correction.
                        new = _state_text(texts[cfi], _element(cold_decl, cold), dq_decl.init,
                                          func, s)
                    else:
                        key = (cold.name.lower(), dq.name.lower())
                        if key not in made:
                            made[key] = fresh.new("rcState")
                            dims = tuple(int(x.value) for x in dq_decl.dims)
                            value = _state_text(texts[cfi], cold_decl.init, dq_decl.init, func,
                                                s, dims)
                            type_name = "jointtarget" if func == FUNC_J else "robtarget"
                            shape = "{" + ",".join(map(str, dims)) + "}" if dims else ""
                            edits[dfi].append(SpanEdit(
                                dq_decl.span.end, dq_decl.span.end,
                                f"\nCONST {type_name} {made[key]}{shape}:={value};",
                                "state value"))
                        new = made[key] + text[cold.span.start:cold.span.end][len(cold.name):]
                edits[fi].append(SpanEdit(node.span.start, node.span.end, new, "state value"))
    return {fi: apply_edits(texts[fi], sorted(es, key=BY_SPAN))
            for fi, es in edits.items()}


def _declared(decls: dict, ref, func: str):
    if ref.name.lower() not in decls:
        raise InternalError(f"{func}: {ref.name} is not declared in the output")
    return decls[ref.name.lower()]


def _element(decl, ref):
    """The literal of decl's element that `ref` (literal indices) names."""
    node = decl.init
    for sel in ref.selectors:
        if not isinstance(sel, A.Index):
            raise InternalError(f"{ref.name}: a component where an element was expected")
        for idx in sel.indices:
            if not isinstance(idx, A.Num) or not isinstance(node, (A.Agg, A.NumAgg)):
                raise InternalError(f"{ref.name}: an element that is not a literal")
            node = node.items[int(idx.value) - 1]
    return node

"""`rapidcomp inspect`: what the parser found, as text or JSON."""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterator
from pathlib import Path

from . import ast as A
from .model import ParsedFile
from .values import JointTarget, RobTarget


def _fmt(x: float) -> str:
    return f"{x:.6g}"


def _value_summary(value) -> dict | None:
    if isinstance(value, RobTarget):
        return {"trans": list(value.xyz), "rot": list(value.quat_wxyz),
                "conf": list(value.conf), "extax": list(value.ext)}
    if isinstance(value, JointTarget):
        return {"robax": list(value.joints), "extax": list(value.ext)}
    return None


def alone(program: str) -> bool:
    """PROGRAM is one module file (not a task folder, program file or
    backup): inspect reads it as given, its JSON the module's report."""
    path = Path(program)
    return path.is_file() and path.suffix.lower() != ".pgf"


def modules_of(program: str, problems: list | None = None,
               unread: list | None = None, notes: list | None = None) -> Iterator[ParsedFile]:
    """The modules `inspect PROGRAM` reads, parsed one at a time: a module
    file as given; each module of a task folder, program file (.pgf) or
    controller backup (each of its tasks, motion or not), named by the path
    the user can open. problems, when given, receives why the controller
    would not load a task (task.load_problem: what check and fix refuse),
    as its InputError, once the task's modules are read. unread, when
    given, receives the EncryptedModule error of each of a task's modules
    that cannot be read (check and fix take it as a module not given);
    without it that is bad input. notes, when given, receives what a task
    says of the modules it takes (a backup's list of them)."""
    from ..source import EncryptedModule
    from .parse import parse_file
    from .task import load_problem, tasks_of
    if alone(program):
        yield parse_file(program)
        return
    for source in tasks_of(program, (), motion_only=False):
        if notes is not None:
            notes.extend(source.notes)
        files = []
        for rel in source.modules:
            try:
                pf = parse_file(source.root / rel)
            except EncryptedModule as exc:
                if unread is None:
                    raise
                unread.append(exc)
                continue
            if problems is not None and len(source.modules) > 1:
                files.append(pf)
            yield pf
        problem = load_problem(source, files, list(source.modules)) if files else None
        if problem is not None:
            problems.append(problem)


def report(pf: ParsedFile) -> dict:
    """A JSON-ready description of the file (no absolute paths, no times)."""
    src = pf.source
    out = {
        "file": src.display_path,
        "encoding": src.encoding,
        "bom": src.has_bom,
        "newlines": src.newline,
        "header": pf.header is not None,
        "modules": [],
    }
    for m in pf.modules:
        kinds = Counter(d.type for d in m.declarations)
        decl_rows = []
        for d in m.declarations:
            if d.type not in ("robtarget", "jointtarget", "tooldata", "wobjdata", "loaddata"):
                continue
            row = {"name": d.name, "type": d.type, "storage": d.storage, "scope": d.scope,
                   "routine": d.routine, "line": pf.line(d.span),
                   "dims": list(d.dims) if d.dims else None}
            if d.issue:
                row["issue"] = d.issue
            if isinstance(d.value, tuple):
                row["values"] = [_value_summary(v) for v in d.value]
            elif d.value is not None and _value_summary(d.value) is not None:
                row["value"] = _value_summary(d.value)
            decl_rows.append(row)
        motion_rows = []
        for mo in m.motions:
            row = {"line": pf.line(mo.span), "instruction": mo.spec.name,
                   "routine": mo.routine,
                   "targets": [], "speed": pf.text(mo.speed) if mo.speed else None,
                   "zone": pf.text(mo.zone) if mo.zone else None,
                   "tool": pf.text(mo.tool) if mo.tool else None,
                   "wobj": pf.text(mo.wobj) if mo.wobj else None,
                   "optional": [pf.text(a) for a in mo.optional],
                   "loops": [lp.var for lp in mo.loops]}
            for t in mo.targets:
                tr = {"role": t.role}
                if isinstance(t.expr, (A.Agg, A.NumAgg)):
                    tr["inline"] = True
                    if t.value is not None:
                        tr.update(_value_summary(t.value))
                    else:
                        tr["issue"] = t.issue
                else:
                    tr["expr"] = pf.text(t.expr)
                row["targets"].append(tr)
            motion_rows.append(row)
        out["modules"].append({
            "name": m.name,
            "attributes": list(m.attributes),
            "counts": {
                "declarations": len(m.declarations),
                "robtargets": kinds.get("robtarget", 0),
                "jointtargets": kinds.get("jointtarget", 0),
                "tooldata": kinds.get("tooldata", 0),
                "wobjdata": kinds.get("wobjdata", 0),
                "routines": len(m.routines),
                "records": len(m.records),
                "motions": len(m.motions),
                "inline_targets": sum(1 for mo in m.motions for t in mo.targets
                                      if isinstance(t.expr, (A.Agg, A.NumAgg))),
            },
            "routines": [{"kind": r.kind, "name": r.name, "line": pf.line(r.node.span)}
                         for r in m.routines],
            "declarations": decl_rows,
            "motions": motion_rows,
        })
    return out


def render_text(rep: dict) -> str:
    lines = [f"{rep['file']}: {rep['encoding']}{' with BOM' if rep['bom'] else ''}, "
             f"{rep['newlines']} newlines{', %%% header' if rep['header'] else ''}"]
    for m in rep["modules"]:
        c = m["counts"]
        attrs = f" ({', '.join(m['attributes'])})" if m["attributes"] else ""
        lines.append(f"MODULE {m['name']}{attrs}")
        lines.append("  " + ", ".join(f"{k.replace('_', ' ')}: {v}" for k, v in c.items()))
        if m["routines"]:
            lines.append("  routines: " + ", ".join(
                f"{r['kind']} {r['name']} (line {r['line']})" for r in m["routines"]))
        if m["declarations"]:
            lines.append("  data:")
            for d in m["declarations"]:
                where = f" in {d['routine']}" if d["routine"] else ""
                dims = "{" + ",".join(str(x) for x in d["dims"]) + "}" if d["dims"] else ""
                extra = ""
                if "value" in d and "conf" in d["value"]:
                    extra = f"  conf [{','.join(str(x) for x in d['value']['conf'])}]"
                elif "issue" in d:
                    extra = f"  (no literal value: {d['issue']})"
                scope = f"{d['scope']} " if d["scope"] else ""
                lines.append(f"    {d['line']:>6}  {scope}{d['storage']} {d['type']} {d['name']}{dims}"
                             f"{where}{extra}")
        if m["motions"]:
            lines.append("  motions:")
            for mo in m["motions"]:
                tg = []
                for t in mo["targets"]:
                    if "expr" in t:
                        tg.append(t["expr"])
                    elif "conf" in t:
                        tg.append("inline [" + ",".join(_fmt(x) for x in t["trans"]) + "] conf ["
                                  + ",".join(str(x) for x in t["conf"]) + "]")
                    elif "robax" in t:
                        tg.append("inline [" + ",".join(_fmt(x) for x in t["robax"]) + "]")
                    else:
                        tg.append(f"inline (not literal: {t.get('issue')})")
                loop = f"  in FOR {','.join(v or 'WHILE' for v in mo['loops'])}" if mo["loops"] else ""
                lines.append(f"    {mo['line']:>6}  {mo['instruction']} {' / '.join(tg)}  "
                             f"tool {mo['tool'] or '-'}  wobj {mo['wobj'] or 'wobj0'}{loop}")
    return "\n".join(lines) + "\n"

"""fix's JSON report (--json) is json.dumps(doc, indent=2) of the whole
report, targets last; report.as_json encodes each target on its own and
indents it to its place (issue #14: a CAM program's 1e5 targets). Oracle:
json.dumps of the whole document, written here."""

import json
import sys
from pathlib import Path

import pytest

from rapidcomp.compensate import fix as F
from rapidcomp.compensate import report
from rapidcomp.compensate.load import load_solver
from rapidcomp.compensate.plan import Task
from rapidcomp.rapid.parse import parse_file, parse_text

ROOT = Path(__file__).resolve().parents[1]


def _whole(result, meta) -> str:
    doc = {"program": result.program, **meta, "summary": result.summary(),
           "notes": list(result.notes),
           "modules": [{"path": m.path, "changed": bool(m.edits), "diff": list(m.diff)}
                       for m in result.modules],
           "targets": [r.as_dict() for r in result.rows]}
    return json.dumps(doc, indent=2) + "\n"


@pytest.fixture(scope="module")
def solver():
    return load_solver(str(ROOT / "fixtures" / "warm.csv"), None, False, ("J5=-120:120",))


def test_json_report_is_the_whole_documents_dump(solver):
    sys.path.insert(0, str(ROOT / "bench"))
    from fix import cam_module
    tasks = [Task(p.name, (parse_file(p, p.name),)) for p in
             [ROOT / "fixtures" / "cubes.mod", ROOT / "fixtures" / "rapid" / "robodk.mod",
              ROOT / "fixtures" / "rapid" / "cam_inline.mod"]]
    tasks.append(Task("cam.mod", (parse_text(cam_module(300, 4), "cam.mod"),)))
    # No motion at all: no targets.
    tasks.append(Task("none.mod", (parse_text("MODULE N\n  PROC p()\n    WaitTime 1;\n"
                                              "  ENDPROC\nENDMODULE\n", "none.mod"),)))
    kinds = set()
    for task in tasks:
        for mode in ("auto", "absj"):
            result = F.fix(task, solver, mode)
            # Meta with a line break, a quote and a non-ASCII character.
            meta = {"mode": mode, "profile": 'wärm\n"x".csv'}
            assert report.as_json(result, meta) == _whole(result, meta)
            kinds.add((len(result.rows) > 0, result.failed > 0))
    assert kinds >= {(False, False), (True, False), (True, True)}

"""fix's reports are rendered as they are written (issue #14: a CAM
program's JSON report is ~150 MB; held whole as text and again as bytes,
1e5 targets with --json peaked at 1.9 GB). The pieces joined are the
report: oracles are json.dumps of the whole document (written here) and
the Markdown report rendered in one piece; the command writes the same
report whether it renders it as it writes (one program) or a worker
renders it whole (several programs)."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from rapidcomp.compensate import fix as F
from rapidcomp.compensate import report
from rapidcomp.compensate.job import Report
from rapidcomp.compensate.load import load_solver
from rapidcomp.compensate.plan import Task
from rapidcomp.rapid.parse import parse_file, parse_text

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))
from fix import cam_module  # noqa: E402
from test_report_json import _whole as _whole_json  # noqa: E402  (the oracle)


@pytest.fixture(scope="module")
def results():
    solver = load_solver(str(ROOT / "fixtures" / "warm.csv"), None, False, ("J5=-120:120",))
    tasks = [Task("cubes.mod", (parse_file(ROOT / "fixtures" / "cubes.mod", "cubes.mod"),))]
    # 3, 4 and 7 targets: as many rows as a piece holds, one more, and two
    # pieces and one more with the pieces made 3 rows long below.
    for n in (3, 4, 7):
        tasks.append(Task(f"cam{n}.mod", (parse_text(cam_module(n, 5), f"cam{n}.mod"),)))
    tasks.append(Task("none.mod", (parse_text("MODULE N\n  PROC p()\n    WaitTime 1;\n"
                                              "  ENDPROC\nENDMODULE\n", "none.mod"),)))
    return [F.fix(t, solver, "auto") for t in tasks]


@pytest.mark.parametrize("lines", [1, 2, 3, 4, 10 ** 9])
def test_pieces_join_to_the_whole_report(results, monkeypatch, lines):
    meta = {"mode": "auto", "profile": 'wärm\n"x".csv'}
    whole_md = [report.markdown(r, meta) for r in results]
    # (Targets per JSON piece one more than lines per Markdown piece: each
    # counted by its own constant.)
    monkeypatch.setattr(report, "CHUNK_LINES", lines)
    monkeypatch.setattr(report, "CHUNK_TARGETS", lines + 1)
    for result, md in zip(results, whole_md):
        pieces = list(report.as_json(result, meta, pieces=True))
        assert "".join(pieces) == _whole_json(result, meta)
        if lines < 10 ** 9:
            # The targets really are split: a piece per lines + 1 rows,
            # between the head and the tail.
            assert len(pieces) == 2 + -(-len(result.rows) // (lines + 1)) if result.rows \
                else len(pieces) == 1
        md_pieces = list(report.markdown(result, meta, pieces=True))
        assert "".join(md_pieces) == md
        if lines < 10 ** 9:
            # (Each piece ends a line; the meta's line break is inside one.)
            assert len(md_pieces) == -(-(md.count("\n") - 1) // lines)
        for kind, text in (("markdown", md), ("json", _whole_json(result, meta))):
            assert Report(kind, result, meta).render() == text.encode("utf-8")


def test_streamed_and_worker_reports_are_the_same_bytes(tmp_path):
    # One program: the report is rendered as it is written. Two programs:
    # each worker renders its report whole and returns its bytes. (6500
    # targets: over 1 MiB, so the one program's job has its helper, and
    # two JSON pieces of CHUNK_TARGETS.)
    for name, n, seed in (("a.mod", 6500, 2), ("b.mod", 40, 3)):
        (tmp_path / name).write_text(cam_module(n, seed, name[0].upper() + "_M"))
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    prof = str(ROOT / "fixtures" / "warm.csv")
    base = [sys.executable, "-m", "rapidcomp", "fix", "--profile", prof, "-q"]
    (tmp_path / "one").mkdir()
    subprocess.run(base + [str(tmp_path / "a.mod"), "-o", str(tmp_path / "one")], check=True,
                   env=env)
    subprocess.run(base + [str(tmp_path / "a.mod"), str(tmp_path / "b.mod"), "-o",
                           str(tmp_path / "two")], check=True, env=env)
    one = sorted(p.name for p in (tmp_path / "one").iterdir())
    assert one == ["a.md", "a.mod"]
    for name in one:
        assert (tmp_path / "one" / name).read_bytes() == (tmp_path / "two" / name).read_bytes()
    md = (tmp_path / "one" / "a.md").read_text()
    assert md.count("| MoveL |") == 6500 and md.endswith("|\n")
    # --json through the command, in pieces: valid, and the dump of itself.
    subprocess.run(base + [str(tmp_path / "a.mod"), "-o", str(tmp_path / "j.mod"), "--json",
                           str(tmp_path / "j.json")], check=True, env=env)
    text = (tmp_path / "j.json").read_text()
    doc = json.loads(text)
    assert len(doc["targets"]) == 6500
    assert text == json.dumps(doc, indent=2) + "\n"


def test_the_progress_line_shows_the_report_being_written(results, capsys):
    from rapidcomp.progress import Progress
    progress = Progress("cam7.mod", True, delay_s=0.0)
    meta = {"mode": "auto"}
    for kind, says in (("markdown", "writing the report"), ("json", "writing the JSON report")):
        data = b"".join(Report(kind, results[3], meta, progress).chunks())
        assert data.decode() == (report.markdown if kind == "markdown" else report.as_json)(
            results[3], meta)
        err = capsys.readouterr().err
        # Shown while written, then cleared.
        assert err == f"\r\x1b[Krapidcomp: cam7.mod: {says} (" + err.split("(", 1)[1]
        assert err.endswith(" s)\r\x1b[K")


def test_the_progress_line_is_cleared_when_the_write_fails(results, capsys):
    from rapidcomp.progress import Progress
    progress = Progress("cam7.mod", True, delay_s=0.0)
    pieces = Report("markdown", results[3], {"mode": "auto"}, progress).chunks()
    next(pieces)
    pieces.close()            # (as when writing the first piece failed)
    err = capsys.readouterr().err
    assert err.startswith("\r\x1b[Krapidcomp: cam7.mod: writing the report (")
    assert err.endswith(" s)\r\x1b[K")

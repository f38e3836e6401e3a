"""`rapidcomp fix`: golden cases, splice guarantees, exit codes, reports."""

from __future__ import annotations

import difflib
import json
import random

import pytest
from click.testing import CliRunner

from rapidcomp.cli import main
from rapidcomp.compensate.fix import fix
from rapidcomp.compensate.plan import Task
from rapidcomp.edits import EditColumns, SpanEdit, apply_edits
from rapidcomp.kinematics.ik import Solver
from rapidcomp.kinematics.robot import irb140, override_limits
from rapidcomp.rapid.parse import parse_file, parse_text
from rapidcomp.rewrite.diff import unified_diff
from rapidcomp.rewrite.names import NameAllocator

from conftest import FIXTURES, RAPID_FIXTURES
from regen_golden import FIX_CASES, GOLDEN, TASK_CASES, fix_golden, task_golden

ZERO_PROFILE = "joint,dx_mm,dy_mm,dz_mm,rx_deg,ry_deg,rz_deg\n"
WARM = str(FIXTURES / "warm.csv")


@pytest.fixture(scope="module")
def zero_solver():
    # J5 +-120: the paper's point S21 needs 116.9 deg (see the README).
    robot = override_limits(irb140(), ["J5=-120:120"])
    return Solver(robot, robot)


@pytest.mark.parametrize("case", sorted(FIX_CASES))
def test_golden_case(case):
    folder = GOLDEN / "fix" / case
    fixture = FIX_CASES[case][0]
    if fixture is not None:
        assert (folder / "before.mod").read_bytes() == (FIXTURES / fixture).read_bytes()
    after, report = fix_golden(case)
    assert after == (folder / "after.mod").read_bytes()
    assert report == (folder / "report.md").read_text(encoding="utf-8")


@pytest.mark.parametrize("case", sorted(TASK_CASES))
def test_golden_task_case(case):
    folder = GOLDEN / "fix" / case
    src = FIXTURES / "tasks" / TASK_CASES[case][0]
    for p in src.rglob("*"):
        if p.is_file():
            assert (folder / "before" / p.relative_to(src)).read_bytes() == p.read_bytes()
    after, report = task_golden(case)
    for rel, data in after.items():
        assert data == (folder / "after" / rel).read_bytes(), rel
    assert report == (folder / "report.md").read_text(encoding="utf-8")


@pytest.mark.parametrize("path", RAPID_FIXTURES + [FIXTURES / "cubes.mod",
                                                   FIXTURES / "paper_front.mod"],
                         ids=lambda p: p.name)
def test_zero_profile_robtarget_mode_is_byte_identical(path, zero_solver):
    pf = parse_file(path)
    result = fix(Task(path.name, (pf,)), zero_solver, "robtarget")
    assert result.edits == ()
    assert pf.source.encode(result.modules[0].text) == path.read_bytes()


@pytest.mark.parametrize("case", ["cubes_absj", "cubes_robtarget", "paper_front_absj"])
def test_second_run_with_zero_profile_changes_nothing(case, zero_solver):
    after = GOLDEN / "fix" / case / "after.mod"
    result = fix(Task("again", (parse_file(after),)), zero_solver, "robtarget")
    assert result.edits == () and result.failed == 0
    # ... and every target of the compensated module is still resolved.
    assert all(r.status == "compensated" for r in result.rows
               if "CRobT" not in r.target)


@pytest.mark.parametrize("case", sorted(p.name for p in (GOLDEN / "fix").iterdir()))
def test_the_note_counts_the_new_copies_of_targets(case):
    """The report's note on copies of declared targets counts the robtarget
    and jointtarget declarations the output has and the input has not (the
    MoveAbsJ jointtargets, jt_..., not among them); no note where there
    are none."""
    import re
    folder = GOLDEN / "fix" / case
    decl = re.compile(r"CONST (robtarget|jointtarget) (\w+)")

    def text(side: str) -> str:
        # (A module, or a task folder's modules.)
        paths = sorted(p for p in folder.glob(f"{side}*") if p.is_file()) + sorted(
            p for p in (folder / side).rglob("*") if p.is_file())
        return "".join(p.read_text(errors="replace") for p in paths)
    before = set(decl.findall(text("before")))
    after = decl.findall(text("after"))
    new: dict[str, int] = {}
    for kind, name in after:
        if (kind, name) not in before and not name.startswith("jt_"):
            new[kind] = new.get(kind, 0) + 1
    note = [line for line in (folder / "report.md").read_text().splitlines()
            if line.startswith("- new declarations: ")]
    if not new:
        assert note == []
        return
    said = dict((k.rstrip("s"), int(n)) for n, k in re.findall(
        r"(\d+) (robtargets?|jointtargets?)", note[0].split(",")[0] + note[0].split(",")[1]))
    assert said == new


def test_only_numbers_and_instructions_change():
    """Outside the edited spans the output is the input, byte for byte: the
    CRLF line ends, comments and layout of cubes.mod survive. Without the
    new declarations, the output has the input's lines; a changed line is a
    motion whose name and target changed (speed, zone, tool, \\WObj as
    written) or a declaration whose numbers changed."""
    import re
    before = (GOLDEN / "fix" / "cubes_absj" / "before.mod").read_bytes()
    after = (GOLDEN / "fix" / "cubes_absj" / "after.mod").read_bytes()
    assert after.count(b"\r\n") == after.count(b"\n") > before.count(b"\n")
    old = before.decode().split("\r\n")
    new, skipping = [], False
    for line in after.decode().split("\r\n"):
        if line.startswith("    LOCAL CONST jointtarget jt_"):
            skipping = not line.endswith("];")
            continue
        if skipping:
            skipping = not line.endswith("];")
            continue
        new.append(line)
    assert len(new) == len(old)
    numbers = re.compile(r"-?\d+(\.\d+)?(E[+-]\d+)?")
    changed = 0
    for a, b in zip(old, new):
        if a == b:
            continue
        changed += 1
        if a.lstrip().startswith("Move"):
            assert a.split(",")[-3:] == b.split(",")[-3:]
            assert b.lstrip().startswith("MoveAbsJ jt_") or "[[" in b
        else:
            assert numbers.sub("#", a) == numbers.sub("#", b)
    assert changed == 31  # 27 motions, 2 jointtargets, the 2 MoveC robtargets


def test_unified_diff_matches_difflib():
    """The linear-time diff equals difflib's for line-local edits and
    inserted lines (the edits fix makes), also where a comment holds a
    character str.splitlines ends a line at (a form feed, NEL, a line
    separator: found by review)."""
    rng = random.Random(7)
    for _ in range(500):
        n = rng.randint(1, 40)
        lines = [f"    MoveL p{i}, v100, {'z' * rng.randint(0, 5)}, tool0;"
                 + rng.choice([""] * 6 + [" ! \x0c", " ! c\x85", " !\u2028", " ! \x1c"])
                 for i in range(n)]
        sep = rng.choice(["\n", "\r\n"])
        text = sep.join(lines) + (sep if rng.random() < 0.8 else "")
        starts = [0]           # (of the lines as written, which a comment may split)
        for line in lines:
            starts.append(starts[-1] + len(line) + len(sep))
        edits = []
        for k in sorted(rng.sample(range(n), rng.randint(1, min(n, 8)))):
            s, length = starts[k], len(lines[k])
            r = rng.random()
            if r < 0.4:
                edits.append(SpanEdit(s + 4, s + 9, "MoveAbsJ"))
            elif r < 0.7:
                edits.append(SpanEdit(s + length, s + length, sep + "    CONST num x := 1;"))
            else:
                # Several edits on one line (the numbers of a literal), one
                # of them maybe writing what was there.
                cuts = sorted(rng.sample(range(10, length - 6), 4))
                for a, b in ((cuts[0], cuts[1]), (cuts[2], cuts[3])):
                    edits.append(SpanEdit(s + a, s + b, rng.choice(["9", text[s + a:s + b]])))
                if rng.random() < 0.5:
                    edits.append(SpanEdit(s + length, s + length, sep + "    CONST num y:=2;"))
        new = apply_edits(text, edits)
        expected = list(difflib.unified_diff(text.splitlines(), new.splitlines(), "a", "b",
                                             n=3, lineterm=""))
        assert unified_diff(text, edits, "a", "b") == expected



def test_diff_of_edits_within_lines_is_the_blocks_diff():
    """Edits that touch no line break (fix's edits of numbers) are diffed
    line by line (diff._changed_in_lines): the same changes as cutting
    blocks (_changed_blocks), with LF, CRLF and CR, lines holding form feeds
    and NEL, edits that write what was there, at the end of the text;
    edits that add or remove a line break go the general way."""
    from rapidcomp.edits import OverlappingEdits
    from rapidcomp.rewrite import diff as D
    rng = random.Random(3)
    fast = general = 0
    for _ in range(3000):
        n = rng.randint(1, 30)
        lines = [f"    MoveL p{i},{rng.choice(['', chr(12), chr(0x85), 'x'])} v100, "
                 f"{'z' * rng.randint(0, 5)}, tool0;" for i in range(n)]
        sep = rng.choice(["\n", "\r\n", "\r"])
        text = sep.join(lines) + (sep if rng.random() < 0.8 else "")
        kept = text.splitlines(keepends=True)
        starts = [0]
        for line in kept:
            starts.append(starts[-1] + len(line))
        edits = []
        for k in sorted(rng.sample(range(len(kept)), rng.randint(1, min(len(kept), 8)))):
            s, length = starts[k], len(kept[k].rstrip("\r\n"))
            if length < 4:
                continue
            cuts = sorted(rng.sample(range(length + 1), 4))
            for a, b in ((cuts[0], cuts[1]), (cuts[2], cuts[3])):
                edits.append(SpanEdit(s + a, s + b, rng.choice(
                    ["9", text[s + a:s + b], "", "ab"] + ["\n", "x\r"] * (rng.random() < 0.2))))
            if rng.random() < 0.1:
                edits.append(SpanEdit(s + length, s + length, rng.choice(["end", "\r\nX"])))
        if sep == "\r" and len(kept) > 2 and rng.random() < 0.2:
            # Right after a CR: an edit there may make or split a CRLF
            # with no line break in any edit (found by review).
            edits = [e for e in edits if e.start > starts[2] or e.end < starts[1] - 1]
            edits.append(SpanEdit(starts[1], starts[1] + 2, rng.choice(["", "\n", "q"])))
            edits.sort(key=lambda e: (e.start, e.end))
        try:
            new = apply_edits(text, edits)
        except OverlappingEdits:
            continue
        cols = EditColumns.of(edits)
        got = D._changed_in_lines(text, kept, text.splitlines(), cols, new)
        if got is None:
            general += 1
            continue
        fast += 1
        assert got == D._changed_blocks(text, kept, text.splitlines(), cols, new)
    assert fast > 1000 and general > 100
    # The review's case: text inserted between a CR and an LF splits a
    # line, text removed between a CR and an LF joins two; the line count
    # stays, and the fast path must decline.
    text, edits = "x\r\ny\rABC\nz\n", [SpanEdit(2, 2, "A"), SpanEdit(5, 8, "")]
    new = apply_edits(text, edits)
    kept = text.splitlines(keepends=True)
    assert len(new.splitlines()) == len(kept)
    assert D._changed_in_lines(text, kept, text.splitlines(), EditColumns.of(edits), new) is None


def test_a_line_break_to_the_diff_is_one_to_splitlines():
    """The diff tells an edit that touches a line break by a pattern: the
    characters str.splitlines (and difflib's lines) end a line at."""
    from rapidcomp.rewrite.diff import _LINE_BREAK
    for c in range(0x10000):
        assert (len(f"a{chr(c)}b".splitlines()) != 1) is bool(_LINE_BREAK.search(chr(c))), c


def test_new_names_avoid_every_identifier_case_insensitively():
    names = NameAllocator(["MODULE m ! JT_P1 and jt_p1_2 are taken\nCONST num x:=1;"])
    assert names.new("jt_p1") == "jt_p1_3"
    assert names.new("jt_p1") == "jt_p1_4"
    long = names.new("jt_" + "a" * 40)
    assert len(long) == 32 and names.new("jt_" + "a" * 40) == long[:30] + "_2"


def test_refusals_say_why_and_collisions_are_avoided():
    after = (GOLDEN / "fix" / "refusals" / "after.mod").read_text()
    report = (GOLDEN / "fix" / "refusals" / "report.md").read_text()
    assert "jt_p1_2" in after and "LOCAL CONST jointtarget jt_p1 " not in after
    for reason in ("pVar is assigned at run time (before.mod:13)",
                   "tool tStat is a stationary tool", "coordinated with a mechanical unit",
                   "out of reach by", "Offs number k is a VAR num: known at run time only",
                   "the target is computed at run time", "\\Corr has no MoveAbsJ equivalent"):
        assert reason in report, reason
    parse_text(after)


# ---------------------------------------------------------------- command line

def _run(args):
    return CliRunner().invoke(main, args, catch_exceptions=False)


def test_cli_writes_module_and_report_and_leaves_input_alone(tmp_path, monkeypatch):
    prog = tmp_path / "paper_front.mod"
    prog.write_bytes((FIXTURES / "paper_front.mod").read_bytes())
    (tmp_path / "warm.csv").write_bytes((FIXTURES / "warm.csv").read_bytes())
    monkeypatch.chdir(tmp_path)
    r = _run(["fix", "paper_front.mod", "--profile", "warm.csv", "--json", "r.json"])
    assert r.exit_code == 0, r.output
    assert prog.read_bytes() == (FIXTURES / "paper_front.mod").read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "paper_front.mod", "paper_front_comp.md", "paper_front_comp.mod", "r.json", "warm.csv"]
    doc = json.loads((tmp_path / "r.json").read_text())
    assert doc["summary"]["compensated"] == 8 and doc["summary"]["not_compensated"] == 0
    assert doc["modules"][0]["diff"][0] == "--- paper_front.mod"
    md = (tmp_path / "paper_front_comp.md").read_text()
    assert str(tmp_path) not in md and str(tmp_path) not in (tmp_path / "r.json").read_text()
    # Deterministic: a second run writes the same bytes.
    first = (tmp_path / "r.json").read_bytes(), md
    again = _run(["fix", "paper_front.mod", "--profile", "warm.csv", "--json", "r.json"])
    assert again.exit_code == 0
    assert ((tmp_path / "r.json").read_bytes(), (tmp_path / "paper_front_comp.md").read_text()) \
        == first


def test_cli_unreachable_target_exit_1_writes_nothing_unless_allowed(tmp_path):
    prog = GOLDEN / "fix" / "refusals" / "before.mod"
    out = tmp_path / "out.mod"
    r = _run(["fix", str(prog), "--profile", WARM, "-o", str(out)])
    assert r.exit_code == 1
    assert "line 20 MoveL pFar: nominal: out of reach by 31.770 mm" in r.output
    assert list(tmp_path.iterdir()) == []
    # (Its first line, which names the output, says it is not written.)
    assert r.output.startswith(f"{prog} -> {out} (auto; not written)\n"), r.output
    r = _run(["fix", str(prog), "--profile", WARM, "-o", str(out), "--allow-partial"])
    assert r.exit_code == 1
    assert r.output.startswith(f"{prog} -> {out} (auto)\n"), r.output
    assert out.read_bytes() == (GOLDEN / "fix" / "refusals" / "after.mod").read_bytes()
    assert "MoveL pFar, v100" in out.read_text()


def test_cli_bad_input_exit_2_with_position_and_no_output(tmp_path):
    bad = FIXTURES / "invalid" / "unclosed_aggregate.mod"
    r = _run(["fix", str(bad), "--profile", WARM, "-o", str(tmp_path / "x.mod")])
    assert r.exit_code == 2
    assert "unclosed_aggregate.mod:" in r.output and list(tmp_path.iterdir()) == []
    prof = tmp_path / "bad.csv"
    prof.write_text("joint,dx_mm,dy_mm,dz_mm,rx_deg,ry_deg,rz_deg\nJ9,0,0,0,0,0,0\n")
    r = _run(["fix", str(FIXTURES / "paper_front.mod"), "--profile", str(prof),
              "-o", str(tmp_path / "x.mod")])
    assert r.exit_code == 2 and "bad.csv:2" in r.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.csv"]


def test_cli_refuses_to_overwrite_the_input(tmp_path):
    prog = tmp_path / "p.mod"
    prog.write_bytes((FIXTURES / "paper_front.mod").read_bytes())
    r = _run(["fix", str(prog), "--profile", WARM, "-o", str(prog)])
    assert r.exit_code == 2 and "would overwrite" in r.output
    assert prog.read_bytes() == (FIXTURES / "paper_front.mod").read_bytes()


def test_cli_two_programs_of_one_name_into_one_folder_are_named(tmp_path, monkeypatch):
    """a/p.mod and b/p.mod into -o out/: both would write out/p.mod. The
    message names that file and both programs (not the report, which
    clashes too), and nothing is written; the first line of check and
    fix names each input as given."""
    monkeypatch.chdir(tmp_path)
    for d in ("a", "b"):
        (tmp_path / d).mkdir()
        (tmp_path / d / "p.mod").write_bytes((FIXTURES / "paper_front.mod").read_bytes())
    r = _run(["fix", "a/p.mod", "b/p.mod", "--profile", WARM, "-o", "out/"])
    assert r.exit_code == 2
    assert ("out/p.mod: would be both the module of a/p.mod and the module of b/p.mod"
            in r.output), r.output
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
    r = _run(["fix", "a/p.mod", "--profile", WARM, "--json", "x.md", "-o", "x.mod"])
    assert r.exit_code == 2 and "x.md: would be both the report of a/p.mod and the JSON" \
        in r.output
    r = _run(["check", "b/p.mod", "--profile", WARM])
    assert r.output.startswith("b/p.mod: predicted error on the warm robot"), r.output
    r = _run(["fix", "b/p.mod", "--profile", WARM, "-o", "y.mod"])
    assert r.output.startswith("b/p.mod -> y.mod (auto)"), r.output


@pytest.mark.parametrize("cpus", [1, 2])
def test_cli_several_modules_into_a_directory(tmp_path, monkeypatch, cpus):
    """Several modules: a pool of two workers, or where the process may use
    one CPU only, one after the other; the same files either way."""
    from rapidcomp.compensate import job
    monkeypatch.setattr(job, "side_by_side", lambda: cpus)
    out = tmp_path / "out"
    r = _run(["fix", str(FIXTURES / "paper_front.mod"),
              str(FIXTURES / "rapid" / "cam_confoff.mod"), "--profile", WARM, "-o", str(out),
              "-q"])
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in out.iterdir()) == [
        "cam_confoff.md", "cam_confoff.mod", "paper_front.md", "paper_front.mod"]
    single = _run(["fix", str(FIXTURES / "paper_front.mod"), "--profile", WARM,
                   "-o", str(tmp_path / "one.mod"), "-q"])
    assert single.exit_code == 0
    assert (out / "paper_front.mod").read_bytes() == (tmp_path / "one.mod").read_bytes()


FAR = """MODULE Far
  PERS wobjdata wFar:=[FALSE,TRUE,"",[[-99500,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
  CONST robtarget pA:=[[99999.95,0,500],[0,0,1,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
  PROC main()
    ConfL\\On;
    MoveL pA,v100,fine,tool0\\WObj:=wFar;
  ENDPROC
ENDMODULE
"""


def test_compensation_past_the_input_position_bound_is_not_bad_input(tmp_path):
    """A position within the 100 m plausibility bound of input, moved past
    it by the compensation (x 99999.95 -> 100000.02 mm in its work object),
    is rapidcomp's own output: verification must not call it bad input at
    the input's line (it did: exit 2 with the written numbers). As a
    MoveAbsJ it is compensated. As a robtarget, float32 near 1e5 mm has a
    7.8 um step, so the written value cannot hold the pose to 1 um: not
    compensated, and the report says by how much it would miss."""
    prog = tmp_path / "far.mod"
    prog.write_text(FAR)
    out = tmp_path / "o.mod"
    r = _run(["fix", str(prog), "--profile", WARM, "--emit", "absj", "-o", str(out)])
    assert r.exit_code == 0, r.output
    assert "MoveAbsJ jt_pA,v100,fine,tool0\\WObj:=wFar;" in out.read_text()
    r = _run(["fix", str(prog), "--profile", WARM, "--emit", "robtarget", "-o", str(out)])
    assert r.exit_code == 1, r.output
    assert "line 6 MoveL pA: the written value would miss by 1.692 um" in r.output
    # Input past the bound is still bad input, at its place.
    prog.write_text(FAR.replace("99999.95", "100000.01"))
    r = _run(["fix", str(prog), "--profile", WARM, "--emit", "absj", "-o", str(out)])
    assert r.exit_code == 2 and "far.mod:3:25: pA: the position [100000, 0, 500] mm is beyond " \
        "100000 mm of the robot" in r.output, r.output


def _fixed(tmp_path, stem: str, text: str):
    """fix --emit robtarget of a module of this text: (result, input, output)."""
    prog, out = tmp_path / f"{stem}.mod", tmp_path / f"{stem}_out.mod"
    prog.write_text(text)
    return _run(["fix", str(prog), "--profile", WARM, "--emit", "robtarget", "-o", str(out)]), \
        prog, out


def test_a_kept_hexadecimal_field_is_verified_by_parsing_the_output(tmp_path):
    """A robtarget whose confdata is written 0x1 (a jointtarget with an
    external axis 0x0) is decoded field by field; fix keeps that field's
    text. Verification reads the written literal as the parser does: the
    regex does not read 0x1, so the output is parsed again (it crashed
    with a ValueError when float() was asked). Each alone in its module
    (the first literal that does not re-lex decides for the module)."""
    decl = {"p1": "CONST robtarget p1:=[[400,300,250],[0.707107,0,0.707107,0],[0,0,-1,0x1],"
                  "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];",
            "j1": "CONST jointtarget j1:=[[10,20,30,0,45,0],[0x0,9E+09,9E+09,9E+09,9E+09,9E+09]];"}
    move = {"p1": "MoveL p1,v100,fine,tool0;", "j1": "MoveAbsJ j1,v100,fine,tool0;"}
    kept = {"p1": "[0,0,-1,0x1],[9E+09", "j1": "],[0x0,9E+09,9E+09,9E+09,9E+09,9E+09]];"}
    for name in ("p1", "j1"):
        r, _, out = _fixed(tmp_path, name, f"MODULE Hex\n  {decl[name]}\n  PROC main()\n"
                                           f"    {move[name]}\n  ENDPROC\nENDMODULE\n")
        assert r.exit_code == 0, r.output
        text = out.read_text()
        assert kept[name] in text and decl[name][-60:] not in text


_IDENTITY_WOBJ = '[FALSE, TRUE, "", [[0, 0, 0], [1, 0, 0, 0]], [[0, 0, 0], [1, 0, 0, 0]]]'
_TOOL150 = "[TRUE,[[0,0,150],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]]"
# (declaration, statements before the move, the move's tool argument, what
# becomes of the move: "conflict" untouched, or the x its robtarget gets)
OWN = {
    "wobj0, another user frame": (
        '  TASK PERS wobjdata wObj0:=[FALSE,TRUE,"",[[100,-200,50],[1,0,0,0]],'
        '[[0,0,0],[1,0,0,0]]];', "", "tool0\\WObj:=wObj0", "conflict"),
    "wobj0, another object frame": (
        '  TASK PERS wobjdata wobj0:=[FALSE,TRUE,"",[[0,0,0],[1,0,0,0]],'
        '[[0,0,20],[1,0,0,0]]];', "", "tool0\\WObj:=wobj0", "conflict"),
    "wobj0 as BASE declares it": (f"  TASK PERS wobjdata wobj0:={_IDENTITY_WOBJ};", "",
                                  "tool0\\WObj:=wobj0", "400.153"),
    "tool0, another frame": (f"  PERS tooldata TOOL0:={_TOOL150};", "", "TOOL0", "conflict"),
    "tool0, held by no robot": ("  PERS tooldata tool0:=[FALSE,[[0,0,0],[1,0,0,0]],[1,[0,0,1],"
                                "[1,0,0,0],0,0,0]];", "", "tool0", "conflict"),
    "tool0 as BASE declares it": ("  PERS tooldata tool0:=[TRUE,[[0,0,0],[-1,0,0,0]],"
                                  "[0.001,[0,0,0.001],[1,0,0,0],0,0,0]];", "", "tool0", "400.153"),
    # (Declared as the identity, then assigned: that data, its assignment
    # followed; a LOCAL one hides the controller's.)
    "tool0 as BASE declares it, assigned": (
        "  PERS tooldata tool0:=[TRUE,[[0,0,0],[1,0,0,0]],[0.001,[0,0,0.001],[1,0,0,0],0,0,0]];",
        f"    tool0 := {_TOOL150};\n", "tool0", "400.184"),
    "a LOCAL tool0": (f"  LOCAL PERS tooldata tool0:={_TOOL150};", "", "tool0", "400.184"),
}


@pytest.mark.parametrize("case", list(OWN))
def test_a_module_declaring_the_controllers_own_tool0_or_wobj0(case, tmp_path):
    """tool0 and wobj0 are the controller's own (its BASE module declares
    them, the identity). A module that declares one of them globally with
    another value leaves which one the controller takes unknown: its moves
    are left as written, said with where it is declared. Declared as the
    identity (BASE's own text), it is that data, what assigns it followed;
    declared LOCAL, it is the module's own."""
    decl, before, use, want = OWN[case]
    target = ("[[400,300,250],[0.707107,0,0.707107,0],[0,0,-1,1],"
              "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]")
    r, prog, out = _fixed(tmp_path, "own", f"MODULE Own\n{decl}\n  PROC main()\n{before}"
                                           f"    MoveL {target},v100,fine,{use};\n"
                                           "  ENDPROC\nENDMODULE\n")
    assert r.exit_code == 0, r.output
    if want == "conflict":
        name = "wobj0" if "wobj0" in case else "tool0"
        assert "0 of 1 target uses compensated, 0 not compensated, 1 untouched" in r.output
        assert (f"is declared at own.mod:2 with another value than the controller's own "
                f"{name}") in r.output, r.output
        assert out.read_text() == prog.read_text()
    else:
        assert "1 of 1 target uses compensated" in r.output, r.output
        assert f"MoveL [[{want}" in out.read_text()


@pytest.mark.parametrize("first", ["builtin", "local"])
def test_the_moveabsj_note_names_a_modules_own_tool0_not_the_controllers(first, tmp_path):
    """Moves turned into MoveAbsJ go to joints computed with their tool and
    work object: the note names the data a later change would leave behind.
    The controller's own tool0 (the identity, nothing changes it) is not
    named; a module's LOCAL tool0, data like any other, is, even where a
    module before it moves with the controller's by the same text."""
    target = ("[[400,300,250],[0.707107,0,0.707107,0],[0,0,-1,1],"
              "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]")
    folder = tmp_path / "task"
    folder.mkdir()
    names = {"builtin": "A_Plain" if first == "builtin" else "B_Plain",
             "local": "A_Own" if first == "local" else "B_Own"}
    decl = {"builtin": "", "local": f"  LOCAL PERS tooldata tool0:={_TOOL150};\n"}
    for kind, name in names.items():
        (folder / f"{name}.mod").write_text(
            f"MODULE {name}\n{decl[kind]}  PROC {name}_p()\n"
            "    MoveAbsJ [[0,0,0,0,30,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],v100,fine,"
            f"tool0;\n    MoveL {target},v100,fine,tool0;\n  ENDPROC\nENDMODULE\n")
    r = _run(["fix", str(folder), "--profile", WARM, "--emit", "absj", "-o",
              str(tmp_path / "out")])
    assert r.exit_code == 0, r.output
    assert "4 of 4 target uses compensated" in r.output, r.output
    assert "the moves turned into MoveAbsJ go to joints computed with tool0 as the modules " \
        "declare them" in r.output, r.output
    # The controller's own alone: no such note.
    (folder / f"{names['local']}.mod").unlink()
    r = _run(["fix", str(folder), "--profile", WARM, "--emit", "absj", "-o",
              str(tmp_path / "out2")])
    assert r.exit_code == 0, r.output
    assert "2 of 2 target uses compensated" in r.output and "computed with" not in r.output


LOOP_MODES = """MODULE A60
  PERS tooldata tSp:=[TRUE,[[0,0,150],[1,0,0,0]],[2,[0,0,75],[1,0,0,0],0,0,0]];
  CONST robtarget arr{3}:=[[[503.758,351.759,678.631],[0.852930,-0.401623,0.332113,-0.030167],[0,-1,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],[[565.609,262.245,695.010],[0.665331,-0.057324,0.302898,0.679927],[0,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],[[423.478,-388.744,940.242],[0.793380,0.316255,0.204394,-0.478282],[-1,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]];
  CONST jointtarget jh:=[[-6.4065,44.5494,-5.2697,49.2436,-69.5322,7.1197],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
  PROC R1P(robtarget prm)
    MoveAbsJ jh,v100,fine,tSp;
    FOR i FROM 1 TO 3 DO
      MoveL arr{i},v100,fine,tSp;
      MoveL p6,v100,fine,tSp;
    ENDFOR
  ENDPROC
ENDMODULE
"""


@pytest.mark.parametrize("mode", ["absj", "auto", "robtarget"])
def test_a_loops_move_that_must_stay_a_robtarget_move_stays_one_in_every_iteration(mode):
    """A move in a FOR loop is one statement for all iterations: where one
    iteration must stay a robtarget move (after p6, which no module
    declares, the position is not known: its configuration is assumed),
    the iteration that could become MoveAbsJ stays one too, and says why.
    Before (found by review): the two wanted to rewrite the same target,
    and fix stopped with 'conflicting edits' (exit 2)."""
    from rapidcomp.compensate.load import load_solver
    solver = load_solver(str(FIXTURES / "warm.csv"), None, False)
    result = fix(Task("a.mod", (parse_text(LOOP_MODES, "a.mod"),)), solver, mode)
    rows = [r for r in result.rows if r.target.startswith("arr")]
    assert [r.status for r in rows] == ["compensated"] * 3
    assert "      MoveL arr{i},v100,fine,tSp;" in result.modules[0].text
    kept = [r for r in rows if any(w.startswith("kept as MoveL: in another iteration")
                                   for w in r.warnings)]
    assert [r.target for r in kept] == (["arr{i} [i=1]"] if mode == "absj" else [])
    assert all(r.action == "robtarget arr rewritten in place" for r in rows)
    parse_text(result.modules[0].text, "out.mod")


ALIASED = """MODULE M
    ALIAS robtarget myrt;
    CONST myrt p1:=[[400,0,250],[0.707107,0,0.707107,0],[0,0,0,1],[9E9,9E9,9E9,9E9,9E9,9E9]];
    PROC main()
        MoveL p1,v100,fine,tool0;
    ENDPROC
ENDMODULE
"""


@pytest.mark.parametrize("mode", ["robtarget", "absj"])
def test_a_target_of_an_alias_type_is_the_type_it_names(mode):
    """`ALIAS robtarget myrt; CONST myrt p1` is robtarget data (the controller
    runs the move): compensated as a robtarget (it was refused, "p1 is a
    myrt, not a target"); a declaration edited in place keeps its type's
    name as written."""
    pf = parse_text(ALIASED, "m.mod")
    assert pf.modules[0].declarations[0].type == "robtarget"
    result = fix(Task("m", (pf,)), Solver(irb140(), irb140()), mode)
    assert [r.status for r in result.rows] == ["compensated"]
    after = apply_edits(ALIASED, result.modules[0].edits)
    assert "CONST myrt p1:=" in after
    assert ("MoveAbsJ jt_p1," in after) == (mode == "absj")


def test_an_alias_another_module_declares_types_the_data_too(tmp_path):
    """A task is one namespace: a global ALIAS in one module types the data
    of another (a folder, and a module with --with); a LOCAL one its own
    module's only."""
    task = tmp_path / "task"
    task.mkdir()
    (task / "Types.sys").write_text("MODULE Types(SYSMODULE)\n    ALIAS robtarget myrt;\n"
                                    "ENDMODULE\n")
    (task / "Main.mod").write_text(ALIASED.replace("    ALIAS robtarget myrt;\n", ""))
    warm = str(FIXTURES / "warm.csv")
    for args in ([str(task)], [str(task / "Main.mod"), "--with", str(task / "Types.sys")]):
        r = _run(["check", *args, "--profile", warm])
        assert r.exit_code == 0 and "1 of 1 target uses compensable" in r.output, r.output
    (task / "Types.sys").write_text("MODULE Types(SYSMODULE)\n    LOCAL ALIAS robtarget myrt;\n"
                                    "ENDMODULE\n")
    r = _run(["check", str(task), "--profile", warm])
    assert r.exit_code == 1 and "p1 is a myrt, not a target" in r.output, r.output


def test_an_output_named_with_a_slash_is_a_folder(tmp_path, monkeypatch):
    """-o out/ of one module: the folder out (made), the module in it; it
    was a file named out."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "paper_front.mod").write_bytes((FIXTURES / "paper_front.mod").read_bytes())
    r = _run(["fix", "paper_front.mod", "--profile", str(FIXTURES / "warm.csv"), "-o", "out/"])
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["paper_front.md",
                                                                    "paper_front.mod"]
    (tmp_path / "file").write_text("")
    r = _run(["fix", "paper_front.mod", "--profile", str(FIXTURES / "warm.csv"), "-o", "file/"])
    assert r.exit_code == 2 and "-o file/: file is a file, not a folder" in r.output, r.output


@pytest.mark.parametrize("storage", ["PERS", "CONST"])
def test_a_move_kept_a_robtarget_move_under_absj_says_why(storage, tmp_path):
    """--emit absj turns MoveL into MoveAbsJ, but for a move whose target is
    PERS data (ModPos or another task may change it): kept, the row says
    so, and a note counts such moves (found by a new user: they stayed
    MoveL with no word why). A CONST target: turned, no such word."""
    target = ("[[400,300,250],[0.707107,0,0.707107,0],[0,0,-1,1],"
              "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]")
    prog, out = tmp_path / "pk.mod", tmp_path / "pk_out.mod"
    prog.write_text(f"MODULE Pk\n  {storage} robtarget pA:={target};\n  PROC main()\n"
                    "    MoveAbsJ [[0,0,0,0,30,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],v100,"
                    "fine,tool0;\n    MoveL pA,v100,fine,tool0;\n  ENDPROC\nENDMODULE\n")
    r = _run(["fix", str(prog), "--profile", WARM, "--emit", "absj", "-o", str(out),
              "--json", str(tmp_path / "pk.json")])
    assert r.exit_code == 0, r.output
    row = next(t for t in json.loads((tmp_path / "pk.json").read_text())["targets"]
               if t["line"] == 5)
    note = ("kept robtarget moves, not turned into MoveAbsJ: 1 statement (pk.mod: lines 5); "
            "the report's rows say why")
    if storage == "PERS":
        assert "MoveL pA,v100,fine,tool0;" in out.read_text()
        assert "kept as MoveL: pA is PERS data (ModPos or another task may change it; a " \
            "MoveAbsJ would not follow)" in row["warnings"], row
        assert note in r.output, r.output
    else:
        assert "MoveAbsJ jt_pA,v100,fine,tool0;" in out.read_text()
        assert not any("kept as" in w for w in row["warnings"]) and note not in r.output


def test_a_kept_move_says_why_beside_its_other_warnings(tmp_path):
    # (Found by a review.) A PERS target near J5 = 0: its row warns of the
    # wrist singularity and says why it stays a MoveL, both.
    prog = tmp_path / "k.mod"
    prog.write_text(
        "MODULE K\n"
        "  PERS tooldata tSpindle:=[TRUE,[[0,0,150],[1,0,0,0]],[2,[0,0,75],[1,0,0,0],0,0,0]];\n"
        "  PERS robtarget pS:=[[697.078,123.013,391.820],[0.490144,-0.000114,0.867326,"
        "0.086626],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];\n"
        "  PROC main()\n    MoveL pS,v100,z1,tSpindle;\n  ENDPROC\nENDMODULE\n")
    r = _run(["fix", str(prog), "--profile", WARM, "--emit", "absj", "-o",
              str(tmp_path / "k_out.mod"), "--json", str(tmp_path / "k.json")])
    assert r.exit_code == 0, r.output
    (row,) = json.loads((tmp_path / "k.json").read_text())["targets"]
    assert row["warnings"][0].startswith("near wrist singularity"), row
    assert row["warnings"][1] == ("kept as MoveL: pS is PERS data (ModPos or another task may "
                                  "change it; a MoveAbsJ would not follow)")


def test_what_a_run_writes_over_is_said(tmp_path, monkeypatch):
    """A file already where the output, report or a folder's module goes is
    replaced (an earlier run's output, as a compiler's), and the "wrote"
    line says so, each by name (a folder: how many of its files); a first
    run says nothing of it."""
    monkeypatch.chdir(tmp_path)
    profile = str(FIXTURES / "warm.csv")

    def wrote(*args):
        r = CliRunner().invoke(main, ["fix", *args, "--profile", profile])
        assert r.exit_code == 0, r.output
        return r.output.splitlines()[-1]
    front = str(FIXTURES / "paper_front.mod")
    assert wrote(front, "-o", "a.mod") == "wrote a.mod, a.md"
    assert wrote(front, "-o", "a.mod") == ("wrote a.mod (replaced the file there), a.md "
                                           "(replaced the file there)")
    (tmp_path / "mine.mod").write_text("MODULE mine\nENDMODULE\n")
    assert wrote(front, "-o", "b.mod", "--report", "mine.mod") == (
        "wrote b.mod, mine.mod (replaced the file there)")
    cell = str(FIXTURES / "tasks" / "cell")
    assert wrote(cell, "-o", "out") == "wrote out/, out.md"
    (tmp_path / "out" / "MainModule.mod").unlink()
    assert wrote(cell, "-o", "out") == ("wrote out/ (replaced 1 file there), out.md (replaced "
                                        "the file there)")
    # (The folder as however it is written: ./out, out/; its report beside
    # it, not out/.md in it.)
    assert wrote(cell, "-o", "./out") == ("wrote out/ (replaced 2 files there), out.md "
                                          "(replaced the file there)")
    assert wrote(cell, "-o", "other/") == "wrote other/, other.md"
    assert sorted(p.name for p in (tmp_path / "other").iterdir()) == ["CellData.mod",
                                                                     "MainModule.mod"]


def test_a_module_written_under_a_name_no_controller_loads_is_refused(tmp_path):
    """-o out for a module (no suffix: a new user's typo for out.mod or
    out/) is refused, exit 2, nothing written: a file named `out` is not
    one a FlexPendant offers to load, and which was meant is not guessed.
    -o out.MOD and -o out/ are written."""
    prog = FIXTURES / "paper_front.mod"
    for name in ("out", "out.txt"):
        r = _run(["fix", str(prog), "--profile", WARM, "-o", str(tmp_path / name)])
        assert r.exit_code == 2, r.output
        assert (f"-o {tmp_path / name}: a module is written as a module file: give a name the "
                "controller loads (.mod, .modx, .sys, .prg), or a folder") in r.output
        assert list(tmp_path.iterdir()) == []
    assert _run(["fix", str(prog), "--profile", WARM, "-o", str(tmp_path / "o.MOD")]).exit_code == 0
    assert _run(["fix", str(prog), "--profile", WARM, "-o", str(tmp_path / "d") + "/"]
                ).exit_code == 0
    assert sorted(p.name for p in tmp_path.rglob("*")) == [
        "d", "o.MOD", "o.md", "paper_front.md", "paper_front.mod"]


def test_what_keeps_a_move_a_robtarget_move_is_said_once_alike(tmp_path):
    """A MoveL --emit absj would turn into MoveAbsJ, written with \\Corr and
    ToPoint:=: its row says both (each argument MoveAbsJ has not, then the
    name); a MoveJ with ToPoint:=, which check's auto would turn, is said
    alike by check and fix (one wording, place.kept_robtarget; the rows
    made their own for these, which check never said)."""
    target = ("[[400,300,250],[0.707107,0,0.707107,0],[0,0,-1,1],"
              "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]")
    prog, out = tmp_path / "k.mod", tmp_path / "k_out.mod"
    prog.write_text(f"MODULE K\n  CONST robtarget pA:={target};\n  PROC main()\n"
                    "    MoveAbsJ [[0,0,0,0,30,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],v100,"
                    "fine,tool0;\n    MoveL ToPoint:=pA, v100, fine, tool0 \\Corr;\n"
                    "    MoveJ ToPoint:=pA, v100, fine, tool0;\n  ENDPROC\nENDMODULE\n")
    name = ("its target is passed by name (ToPoint:=), which rapidcomp does not rewrite as "
            "MoveAbsJ's ToJointPos:=")
    r = _run(["fix", str(prog), "--profile", WARM, "--emit", "absj", "-o", str(out),
              "--json", str(tmp_path / "k.json")])
    assert r.exit_code == 0, r.output
    rows = {t["line"]: t for t in json.loads((tmp_path / "k.json").read_text())["targets"]}
    assert rows[5]["warnings"] == ["kept as MoveL: \\Corr has no MoveAbsJ equivalent; " + name]
    assert rows[6]["warnings"] == ["kept as MoveJ: " + name]
    assert "MoveL ToPoint:=pA, v100, fine, tool0 \\Corr;" in out.read_text()
    r = _run(["check", str(prog), "--profile", WARM, "--json"])
    rows = {t["line"]: t for t in json.loads(r.output)["targets"]}
    assert rows[6]["warnings"] == ["kept as MoveJ: " + name] and rows[5]["warnings"] == []

"""Bad input, as a tester makes it: seeded mutations of the fixtures through
parse -> fix -> report, and a table of bad command lines for every command.

Only rapidcomp's own errors may come out (RapidcompError: a message with a
place, exit 2); a run that exits 2 writes nothing; inputs are never
modified. The mutation test is bounded in time (a few thousand mutants)
and seeded: the same mutants every run, as many as the time allows.
"""

from __future__ import annotations

import os
import random
import re
import stat
import time

import pytest
from click.testing import CliRunner

from rapidcomp.cli import main
from rapidcomp.compensate import report
from rapidcomp.compensate.fix import fix
from rapidcomp.compensate.plan import Task
from rapidcomp.errors import InternalError, RapidcompError
from rapidcomp.kinematics.ik import Solver
from rapidcomp.kinematics.profile import deform, read_profile
from rapidcomp.kinematics.robot import irb140
from rapidcomp.rapid.parse import parse_text

from conftest import FIXTURES

WARM = FIXTURES / "warm.csv"
SOURCES = [FIXTURES / "paper_front.mod", FIXTURES / "rapid" / "robodk.mod",
           FIXTURES / "rapid" / "handwritten_cp1252.mod",
           FIXTURES / "rapid" / "robotstudio_crlf.mod",
           FIXTURES / "tasks" / "cell" / "MainModule.mod",
           FIXTURES / "tasks" / "glue" / "GlueData.mod"]
REFUSALS = FIXTURES.parent / "tests" / "golden" / "fix" / "refusals" / "before.mod"
# Numbers a tester types where a number goes.
ODD_NUMBERS = ["1e308", "-1e308", "1E999", "9E+99999", "0", "-0", "1e-320", "3.5E38", "9E9",
               "123456789012345678901234567890", "0.5", "-7", "2147483648"]
ODD_AGGREGATES = ["[0,0,0,0]", "[0,0,0,9]", "[0,0,0,1e308]", "[1,2]", "[0,0,0,0,0,0,0]",
                  "[\"a\",0,0,0]", "[[0,0,0],[0,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]"]
NUMBER = re.compile(r"(?<![A-Za-z_])[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")
# (~900 mutants in 5 s on this machine's 2 cores, half that in its noisy
# hours: the whole suite stays under 3 minutes.)
BUDGET_S = 5.0
MAX_MUTANTS = 4000


def _mutate(rng: random.Random, text: str) -> str:
    kind = rng.randrange(7)
    if kind == 0 and text:                       # bytes: delete, insert, replace
        i = rng.randrange(len(text))
        ch = rng.choice(["", rng.choice("[]{}(),;:=\\\"!%<>-+.0123456789eEabc \n\t")])
        return text[:i] + ch + text[i + rng.randrange(2):]
    lines = text.splitlines(keepends=True)
    if kind == 1 and lines:                      # lines: drop, duplicate, swap
        i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
        op = rng.randrange(3)
        if op == 0:
            del lines[i]
        elif op == 1:
            lines.insert(j, lines[i])
        else:
            lines[i], lines[j] = lines[j], lines[i]
        return "".join(lines)
    numbers = list(NUMBER.finditer(text))
    if kind in (2, 3, 4) and numbers:            # a number out of range
        m = rng.choice(numbers)
        return text[:m.start()] + rng.choice(ODD_NUMBERS) + text[m.end():]
    aggs = [m for m in re.finditer(r"\[[^\[\]]*\]", text)]
    if kind == 5 and aggs:                       # an aggregate of another shape
        m = rng.choice(aggs)
        return text[:m.start()] + rng.choice(ODD_AGGREGATES) + text[m.end():]
    words = [m for m in re.finditer(r"[A-Za-z_]\w*", text)]
    if words:                                    # a name swapped for another
        a, b = rng.choice(words), rng.choice(words)
        return text[:a.start()] + b.group() + text[a.end():]
    return text


@pytest.fixture(scope="module")
def solver():
    robot = irb140()
    return Solver(robot, deform(robot, read_profile(WARM)))


def test_mutants_raise_only_rapidcomps_own_errors(solver):
    rng = random.Random(20261122)
    texts = [(p.name, p.read_bytes().decode("utf-8", "replace")) for p in SOURCES
             if p.exists()] + [("refusals.mod", REFUSALS.read_text())]
    counts = {"mutants": 0, "parsed": 0, "rejected": 0, "compensated": 0, "internal": 0}
    start = time.perf_counter()
    while counts["mutants"] < MAX_MUTANTS and time.perf_counter() - start < BUDGET_S:
        name, text = texts[counts["mutants"] % len(texts)]
        mutant = text
        for _ in range(rng.randint(1, 3)):
            mutant = _mutate(rng, mutant)
        counts["mutants"] += 1
        try:
            pf = parse_text(mutant, name)
            counts["parsed"] += 1
            mode = ("auto", "absj", "robtarget")[counts["mutants"] % 3]
            result = fix(Task(name, (pf,)), solver, mode)
            report.markdown(result, {"mode": mode})
            report.as_json(result, {"mode": mode})
            counts["compensated"] += 1
        except InternalError:
            counts["internal"] += 1
        except RapidcompError as exc:
            counts["rejected"] += 1
            assert str(exc)
    print(counts)
    assert counts["mutants"] >= 300 and counts["parsed"] >= 60
    assert counts["internal"] == 0


def test_mutants_through_the_command_line_write_nothing_on_bad_input(tmp_path):
    rng = random.Random(7)
    src = (FIXTURES / "paper_front.mod").read_text()
    runner = CliRunner()
    codes = set()
    for n in range(40):
        mutant = src
        for _ in range(rng.randint(1, 2)):
            mutant = _mutate(rng, mutant)
        prog = tmp_path / f"m{n}.mod"
        prog.write_text(mutant)
        before = prog.read_bytes()
        out = tmp_path / f"out{n}"
        r = runner.invoke(main, ["fix", str(prog), "--profile", str(WARM), "-o",
                                 str(out / "m.mod")])
        assert isinstance(r.exception, SystemExit) or r.exception is None, r.output
        assert r.exit_code in (0, 1, 2), r.output
        codes.add(r.exit_code)
        assert prog.read_bytes() == before
        if r.exit_code in (1, 2):
            assert not out.exists(), r.output
        if r.exit_code == 2:
            assert r.output.strip(), "a bad input says why"
    assert 2 in codes


def _bad_module(tmp_path, old: str, new: str) -> str:
    text = (FIXTURES / "paper_front.mod").read_text()
    assert old in text
    p = tmp_path / "bad.mod"
    p.write_text(text.replace(old, new, 1))
    return str(p)


P4 = "[[400,-150,250],[0.707107,0,0.707107,0],[-1,-1,0,1]"


# (args, exit code, a fragment of the message); {tmp} is a fresh folder,
# {mod:OLD=>NEW} paper_front.mod with OLD replaced by NEW.
BAD = [
    (["fix", "nothing.mod", "--profile", "{warm}"], 2, "nothing.mod: no such file"),
    (["fix", "{paper}", "{paper}", "--profile", "{warm}", "-o", "{tmp}/both.mod"], 2,
     "several programs are written into a folder, each under its own name; give a folder, not "
     "a module file name"),
    (["fix", "{paper}", "--profile", "nothing.csv"], 2, "nothing.csv: no such file"),
    (["fix", "{paper}", "--profile", "{warm}", "--limit", "J5=a:b"], 2, "--limit J5=a:b"),
    (["fix", "{paper}", "--profile", "{warm}", "--limit", "J5=-1e400:5"], 2, "--limit"),
    (["fix", "{paper}", "--profile", "{warm}", "--start", "1,2"], 2, "J1,...,J6"),
    (["fix", "{paper}", "--profile", "{warm}", "--start", "0,0,0,0,0,5000"], 2, "out of range"),
    (["fix", "{paper}", "--profile", "{warm}", "--base", "0,0,0,0,0,0,0"], 2, "not a rotation"),
    (["fix", "{paper}", "--profile", "{warm}", "--track", "q:z"], 2, "--track q:z"),
    (["fix", "{paper}", "--profile", "{warm}", "--task", "T_ROB1"], 2, "--task picks tasks"),
    (["fix", "{mod:[0.707107,0,0.707107,0],[-1,-1,0,1]=>[0,0,0,0],[-1,-1,0,1]}", "--profile",
      "{warm}"], 2, "is not a rotation (norm 0)"),
    (["fix", "{mod:[-1,-1,0,1]=>[-1,-1,0,9]}", "--profile", "{warm}"], 2, "cfx is 9, expected 0..7"),
    # (A three-digit exponent: an aggregate of numbers, each read on its
    # own, not one token: the field is named.)
    (["fix", "{mod:[-1,-1,0,1]=>[-1,-1,0,1e308]}", "--profile", "{warm}"], 2,
     "p4.robconf.cfx is 1e308, beyond what a RAPID num holds"),
    (["fix", "{mod:[400,-150,250]=>[400,-150,3E38]}", "--profile", "{warm}"], 2,
     "mm is beyond 100000 mm of the robot"),
    (["fix", "{mod:[400,-150,250]=>[400,-150]}", "--profile", "{warm}"], 2,
     "has 2 components, expected 3"),
    (["fix", "{mod:FOR i FROM 1 TO NROW=>FOR i FROM 1 TO 9E9}", "--profile", "{warm}"], 2,
     "walks 9000000000 iterations"),
    (["fix", "{mod:FOR i FROM 1 TO NROW=>FOR i FROM 1 TO 4}", "--profile", "{warm}"], 2,
     "index 4 of pRow is outside 1..3"),
    # (Beyond every RAPID type, a dnum too: refused where it is read, as a
    # number in any aggregate of numbers is.)
    (["fix", "{mod:[400,-150,250]=>[400,-150,1E999]}", "--profile", "{warm}"], 2,
     "number 1E999 is out of range (a num holds +-3.4E38, a dnum +-1.8E308)"),
    (["fix", "{mod:TO NROW DO=>TO 1E999 DO}", "--profile", "{warm}"], 2,
     "number 1E999 is out of range"),
    (["check", "{paper}", "--profile", "{badprofile}"], 2, "unknown joint 'J9'"),
    (["check", "{tmp}", "--profile", "{warm}"], 2, "no module files"),
    (["inspect", "{binary}"], 2, "binary or encrypted module"),
    (["discover", "{same}"], 2, "1 distinct pose(s)"),
    (["discover", "{far}"], 2, "x is 1e300, expected a position in mm"),
    (["discover", "{spin}"], 2, "j1 is 5000, expected a joint angle"),
    (["discover", "{measured}", "--sigma", "0"], 2, "expected a standard deviation"),
    (["discover", "{measured}", "--sigma", "inf"], 2, "expected a standard deviation"),
    (["discover", "{measured}", "--tool", "0,0,1e9"], 2, "out of range"),
    (["simulate", "-o", "{tmp}/m.csv", "--seed", "-1"], 2, "-1 is not in the range"),
    (["simulate", "-o", "{tmp}/m.csv", "--noise", "inf"], 2, "expected a standard deviation"),
    (["simulate", "-o", "{tmp}/m.csv", "--effect", "joint_offset:J2=1e6"], 2,
     "needs 1e+06 deg"),
    (["simulate", "-o", "{tmp}/m.csv", "--points", "random:100000000"], 2,
     "1 <= N <= 100000"),
]


def _arg(a: str, tmp_path) -> str:
    if a.startswith("{mod:"):
        old, new = a[5:-1].split("=>")
        return _bad_module(tmp_path, old, new)
    table = {"{warm}": str(WARM), "{paper}": str(FIXTURES / "paper_front.mod"),
             "{measured}": str(FIXTURES / "measured.csv"), "{tmp}": str(tmp_path / "empty")}
    if a == "{badprofile}":
        p = tmp_path / "bad.csv"
        p.write_text("joint,dx_mm,dy_mm,dz_mm,rx_deg,ry_deg,rz_deg\nJ9,0,0,0,0,0,0\n")
        return str(p)
    if a == "{binary}":
        p = tmp_path / "enc.mod"
        p.write_bytes(b"\x00\x01\x02MODULE")
        return str(p)
    if a in ("{same}", "{far}", "{spin}"):
        rows = (FIXTURES / "measured.csv").read_text().splitlines()
        head = [r for r in rows if r.startswith("point")]
        body = [r for r in rows if r and r[0].isalnum() and not r.startswith("point")]
        if a == "{same}":
            body = [f"P{k}," + body[0].split(",", 1)[1] for k in range(1, 30)]
        elif a == "{far}":
            body[3] = ",".join(body[3].split(",")[:7] + ["1e300"] + body[3].split(",")[8:])
        else:
            body[3] = ",".join(body[3].split(",")[:1] + ["5000"] + body[3].split(",")[2:])
        p = tmp_path / "m.csv"
        p.write_text("\n".join(head + body) + "\n")
        return str(p)
    for k, v in table.items():
        a = a.replace(k, v)
    return a


@pytest.mark.parametrize("args, code, fragment", BAD, ids=[" ".join(b[0])[:60] for b in BAD])
def test_bad_command_lines(args, code, fragment, tmp_path):
    (tmp_path / "empty").mkdir()
    argv = [_arg(a, tmp_path) for a in args]
    out = tmp_path / "out"
    if argv[0] in ("fix",):
        argv += ["-o", str(out / "o.mod")] if "-o" not in argv else []
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    r = CliRunner().invoke(main, argv)
    assert r.exception is None or isinstance(r.exception, SystemExit), r.output
    assert r.exit_code == code, r.output
    assert fragment in r.output, r.output
    assert "Traceback" not in r.output
    after = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    assert after == before            # nothing written, nothing changed


def test_unwritable_output_is_a_clean_error(tmp_path):
    """An output under a file (as a read-only or full disk does, an OS
    error at write time): the path and the reason, exit 2, nothing left."""
    blocker = tmp_path / "file.txt"
    blocker.write_text("x")
    r = CliRunner().invoke(main, ["fix", str(FIXTURES / "paper_front.mod"), "--profile",
                                  str(WARM), "-o", str(blocker / "x.mod")])
    assert r.exit_code == 2 and "cannot write" in r.output and str(blocker) in r.output
    # (What is wrong with the path, not the OS's "File exists".)
    assert f"cannot write: {blocker} is a file, not a folder; nothing written" in r.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.txt"]


@pytest.mark.parametrize("cpus", [1, 2])
def test_several_programs_report_every_bad_one(tmp_path, monkeypatch, cpus):
    """Every bad program is named, in a pool of two workers and, where the
    process may use one CPU only, one after the other."""
    from rapidcomp.compensate import job
    monkeypatch.setattr(job, "side_by_side", lambda: cpus)
    a = tmp_path / "a.mod"
    b = tmp_path / "b.mod"
    a.write_text("MODULE a\n  PROC p()\n    MoveL [[1,2],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,"
                 "9E9,9E9,9E9]],v100,fine,tool0;\n  ENDPROC\nENDMODULE\n")
    b.write_text("MODULE 2b\nENDMODULE\n")
    r = CliRunner().invoke(main, ["fix", str(a), str(b), str(FIXTURES / "paper_front.mod"),
                                  "--profile", str(WARM), "-o", str(tmp_path / "out")])
    assert r.exit_code == 2
    assert "a.mod:3:12:" in r.output and "b.mod:1:8:" in r.output
    assert not (tmp_path / "out").exists()


def test_written_files_follow_the_umask(tmp_path):
    old = os.umask(0o027)
    try:
        r = CliRunner().invoke(main, ["fix", str(FIXTURES / "paper_front.mod"), "--profile",
                                      str(WARM), "-o", str(tmp_path / "p.mod")])
    finally:
        os.umask(old)
    assert r.exit_code == 0
    assert stat.S_IMODE((tmp_path / "p.mod").stat().st_mode) == 0o640


def test_utf16_modules_are_read_and_written_as_they_came(tmp_path):
    """RobotStudio can save a module as UTF-16: decoded, compensated, and
    written back in UTF-16 with its byte order mark."""
    text = (FIXTURES / "paper_front.mod").read_text()
    prog = tmp_path / "u16.mod"
    prog.write_bytes(("\ufeff" + text).encode("utf-16-le"))
    r = CliRunner().invoke(main, ["fix", str(prog), "--profile", str(WARM), "--emit",
                                  "robtarget", "-o", str(tmp_path / "o.mod")])
    assert r.exit_code == 0, r.output
    data = (tmp_path / "o.mod").read_bytes()
    assert data.startswith(b"\xff\xfe")
    out = data.decode("utf-16-le")
    assert out.startswith("\ufeffMODULE PaperFront") and out != "\ufeff" + text


def test_a_utf32_module_is_named_so(tmp_path):
    """UTF-32's byte order mark begins as UTF-16's: such a module is
    refused as UTF-32 (it was read as UTF-16 and refused at its first NUL
    character, which said nothing of why)."""
    for encoding in ("utf-32", "utf-32-be"):
        prog = tmp_path / "u32.mod"
        prog.write_bytes("\ufeffMODULE M\nENDMODULE\n".encode(encoding))
        r = CliRunner().invoke(main, ["inspect", str(prog)])
        assert r.exit_code == 2
        assert "u32.mod:1:1: UTF-32 text (its byte order mark): expected RAPID source text" \
            in r.output, r.output


def test_a_spreadsheet_profile_with_semicolons_and_decimal_commas_is_read(tmp_path):
    from rapidcomp.kinematics.profile import read_profile as read
    plain = (FIXTURES / "warm.csv").read_text()
    lines = [ln if ln.startswith("#") else ln.replace(",", ";") for ln in plain.splitlines()]
    lines = [ln if ln.startswith(("#", "joint")) else ln.replace(".", ",") for ln in lines]
    p = tmp_path / "excel.csv"
    p.write_text("\n".join(lines) + "\n")
    assert read(p).displacements == read(FIXTURES / "warm.csv").displacements


def test_a_quaternion_off_unit_length_is_normalised_with_a_warning(tmp_path):
    prog = _bad_module(tmp_path, "[400,-150,250],[0.707107,0,0.707107,0]",
                       "[400,-150,250],[0.71,0,0.71,0]")
    r = CliRunner().invoke(main, ["fix", prog, "--profile", str(WARM), "--json",
                                  str(tmp_path / "r.json"), "-o", str(tmp_path / "o.mod")])
    assert r.exit_code == 0, r.output
    import json
    rows = json.loads((tmp_path / "r.json").read_text())["targets"]
    warned = [w for row in rows for w in row["warnings"] if "quaternion norm" in w]
    assert warned and "p4 (bad.mod:9): quaternion norm 1.004092, not 1" in warned[0]


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes are POSIX")
def test_a_pipe_given_for_a_file_is_refused_not_waited_on(tmp_path):
    """A FIFO named as a module, program file, measurement or URDF (a
    `mkfifo`, a process substitution): exit 2 naming it, at once (reading
    it waited for a writer forever). Run as a process with a time limit,
    so that a regression fails instead of hanging the suite."""
    import subprocess
    import sys
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    for name, args in (
            ("m.mod", ["inspect", "{p}"]),
            ("m.mod", ["fix", "{p}", "--profile", str(WARM)]),
            ("p.pgf", ["check", "{p}", "--profile", str(WARM)]),
            ("m.csv", ["discover", "{p}"]),
            ("w.csv", ["fix", str(FIXTURES / "cubes.mod"), "--profile", "{p}"]),
            ("d.mod", ["fix", str(FIXTURES / "cubes.mod"), "--profile", str(WARM),
                       "--with", "{p}"]),
            ("arm.urdf", ["check", str(FIXTURES / "cubes.mod"), "--profile", str(WARM),
                          "--robot", "{p}"])):
        p = tmp_path / name
        if p.exists():
            p.unlink()
        os.mkfifo(p)
        r = subprocess.run([sys.executable, "-m", "rapidcomp",
                            *[a.format(p=p) for a in args]], capture_output=True, text=True,
                           timeout=60, cwd=tmp_path)
        assert r.returncode == 2, (args, r.stderr)
        assert f"{name}: not a regular file (a pipe or a device: give the file itself)" \
            in r.stderr, (args, r.stderr)
        assert "Traceback" not in r.stderr
        p.unlink()

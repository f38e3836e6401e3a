"""Transient compensation (#13): the generated support module executed by a
RAPID evaluator of its own (tests/rapid_eval.py) against the Python twin of
the state law, and `fix --transient` re-evaluated independently at every
thermal state with Pinocchio on the robot deformed by s . profile."""

from __future__ import annotations

import math
import re
import subprocess
import sys
from datetime import datetime, timedelta

import numpy as np
import pinocchio as pin
import pytest

from rapidcomp.compensate.transient import (GLOBAL_NAMES, Transient, day_number, make_transient,
                                            state_after, support_module)
from rapidcomp.errors import RapidcompError
from rapidcomp.kinematics.frames import DEG, quat_wxyz_to_matrix
from rapidcomp.kinematics.profile import deform, read_profile, scaled
from rapidcomp.kinematics.robot import irb140
from rapidcomp.rapid.parse import parse_text

from conftest import FIXTURES
from rapid_eval import Machine

CLOCK = Transient(45.0, 90.0, 2.0)
SENSOR = Transient(signal="aiMotorTemp", t_cold=22.0, t_warm=47.0)


class Clock:
    """The controller's calendar clock at a settable time; `race` makes the
    date change between two reads (midnight passing during rcNow)."""

    def __init__(self, t: datetime):
        self.t = t
        self.reads = 0
        self.race_at = None

    def __call__(self):
        self.reads += 1
        t = self.t
        if self.race_at is not None and self.reads >= self.race_at:
            t = self.t + timedelta(seconds=2)
        return t.strftime("%Y-%m-%d"), t.strftime("%H:%M:%S")


def test_the_support_module_parses_and_keeps_to_what_an_irc5_loads():
    for tr in (CLOCK, SENSOR):
        for nl in ("\n", "\r\n"):
            text = support_module(tr, nl)
            pf = parse_text(text, "rcThermal.sys")
            assert pf.modules[0].name == "rcThermal"
            assert text.count("\r\n") == (text.count("\n") if nl == "\r\n" else 0)
            words = set(re.findall(r"\b[A-Za-z][A-Za-z0-9_]*\b", text))
            assert max(len(w) for w in words) <= 32
            # No option a controller may not have.
            for option in ("PathOffset", "EGM", "CorrWrite", "CorrCon", "WorldZone"):
                assert option not in text
    assert "AInput(aiMotorTemp)" in support_module(SENSOR)


def test_the_clock_law_in_rapid_matches_its_python_twin():
    """A shift: run 60 min (a compensated move every 20 s), stand 30 min,
    run 40 min, over midnight; s after every move as the RAPID computes it
    (float32) and as the twin does."""
    clock = Clock(datetime(2026, 11, 22, 23, 10, 0))
    m = Machine(support_module(CLOCK), clock)
    s, t_prev = 0.0, None
    schedule = [(60, 20), (None, 30 * 60), (40, 20)]
    for minutes, step in schedule:
        if minutes is None:
            clock.t += timedelta(seconds=step)
            continue
        for _ in range(int(minutes * 60 / step)):
            clock.t += timedelta(seconds=step)
            m.call("rcUpdate")
            if t_prev is not None:
                s = state_after(s, (clock.t - t_prev).total_seconds() / 60, CLOCK)
            t_prev = clock.t
            assert float(m.data["rcs"]) == pytest.approx(s, abs=2e-5)
    # By hand: the first update only stamps the time (59 2/3 min of heating
    # follow), the first after the stop cools over 30 min 20 s.
    expected = 1 - math.exp(-(60 - 20 / 60) / 45)
    expected *= math.exp(-(30 + 20 / 60) / 90)
    expected = 1 - (1 - expected) * math.exp(-(40 - 20 / 60) / 45)
    assert float(m.data["rcs"]) == pytest.approx(expected, abs=1e-4)


@pytest.mark.parametrize("before, after", [
    (datetime(2026, 12, 31, 23, 59, 0), datetime(2027, 1, 1, 0, 0, 30)),
    (datetime(2028, 2, 28, 23, 0, 0), datetime(2028, 3, 1, 1, 0, 0)),   # leap day between
    (datetime(2026, 11, 20, 17, 0, 0), datetime(2026, 11, 27, 17, 1, 0)),  # a week off
])
def test_gaps_across_midnight_years_and_power_off(before, after):
    clock = Clock(before)
    m = Machine(support_module(CLOCK), clock)
    m.call("rcThermalSet", 0.8)
    clock.t = after
    m.call("rcUpdate")
    dt = (after - before).total_seconds() / 60
    assert float(m.data["rcs"]) == pytest.approx(state_after(0.8, dt, CLOCK), abs=2e-5)
    y, mo, d = after.year, after.month, after.day
    assert float(m.data["rclastday"]) == day_number(y, mo, d)
    assert day_number(y, mo, d) == (after.date() - datetime(2000, 3, 1).date()).days


def test_midnight_between_date_and_time_reads_and_a_clock_set_back():
    clock = Clock(datetime(2026, 11, 22, 23, 59, 59))
    m = Machine(support_module(CLOCK), clock)
    m.call("rcThermalSet", 0.5)
    # The date changes between the first and the second CDate of rcNow.
    clock.reads, clock.race_at = 0, 3
    m.call("rcUpdate")
    assert float(m.data["rclastday"]) == day_number(2026, 11, 23)
    assert float(m.data["rclastmin"]) == pytest.approx(1 / 60, abs=1e-6)
    assert float(m.data["rcs"]) == pytest.approx(state_after(0.5, 2 / 60, CLOCK), abs=2e-5)
    # The clock set back an hour: nothing is known of the gap, s stays.
    clock.race_at = None
    clock.t = datetime(2026, 11, 22, 23, 0, 0)
    before = float(m.data["rcs"])
    m.call("rcUpdate")
    assert float(m.data["rcs"]) == pytest.approx(before, abs=1e-7)


def test_the_sensor_law_and_the_operators_routines():
    m = Machine(support_module(SENSOR), inputs={"aiMotorTemp": 34.5})
    m.call("rcUpdate")
    assert float(m.data["rcs"]) == pytest.approx(0.5, abs=1e-6)
    for temp, s in ((10.0, 0.0), (60.0, 1.0)):
        m.inputs["aiMotorTemp"] = temp
        m.call("rcThermalShow")
        assert float(m.data["rcs"]) == s
    assert m.printed[-1].startswith("rapidcomp thermal state") and m.printed[-1].endswith("1")
    # The sensor sets the state: no rcThermalSet to contradict it.
    assert "rcthermalset" not in m.routines
    clock = Machine(support_module(CLOCK), Clock(datetime(2026, 11, 22, 8, 0, 0)))
    clock.call("rcThermalSet", 7)
    assert float(clock.data["rcs"]) == 1.0


def test_rctcj_and_rctcr_compute_cold_plus_s_times_the_correction():
    m = Machine(support_module(CLOCK), Clock(datetime(2026, 11, 22, 8, 0, 0)))
    m.data["rcs"] = np.float32(0.25)
    cold = [[10, 20, 30, 40, 50, 60], [9e9] * 6]
    dq = [[0.04, -0.02, 0, 0, 0, 0.008], [0] * 6]
    jt = m.call("rcTcJ", cold, dq)
    assert [float(jt["robax"][f"rax_{k}"]) for k in (1, 2, 6)] == pytest.approx(
        [10.01, 19.995, 60.002], abs=1e-5)
    assert float(jt["extax"]["eax_a"]) == pytest.approx(9e9)
    rt = [[400, 0, 250], [0.7071068, 0, 0.7071068, 0], [0, 0, 0, 1], [9e9] * 6]
    rt = m.call("rcTcR", rt, [[0.08, -0.04, 0.12], [0.0001, 0, -0.0001, 0]])
    assert float(rt["trans"]["x"]) == pytest.approx(400.02, abs=1e-4)
    q = [float(rt["rot"][k]) for k in ("q1", "q2", "q3", "q4")]
    assert np.linalg.norm(q) == pytest.approx(1, abs=1e-6)


def test_options_are_checked():
    with pytest.raises(RapidcompError, match="needs how the thermal state"):
        make_transient(None, None, None, None)
    with pytest.raises(RapidcompError, match="SIGNAL:T_COLD:T_WARM"):
        make_transient(None, None, None, "ai1:20")
    with pytest.raises(RapidcompError, match="not a RAPID signal"):
        make_transient(None, None, None, "1ai:20:40")
    with pytest.raises(RapidcompError, match="different"):
        make_transient(None, None, None, "ai1:20:20")
    with pytest.raises(RapidcompError, match="give one"):
        make_transient(30, None, None, "ai1:20:40")
    with pytest.raises(RapidcompError, match="from 0.001 to 100000"):
        make_transient(-5, None, None, None)
    assert make_transient(30, None, None, None) == Transient(30, 30, 2.0)


def _rapidcomp(*args, cwd):
    return subprocess.run([sys.executable, "-m", "rapidcomp", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True)


def _literal(text):
    return [float(x) for x in re.findall(r"[-+]?[\d.]+(?:[eE][-+]?\d+)?", text)]


def test_fix_transient_holds_at_every_thermal_state(tmp_path):
    """The cube program (--emit absj: MoveL becomes MoveAbsJ; the MoveC
    keeps its robtargets through rcTcR): every MoveAbsJ target of the
    output, executed with the evaluator at s, put through Pinocchio's FK of
    the IRB 140 deformed by s . profile, lands on the program's own target
    (read from the input module, tool0 in the base frame) within 1 um; at
    s = 0 the written joints are the program's (the paper's Table 5)."""
    out = tmp_path / "cubes_tr.mod"
    r = _rapidcomp("fix", FIXTURES / "cubes.mod", "--profile", FIXTURES / "warm.csv",
                   "--transient", "--tau-heat", "45", "--emit", "absj", "--limit", "J5=-120:120",
                   "-o", out, cwd=tmp_path)
    assert r.returncode == 0, r.stderr + r.stdout
    assert "76 of 76" in r.stdout and "transient" in r.stdout
    # The notes' advice is an option --transient takes (it refuses --emit
    # robtarget): --emit auto keeps a MoveL linear (rcTcR).
    assert "use --emit auto to keep MoveL linear" in r.stdout
    assert "or keep MoveL robtarget moves with --emit auto." in r.stdout
    assert "--emit robtarget" not in r.stdout
    # (Where MoveL stay robtarget moves, their constants (pS25_reltool's
    # too) are said by the transient note, not as copies of targets.)
    auto = _rapidcomp("fix", FIXTURES / "cubes.mod", "--profile", FIXTURES / "warm.csv",
                      "--transient", "--tau-heat", "45", "--limit", "J5=-120:120", "-o",
                      tmp_path / "auto" / "cubes.mod", cwd=tmp_path)
    assert auto.returncode == 0 and "RelTool(rcTcR(pS25, pS25_reltool_dq)" in (
        tmp_path / "auto" / "cubes.mod").read_text(), auto.stderr
    assert "new declarations" not in auto.stdout
    report = (tmp_path / "cubes_tr.md").read_text()
    assert "the worst over the thermal states" in report and "| transient | clock:" in report
    support = (tmp_path / "rcThermal.sys").read_text()
    parse_text(out.read_text(), "cubes_tr.mod")
    source = (FIXTURES / "cubes.mod").read_text()
    text = out.read_text()
    robot = irb140()
    profile = read_profile(FIXTURES / "warm.csv")
    models = {s: deform(robot, scaled(profile, s)) for s in (0, 0.25, 0.5, 0.75, 1)}
    m = Machine(support, Clock(datetime(2026, 11, 22, 8, 0, 0)))
    checked = 0
    for name in [f"pS{k}" for k in range(1, 10)]:
        assert re.search(rf"MoveAbsJ rcTcJ\(jt_{name}, jt_{name}_dq\)", text)
        target = _literal(re.search(rf"CONST robtarget {name}\s*:=\s*(\[.*?\]);", source,
                                    re.S).group(1))
        R = quat_wxyz_to_matrix(target[3:7])
        p = np.array(target[:3])
        cold = _literal(re.search(rf"CONST jointtarget jt_{name}:=(\[.*?\]);", text).group(1))
        dq = _literal(re.search(rf"CONST jointtarget jt_{name}_dq:=(\[.*?\]);", text).group(1))
        for s, model in models.items():
            m.data["rcs"] = np.float32(s)
            m.data["rclastday"] = np.float32(-1)
            jt = m.call("rcTcJ", [cold[:6], cold[6:]], [dq[:6], dq[6:]])
            q = np.array([float(jt["robax"][f"rax_{k}"]) for k in range(1, 7)])
            M = model.base_M_flange(q)
            assert np.linalg.norm(M.translation - p) * 1000 < 1.0
            assert np.linalg.norm(pin.log3(M.rotation @ R.T)) / DEG < 1e-4
            checked += 1
    assert checked == 45
    # s = 0: the cold robot goes to the program's own joints (Table 5 row 1).
    cold = _literal(re.search(r"CONST jointtarget jt_pFront\{45\}:=\s*\[\s*(\[\[.*?\]\])",
                              text, re.S).group(1))
    assert cold[:6] == pytest.approx([41.85, 44.63, 25.88, 43.53, -75.61, -13.29], abs=0.006)
    assert "MoveC rcTcR(pS22, pS22_dq), rcTcR(pS23, pS23_dq)" in text
    # The support module's names are the task's now: compensating the
    # output again is refused.
    again = _rapidcomp("fix", out, "--profile", FIXTURES / "warm.csv", "--transient",
                       "--tau-heat", "45", "-o", tmp_path / "twice.mod", cwd=tmp_path)
    assert again.returncode == 2 and "rcTcJ" in again.stderr
    assert not (tmp_path / "twice.mod").exists()


@pytest.mark.parametrize("args, message", [
    (["--tau-heat", "45"], "--tau-heat applies to --transient only"),
    (["--transient"], "needs how the thermal state is known"),
    (["--transient", "--tau-heat", "45", "--emit", "robtarget"], "--emit robtarget is not one"),
    (["--transient", "--temperature", "ai:20"], "SIGNAL:T_COLD:T_WARM"),
    # (The same num to the controller: its division by their difference
    # stopped the first move.)
    (["--transient", "--temperature", "ai:1000:1000.00001"], "the same number to the controller"),
])
def test_bad_transient_options_exit_2_with_nothing_written(tmp_path, args, message):
    r = _rapidcomp("fix", FIXTURES / "cubes.mod", "--profile", FIXTURES / "warm.csv",
                   "-o", tmp_path / "o.mod", *args, cwd=tmp_path)
    assert r.returncode == 2 and message in r.stderr and "Traceback" not in r.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("extra, args, message", [
    # (AInput(aiT) of a num: a type error, the task did not load.)
    ("  VAR num aiT:=1;\n", ["--temperature", "aiT:20:40"],
     "extra.mod:2 declares aiT as num data, not an analog input (signalai)"),
    ("", ["--temperature", "tool0:20:40"], "a predefined data name"),
    # (AInput(TRUE), AInput(v100), AInput(MoveL): none loads.)
    *[("", ["--temperature", f"{name}:20:40"], what) for name, what in (
        ("TRUE", "a word RAPID reserves"), ("v100", "a predefined data name"),
        ("fine", "a predefined data name"), ("ERRNO", "a predefined data name"),
        ("MoveL", "a predefined routine's name"), ("AInput", "a predefined routine's name"))],
    # (A routine hides the predefined one of its name: the support module
    # would call the task's Exp.)
    ("  FUNC num Exp(num x)\n    RETURN x;\n  ENDFUNC\n", ["--tau-heat", "30"],
     "extra.mod:2: a FUNC named Exp hides the predefined Exp"),
])
def test_names_the_support_module_calls_are_the_controllers(tmp_path, extra, args, message):
    """The support module's calls reach what it means: a task routine or
    data hiding a predefined routine it calls, or a --temperature signal
    that is the task's data of another type, is refused (exit 2, nothing
    written); a LOCAL one in another module hides nothing."""
    (tmp_path / "extra.mod").write_text("MODULE Extra\n" + extra + "ENDMODULE\n")
    out = str(tmp_path / "out") + "/"      # (a folder: out/cubes.mod)
    r = _rapidcomp("fix", FIXTURES / "cubes.mod", "--profile", FIXTURES / "warm.csv", "--with",
                   tmp_path / "extra.mod", "-o", out, "--transient", *args, cwd=tmp_path)
    assert r.returncode == 2 and message in r.stderr, r.stderr
    assert not (tmp_path / "out").exists()
    if extra:
        (tmp_path / "extra.mod").write_text("MODULE Extra\n  LOCAL " + extra.lstrip()
                                            + "ENDMODULE\n")
        r = _rapidcomp("fix", FIXTURES / "cubes.mod", "--profile", FIXTURES / "warm.csv",
                       "--with", tmp_path / "extra.mod", "-o", out, "--transient",
                       "--limit", "J5=-120:120", *args, cwd=tmp_path)
        assert r.returncode == 0, r.stderr


def test_names_of_the_support_module_are_its_own():
    assert len(set(n.lower() for n in GLOBAL_NAMES)) == len(GLOBAL_NAMES)
    text = support_module(CLOCK)
    pf = parse_text(text, "x.sys")
    declared = {i.name.lower() for i in pf.modules[0].node.items if hasattr(i, "name")}
    assert declared | {"rctcold", "rctwarm", "rcthermal"} >= {n.lower() for n in GLOBAL_NAMES}


def test_the_support_module_goes_where_the_task_loads_it(tmp_path):
    """A program file lists it after its last module; a backup has it in the
    task's SYSMOD folder; a task folder next to its modules; robtarget moves
    keep their kind (MoveL rcTcR(...)), a J4 on its quadrant boundary gets a
    cold copy with the confdata both states share."""
    glue = tmp_path / "glueT"
    r = _rapidcomp("fix", FIXTURES / "tasks" / "glue" / "Glue.pgf", "--profile",
                   FIXTURES / "warm.csv", "--transient", "--tau-heat", "30", "-o", glue,
                   cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    pgf = (glue / "Glue.pgf").read_text()
    assert pgf.splitlines()[-2].strip() == "<Module>rcThermal.sys</Module>"
    assert (glue / "rcThermal.sys").is_file()
    backup = tmp_path / "bk"
    r = _rapidcomp("fix", FIXTURES / "tasks" / "backup_irbt", "--profile", FIXTURES / "warm.csv",
                   "--transient", "--tau-heat", "30", "--track", "a:x", "-o", backup,
                   cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert (backup / "RAPID" / "TASK1" / "SYSMOD" / "rcThermal.sys").is_file()
    cell = tmp_path / "cellT"
    r = _rapidcomp("fix", FIXTURES / "tasks" / "cell", "--profile", FIXTURES / "warm.csv",
                   "--transient", "--tau-heat", "30", "-o", cell, cwd=tmp_path)
    assert r.returncode == 0 and "29 of 30" in r.stdout, r.stderr + r.stdout
    main = (cell / "MainModule.mod").read_text()
    assert "MoveL rcTcR(pPlace_cold{i}, pPlace_dq{i})" in main
    assert (cell / "rcThermal.sys").is_file()
    parse_text(main, "MainModule.mod")


@pytest.mark.parametrize("encoding, nl", [("latin-1", "\r\n"), ("utf-16", "\r\n"),
                                         ("latin-1", "\r")])
def test_a_program_file_gets_one_line_and_keeps_every_byte(tmp_path, encoding, nl):
    """The program file's text is the input's with one line added after its
    last module, in its own line breaks and encoding (a RobotStudio .pgf is
    CRLF; read as text, every CRLF became LF); a module commented out is
    none (the line went into the comment, and the controller did not load
    the support module)."""
    glue = tmp_path / "glue"
    glue.mkdir()
    for f in ("GlueData.mod", "GlueMain.mod"):
        (glue / f).write_bytes((FIXTURES / "tasks" / "glue" / f).read_bytes())
    declared = "UTF-16" if encoding == "utf-16" else "ISO-8859-1"
    lines = [f'<?xml version="1.0" encoding="{declared}" ?>', "<!-- cell 4, not edited -->",
             "<Program>", "\t<Module>GlueData.mod</Module>", "\t<Module>GlueMain.mod</Module>",
             "\t<!-- <Module>OldMain.mod</Module> -->", "</Program>", ""]
    (glue / "Glue.pgf").write_bytes(nl.join(lines).encode(encoding))
    r = _rapidcomp("fix", glue / "Glue.pgf", "--profile", FIXTURES / "warm.csv", "--transient",
                   "--tau-heat", "30", "-o", tmp_path / "out", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    want = lines[:5] + ["\t<Module>rcThermal.sys</Module>"] + lines[5:]
    assert (tmp_path / "out" / "Glue.pgf").read_bytes() == nl.join(want).encode(encoding)


def test_a_task_folders_program_file_lists_the_support_module(tmp_path):
    """A task folder holding a .pgf: the copy of the .pgf lists rcThermal.sys
    too (it was copied as it was: the program loaded without the support
    module, and rcTcR was not defined)."""
    glue, out = tmp_path / "glue", tmp_path / "out"
    glue.mkdir()
    for f in ("Glue.pgf", "GlueData.mod", "GlueMain.mod"):     # (not its stale old/ copy)
        (glue / f).write_bytes((FIXTURES / "tasks" / "glue" / f).read_bytes())
    r = _rapidcomp("fix", glue, "--profile", FIXTURES / "warm.csv", "--transient", "--tau-heat",
                   "30", "-o", out, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    src = (glue / "Glue.pgf").read_bytes()
    cut = src.rindex(b"</Module>") + len(b"</Module>")
    assert (out / "Glue.pgf").read_bytes() == (src[:cut] + b"\r\n    <Module>rcThermal.sys"
                                               b"</Module>" + src[cut:])
    assert (out / "rcThermal.sys").is_file()


def _nominal_ik(robot, R, p, q0):
    """Damped Newton on Pinocchio's model (mm) from q0 (deg): an IK of the
    test's own, not rapidcomp's closed form."""
    model, data = robot.model, robot.model.createData()
    q = np.array(q0, float) * DEG
    for _ in range(50):
        M = robot.base_M_flange(q / DEG)
        err = np.concatenate([np.asarray(p) - M.translation, pin.log3(R @ M.rotation.T)])
        if np.linalg.norm(err[:3]) < 1e-10 and np.linalg.norm(err[3:]) < 1e-13:
            break
        J = pin.computeFrameJacobian(model, data, q, robot.flange_frame,
                                     pin.LOCAL_WORLD_ALIGNED)
        q = q + np.linalg.solve(J, err)
    return q / DEG


def test_fix_transient_keeps_movel_linear_and_holds_at_every_state(tmp_path):
    """Default --emit auto: a MoveL keeps its kind, its target rcTcR(pSk,
    pSk_dq). Evaluated with the RAPID evaluator at s, solved by an IK of the
    test's own on the nominal robot (what the controller does with a
    robtarget), the robot deformed by s . profile puts the flange on the
    program's target within 1 um."""
    out = tmp_path / "cubes_tr.mod"
    r = _rapidcomp("fix", FIXTURES / "cubes.mod", "--profile", FIXTURES / "warm.csv",
                   "--transient", "--tau-heat", "45", "--limit", "J5=-120:120", "-o", out,
                   cwd=tmp_path)
    assert r.returncode == 0 and "76 of 76" in r.stdout, r.stderr + r.stdout
    text, source = out.read_text(), (FIXTURES / "cubes.mod").read_text()
    m = Machine((tmp_path / "rcThermal.sys").read_text(), Clock(datetime(2026, 11, 22)))
    robot = irb140()
    profile = read_profile(FIXTURES / "warm.csv")
    side = [(-83.07, 45.14, -44.24, 90.10, 83.07, 269.09)]
    for name in ("pS2", "pS5", "pS9"):
        assert f"MoveL rcTcR({name}, {name}_dq)" in text
        cold = _literal(re.search(rf"CONST robtarget {name}\s*:=\s*(\[.*?\]);", source,
                                  re.S).group(1))
        dq = _literal(re.search(rf"CONST pose {name}_dq:=(\[.*?\]);", text).group(1))
        R0, p0 = quat_wxyz_to_matrix(cold[3:7]), np.array(cold[:3])
        q_cold = _nominal_ik(robot, R0, p0, side[0])
        for s in (0, 0.25, 0.5, 0.75, 1):
            m.data["rcs"] = np.float32(s)
            m.data["rclastday"] = np.float32(-1)
            rt = m.call("rcTcR", [cold[0:3], cold[3:7], cold[7:11], cold[11:17]],
                        [dq[0:3], dq[3:7]])
            p = np.array([float(rt["trans"][k]) for k in "xyz"])
            R = quat_wxyz_to_matrix([float(rt["rot"][k]) for k in ("q1", "q2", "q3", "q4")])
            q = _nominal_ik(robot, R, p, q_cold)
            M = deform(robot, scaled(profile, s)).base_M_flange(q)
            assert np.linalg.norm(M.translation - p0) * 1000 < 1.0, (name, s)
            assert np.linalg.norm(pin.log3(M.rotation @ R0.T)) / DEG < 1e-4


def test_review_cases_literal_index_backinfo_overwrite_and_static_profiles(tmp_path):
    """An array element with a literal index (jA{1}, pA{2}) is compensated;
    a backup's backinfo.txt lists the support module; an existing different
    rcThermal.sys is not overwritten; a profile discover marked static and a
    reserved word as signal are refused; tau_heat_min with '=' is read, twice
    is an error."""
    mod = tmp_path / "m1.mod"
    mod.write_text(
        "MODULE M1\n"
        "    CONST jointtarget jA{2}:=[[[0,-30,30,0,60,0],[9E9,9E9,9E9,9E9,9E9,9E9]],"
        "[[90,-30,30,0,60,180],[9E9,9E9,9E9,9E9,9E9,9E9]]];\n"
        "    CONST robtarget pA{2}:=[[[500,0,400],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]],"
        "[[500,100,400],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]];\n"
        "    PROC main()\n        MoveAbsJ jA{1}, v200, fine, tool0;\n"
        "        MoveL pA{2}, v200, fine, tool0;\n    ENDPROC\nENDMODULE\n")
    out = tmp_path / "o" / "m1.mod"
    r = _rapidcomp("fix", mod, "--profile", FIXTURES / "warm.csv", "--transient", "--tau-heat",
                   "40", "-o", out, cwd=tmp_path)
    assert r.returncode == 0 and "2 of 2" in r.stdout, r.stderr + r.stdout
    text = out.read_text()
    assert "MoveAbsJ rcTcJ(jA{1}, jA_1_dq)" in text
    assert re.search(r"MoveL rcTcR\((pA\{2\}|pA_2_cold), pA_2_dq\)", text)
    # Another law into the same folder: refused, the first module kept.
    before = (out.parent / "rcThermal.sys").read_bytes()
    r = _rapidcomp("fix", mod, "--profile", FIXTURES / "warm.csv", "--transient", "--tau-heat",
                   "90", "-o", out.parent / "again.mod", cwd=tmp_path)
    assert r.returncode == 2 and "exists and is not this support module" in r.stderr
    # (It says where they differ: the line of the time constant.)
    at = next(i for i, line in enumerate(before.decode().splitlines(), 1)
              if "rcTauHeat:=" in line and "CONST" in line)
    assert (f"rcThermal.sys:{at}:26: exists and is not this support module: its line {at} "
            "holds `CONST num rcTauHeat:=40;` where this run writes `CONST num rcTauHeat:=90;`"
            in r.stderr), r.stderr
    assert (out.parent / "rcThermal.sys").read_bytes() == before
    assert not (out.parent / "again.mod").exists()
    # The same law again: the module there is the one it would write, kept,
    # and the command says so beside what it wrote.
    r = _rapidcomp("fix", mod, "--profile", FIXTURES / "warm.csv", "--transient", "--tau-heat",
                   "40", "-o", out.parent / "again.mod", cwd=tmp_path)
    assert r.returncode == 0 and (out.parent / "again.mod").is_file(), r.stderr
    assert r.stdout.splitlines()[-1] == (
        f"wrote {out.parent / 'again.mod'}, {out.parent / 'again.md'}; kept "
        f"{out.parent / 'rcThermal.sys'} (the same "
        "support module was there)"), r.stdout
    assert (out.parent / "rcThermal.sys").read_bytes() == before
    # Two programs into one folder share its support module: named once,
    # written (first run) or kept (second).
    mod2 = tmp_path / "m2.mod"
    mod2.write_text(mod.read_text().replace("MODULE M1", "MODULE M2"))
    lines = []
    for _ in range(2):
        r = _rapidcomp("fix", mod, mod2, "--profile", FIXTURES / "warm.csv", "--transient",
                       "--tau-heat", "40", "-o", tmp_path / "two", cwd=tmp_path)
        assert r.returncode == 0, r.stderr
        lines.append(r.stdout.splitlines()[-1])
    assert lines[0].count("rcThermal.sys") == 1 and "kept" not in lines[0], lines[0]
    assert lines[1].endswith(f"; kept {tmp_path / 'two' / 'rcThermal.sys'} (the same support "
                             "module was there)"), lines[1]
    backup = tmp_path / "bk"
    r = _rapidcomp("fix", FIXTURES / "tasks" / "backup_irbt", "--profile", FIXTURES / "warm.csv",
                   "--transient", "--tau-heat", "30", "--track", "a:x", "-o", backup,
                   cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    info = (backup / "BACKINFO" / "backinfo.txt").read_text().splitlines()
    task1 = info[info.index(">>TASK1: (T_ROB1,,)") + 1:]
    assert task1[:3] == ["SYSMOD/user.sys", "PROGMOD/Track.mod", "SYSMOD/rcThermal.sys"]
    assert "TASK PERS num rcS:=0;" in (backup / "RAPID" / "TASK1" / "SYSMOD" /
                                       "rcThermal.sys").read_text()
    static = tmp_path / "static.csv"
    static.write_text("# static: nothing changed over time\njoint,dx_mm,dy_mm,dz_mm,rx_deg,"
                      "ry_deg,rz_deg\nJ2,0.01,0,0,0,0,0\n")
    r = _rapidcomp("fix", mod, "--profile", static, "--transient", "--tau-heat", "40",
                   "-o", tmp_path / "s.mod", cwd=tmp_path)
    assert r.returncode == 2 and "effects are static" in r.stderr
    r = _rapidcomp("fix", mod, "--profile", FIXTURES / "warm.csv", "--transient",
                   "--temperature", "IF:20:40", "-o", tmp_path / "t.mod", cwd=tmp_path)
    assert r.returncode == 2 and "reserved word" in r.stderr
    eq = tmp_path / "eq.csv"
    eq.write_text("# tau_heat_min = 33\n" + (FIXTURES / "warm.csv").read_text())
    r = _rapidcomp("fix", mod, "--profile", eq, "--transient", "-o", tmp_path / "e" / "e.mod",
                   cwd=tmp_path)
    assert r.returncode == 0 and "heating tau 33 min" in r.stdout and "tau from eq.csv" in r.stdout
    eq.write_text("# tau_heat_min: 33\n# tau_heat_min: 40\n" + (FIXTURES / "warm.csv").read_text())
    r = _rapidcomp("fix", mod, "--profile", eq, "--transient", "-o", tmp_path / "f.mod",
                   cwd=tmp_path)
    assert r.returncode == 2 and "given twice" in r.stderr


def test_two_programs_in_one_folder_share_the_support_module(tmp_path):
    """A CRLF module and an LF one compensated into one folder with the same
    law: the module the first wrote serves the second (only its line
    breaks would differ); it is not refused nor rewritten."""
    out = tmp_path / "o"
    for name in ("cam_confoff.mod", "robotstudio_crlf.mod"):
        r = _rapidcomp("fix", FIXTURES / "rapid" / name, "--profile", FIXTURES / "warm.csv",
                       "--transient", "--tau-heat", "40", "--allow-partial", "-o", out / name,
                       cwd=tmp_path)
        assert r.returncode in (0, 1) and "exists" not in r.stderr, r.stderr
        assert (out / name).is_file()
    assert b"\r\n" not in (out / "rcThermal.sys").read_bytes()


def test_a_target_read_once_that_the_transient_writer_refuses_is_its_own_group(tmp_path,
                                                                                monkeypatch):
    """A declared target one move reads alone (place.Singles) that the
    transient writer refuses (as it refuses confdata one robtarget cannot
    carry in both states) is refused with that reason in its row and the
    summary, its move left as written, the other 75 written: the element
    becomes the Group of its own it is (place.split_off)."""
    from click.testing import CliRunner

    from rapidcomp.cli import main
    from rapidcomp.compensate import edit
    from rapidcomp.compensate import place as P
    real, kept = edit.Editor._apply_transient, edit.Values.conf_kept
    kept_literal = edit.Values.kept_pose_literal

    def refusing(self, g):
        if [u.line for u in g.uses] == [106]:          # MoveL pS3, v200, fine, tool0;
            g.failure = ("refused here (a test's reason)", None)
            return None
        return real(self, g)

    def not_kept(self, g, k):
        # (Its confdata not the written one: not the Singles' own way, the
        # Group's, where the writer refuses it.)
        lines = [g.uses[k].line] if type(g) is P.Singles else [u.line for u in g.uses]
        return False if lines == [106] else kept(self, g, k)

    def no_literal(self, s, n):
        # (The Singles' way of asking the same.)
        return None if s.uses[n].line == 106 else kept_literal(self, s, n)
    monkeypatch.setattr(edit.Editor, "_apply_transient", refusing)
    monkeypatch.setattr(edit.Values, "conf_kept", not_kept)
    monkeypatch.setattr(edit.Values, "kept_pose_literal", no_literal)
    out = tmp_path / "o.mod"
    r = CliRunner().invoke(main, ["fix", str(FIXTURES / "cubes.mod"), "--profile",
                                  str(FIXTURES / "warm.csv"), "--transient", "--tau-heat", "45",
                                  "--limit", "J5=-120:120", "--allow-partial", "-o", str(out)])
    assert r.exit_code == 1, r.output
    assert "75 of 76 target uses compensated, 1 not compensated" in r.output
    assert "line 106 MoveL pS3: refused here (a test's reason)" in r.output
    text = out.read_text()
    assert "        MoveL pS3, v200, fine, tool0;" in text and "pS3_dq" not in text
    assert "MoveL rcTcR(pS4, pS4_dq), v200, fine, tool0;" in text


def test_new_names_come_in_the_groups_order_with_targets_read_once(tmp_path, monkeypatch):
    """A transient output's new names (<name>_dq) are made in the order a
    Group each makes them, where targets read once (place.Singles) and
    others share a stem: two 32-character names alike in their first 29
    (one read once, one read twice, at a later line) get the same names
    either way (the first met the first), and the whole output is the
    same."""
    from click.testing import CliRunner

    from rapidcomp.cli import main
    from rapidcomp.compensate import place as P
    text = (FIXTURES / "cubes.mod").read_text()
    text = text.replace("        MoveL pS26, v200, fine, tool0;\n",
                        "        MoveL pS26, v200, fine, tool0;\n        MoveL pS9, v200, fine, tool0;\n")
    text = re.sub(r"\bpS2\b", "a" * 29 + "001", text)
    text = re.sub(r"\bpS9\b", "a" * 29 + "002", text)
    program = tmp_path / "names.mod"
    program.write_text(text)

    def run(where):
        r = CliRunner().invoke(main, ["fix", str(program), "--profile", str(FIXTURES / "warm.csv"),
                                      "--transient", "--tau-heat", "45", "--limit",
                                      "J5=-120:120", "-o", str(where / "o.mod")])
        assert r.exit_code == 0, r.output
        return (where / "o.mod").read_text()
    singles = run(tmp_path / "singles")
    # (The second, cut to 32 characters with its suffix: <29 a>__2.)
    assert f"{'a' * 29}001, {'a' * 29}_dq)" in singles
    assert f"{'a' * 29}002, {'a' * 29}__2)" in singles
    real = P.grouping
    monkeypatch.setattr(P, "grouping", lambda *a, **k: real(*a, **{**k, "singles": False}))
    assert run(tmp_path / "groups") == singles


def test_a_support_module_of_another_program_is_refused_before_the_work(tmp_path, monkeypatch):
    """Where rcThermal.sys of other settings is in the way, the command says
    so before it compensates anything (a CAM program's work is not done
    only to be refused): exit 2, the message, nothing written."""
    from click.testing import CliRunner

    from rapidcomp.cli import main
    from rapidcomp.compensate import job

    (tmp_path / "rcThermal.sys").write_text("MODULE rcThermal(SYSMODULE)\nENDMODULE\n")

    def no_work(*args, **kwargs):
        raise AssertionError("compensated before the refusal")
    monkeypatch.setattr(job, "fix", no_work)
    r = CliRunner().invoke(main, ["fix", str(FIXTURES / "cubes.mod"), "--profile",
                                  str(FIXTURES / "warm.csv"), "--transient", "--tau-heat", "40",
                                  "-o", str(tmp_path / "out.mod")])
    assert r.exit_code == 2 and "exists and is not this support module" in r.output, r.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rcThermal.sys"]


def test_signal_names_only_the_predefined_ones_are_refused():
    """RAPID's predefined speed, zone and stop data are fixed lists: v7,
    z2, err_temp or stoptimeJ2 are names an analog input may have."""
    from rapidcomp.compensate.transient import _check_signal
    from rapidcomp.errors import RapidcompError
    for name in ("v7", "z2", "err_temp", "stoptimeJ2", "aiTemp", "vlin15"):
        _check_signal(name)
    for name in ("v100", "z50", "fine", "vrot10", "inpos50", "ERRNO", "TRUE", "MoveL", "Offs"):
        with pytest.raises(RapidcompError):
            _check_signal(name)


def test_a_large_modules_words_are_read_as_its_parse_found_them(monkeypatch):
    """check_names reads a module's words where its parse found them
    (rapid/predecode.py, a large module's): a support module's name in a
    comment or a string is refused there as in a small module's text, and
    a module without one passes."""
    from rapidcomp.compensate.plan import Task
    from rapidcomp.compensate.transient import check_names
    from rapidcomp.rapid import predecode as PD
    monkeypatch.setattr(PD, "PREDECODE_FROM", 0)
    monkeypatch.setattr(PD, "enabled", True)
    move = "    MoveL [[500,0,400],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]],v100,z1,tool0;\n"
    for extra, clash in (("    ! see RCTCR before\n", "rcTcR"),
                         ('    TPWrite "rcThermals rcTcRx";\n', None),
                         ('    TPWrite "s rcTcJ";\n', "rcTcJ")):
        text = "MODULE M\n  PROC p()\n" + move * 3 + extra + "  ENDPROC\nENDMODULE\n"
        pf = parse_text(text, "m.mod")
        assert pf.words is not None
        if clash is None:
            check_names(Task("m.mod", (pf,)))
            continue
        with pytest.raises(RapidcompError, match=f"uses {clash}, a name of the transient"):
            check_names(Task("m.mod", (pf,)))


def test_cold_values_with_other_confdata_are_counted_in_a_note(tmp_path):
    """A robtarget move whose warm robot needs another J4 quadrant (J4 at
    0 exactly: orientation [0,0,1,0]) keeps its kind with a cold value that
    carries that confdata: a declared target's copy <name>_cold, an inline
    literal rewritten in the call. The note counts them as the output and
    the rows hold them (counted here from the output's text and the
    input's confdata, not from the tool's lists)."""
    ext = "[9E9,9E9,9E9,9E9,9E9,9E9]"
    pts = [(478.062, 138.973, 529.132), (509.096, 115.489, 328.158),
           (471.701, 134.306, 429.830), (502.485, 175.660, 414.361)] * 2
    lines = ["MODULE Cold"]
    lines += [f"    CONST robtarget p{i}:=[[{x},{y},{z}],[0,0,1,0],[0,0,0,0],{ext}];"
              for i, (x, y, z) in enumerate(pts[:4])]
    lines += ["    PROC main()"] + [f"        MoveL p{i},v100,fine,tool0;" for i in range(4)]
    lines += [f"        MoveL [[{x},{y},{z}],[0,0,1,0],[0,0,0,0],{ext}],v100,fine,tool0;"
              for x, y, z in pts[4:]]
    lines += ["    ENDPROC", "ENDMODULE", ""]
    (tmp_path / "cold.mod").write_text("\n".join(lines))
    r = _rapidcomp("fix", tmp_path / "cold.mod", "--profile", FIXTURES / "warm.csv",
                   "--transient", "--tau-heat", "45", "-o", tmp_path / "out" / "cold.mod",
                   cwd=tmp_path)
    assert r.returncode == 0 and "8 of 8" in r.stdout, r.stderr + r.stdout
    out = (tmp_path / "out" / "cold.mod").read_text()
    copies = re.findall(r"CONST robtarget (\w+_cold):=\[\[[^]]*\],\[[^]]*\],\[([^]]*)\]", out)
    inline = [c for c in re.findall(r"rcTcR\(\[\[[^]]*\],\[[^]]*\],\[([^]]*)\]", out)
              if c != "0,0,0,0"]
    assert copies and inline and all(conf != "0,0,0,0" for _, conf in copies)
    names = [name for name, _ in copies]
    n = len(copies) + len(inline)             # (each copy read by its one move)
    shown = ", ".join(names[:3]) + (", ..." if len(names) > 3 else "")
    what = (f"{len(names)} read from {len(names)} cop{'ies' if len(names) > 1 else 'y'} of "
            f"declared targets ({shown})")
    assert (f"note: transient: {n} target use{'s' if n > 1 else ''} of robtarget moves carr"
            f"{'y' if n > 1 else 'ies'} a cold value with other confdata than written, the "
            f"one every thermal state needs: {what}, {len(inline)} inline; the warm robot "
            "needs another quadrant of J1, J4 or J6") in r.stdout
    report = (tmp_path / "out" / "cold.md").read_text()
    assert report.count("rcTcR(written with the confdata every state needs, correction)") == (
        len(inline))


def test_where_a_support_module_in_the_way_differs():
    """The refusal of another rcThermal.sys names the first line of code
    that differs (a comment that differs, where no code does), both
    lines, a long one around where they differ, line breaks aside; and
    where one of them ends."""
    from rapidcomp.compensate.transient import differs
    ours = b"MODULE rcThermal\n    ! tau 40 min\n    CONST num rcTauHeat:=40;\nENDMODULE\n"
    theirs = ours.replace(b"40", b"45").replace(b"\n", b"\r\n")
    assert differs(theirs, ours) == (":3:27", "its line 3 holds `CONST num rcTauHeat:=45;` "
                                     "where this run writes `CONST num rcTauHeat:=40;`")
    assert differs(ours.replace(b"! tau 40", b"! tau 45"), ours) == (
        ":2:12", "its line 2 holds `! tau 45 min` where this run writes `! tau 40 min`")
    assert differs(ours.replace(b"\n", b"\r\n"), ours) == ("", "")
    assert differs(ours + b"MODULE x\n", ours) == (
        ":5:1", "its line 5 holds `MODULE x` where this run's ends")
    assert differs(ours[:-10], ours) == (
        ":3:29", "it ends at its line 3 where this run's goes on with `ENDMODULE`")
    assert differs(None, ours) == ("", "")
    assert differs(b"", ours) == (":1:1", "it is empty where this run's begins with "
                                  "`MODULE rcThermal`")
    long = b"    ! " + b"x" * 100 + b"a" + b"y" * 100 + b"\n"
    there, what = differs(long.replace(b"a", b"b"), long)
    assert there == ":1:107" and what.count("...") == 4 and "xb" in what and "xa" in what

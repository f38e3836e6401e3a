"""An element of a FOR-walked array that a move reads by its literal index
and the loop does not reach (`MoveL pArr{1}` before `FOR i FROM 2 TO 3`):
its value is written in the array, where it is, as the loop's elements
are; not into a copy with the move renamed to it. The oracle: the same
target declared alone, read by the same move, gets the same numbers."""

from __future__ import annotations

import re

from click.testing import CliRunner

from rapidcomp.cli import main

from conftest import FIXTURES

P1 = "[[400,-300,250],[0.707107,0,0.707107,0],[-1,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
P2 = "[[400,-300,400],[0.707107,0,0.707107,0],[-1,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
P3 = "[[400,-150,400],[0.707107,0,0.707107,0],[-1,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
ARRAY = f"""MODULE Arr
    CONST robtarget pArr{{3}}:=[
        {P1},
        {P2},
        {P3}];
    PROC main()
        MoveL pArr{{1}}, v200, fine, tool0;
        FOR i FROM 2 TO 3 DO
            MoveL pArr{{i}}, v200, fine, tool0;
        ENDFOR
    ENDPROC
ENDMODULE
"""
ALONE = f"""MODULE Alone
    CONST robtarget pOne:={P1};
    PROC main()
        MoveL pOne, v200, fine, tool0;
    ENDPROC
ENDMODULE
"""


def _fix(tmp_path, name, text, mode):
    src = tmp_path / f"{name}.mod"
    src.write_text(text)
    out = tmp_path / f"{name}_{mode}.mod"
    r = CliRunner().invoke(main, ["fix", str(src), "--profile", str(FIXTURES / "warm.csv"),
                                  "--emit", mode, "-o", str(out)])
    assert r.exit_code == 0, r.output
    return r.output, out.read_text()


def test_an_element_the_loop_does_not_reach_is_written_in_the_array(tmp_path):
    _, alone = _fix(tmp_path, "alone", ALONE, "robtarget")
    want = re.search(r"pOne:=(\[.*\]);", alone).group(1)
    said, out = _fix(tmp_path, "arr", ARRAY, "robtarget")
    assert "3 of 3 target uses compensated" in said and "new declarations" not in said
    assert out.splitlines()[2] == f"        {want},"
    assert "MoveL pArr{1}, v200" in out and "_c" not in out
    # Turned into MoveAbsJ: the move reads the array's jointtarget element.
    _, alone = _fix(tmp_path, "alone", ALONE, "absj")
    want = re.search(r"jt_pOne:=(\[.*\]);", alone).group(1)
    said, out = _fix(tmp_path, "arr", ARRAY, "absj")
    assert "3 of 3 target uses compensated" in said
    assert "MoveAbsJ jt_pArr{1}, v200" in out and "jt_pArr_1" not in out
    assert re.search(r"jt_pArr\{3\}:=\[\s*" + re.escape(want) + ",", out), out


def test_a_new_arrays_rows_are_indented_as_the_modules(tmp_path):
    """The jointtarget array written for a robtarget array (absj) has its
    rows indented as the robtarget array's rows are (tabs in a module
    indented with tabs); where those share the declaration's line, one
    step past the declaration: a tab in a module indented with tabs."""
    tabs = ARRAY.replace("    ", "\t")
    _, out = _fix(tmp_path, "tabs", tabs, "absj")
    rows = [line for line in out.splitlines() if line.lstrip().startswith("[[-")]
    assert len(rows) == 3 and all(line.startswith("\t\t[[-") for line in rows), rows
    one_line = tabs.replace(",\n\t\t", ",").replace("[\n\t\t", "[")
    assert f"pArr{{3}}:=[{P1},{P2},{P3}];" in one_line
    _, out = _fix(tmp_path, "one_line", one_line, "absj")
    rows = [line for line in out.splitlines() if line.lstrip().startswith("[[-")]
    assert len(rows) == 3 and all(line.startswith("\t\t[[-") for line in rows), rows
    _, out = _fix(tmp_path, "spaces", ARRAY.replace("        [[", "      [["), "absj")
    rows = [line for line in out.splitlines() if line.lstrip().startswith("[[-")]
    assert len(rows) == 3 and all(line.startswith("      [[-") for line in rows), rows


def test_an_element_outside_the_loop_that_fails_fails_alone(tmp_path):
    """Where the element only a literal index reads cannot be compensated
    (J1 past a limit set just below it), it alone is refused: the loop's
    elements are written as they are without it."""
    limit = ("--limit", "J1=-0.001:170", "--allow-partial")
    at = "[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]"
    text = (ARRAY.replace(P1, f"[[500,0,400],{at}").replace(P2, f"[[500,100,400],{at}")
            .replace(P3, f"[[500,150,400],{at}"))
    for mode in ("robtarget", "absj"):
        src = tmp_path / f"fail_{mode}.mod"
        src.write_text(text)
        r = CliRunner().invoke(main, ["fix", str(src), "--profile", str(FIXTURES / "warm.csv"),
                                      "--emit", mode, "-o", str(tmp_path / f"o_{mode}.mod"),
                                      *limit])
        assert r.exit_code == 1, r.output
        assert "2 of 3 target uses compensated, 1 not compensated" in r.output, r.output
        assert "not compensated: line 7 MoveL pArr{1}: J1 beyond its limit" in r.output
        out = (tmp_path / f"o_{mode}.mod").read_text()
        if mode == "robtarget":
            # In place, no copy: the refused element as written, the others
            # compensated.
            rows = out.splitlines()[2:5]
            assert rows[0] == f"        [[500,0,400],{at}," and "_c" not in out, out
            assert not rows[1].startswith("        [[500,100,400]"), out


AT = "[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]"


def _far(loop: bool) -> str:
    """pArr{1} out of reach (no nominal solution), {2}, {3} fine; read by
    literal indices, or {2}, {3} by a FOR loop."""
    moves = ("        FOR i FROM 2 TO 3 DO\n            MoveL pArr{i}, v200, fine, tool0;\n"
             "        ENDFOR\n" if loop else
             "        MoveL pArr{2}, v200, fine, tool0;\n        MoveL pArr{3}, v200, fine, tool0;\n")
    return (f"MODULE Far\n    CONST robtarget pArr{{3}}:=[\n        [[2500,0,400],{AT},\n"
            f"        [[500,100,400],{AT},\n        [[500,150,400],{AT}];\n    PROC main()\n"
            f"        MoveL pArr{{1}}, v200, fine, tool0;\n{moves}    ENDPROC\nENDMODULE\n")


def test_an_element_with_no_solution_fails_alone(tmp_path):
    """A use with no nominal solution is not the array's group (whose key
    it shared): with a loop or without, the other elements are written."""
    for loop in (False, True):
        for mode in ("robtarget", "absj"):
            src = tmp_path / f"far_{loop}_{mode}.mod"
            src.write_text(_far(loop))
            r = CliRunner().invoke(main, ["fix", str(src), "--profile",
                                          str(FIXTURES / "warm.csv"), "--emit", mode,
                                          "--allow-partial", "-o", str(tmp_path / f"o{loop}{mode}.mod")])
            assert "2 of 3 target uses compensated, 1 not compensated" in r.output, r.output
            assert "not compensated: line 7 MoveL pArr{1}: nominal: out of reach" in r.output


def _missing(monkeypatch, label: str) -> None:
    """The verification finds the written value of the use labelled
    `label` 50 um off (forced: what the ideal controller's IK would say of
    a value that does not reproduce its joints)."""
    from rapidcomp.compensate import fix as F
    real = F.verify

    def verify(plan, solved, keys, *args, **kwargs):
        got = real(plan, solved, keys, *args, **kwargs)
        for u in plan.uses:
            if u.label == label and u.key in got:
                got[u.key] = (50.0, 1.0)
        return got
    monkeypatch.setattr(F, "verify", verify)


def _fix_partial(tmp_path, name: str, text: str, mode: str):
    """fix --allow-partial of text: (what it said, what it wrote)."""
    src = tmp_path / f"{name}.mod"
    src.write_text(text)
    r = CliRunner().invoke(main, ["fix", str(src), "--profile", str(FIXTURES / "warm.csv"),
                                  "--emit", mode, "--allow-partial",
                                  "-o", str(tmp_path / f"{name}_out.mod")])
    return r.output, (tmp_path / f"{name}_out.mod").read_text()


def test_an_element_outside_the_loop_that_misses_fails_alone(tmp_path, monkeypatch):
    """Where the written value of an element only a literal index reads
    would miss (the verification; forced here), it alone fails, and the
    array's group is written again without it."""
    _missing(monkeypatch, "pArr{1}")
    for mode in ("robtarget", "absj"):
        said, out = _fix_partial(tmp_path, f"miss_{mode}", ARRAY, mode)
        assert "2 of 3 target uses compensated, 1 not compensated" in said, said
        assert "line 7 MoveL pArr{1}: the written value would miss by 50.000 um" in said
        # (The array written in place: the element that failed is left as
        # written there, which its move reads.)
        assert "MoveL pArr{1}, v200" in out and ("MoveL pArr{i}" in out if mode == "robtarget"
                                                 else "MoveAbsJ jt_pArr{i}" in out), out
        assert "_c" not in out and out.splitlines()[2] == f"        {P1},"


def test_a_circle_point_outside_the_loop_keeps_a_group_of_its_own(tmp_path):
    """A MoveC circle point no loop reads is written as before: a copy,
    its confdata as written; the arc's end point joins the array."""
    text = ARRAY.replace("MoveL pArr{1}, v200, fine, tool0;",
                         "MoveC pArr{1}, pArr{3}, v200, fine, tool0;")
    said, out = _fix(tmp_path, "arc", text, "robtarget")
    assert "4 of 4 target uses compensated" in said, said
    assert "MoveC pArr_1_c, pArr{3}, v200" in out
    assert re.search(r"pArr_1_c:=\[\[[^]]*\],\[[^]]*\],\[-1,-1,0,1\]", out), out


def test_a_loop_element_refused_with_another_says_which_and_why(tmp_path):
    """Turned into MoveAbsJ (--emit absj), the FOR loop's elements are one
    jointtarget array, which needs every element's joints: where one is not
    compensated (J1 past a limit set between them), the others are refused
    with it, and their rows say which element, that it is written with
    them, and its reason. Kept robtarget moves (the default for a MoveL),
    the others are written and that element stays as written
    (test_a_loop_element_that_fails_fails_alone)."""
    text = (ARRAY.replace(P1, f"[[500,0,400],{AT}").replace(P2, f"[[500,100,400],{AT}")
            .replace(P3, f"[[500,150,400],{AT}"))
    src = tmp_path / "loop.mod"
    src.write_text(text)
    r = CliRunner().invoke(main, ["fix", str(src), "--profile", str(FIXTURES / "warm.csv"),
                                  "--limit", "J1=-1:14", "--allow-partial", "--emit", "absj",
                                  "-o", str(tmp_path / "o.mod")])
    assert "1 of 3 target uses compensated, 2 not compensated" in r.output, r.output
    assert ("not compensated: line 9 MoveL pArr{i} [i=2]: pArr{3}, written with it as one "
            "array (the moves turned into MoveAbsJ read a jointtarget array, which needs every "
            "element's joints), is not compensated: nominal: J1 beyond its limit by"
            ) in r.output, r.output
    r = CliRunner().invoke(main, ["fix", str(src), "--profile", str(FIXTURES / "warm.csv"),
                                  "--limit", "J1=-1:14", "--allow-partial",
                                  "-o", str(tmp_path / "o.mod")])
    assert "2 of 3 target uses compensated, 1 not compensated" in r.output, r.output
    assert ("not compensated: line 9 MoveL pArr{i} [i=3]: nominal: J1 beyond its limit by"
            in r.output), r.output
    assert "written with it" not in r.output


def test_an_element_outside_the_loop_is_written_when_the_loops_fail(tmp_path, monkeypatch):
    """Where the loop's elements are refused (one of them would miss: the
    verification, forced), the element only a literal index reads is
    written all the same (its own copy, as before it joined the array)."""
    _missing(monkeypatch, "pArr{i} [i=3]")
    for mode in ("robtarget", "absj"):
        said, out = _fix_partial(tmp_path, f"loopmiss_{mode}", ARRAY, mode)
        assert "1 of 3 target uses compensated, 2 not compensated" in said, said
        assert ("line 9 MoveL pArr{i} [i=2]: pArr{3}, written with it as one array, is not "
                "compensated: the written value would miss by 50.000 um") in said, said
        assert re.search(r"pArr_1_c:=", out) or "jt_pArr_1:=" in out, out


# A glue path: four points walked by a FOR loop, the third at the wrist
# singularity (joints [16,20,10,0,0.004,0]; the others J5 = 40), made by the
# nominal FK of those joints; cfx 0 (the controller model reaches each on
# its joints).
PATH = """MODULE Glue
    CONST robtarget pArr{4}:=[
        [[545.708,14.290,441.391],[0.158766,0.195722,0.956428,0.147421],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],
        [[538.408,90.099,441.391],[0.148095,0.128528,0.967751,0.158136],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],
        [[556.096,159.458,467.785],[0.495104,-0.120530,0.857615,0.069582],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],
        [[492.717,235.014,441.391],[0.124646,-0.007408,0.976220,0.177208],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]];
    PROC main()
        FOR i FROM 1 TO 4 DO
            MoveL pArr{i}, v200, fine, tool0;
        ENDFOR
    ENDPROC
ENDMODULE
"""


def test_a_loop_element_that_fails_fails_alone(tmp_path):
    """Kept robtarget moves, a FOR-walked array whose one element cannot be
    compensated (the wrist singularity: a robtarget cannot carry the J4/J6
    split) has the others written in place and that one left as written.
    Oracle: the controller model (tests/controller.py) runs input and
    output; the warm robot lands on each compensated point's pose, and the
    refused point's move commands the joints the input commands."""
    src, out = tmp_path / "glue.mod", tmp_path / "glue_out.mod"
    src.write_text(PATH)
    for mode in ("auto", "robtarget"):
        r = CliRunner().invoke(main, ["fix", str(src), "--profile", str(FIXTURES / "warm.csv"),
                                      "--emit", mode, "--allow-partial", "-o", str(out)])
        assert r.exit_code == 1, r.output
        assert "3 of 4 target uses compensated, 1 not compensated" in r.output, r.output
        assert ("not compensated: line 9 MoveL pArr{i} [i=3]: at the wrist singularity "
                "(J5 0.00 deg) the compensation needs a J4/J6 split") in r.output, r.output
        assert "written with it" not in r.output
        lines, before = out.read_text().splitlines(), PATH.splitlines()
        assert lines[4] == before[4] and "_c" not in out.read_text()
        assert [a == b for a, b in zip(lines, before)] == [True] * 2 + [False] * 2 + [True] \
            + [False] + [True] * 6
    _lands(src, out, 4, {2})
    # check says the same of each point.
    r = CliRunner().invoke(main, ["check", str(src), "--profile", str(FIXTURES / "warm.csv")])
    assert "3 of 4 target uses compensable, 1 not compensable" in r.output, r.output


def _lands(src, out, n: int, refused: set) -> None:
    """The controller model (tests/controller.py) runs input and output:
    each of the n moves but the refused ones (their order) lands the warm
    robot on its pose; each refused one commands the input's joints."""
    import numpy as np
    import pinocchio as pin

    from controller import Controller, fk
    from rapidcomp.kinematics.profile import deform, read_profile
    from rapidcomp.kinematics.robot import irb140
    from rapidcomp.rapid.parse import parse_file
    nominal = irb140()
    warm = deform(nominal, read_profile(FIXTURES / "warm.csv"))
    a = Controller([parse_file(src, src.name)], nominal).run("main")
    b = Controller([parse_file(out, out.name)], nominal).run("main")
    assert len(a) == len(b) == n
    for k, (x, y) in enumerate(zip(a, b)):
        if k in refused:
            assert np.array_equal(x.q_deg, y.q_deg)
            continue
        got = fk(warm, y.q_deg)
        assert np.linalg.norm(got.translation - x.pose.translation) * 1000 < 1.0, k
        assert np.degrees(np.linalg.norm(pin.log3(x.pose.rotation.T @ got.rotation))) < 1e-4


def test_an_array_read_by_two_loops_keeps_its_refused_element_where_it_is(tmp_path):
    """The array read by a second loop through Offs (a copy of its own,
    pArr_offs_c): the plain loop writes the array in place, its refused
    point left as written there, and the Offs loop's copy holds every
    point compensated for it (the point 50 mm above the singular one is
    not singular). A new user's case: it was 4 of 8, the plain loop
    refused as one because the Offs loop had more uses."""
    text = PATH.replace("            MoveL pArr{i}, v200, fine, tool0;\n",
                        "            MoveL pArr{i}, v200, fine, tool0;\n"
                        "            MoveL Offs(pArr{i},0,0,50), v200, z5, tool0;\n")
    src, out = tmp_path / "two.mod", tmp_path / "two_out.mod"
    src.write_text(text)
    r = CliRunner().invoke(main, ["fix", str(src), "--profile", str(FIXTURES / "warm.csv"),
                                  "--allow-partial", "-o", str(out)])
    assert "7 of 8 target uses compensated, 1 not compensated" in r.output, r.output
    assert "not compensated: line 9 MoveL pArr{i} [i=3]: at the wrist singularity" in r.output
    written = out.read_text()
    assert written.splitlines()[4] == text.splitlines()[4]
    assert "MoveL pArr{i}, v200" in written and "MoveL Offs(pArr_offs_c{i},0,0,50)" in written
    _lands(src, out, 8, {4})


def test_a_loop_element_that_fails_refuses_an_array_written_as_a_copy(tmp_path):
    """Where the array cannot be written in place (PERS data of a --with
    module, which is never written), the loop's moves would read a copy,
    and so would the refused point's: cut off from the PERS that ModPos or
    another task changes, and renamed where its row says nothing. The
    array is refused as one, each row saying which element and why (as
    before elements failed alone), and nothing of it is renamed."""
    data, rest = PATH.split("    PROC main()")
    (tmp_path / "data.mod").write_text(data.replace("MODULE Glue", "MODULE GlueData")
                                       .replace("CONST", "PERS") + "ENDMODULE\n")
    (tmp_path / "main.mod").write_text("MODULE Glue\n    PROC main()" + rest)
    r = CliRunner().invoke(main, ["fix", str(tmp_path / "main.mod"), "--profile",
                                  str(FIXTURES / "warm.csv"), "--with",
                                  str(tmp_path / "data.mod"), "--allow-partial",
                                  "-o", str(tmp_path / "o.mod")])
    assert "0 of 4 target uses compensated, 4 not compensated" in r.output, r.output
    assert ("not compensated (3): pArr{3}, written with it as one array (pArr is not edited in "
            "place here: its moves would read a copy, the refused point's too), is not "
            "compensated: at the wrist singularity") in r.output, r.output
    # (Which runs of the loop: a new user could not tell which three.)
    assert "kept a robtarget move [line 4 (i=1, i=2, i=4)]" in r.output, r.output
    assert (tmp_path / "o.mod").read_text() == (tmp_path / "main.mod").read_text()


def test_a_transient_output_gives_the_refused_element_no_correction(tmp_path):
    """--transient: the loop's moves go to rcTcR(pArr{i}, pArr_dq{i}); the
    refused point's correction is zero, so at every thermal state its move
    goes to pArr{3} as written; the others' are theirs (verified at every
    state as any output). With --emit absj the moves are MoveAbsJ, which
    carry the split: all four compensated."""
    src = tmp_path / "glue.mod"
    src.write_text(PATH)
    r = CliRunner().invoke(main, ["fix", str(src), "--profile", str(FIXTURES / "warm.csv"),
                                  "--transient", "--tau-heat", "30",
                                  "--allow-partial", "-o", str(tmp_path / "t.mod")])
    assert "3 of 4 target uses compensated, 1 not compensated" in r.output, r.output
    assert "not compensated: line 9 MoveL pArr{i} [i=3]: at the wrist singularity" in r.output
    out = (tmp_path / "t.mod").read_text()
    assert "MoveL rcTcR(pArr{i}, pArr_dq{i}), v200, fine, tool0;" in out
    rows = out.split("pArr_dq{4}:=[")[1].split("];")[0].split("\n")
    assert [row.strip().rstrip(",") == "[[0,0,0],[0,0,0,0]]" for row in rows[1:]] == [
        False, False, True, False], rows
    assert out.split("    LOCAL CONST pose")[0] == PATH.split("    PROC main()")[0]
    r = CliRunner().invoke(main, ["fix", str(src), "--profile", str(FIXTURES / "warm.csv"),
                                  "--transient", "--tau-heat", "30", "--emit", "absj",
                                  "--allow-partial", "-o", str(tmp_path / "a.mod")])
    assert "4 of 4 target uses compensated" in r.output, r.output
    assert "MoveAbsJ rcTcJ(jt_pArr{i}, jt_pArr_dq{i})" in (tmp_path / "a.mod").read_text()


def test_every_element_failing_refuses_each_for_itself(tmp_path):
    """Where every element of the loop fails, nothing of the array is
    written and each row says its own reason (not "pArr{1}, written with
    it as one array": each is refused for itself)."""
    src = tmp_path / "glue.mod"
    # (Three points at J5 ~ 0, made by the nominal FK of joints with J5 =
    # 0.004, 0.003, 0.005 deg, cfx 0; the second read again after the loop.)
    three = """MODULE C11
    CONST robtarget pArr{3}:=[[[358.447,427.185,435.045],[0.195115,0.229568,0.856801,0.418473],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],[[322.939,461.208,392.227],[0.227045,0.039526,0.905458,0.356418],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],[[432.261,302.677,444.489],[0.281064,0.266721,0.845971,0.366328],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]];
    PROC main()
        FOR i FROM 1 TO 3 DO
            MoveL pArr{i}, v200, fine, tool0;
        ENDFOR
        MoveL pArr{2}, v200, fine, tool0;
    ENDPROC
ENDMODULE
"""
    src.write_text(three)
    r = CliRunner().invoke(main, ["fix", str(src), "--profile", str(FIXTURES / "warm.csv"),
                                  "--allow-partial", "-o", str(tmp_path / "o.mod")])
    assert "0 of 4 target uses compensated, 4 not compensated" in r.output, r.output
    assert ("not compensated (4): at the wrist singularity (J5 0.00 deg) the compensation needs "
            "a J4/J6 split a robtarget cannot carry (the controller's IK chooses the split "
            "itself): a MoveAbsJ can (--emit absj for a MoveL) [lines 5, 7]") in r.output, r.output
    assert "written with it" not in r.output
    assert (tmp_path / "o.mod").read_text() == three
    src.write_text(PATH.replace("FOR i FROM 1 TO 4", "FOR i FROM 3 TO 3"))
    r = CliRunner().invoke(main, ["fix", str(src), "--profile", str(FIXTURES / "warm.csv"),
                                  "--allow-partial", "-o", str(tmp_path / "o.mod")])
    assert "0 of 1 target uses compensated, 1 not compensated" in r.output, r.output


def test_the_refused_elements_reason_names_its_own_moves(tmp_path):
    """The reason of a refused element (at the wrist singularity: what a
    MoveAbsJ could do) names its own moves, not the compensated elements'
    (a review found lines 4 and 8, pArr{1} and pArr{2}, named for pArr{3})."""
    text = PATH.replace("        FOR i FROM 1 TO 4 DO",
                        "        MoveL pArr{1}, v200, fine, tool0;\n        FOR i FROM 1 TO 4 DO")
    text = text.replace("        ENDFOR\n",
                        "        ENDFOR\n        MoveL ToPoint:=pArr{2}, v200, fine, tool0;\n")
    src = tmp_path / "h.mod"
    src.write_text(text)
    r = CliRunner().invoke(main, ["fix", str(src), "--profile", str(FIXTURES / "warm.csv"),
                                  "--allow-partial", "-o", str(tmp_path / "o.mod")])
    assert "5 of 6 target uses compensated, 1 not compensated" in r.output, r.output
    assert r.output.count("not compensated: line 10 MoveL pArr{i} [i=3]: at the wrist "
                          "singularity") == 1, r.output
    assert "a MoveAbsJ can (--emit absj for a MoveL)\n" in r.output
    assert "ToPoint" not in r.output and "lines" not in r.output


def test_a_refused_points_row_does_not_say_it_is_compensated(tmp_path):
    """The refused point at the wrist singularity: its row's reason says
    why, and no warning of the solution not written ("the position is
    compensated exactly ...": a new user read it as compensated); a
    compensated point at the wrist singularity (MoveAbsJ) keeps it."""
    import json
    src = tmp_path / "glue.mod"
    src.write_text(PATH)
    for mode, status in (("auto", "not compensated"), ("absj", "compensated")):
        r = CliRunner().invoke(main, ["fix", str(src), "--profile", str(FIXTURES / "warm.csv"),
                                      "--emit", mode, "--allow-partial", "-o",
                                      str(tmp_path / f"{mode}.mod"), "--json",
                                      str(tmp_path / f"{mode}.json")])
        assert r.exit_code in (0, 1), r.output
        row = json.loads((tmp_path / f"{mode}.json").read_text())["targets"][2]
        assert row["status"] == status, row
        said = any("position is compensated exactly" in w for w in row["warnings"])
        assert said is (mode == "absj"), row


def test_an_array_that_cannot_stay_in_place_after_a_retry_is_refused_as_one(tmp_path,
                                                                           monkeypatch):
    """The plain loop left its refused point out and writes the array in
    place; the Offs loop's copy then fails its verification (forced), so
    the array would be a copy too, which the refused point's move would
    read: the array is refused as one, nothing renamed (a review: the
    refused point of a PERS array read a CONST pArr_c{3})."""
    _missing(monkeypatch, "Offs(pArr{i},0,0,50) [i=1]")
    text = PATH.replace("CONST robtarget pArr", "PERS robtarget pArr").replace(
        "            MoveL pArr{i}, v200, fine, tool0;\n",
        "            MoveL pArr{i}, v200, fine, tool0;\n"
        "            MoveL Offs(pArr{i},0,0,50), v200, z5, tool0;\n")
    said, out = _fix_partial(tmp_path, "retry", text, "auto")
    assert "0 of 8 target uses compensated, 8 not compensated" in said, said
    assert ("pArr{3}, written with it as one array (pArr is not edited in place here: its moves "
            "would read a copy, the refused point's too), is not compensated: at the wrist "
            "singularity") in said, said
    assert out == text


def test_a_transient_cold_copy_takes_the_array_as_one(tmp_path):
    """--transient: where the cold values must be a copy with the warm
    robot's confdata (pArr{3}'s J4 quadrant changes), the loop would read
    the copy, the refused point's move too: the array is refused as one,
    its rows say so (a review: the refused point of a PERS array read a
    CONST pArr_cold{2})."""
    text = """MODULE M2
    PERS robtarget pArr{3}:=[
        [[481.677,49.424,456.000],[0.166510,0.056023,0.981060,0.081588],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],
        [[556.096,159.458,467.785],[0.495104,-0.120530,0.857615,0.069582],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],
        [[552.606,-48.347,443.998],[0.258573,0.042133,0.965006,-0.011290],[-1,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]];
    PROC main()
        FOR i FROM 1 TO 3 DO
            MoveL pArr{i}, v200, fine, tool0;
        ENDFOR
    ENDPROC
ENDMODULE
"""
    src = tmp_path / "m2.mod"
    src.write_text(text)
    r = CliRunner().invoke(main, ["fix", str(src), "--profile", str(FIXTURES / "warm.csv"),
                                  "--transient", "--tau-heat", "30", "--allow-partial",
                                  "-o", str(tmp_path / "o.mod")])
    assert "0 of 3 target uses compensated, 3 not compensated" in r.output, r.output
    assert ("pArr{2}, written with it as one array (its cold values are a copy with the warm "
            "robot's confdata, which the refused point's move would read too)") in r.output
    assert "cold" not in (tmp_path / "o.mod").read_text()

"""Thermal profile parsing and semantics (hand-computed displacements)."""

import math

import numpy as np
import pytest

from rapidcomp.errors import InputError
from rapidcomp.kinematics.profile import deform, parse_profile, read_profile
from rapidcomp.kinematics.robot import irb140

from conftest import FIXTURES

HEAD = "joint,dx_mm,dy_mm,dz_mm,rx_deg,ry_deg,rz_deg\n"
ROBOT = irb140()


def test_paper_tables_1_and_2():
    prof = read_profile(FIXTURES / "warm.csv")
    assert prof.get("J1").d_mm == (-0.0200698, 0.000154, -0.05297)
    assert prof.get("J1").r_deg == (0, -0.011, -0.0137)
    assert prof.get("J3").d_mm == (0.1008636, 0.1148552, -0.001420766)
    assert prof.get("J5").is_zero and prof.get("flange").is_zero


def test_translation_of_last_joint_shifts_flange():
    d = deform(ROBOT, parse_profile(HEAD + "J6,-0.0162926,0,0,0,0,0\n", "p.csv"))
    assert np.allclose(d.base_M_flange([0] * 6).translation, (515 - 0.0162926, 0, 712), atol=1e-12)


def test_rotation_about_joint_origin():
    theta = 0.0108
    d = deform(ROBOT, parse_profile(HEAD + f"J2,0,0,0,{theta},0,0\n", "p.csv"))
    t = math.radians(theta)
    # J2 at (70, 0, 352); the flange is (445, 0, 360) from it, rotated about x.
    expected = (515, -360 * math.sin(t), 352 + 360 * math.cos(t))
    assert np.allclose(d.base_M_flange([0] * 6).translation, expected, atol=1e-12)


def test_rotate_then_translate():
    theta = 0.01
    d = deform(ROBOT, parse_profile(HEAD + f"J3,0.1,0.2,0,0,0,{theta}\n", "p.csv"))
    t = math.radians(theta)
    expected = (70 + 0.1 + 445 * math.cos(t), 0.2 + 445 * math.sin(t), 712)
    assert np.allclose(d.base_M_flange([0] * 6).translation, expected, atol=1e-12)


def test_flange_row_and_missing_rows():
    d = deform(ROBOT, parse_profile(HEAD + "flange,0,0,0.05,0,0,0\n", "p.csv"))
    # The flange frame's z is base x at the zero pose.
    assert np.allclose(d.base_M_flange([0] * 6).translation, (515.05, 0, 712), atol=1e-12)


def test_nominal_model_is_untouched():
    before = [ROBOT.model.jointPlacements[i].copy() for i in range(1, 7)]
    deform(ROBOT, read_profile(FIXTURES / "warm.csv"))
    assert all(before[i - 1] == ROBOT.model.jointPlacements[i] for i in range(1, 7))


@pytest.mark.parametrize("body,line,phrase", [
    ("J7,0,0,0,0,0,0\n", 2, "unknown joint 'J7'"),
    ("J1,0,0,0,0,0,0\nJ1,0,0,0,0,0,0\n", 3, "duplicate row for J1 (first on line 2)"),
    ("J1,0,x,0,0,0,0\n", 2, "dy_mm is 'x', expected a number"),
    ("J1,0,nan,0,0,0,0\n", 2, "dy_mm is nan, expected a finite number"),
    ("J1,6,0,0,0,0,0\n", 2, "shift of 6.000 mm exceeds 5.0 mm"),
    ("J1,0,0,0,0,1.5,0\n", 2, "rotation of 1.5 deg exceeds 1.0 deg"),
    ("J1,0,0,0,0,0\n", 2, "6 values, expected 7"),
    # (Ten to Python's float(), no number in a file.)
    ("J1,0,1_0,0,0,0,0\n", 2, "dy_mm is '1_0', expected a number"),
])
def test_profile_errors_name_file_and_line(body, line, phrase):
    with pytest.raises(InputError) as exc:
        parse_profile(HEAD + body, "warm.csv")
    assert exc.value.format().startswith(f"warm.csv:{line}: ")
    assert phrase in exc.value.format()


@pytest.mark.parametrize("head, phrase", [
    # A misspelt offset_deg was read as no offset at all.
    ("joint,dx_mm,dy_mm,dz_mm,rx_deg,ry_deg,rz_deg,ofset_deg\n", "unknown column ofset_deg"),
    ("joint,dx_mm,dy_mm,dz_mm,rx_deg,ry_deg,rz_deg,dx_mm\n",
     "column dx_mm is named twice (columns 2 and 8)"),
])
def test_a_column_the_profile_cannot_mean_is_refused(head, phrase):
    with pytest.raises(InputError) as exc:
        parse_profile(head + "J1,0,0,0,0,0,0,0.5\n", "w.csv")
    assert exc.value.format().startswith(f"w.csv:1: {phrase}")


def test_missing_column():
    with pytest.raises(InputError) as exc:
        parse_profile("joint,dx_mm,dy_mm,dz_mm,rx_deg,ry_deg\nJ1,0,0,0,0,0\n", "w.csv")
    assert exc.value.format().startswith("w.csv:1: missing column(s) rz_deg")


def test_force_allows_large_values():
    prof = parse_profile(HEAD + "J1,6,0,0,0,1.5,0\n", "w.csv", force=True)
    assert prof.get("J1").d_mm[0] == 6


@pytest.mark.parametrize("row, phrase", [
    ("J2,1e30,0,0,0,0,0", "J2 shift of 1e+30 mm exceeds 100.0 mm"),
    ("J2,0,0,0,0,25,0", "J2 rotation of 25 deg exceeds 20.0 deg"),
])
def test_force_lifts_the_bounds_twenty_times_no_further(row, phrase):
    """--force studies a robot beyond any real one, not one the model
    cannot compute: 1e30 mm made the IK's matrix singular (a traceback)."""
    with pytest.raises(InputError) as exc:
        parse_profile(HEAD + row + "\n", "w.csv", force=True)
    assert exc.value.format().startswith("w.csv:2: " + phrase)
    assert "--force allows 20 times the bound of a real robot, no more" in exc.value.format()
    from click.testing import CliRunner
    from rapidcomp.cli import main
    r = CliRunner().invoke(main, ["simulate", "-o", "unused.csv", "--force", "--effect",
                                  "link_elongation:J2-J3=1e6"])
    assert r.exit_code == 2 and "--force allows 20 times" in r.output, r.output


def test_a_long_comment_or_cell_is_read_not_a_crash():
    """A comment line (or a cell) longer than the csv module's default
    field limit (128 KiB) is part of the file like any other: the profile
    reads as without it; the measured-data reader shares the table code."""
    text = (FIXTURES / "warm.csv").read_text()
    head, rest = text.split("\n", 1)
    long = head + "\n# " + "x" * 200_000 + "\n" + rest
    assert parse_profile(long, "p.csv") == parse_profile(text, "p.csv")


@pytest.mark.parametrize("com, ok", [("0,0,60", True), ("0,0,1e30", False), ("-2500,0,0", False)])
def test_a_payloads_centre_of_mass_is_bounded_as_payload_is(com, ok):
    """The payload row's centre of mass is held to the bound --payload
    has (2000 mm from the flange): 1e30 mm made a J2 sag of 1e24 deg."""
    text = ("joint,dx_mm,dy_mm,dz_mm,rx_deg,ry_deg,rz_deg,compliance_deg_per_nm,mass_kg\n"
            "J2,0,0,0,0,0,0,0.0001,\n"
            f"payload,{com},0,0,0,,5\n")
    if ok:
        assert parse_profile(text, "p.csv").payload.mass_kg == 5
        return
    with pytest.raises(InputError) as exc:
        parse_profile(text, "p.csv")
    assert exc.value.format().startswith("p.csv:3: the payload's centre of mass [")
    assert "is not within 2000 mm of the flange" in exc.value.format()


def test_a_file_without_its_header_says_so():
    """The first row holds numbers: the header is missing (not "column 0
    is named twice")."""
    with pytest.raises(InputError) as exc:
        parse_profile("J1,0,0,0,0,0,0\nJ2,0,0,0,0,0,0\n", "p.csv")
    assert exc.value.format().startswith("p.csv:1: no header: this row holds numbers; "
                                         "expected the header joint,")


def test_a_profile_that_is_no_regular_file_is_named_so(tmp_path):
    from click.testing import CliRunner
    from rapidcomp.cli import main
    r = CliRunner().invoke(main, ["fix", str(FIXTURES / "cubes.mod"), "--profile", "/dev/zero",
                                  "-o", str(tmp_path / "o.mod")])
    assert r.exit_code == 2 and "/dev/zero: not a regular file" in r.output, r.output


def test_a_value_in_a_column_the_header_leaves_unnamed_is_refused():
    """A spreadsheet's trailing ',' leaves a column unnamed: empty, it is
    no column; a value in it was silently dropped (a 0.5 meant for some
    column): refused at its row. The measurements' reader likewise, and
    its note of ignored columns names no blank one."""
    from rapidcomp.discover.measured import parse_measured
    head = "joint,dx_mm,dy_mm,dz_mm,rx_deg,ry_deg,rz_deg,\n"
    prof = parse_profile(head + "J3,0,0,0,0,0,0.001,\n", "w.csv")
    assert prof.get("J3").r_deg[2] == 0.001
    with pytest.raises(InputError) as exc:
        parse_profile(head + "J2,0,0,0,0,0,0,\nJ3,0,0,0,0,0,0,0.5\n", "w.csv")
    assert exc.value.format().startswith(
        "w.csv:3: a value (0.5) in column 8, which the header leaves unnamed: name the "
        "column, or remove the value")
    rows = "".join(f"P{i},0,{i},{i},0,30,0,{600 + i},0,{500 + i},\n" for i in range(8))
    got = parse_measured("point,j1,j2,j3,j4,j5,j6,x,y,z,\n" + rows, "m.csv")
    assert got.ignored_columns == ()
    with pytest.raises(InputError) as exc:
        parse_measured("point,j1,j2,j3,j4,j5,j6,x,y,z,\n" + rows.replace(",\n", ",7\n", 1),
                       "m.csv")
    assert exc.value.format().startswith("m.csv:2: a value (7) in column 11, which the header")


def test_a_value_just_past_a_bound_is_said_with_the_digits_that_tell():
    """Rounded to the message's usual digits, 5.0000001 mm read "5.000 mm
    exceeds 5.0 mm": past a bound, as many digits as tell it from it."""
    head = "joint,dx_mm,dy_mm,dz_mm,rx_deg,ry_deg,rz_deg\n"
    for row, says in (("J2,5.0000001,0,0,0,0,0", "J2 shift of 5.0000001 mm exceeds 5.0 mm"),
                      ("J2,6,0,0,0,0,0", "J2 shift of 6.000 mm exceeds 5.0 mm"),
                      ("J2,0,0,0,0,0,1.0000001", "J2 rotation of 1.0000001 deg exceeds 1.0 deg")):
        with pytest.raises(InputError) as exc:
            parse_profile(head + row + "\n", "w.csv")
        assert exc.value.format().startswith(f"w.csv:2: {says} ("), exc.value.format()

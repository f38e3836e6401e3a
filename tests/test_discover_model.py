"""The discover model against independent oracles: Pinocchio's generalized
gravity, Pinocchio FK of the profile the effects are written as, central
differences for the Jacobian, and hand-computed joint maps."""

from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest

from rapidcomp.discover.effects import catalogue, find, to_profile
from rapidcomp.discover.model import ParamModel
from rapidcomp.discover.simulate import simulate_positions
from rapidcomp.errors import InputError
from rapidcomp.kinematics.frames import DEG
from rapidcomp.kinematics.gravity import GravityModel, Payload
from rapidcomp.kinematics.ik import Solver
from rapidcomp.kinematics.profile import deform, format_profile, parse_profile, read_profile
from rapidcomp.kinematics.robot import irb140

from conftest import FIXTURES

ROBOT = irb140()
WARM = read_profile(FIXTURES / "warm.csv")
CAT = catalogue(ROBOT)
PAYLOAD = Payload(2.5, (10.0, -20.0, 60.0))
HEAD = "joint,dx_mm,dy_mm,dz_mm,rx_deg,ry_deg,rz_deg"


def _random_values(rng):
    small = {"joint_scale": 1e-4, "link_elongation": 1e-4, "gravity_compliance": 1e-6}
    out = {e: rng.normal(0, small.get(e.kind, 1e-3), e.size) for e in CAT}
    # A compliance is >= 0 (the profile refuses negative ones).
    return {e: np.abs(v) if e.kind == "gravity_compliance" else v for e, v in out.items()}


def test_catalogue_ids_for_the_irb140():
    ids = [e.id for e in CAT]
    assert [i for i in ids if i.startswith("link_elongation")] == [
        "link_elongation:J1-J2", "link_elongation:J2-J3", "link_elongation:J4-J5",
        "link_elongation:J6-flange"]
    assert sum(e.size for e in CAT) == 6 + 3 + 6 + 6 + 6 + 4 + 12 + 18 + 6 + 36
    assert [i for i in ids if i.startswith("cyclic:J2")] == ["cyclic:J2:2", "cyclic:J2:3",
                                                             "cyclic:J2:4"]
    assert [i for i in ids if i.startswith("backlash")] == [f"backlash:J{k}" for k in range(1, 7)]
    assert find(CAT, "axis_tilt:J2").params == ("rx_deg", "rz_deg")    # J2 turns about y
    assert find(CAT, "axis_tilt:J1").params == ("rx_deg", "ry_deg")


def test_gravity_torque_is_minus_pinocchio_generalized_gravity():
    rng = np.random.default_rng(3)
    q = rng.uniform(-2, 2, (6, 6))
    tau = GravityModel.from_robot(ROBOT, PAYLOAD).torques_nm(q)
    model = ROBOT.copy_model()
    flange = model.frames[ROBOT.flange_frame].placement
    model.appendBodyToJoint(6, pin.Inertia(PAYLOAD.mass_kg, flange.act(np.array(PAYLOAD.com_mm)),
                                           np.eye(3)), pin.SE3.Identity())
    data = model.createData()
    # model units kg mm^2/s^2 = 1e-6 N m
    ref = np.array([-pin.computeGeneralizedGravity(model, data, x) * 1e-6 for x in q])
    assert np.max(np.abs(tau - ref)) < 1e-9
    assert np.max(np.abs(tau[:, 0])) < 1e-9          # a vertical axis carries no gravity torque
    assert 20 < np.max(np.abs(tau[:, 1])) < 300      # the shoulder: tens of N m


def test_model_matches_pinocchio_on_the_written_profile():
    rng = np.random.default_rng(1)
    q = rng.uniform(-90, 90, (9, 6))
    tool = np.array([12.0, -7.0, 150.0])
    values = _random_values(rng)
    values[find(CAT, "gravity_compliance:J2")] = np.array([2e-6])   # c >= 0
    values[find(CAT, "gravity_compliance:J3")] = np.array([1e-6])
    model = ParamModel(ROBOT, WARM, q, tool, PAYLOAD)
    X, _ = model.evaluate(tuple(values), tuple(values.values()))
    ref = simulate_positions(ROBOT, WARM, values, q, tool, PAYLOAD)
    assert np.max(np.abs(X - ref)) < 1e-9
    # The effects are not nothing: they move the point by tens of microns.
    assert np.max(np.abs(ref - simulate_positions(ROBOT, WARM, {}, q, tool, PAYLOAD))) > 0.01


def test_jacobian_matches_central_differences():
    rng = np.random.default_rng(2)
    q = rng.uniform(-90, 90, (5, 6))
    model = ParamModel(ROBOT, WARM, q, (5.0, 0.0, 100.0), PAYLOAD)
    values = _random_values(rng)
    effects = tuple(values)
    x = np.concatenate(list(values.values()))
    cuts = np.cumsum([e.size for e in effects])[:-1]
    _, J = model.evaluate(effects, tuple(np.split(x, cuts)))
    h = 1e-6
    for i in range(len(x)):
        d = np.zeros(len(x))
        d[i] = h
        fd = (model.evaluate(effects, tuple(np.split(x + d, cuts)), False)[0]
              - model.evaluate(effects, tuple(np.split(x - d, cuts)), False)[0]) / (2 * h)
        scale = max(1.0, np.max(np.abs(J[:, :, i])))
        assert np.max(np.abs(fd - J[:, :, i])) < 1e-6 * scale, i


def test_joint_offset_and_scale_by_hand():
    prof = parse_profile(HEAD + ",offset_deg,scale\nJ2,0,0,0,0,0,0,0.01,0.001\n", "p.csv")
    warm = deform(ROBOT, prof)
    q = np.array([10.0, 30.0, -20.0, 5.0, 40.0, 0.0])
    moved = q.copy()
    moved[1] = 30.0 * 1.001 + 0.01
    assert np.allclose(warm.base_M_flange(q).translation,
                       ROBOT.base_M_flange(moved).translation, atol=1e-12)


def test_joint_map_inverts_with_compliance():
    prof = parse_profile(HEAD + ",offset_deg,scale,compliance_deg_per_nm,mass_kg\n"
                         "J2,0,0,0,0,0,0,0.01,0.0002,0.0001,\n"
                         "J3,0,0,0,0,0,0,0,0,0.0002,\npayload,0,0,60,,,,,,,3\n", "p.csv")
    jm = deform(ROBOT, prof).joint_map
    q = np.random.default_rng(0).uniform(-1.5, 1.5, (20, 6))
    assert np.max(np.abs(jm.invert(jm.apply(q)) - q)) < 1e-14
    # Independently: q + c * tau with tau from Pinocchio (minus generalized gravity).
    model = ROBOT.copy_model()
    flange = model.frames[ROBOT.flange_frame].placement
    model.appendBodyToJoint(6, pin.Inertia(3.0, flange.act(np.array([0, 0, 60.0])), np.eye(3)),
                            pin.SE3.Identity())
    data = model.createData()
    tau = -pin.computeGeneralizedGravity(model, data, q[0]) * 1e-6
    expected = q[0].copy()
    expected[1] = q[0][1] * 1.0002 + 0.01 * DEG + 0.0001 * DEG * tau[1]
    expected[2] = q[0][2] + 0.0002 * DEG * tau[2]
    assert np.allclose(jm.apply(q[:1])[0], expected, atol=1e-15)


def test_extended_profile_round_trips_through_its_text():
    rng = np.random.default_rng(5)
    values = _random_values(rng)
    values[find(CAT, "gravity_compliance:J2")] = np.array([2e-6])
    values[find(CAT, "gravity_compliance:J3")] = np.array([0.0])
    prof = to_profile(ROBOT, replace(WARM, payload=PAYLOAD), values)
    text = format_profile(prof, ROBOT.joint_names, ["a comment"])
    again = parse_profile(text, "new.csv")
    q = rng.uniform(-90, 90, (6, 6))
    a, b = deform(ROBOT, prof), deform(ROBOT, again)
    for x in q:
        assert np.allclose(a.base_M_flange(x).translation, b.base_M_flange(x).translation,
                           atol=1e-8)
    assert text.splitlines()[1].endswith("compliance_deg_per_nm,mass_kg")
    assert format_profile(again, ROBOT.joint_names) == format_profile(prof, ROBOT.joint_names)


def test_plain_profile_stays_plain():
    text = format_profile(WARM, ROBOT.joint_names)
    assert text.splitlines()[0] == HEAD
    assert parse_profile(text, "w.csv") == replace(WARM, source="w.csv")


@pytest.mark.parametrize("body,phrase", [
    ("base,0,0,0,0,0,0,0.1,,,\n", "offset_deg applies to joint rows only"),
    ("J2,0,0,0,0,0,0,,,,5\n", "mass_kg applies to the payload row only"),
    ("J2,0,0,0,0,0,0,,,-1e-5,\n", "expected >= 0"),
    ("payload,0,0,60,1,0,0,,,,3\n", "its rotations must be 0"),
    ("J2,0,0,0,0,0,0,,0.5,,\n", "scale of 0.5 exceeds"),
])
def test_extended_profile_errors(body, phrase):
    with pytest.raises(InputError) as exc:
        parse_profile(HEAD + ",offset_deg,scale,compliance_deg_per_nm,mass_kg\n" + body, "p.csv")
    assert exc.value.format().startswith("p.csv:2: ")
    assert phrase in exc.value.format()


def test_fix_solver_reaches_targets_on_a_model_with_joint_terms():
    """Compensated joints, put through the joint map written out by hand and
    Pinocchio FK of the deformed model, land on the targets."""
    prof = parse_profile(HEAD + ",offset_deg,scale,compliance_deg_per_nm,mass_kg\n"
                         "J2,0.02,0,0,0,0,0,0.01,0.0002,0.0001,\n"
                         "base,0.05,-0.03,0,0,0,0.003,,,,\npayload,0,0,60,,,,,,,3\n", "p.csv")
    warm = deform(ROBOT, prof)
    solver = Solver(ROBOT, warm)
    q = np.array([[10.0, 30.0, -20.0, 5.0, 40.0, 0.0], [-40.0, 50.0, 10.0, -30.0, -60.0, 90.0]])
    R, p, seed = solver.seed_from_joints(q)
    out = solver.solve_deformed(R, p, seed)
    assert out.success.all()
    gravity = GravityModel.from_robot(ROBOT, Payload(3.0, (0, 0, 60.0)))
    for i, qc in enumerate(out.q_deg):
        qa = qc * DEG
        tau = gravity.torques_nm(qa[None])[0]
        qa[1] = qa[1] * 1.0002 + 0.01 * DEG + 0.0001 * DEG * tau[1]
        data = warm.model.createData()
        pin.framesForwardKinematics(warm.model, data, qa)
        assert np.linalg.norm(data.oMf[warm.flange_frame].translation - p[i]) < 1e-8

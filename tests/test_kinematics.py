"""Kinematics against independent expectations: the paper's tables, poses
computed by hand, Pinocchio's own FK, and a confdata oracle written here."""

import math

import numpy as np
import pinocchio as pin
import pytest

from rapidcomp.kinematics.chain import Chain
from rapidcomp.kinematics.frames import DEG, rot_y, stack_times
from rapidcomp.kinematics.ik import IKOptions, Solver, Status, solve_deformed_pinocchio
from rapidcomp.kinematics.profile import deform, parse_profile, read_profile
from rapidcomp.kinematics.robot import irb140

from conftest import FIXTURES

ROBOT = irb140()
WARM = read_profile(FIXTURES / "warm.csv")
DEFORMED = deform(ROBOT, WARM)
RY90 = rot_y(np.pi / 2)  # the paper's TCP orientation (Ox=0, Oy=90, Oz=0)

# Paper Table 5 (front cube, RoboDK joints, rounded; row 4 J2 = 40 is a typo
# for 40.71) and Table 6 (side cube, truncated to 2 decimals).
TABLE5 = [((400, 300, 250), (41.85, 44.63, 25.88, 43.53, -75.61, -13.29)),
          ((400, 150, 250), (24.12, 40.71, 39.86, 24.41, -81.4, -3.88)),
          ((400, 0, 250), (0, 39.84, 44.97, 0, -84.81, 0)),
          ((400, -150, 250), (-24.12, 40.71, 39.86, -24.41, -81.4, 3.88)),
          ((400, -300, 250), (-41.85, 44.63, 25.88, -43.53, -75.61, 13.29))]
TABLE6 = [((150, -700, 600), (-83.07, 45.14, -44.24, 90.10, 83.07, 269.09)),
          ((0, -700, 600), (-95.30, 44.67, -43.46, 89.88, 95.30, 268.78)),
          ((-150, -700, 600), (-107.07, 51.86, -55.73, 91.18, 107.03, 274.05)),
          ((-150, -700, 450), (-107.07, 55.62, -39.54, 85.13, 106.38, 253.22)),
          ((0, -700, 450), (-95.30, 50.24, -29.88, 88.14, 94.97, 249.55))]
# confdata written out by hand from the tables: cf = floor(angle/90);
# cfx: front, elbow in front of the lower arm, J5 < 0 on the front cube.
CONF5 = [(0, 0, -1, 1), (0, 0, -1, 1), (0, 0, 0, 1), (-1, -1, 0, 1), (-1, -1, 0, 1)]
CONF6 = [(-1, 1, 2, 0), (-2, 0, 2, 0), (-2, 1, 3, 0), (-2, 0, 2, 0), (-2, 0, 2, 0)]


def solve_table(rows, confs):
    P = np.array([r[0] for r in rows], float)
    R = np.broadcast_to(RY90, (len(P), 3, 3))
    return Solver(ROBOT).solve_nominal(R, P, np.array(confs))


def test_table5_rounded():
    res = solve_table(TABLE5, CONF5)
    assert res.success.all()
    for q, (_, expected) in zip(res.q_deg, TABLE5):
        assert np.all(np.abs(q - expected) <= 0.005 + 1e-9), (q, expected)


def test_table6_truncated():
    res = solve_table(TABLE6, CONF6)
    assert res.success.all()
    for q, (_, expected) in zip(res.q_deg, TABLE6):
        truncated = [math.trunc(round(x * 100, 6)) for x in q]
        assert truncated == [round(e * 100) for e in expected], (q, expected)


def test_zero_pose_and_hand_computed_poses():
    M = ROBOT.base_M_flange([0] * 6)
    assert np.allclose(M.translation, (515, 0, 712), atol=1e-12)
    assert np.allclose(M.rotation, RY90, atol=1e-15)
    # J1 = 90: the whole arm turns to +y.
    assert np.allclose(ROBOT.base_M_flange([90, 0, 0, 0, 0, 0]).translation, (0, 515, 712))
    # J2 = 90: upper arm horizontal (J3 at (430, 0, 352)), forearm pointing down.
    assert np.allclose(ROBOT.base_M_flange([0, 90, 0, 0, 0, 0]).translation, (430, 0, -93))
    # J3 = -90: forearm straight up along the upper arm.
    assert np.allclose(ROBOT.base_M_flange([0, 0, -90, 0, 0, 0]).translation, (70, 0, 712 + 445))
    # J5 = 90: flange turns down about the wrist centre (450, 0, 712).
    assert np.allclose(ROBOT.base_M_flange([0, 0, 0, 0, 90, 0]).translation, (450, 0, 647))


def random_q(rng, n):
    lo = np.array(ROBOT.lower_deg)
    hi = np.array(ROBOT.upper_deg)
    return rng.uniform(lo, hi, size=(n, 6))


def oracle_conf(q_deg):
    """confdata from Pinocchio's wrist centre, written independently of conf.py."""
    data = ROBOT.model.createData()
    pin.forwardKinematics(ROBOT.model, data, np.asarray(q_deg) * DEG)
    w = data.oMi[5].translation
    q1 = q_deg[0] * DEG
    behind_axis1 = math.cos(q1) * w[0] + math.sin(q1) * w[1] < 0
    behind_lower_arm = q_deg[2] < -90
    cfx = 4 * behind_axis1 + 2 * behind_lower_arm + (q_deg[4] < 0)
    return (math.floor(q_deg[0] / 90), math.floor(q_deg[3] / 90), math.floor(q_deg[5] / 90), cfx)


def regular(q_deg):
    """Away from singularities and quadrant boundaries."""
    data = ROBOT.model.createData()
    pin.forwardKinematics(ROBOT.model, data, np.asarray(q_deg) * DEG)
    w = data.oMi[5].translation
    on_boundary = any(abs(q_deg[j] / 90 - round(q_deg[j] / 90)) < 0.01 for j in (0, 3, 5))
    return (abs(q_deg[4]) > 2 and abs(q_deg[2] + 90) > 2 and math.hypot(w[0], w[1]) > 30
            and not on_boundary)


def test_batch_fk_matches_pinocchio():
    rng = np.random.default_rng(1)
    q = random_q(rng, 200)
    for robot in (ROBOT, DEFORMED):
        R, p = Chain.from_robot(robot).fk(q * DEG)
        _, _, J = Chain.from_robot(robot).fk_jacobian(q * DEG)
        data = robot.model.createData()
        for i in range(len(q)):
            M = robot.base_M_flange(q[i])
            assert np.max(np.abs(p[i] - M.translation)) < 1e-12
            assert np.max(np.abs(R[i] - M.rotation)) < 1e-14
            Jp = pin.computeFrameJacobian(robot.model, data, q[i] * DEG, robot.flange_frame,
                                          pin.LOCAL_WORLD_ALIGNED)
            assert np.max(np.abs(J[i] - Jp)) < 1e-9


def test_stack_times_is_the_stacked_product_bit_for_bit():
    """The chain's products of a stack by one matrix or vector: the same
    doubles numpy's stacked product gives, at every stack size the IK's
    chunks and Newton's shrinking active sets take, for a strided stack
    copied contiguous, and for a transposed matrix."""
    rng = np.random.default_rng(11)
    for n in (1, 2, 3, 5, 17, 64, 1000, 8191, 8192):
        A = rng.normal(size=(n, 3, 3)) * 10.0 ** rng.uniform(-3, 3, (n, 1, 1))
        S = rng.normal(size=(n, 6, 3, 3))[:, 4]
        for M in (rng.normal(size=(3, 3)), rng.normal(size=3) * 300, rng.normal(size=(3, 3)).T):
            assert np.array_equal(stack_times(A, M), A @ M)
            assert np.array_equal(stack_times(np.ascontiguousarray(S), M), S @ M)
            assert np.array_equal(stack_times(S, M), S @ M)
    # Four axes: a stack of stacks.
    B = rng.normal(size=(7, 6, 3, 3))
    assert np.array_equal(stack_times(B, M), B @ M)


def test_ik_of_fk_recovers_q_on_all_8_branches():
    rng = np.random.default_rng(2)
    q = np.array([x for x in random_q(rng, 4000) if regular(x)])
    conf = np.array([oracle_conf(x) for x in q])
    assert set(conf[:, 3]) == set(range(8))  # every branch is exercised
    R, p = Chain.from_robot(ROBOT).fk(q * DEG)
    res = Solver(ROBOT).solve_nominal(R, p, conf)
    ok = res.success
    # A random q can be outside a limit only through the branch maths (never),
    # so every one must come back, exactly.
    assert ok.all(), [res.reason(i) for i in np.flatnonzero(~ok)][:5]
    assert np.max(np.abs(res.q_deg - q)) < 1e-7
    assert (res.conf == conf).all()


def clear_of_limits(q_deg, margin=1.0):
    return (np.all(np.asarray(q_deg) > np.asarray(ROBOT.lower_deg) + margin)
            and np.all(np.asarray(q_deg) < np.asarray(ROBOT.upper_deg) - margin))


def test_deformed_ik_residuals_verified_with_pinocchio():
    rng = np.random.default_rng(3)
    q = np.array([x for x in random_q(rng, 900)
                  if regular(x) and clear_of_limits(x) and abs(x[4]) > 10])
    conf = np.array([oracle_conf(x) for x in q])
    R, p = Chain.from_robot(ROBOT).fk(q * DEG)
    nominal, deformed = Solver(ROBOT, DEFORMED).compensate(R, p, conf)
    assert deformed.success.all(), [deformed.reason(i) for i in np.flatnonzero(~deformed.success)]
    for i in range(len(q)):
        M = DEFORMED.base_M_flange(deformed.q_deg[i])
        assert np.linalg.norm(M.translation - p[i]) <= 1e-9
        assert np.linalg.norm(pin.log3(R[i] @ M.rotation.T)) <= 1e-9
        # The uncompensated joints miss on the deformed robot (the problem we fix).
        M0 = DEFORMED.base_M_flange(nominal.q_deg[i])
        assert np.linalg.norm(M0.translation - p[i]) > 1e-3
    # Hundredths of a degree, as in the paper (larger only near singularities).
    assert np.median(np.abs(deformed.joint_change_deg)) < 0.05
    assert np.max(np.abs(deformed.joint_change_deg)) <= 1.0
    # Per-target Pinocchio Newton agrees with the batch kernel.
    for i in range(0, len(q), 37):
        qp, rmm, rrad, _ = solve_deformed_pinocchio(DEFORMED, R[i], p[i], nominal.q_deg[i])
        assert rmm <= 1e-9 and rrad <= 1e-9
        assert np.max(np.abs(qp - deformed.q_deg[i])) < 1e-9


def test_paper_targets_compensated_below_a_nanometre():
    rows = TABLE5 + TABLE6
    P = np.array([r[0] for r in rows], float)
    R = np.broadcast_to(RY90, (len(P), 3, 3))
    nominal, deformed = Solver(ROBOT, DEFORMED).compensate(R, P, np.array(CONF5 + CONF6))
    assert deformed.success.all()
    assert np.max(deformed.residual_mm) <= 1e-9
    # J6 near 270 deg keeps its turn (no jump to -90).
    assert np.all(deformed.q_deg[5:, 5] > 240)


def test_quadrant_change_is_reported_not_forced_back():
    # Table 5 row 3 has J1 = J4 = J6 = 0: the deformation moves J1 below 0.
    P = np.array([[400.0, 0, 250]])
    nominal, deformed = Solver(ROBOT, DEFORMED).compensate(RY90[None], P, [(0, 0, 0, 1)])
    r = deformed.result(0)
    assert r.success and r.q_deg[0] < 0 and r.conf[0] == -1
    assert "joint quadrant changed (cf1/cf4/cf6 recomputed)" in r.warnings


@pytest.mark.parametrize("q,conf", [
    ((0.0, 30, 10, 90.0, -40, 20), (0, 1, 0, 1)),      # J4 exactly 90
    ((10.0, 30, 10, 0, 40, 270.0), (0, 0, 3, 0)),      # J6 exactly 270
    ((10.0, 30, 10, 0, 40, -270.0), (0, 0, -3, 0)),    # J6 at -270, other turn
])
def test_turns_on_quadrant_boundaries(q, conf):
    R, p = Chain.from_robot(ROBOT).fk(np.array([q]) * DEG)
    res = Solver(ROBOT).solve_nominal(R, p, [conf])
    assert res.success[0], res.reason(0)
    assert np.max(np.abs(res.q_deg[0] - q)) < 1e-7


def test_unreachable_reports_distance():
    res = Solver(ROBOT).solve_nominal(RY90[None], np.array([[2000.0, 0, 712]]), [(0, 0, 0, 0)])
    expected = math.hypot(2000 - 65 - 70, 712 - 352) - (360 + 380)
    assert res.status[0] == Status.UNREACHABLE
    assert res.reason(0) == f"out of reach by {expected:.3f} mm"


def test_joint_limit_reports_how_much():
    narrow = ROBOT.with_limits(upper_deg=(180, 110, 50, 200, 60, 400))
    q = (10, 30, 10, 20, 75, 30)
    R, p = Chain.from_robot(ROBOT).fk(np.array([q]) * DEG)
    res = Solver(narrow).solve_nominal(R, p, [(0, 0, 0, 0)])
    assert res.status[0] == Status.JOINT_LIMIT
    assert res.reason(0) == "J5 beyond its limit by 15.0000 deg"


def test_conf_with_impossible_quadrant_fails():
    q = (10, 30, 10, 20, 40, 30)
    R, p = Chain.from_robot(ROBOT).fk(np.array([q]) * DEG)
    res = Solver(ROBOT).solve_nominal(R, p, [(0, 2, 0, 0)])  # J4 cannot be in [180, 270)
    assert res.status[0] == Status.NO_CONFIGURATION and "J4 quadrant" in res.reason(0)


def test_wrist_singularity_warns_and_still_solves():
    q = (10, 30, 10, 0, 0.2, 30)
    R, p = Chain.from_robot(ROBOT).fk(np.array([q]) * DEG)
    nominal, deformed = Solver(ROBOT, DEFORMED).compensate(R, p, [(0, 0, 0, 0)])
    r = deformed.result(0)
    assert r.success and "near wrist singularity (J5 ~ 0)" in r.warnings
    assert r.residual_mm <= 1e-9


def test_joint_jump_beyond_bound_fails():
    big = deform(ROBOT, parse_profile("joint,dx_mm,dy_mm,dz_mm,rx_deg,ry_deg,rz_deg\n"
                                      "J2,0,0,0,0,0.9,0\n", "big.csv"))
    solver = Solver(ROBOT, big, IKOptions(max_joint_change_deg=0.5))
    _, deformed = solver.compensate(RY90[None], np.array([[400.0, 300, 250]]), [(0, 0, -1, 1)])
    assert deformed.status[0] == Status.JOINT_JUMP
    assert deformed.reason(0).endswith(
        "deg from the nominal solution, more than the 0.5 deg a thermal correction may move "
        "a joint")


def test_deformation_pushing_past_a_limit_fails_with_the_amount():
    # J6 0.02 deg below its +400 limit; the warm robot needs it further.
    q = (46.37676702, -18.55191419, -82.41859558, -12.25588469, -27.21272518, 399.97706574)
    R, p = Chain.from_robot(ROBOT).fk(np.array([q]) * DEG)
    _, deformed = Solver(ROBOT, DEFORMED).compensate(R, p, [oracle_conf(q)])
    assert deformed.status[0] == Status.JOINT_LIMIT
    assert deformed.reason(0).startswith("J6 beyond its limit by 0.0")


def test_urdf_arm_goes_through_the_same_code():
    from rapidcomp.kinematics.robot import load_urdf
    urdf = load_urdf(FIXTURES / "robots" / "irb140.urdf")
    assert urdf.lower_deg == pytest.approx(ROBOT.lower_deg)
    rng = np.random.default_rng(5)
    q = np.array([x for x in random_q(rng, 300) if regular(x)])
    for i in range(0, len(q), 17):
        a, b = urdf.base_M_flange(q[i]), ROBOT.base_M_flange(q[i])
        assert np.allclose(a.translation, b.translation, atol=1e-9)
        assert np.allclose(a.rotation, b.rotation, atol=1e-12)
    conf = np.array([oracle_conf(x) for x in q])
    R, p = Chain.from_robot(urdf).fk(q * DEG)
    nominal, deformed = Solver(urdf, deform(urdf, WARM)).compensate(R, p, conf)
    assert np.max(np.abs(nominal.q_deg - q)) < 1e-7
    assert deformed.success.all() or set(deformed.status[~deformed.success]) <= {
        Status.JOINT_LIMIT, Status.JOINT_JUMP, Status.NOT_CONVERGED}


def test_a_urdf_with_negative_axes_is_the_same_robot(tmp_path):
    """FANUC-style URDFs turn some joints about -y or -x (pinocchio: a
    RevoluteUnaligned joint): with J3 and J5 flipped, the robot at q with
    those two angles negated is the IRB 140 at q, for the batch kernel too."""
    from rapidcomp.kinematics.robot import load_urdf
    text = (FIXTURES / "robots" / "irb140.urdf").read_text()
    parts = text.split("<joint ")
    for i, part in enumerate(parts):
        if part.startswith(('name="J3"', 'name="J5"')):
            parts[i] = part.replace('<axis xyz="0 1 0"/>', '<axis xyz="0 -1 0"/>')
    path = tmp_path / "negative.urdf"
    path.write_text("<joint ".join(parts))
    robot = load_urdf(path)
    assert [j.shortname() for j in robot.model.joints[1:]][2] == "JointModelRevoluteUnaligned"
    rng = np.random.default_rng(8)
    q = random_q(rng, 50)
    sign = np.array([1, 1, -1, 1, -1, 1])
    R, p = Chain.from_robot(robot).fk(q * sign * DEG)
    R0, p0 = Chain.from_robot(ROBOT).fk(q * DEG)
    assert np.max(np.abs(p - p0)) < 1e-9 and np.max(np.abs(R - R0)) < 1e-12
    # The Jacobian of a chain with an axis other than x/y/z (its world axes
    # summed, not taken as a column), against Pinocchio's.
    _, _, J = Chain.from_robot(robot).fk_jacobian(q * sign * DEG)
    data = robot.model.createData()
    for i in range(0, len(q), 7):
        Jp = pin.computeFrameJacobian(robot.model, data, q[i] * sign * DEG, robot.flange_frame,
                                      pin.LOCAL_WORLD_ALIGNED)
        assert np.max(np.abs(J[i] - Jp)) < 1e-9


def test_urdf_errors():
    from rapidcomp.errors import InputError
    from rapidcomp.kinematics.robot import load_urdf
    with pytest.raises(InputError):
        load_urdf(FIXTURES / "robots" / "missing.urdf")


_J = '<joint name="{}" type="revolute">'


@pytest.mark.parametrize("old, new, says", [
    (_J.format("J3"), '<joint name="J3" type="prismatic">', "joint J3 is prismatic"),
    ('<origin xyz="0.38 0 0" rpy="0 0 0"/>', '<origin xyz="0 0 0" rpy="0 0 0"/>',
     "J3 to J5 has no length"),
    ('<origin xyz="0 0 0.36" rpy="0 0 0"/>', '<origin xyz="0 0 1e39" rpy="0 0 0"/>',
     "arm.urdf:9: joint J3: its origin [0, 0, 1e+39] m is not within 100 m"),
    # (The flange's frame too: a number no arm has made its IK singular.)
    ('<origin xyz="0.065 0 0"', '<origin xyz="0.065 -9E+09 0"',
     "arm.urdf:17: the flange frame tool0: its origin [0.065, -9e+09, 0] m is not within "
     "100 m of the last joint"),
    ('lower="-1.5707963268" upper="1.9198621772"', 'lower="1.9" upper="-1.5"',
     "J2: its lower limit 108.862 deg is not below its upper limit"),
    ('<mass value="1.0"/>', '<mass value="-1.0"/>', "mass -1 kg is not a mass"),
    ('lower="-1.5707963268" upper="1.9198621772"', 'lower="-1e300" upper="1e300"',
     "J2: its limits -5.72958e+301..5.72958e+301 deg are not within -720..720 deg"),
    ('<origin xyz="0 0 0"/><inertia', '<origin xyz="0 0 1e9"/><inertia',
     "J1: its link's inertial is not a body's"),
    # urdfdom goes on past an inertial it cannot read (the link weighs 0):
    # its own message, refused.
    ('<mass value="1.0"/>', '<mass value="nan"/>', "mass [nan] is not a float"),
    ('<parent link="link_6"/><child link="tool0"/>', '<parent link="link_5"/><child link="tool0"/>',
     "does not hang on the last joint J6"),
    ("</robot>", "</robot", "not a URDF (XML: "),
])
def test_a_urdf_no_arm_has_is_bad_input(tmp_path, old, new, says):
    """Numbers and joints a 6-axis arm cannot have: exit 2 naming them,
    for every command that loads a robot, and no traceback; urdfdom's own
    messages (with its source paths) not on the terminal."""
    from click.testing import CliRunner
    from rapidcomp.cli import main
    text = (FIXTURES / "robots" / "irb140.urdf").read_text()
    assert old in text
    path = tmp_path / "arm.urdf"
    path.write_text(text.replace(old, new, 1))
    for args in (["check", FIXTURES / "cubes.mod", "--profile", FIXTURES / "warm.csv"],
                 ["simulate", "-o", tmp_path / "m.csv", "--points", "random:20"]):
        r = CliRunner().invoke(main, [str(a) for a in args] + ["--robot", str(path)])
        assert r.exit_code == 2 and says in r.output, r.output
        assert "Traceback" not in r.output
        assert not (tmp_path / "m.csv").exists()


def test_urdfdoms_own_messages_are_kept_off_the_terminal(tmp_path):
    """urdfdom prints its errors on the process's stderr (fd 2, with its
    source paths): read there and said by rapidcomp, nothing of urdfdom's
    own text shown; a process started without a stderr (2>&-) is refused
    the same (exit 2; its capture once closed fd 2 under itself: exit 1)."""
    import os
    import subprocess
    import sys
    text = (FIXTURES / "robots" / "irb140.urdf").read_text()
    path = tmp_path / "arm.urdf"
    path.write_text(text.replace('<mass value="1.0"/>', '<mass value="nan"/>', 1))
    args = [sys.executable, "-m", "rapidcomp", "check", str(FIXTURES / "cubes.mod"), "--profile",
            str(FIXTURES / "warm.csv"), "--robot", str(path), "--limit", "J5=-120:120"]
    r = subprocess.run(args, capture_output=True, text=True)
    assert r.returncode == 2 and r.stderr.startswith(f"{path}: cannot load URDF: Inertial: mass "
                                                     "[nan] is not a float"), r.stderr
    assert "at line" not in r.stderr and "urdf_parser" not in r.stderr
    r = subprocess.run(args, stdout=subprocess.DEVNULL, preexec_fn=lambda: os.close(2))
    assert r.returncode == 2
    path.write_text(text)
    r = subprocess.run(args, stdout=subprocess.DEVNULL, preexec_fn=lambda: os.close(2))
    assert r.returncode == 0


def test_a_urdf_in_latin1_loads(tmp_path):
    """A URDF is XML: one that declares ISO-8859-1 and names the robot in it
    is the same arm (Pinocchio read its bytes as UTF-8)."""
    from rapidcomp.kinematics.robot import load_urdf
    text = (FIXTURES / "robots" / "irb140.urdf").read_text()
    text = text.replace('<?xml version="1.0"?>', '<?xml version="1.0" encoding="ISO-8859-1"?>')
    path = tmp_path / "arm.urdf"
    path.write_bytes(text.replace("irb140_urdf", "irb140_\u00e9").encode("latin-1"))
    robot = load_urdf(path)
    assert robot.name == "irb140_\u00e9"
    q = np.array([10.0, 20.0, -30.0, 40.0, 50.0, 60.0])
    a, b = robot.base_M_flange(q), ROBOT.base_M_flange(q)
    assert np.allclose(a.translation, b.translation, atol=1e-9)


def test_quaternion_matrix_round_trip_rapid_order():
    from rapidcomp.kinematics.frames import matrix_to_quat_wxyz, quat_wxyz_to_matrix
    # RAPID's [0.707107,0,0.707107,0] is +90 deg about y.
    assert np.allclose(quat_wxyz_to_matrix([0.707107, 0, 0.707107, 0]), RY90, atol=1e-6)
    rng = np.random.default_rng(7)
    q = rng.normal(size=(500, 4))
    q[:5] = [[0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1], [1e-9, 1, 1, 0], [1, 0, 0, 0]]  # 180 deg cases
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[q[:, 0] < 0] *= -1
    back = matrix_to_quat_wxyz(quat_wxyz_to_matrix(q))
    same = np.minimum(np.abs(back - q).max(axis=1), np.abs(back + q).max(axis=1))
    assert same.max() < 1e-12
    for i in range(0, 500, 50):  # against Pinocchio's own conversion (x,y,z,w order)
        w, x, y, z = q[i]
        assert np.allclose(pin.Quaternion(w, x, y, z).matrix(), quat_wxyz_to_matrix(q[i]), atol=1e-12)


def test_a_urdf_joint_without_limits_takes_them_from_limit(tmp_path):
    """A revolute joint whose <limit> gives no range has 0..0: refused,
    naming --limit; with --limit it is the arm it was."""
    from click.testing import CliRunner
    from rapidcomp.cli import main
    text = (FIXTURES / "robots" / "irb140.urdf").read_text()
    old = 'lower="-3.4906585040" upper="3.4906585040" '
    assert old in text
    path = tmp_path / "arm.urdf"
    path.write_text(text.replace(old, ""))
    args = ["check", str(FIXTURES / "paper_front.mod"), "--profile", str(FIXTURES / "warm.csv"),
            "--robot", str(path)]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 2 and "joint J4: its lower limit 0 deg is not below its upper limit 0 " \
        "deg (give its range with --limit J4=LOWER:UPPER)" in r.output, r.output
    r = CliRunner().invoke(main, args + ["--limit", "J4=-200:200"])
    assert r.exit_code == 0, r.output


def test_a_target_past_the_edge_by_rounding_says_so():
    """A miss of a few nanometres is not written as 'by 0.000 mm' (which
    reads as in reach): its size, and where such a target lies."""
    from rapidcomp.kinematics.ik import IKBatch
    res = Solver(ROBOT).solve_nominal(RY90[None], np.array([[2000.0, 0, 712]]), [(0, 0, 0, 0)])
    tiny = IKBatch(res.q_deg, res.status, np.array([3.2e-6]), res.detail_joint, res.conf,
                   res.residual_mm, res.residual_rad, res.iterations, res.warnings)
    assert tiny.reason(0) == ("out of reach by 3.2e-06 mm (on the edge of the workspace: the "
                              "arm stretched out)")


@pytest.mark.parametrize("ixx", ["-1e-12", "-5"])
def test_a_urdf_rotational_inertia_is_not_used(tmp_path, ixx):
    """Only a link's mass and centre of mass enter (gravity): an inertia
    matrix Pinocchio finds not positive (CAD noise, or worse) loads, as
    the same arm with a valid one (it was a traceback)."""
    from rapidcomp.kinematics.robot import load_urdf
    text = (FIXTURES / "robots" / "irb140.urdf").read_text()
    path = tmp_path / "arm.urdf"
    path.write_text(text.replace('ixx="0.01"', f'ixx="{ixx}"', 1))
    got, want = load_urdf(path), load_urdf(FIXTURES / "robots" / "irb140.urdf")
    q = [10, 20, 30, 40, 50, 60]
    assert np.allclose(got.base_M_flange(q).homogeneous, want.base_M_flange(q).homogeneous)
    assert got.model.inertias[1].mass == want.model.inertias[1].mass

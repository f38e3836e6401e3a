"""Targets near the wrist singularity (J5 ~ 0) that Newton leaves
unconverged or swings J4/J6 for are solved again with the TCP's position
exact and the orientation as close as the joint-change bound allows
(ik.Solver._position_exact): every such row at once (issue #14: one row at
a time took ~8 ms each, a CAM program near J5 = 0 has thousands). Oracle:
the same minimisation written row by row here (the per-row loop the
solver had), on random targets within 3 deg of J5 = 0 and a 150 mm tool."""

from pathlib import Path

import numpy as np
import pytest

from rapidcomp.kinematics.chain import Chain
from rapidcomp.kinematics.conf import confdata
from rapidcomp.kinematics.frames import DEG, rotation_log
from rapidcomp.kinematics.ik import Solver
from rapidcomp.kinematics.profile import deform, read_profile
from rapidcomp.kinematics.robot import irb140

ROOT = Path(__file__).resolve().parents[1]


def _skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _one_row(solver, R, p, q_ref, bound, tcp):
    """The minimisation for one row, as the solver made it before it took
    every row at once: (q, mm, rad) or None."""
    opt, chain = solver.options, solver.deformed_chain
    n = len(q_ref)
    found = []
    for mu in (1e2, 1.0, 1e-2, 1e-4, 1e-6, 1e-8):
        q = q_ref.copy()
        for _ in range(40):
            Rc, pc, J = chain.fk_jacobian(q[None])
            arm = Rc[0] @ tcp
            e_p = (p + R @ tcp) - (pc[0] + arm)
            e_w = rotation_log((R @ Rc[0].T)[None])[0]
            Jw = J[0, 3:]
            Jp = J[0, :3] - _skew(arm) @ Jw
            K = np.zeros((n + 3, n + 3))
            K[:n, :n] = Jw.T @ Jw + mu * np.eye(n)
            K[:n, n:] = Jp.T
            K[n:, :n] = Jp
            rhs = np.concatenate([Jw.T @ e_w - mu * (q - q_ref), e_p])
            dq = np.linalg.solve(K, rhs)[:n]
            q = q + dq
            if np.max(np.abs(dq)) < 1e-13:
                break
        Rc, pc = chain.fk(q[None])
        e_p = float(np.linalg.norm((p + R @ tcp) - (pc[0] + Rc[0] @ tcp)))
        e_w = float(np.linalg.norm(rotation_log((R @ Rc[0].T)[None])[0]))
        if np.max(np.abs(q - q_ref)) > bound:
            break
        if e_p <= opt.tol_mm:
            found.append((q, e_p, e_w))
    if not found:
        return None
    best = min(f[2] for f in found)
    return next(f for f in found if f[2] <= best + 1e-4 * DEG)


@pytest.fixture(scope="module")
def solver():
    robot = irb140()
    return Solver(robot, deform(robot, read_profile(str(ROOT / "fixtures" / "warm.csv"))))


def _near_wrist(n: int, seed: int, j5: float = 3.0):
    rng = np.random.default_rng(seed)
    sign = rng.choice([-1.0, 1.0], size=(n, 3))
    q = np.stack([sign[:, 0] * rng.uniform(5, 40, n), rng.uniform(0, 45, n),
                  rng.uniform(-20, 35, n), sign[:, 1] * rng.uniform(5, 60, n),
                  rng.uniform(-j5, j5, n), sign[:, 2] * rng.uniform(5, 85, n)], axis=1)
    return q


# (bound 0.95 deg, the solver's: every row found, most on a soft mu; 0.02:
# the softer mus leave the bound, a stiffer one is taken; 0.005: none.)
@pytest.mark.parametrize("seed, bound_deg, found", [(1, 0.95, True), (2, 0.95, True),
                                                    (3, 0.02, True), (3, 0.005, False)])
def test_every_row_at_once_is_each_row_alone(solver, seed, bound_deg, found):
    q_deg = _near_wrist(60, seed)
    chain = Chain.from_robot(irb140())
    R, p = chain.fk(q_deg * DEG)
    tcp = np.tile([0.0, 0.0, 150.0], (len(q_deg), 1))
    # The nominal pose as the deformed robot must reach it: q_ref the
    # nominal joints (what the fallback starts from), the target its pose.
    q_ref = q_deg * DEG
    bound = bound_deg * DEG
    got, q, mm, rad = solver._position_exact(R, p, q_ref, bound, tcp)
    kinds = set()
    for i in range(len(q_deg)):
        one = _one_row(solver, R[i], p[i], q_ref[i], bound, tcp[i])
        assert got[i] == (one is not None), i
        if one is None:
            kinds.add("none")
            assert np.array_equal(q[i], q_ref[i]) and np.isnan(mm[i]) and np.isnan(rad[i])
            continue
        kinds.add("found")
        assert np.allclose(q[i], one[0], rtol=0, atol=1e-12), i
        assert abs(mm[i] - one[1]) <= 1e-9 and abs(rad[i] - one[2]) <= 1e-12, i
    assert kinds == {"found" if found else "none"}


def test_the_solve_takes_the_fallback_near_the_wrist_singularity(solver):
    # End to end through solve_deformed: the rows near J5 = 0 the fallback
    # takes hold the TCP exact and say what orientation is left over.
    q_deg = _near_wrist(200, 7, j5=1.0)
    chain = Chain.from_robot(irb140())
    R, p = chain.fk(q_deg * DEG)
    _, frames = chain.joint_frames(q_deg * DEG)
    conf = confdata(q_deg * DEG, frames[:, 4], solver.geometry.phi)
    seed = solver.solve_nominal(R, p, conf)
    tcp = np.tile([0.0, 0.0, 150.0], (len(q_deg), 1))
    out = solver.solve_deformed(R, p, seed, tcp)
    left = (out.warnings & 32) > 0                       # Warn.ORIENTATION_LEFT
    assert left.sum() >= 5
    assert (out.residual_mm[left] <= solver.options.tol_mm).all()

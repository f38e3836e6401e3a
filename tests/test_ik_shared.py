"""The choice of nominal solutions takes each robtarget's confdata
solution and every closed-form candidate from one computation of the
branches (Solver.nominal_and_candidates, issue #14): the same arrays, bit
for bit, as solve_nominal and candidates each computed on their own, on
seeded random poses in reach and beyond it, with valid and invalid
confdata, over more rows than one block of the threaded IK."""

import dataclasses

import numpy as np

from rapidcomp.kinematics import ik
from rapidcomp.kinematics.chain import Chain
from rapidcomp.kinematics.conf import confdata
from rapidcomp.kinematics.frames import DEG
from rapidcomp.kinematics.ik import IKBatch, Solver
from rapidcomp.kinematics.robot import irb140


def test_nominal_and_candidates_are_the_two_computed_apart():
    robot = irb140()
    chain = Chain.from_robot(robot)
    rng = np.random.default_rng(3)
    n = ik.CHUNK + 3001
    q = rng.uniform(np.asarray(robot.lower_deg), np.asarray(robot.upper_deg), (n, 6))
    q[:50, 4] = 0.0                          # wrist singular
    R, p = chain.fk(q * DEG)
    p[-300:] *= 3.0                          # out of reach
    solver = Solver(robot)
    _, frames = chain.joint_frames(q * DEG)
    conf = confdata(q * DEG, frames[:, 4], solver.geometry.phi).astype(int)
    odd = rng.random(n) < 0.3                # another quadrant or branch, or none
    conf[odd] = np.column_stack([rng.integers(-3, 3, (n, 3)), rng.integers(-1, 9, n)])[odd]
    both, cands = solver.nominal_and_candidates(R, p, conf)
    alone = solver.solve_nominal(R, p, conf)
    for f in dataclasses.fields(IKBatch):
        a, b = getattr(both, f.name), getattr(alone, f.name)
        assert (a is None) == (b is None), f.name
        if a is not None:
            assert a.dtype == b.dtype and np.array_equal(a, b, equal_nan=True), f.name
    want = solver.candidates(R, p)
    assert cands.shape == (n, 8, 6) and np.array_equal(cands, want, equal_nan=True)
    # Both kinds of row are there: solved, and refused for reach or confdata.
    assert both.success.sum() > n // 2 and (~both.success).sum() > 2000
    assert np.isnan(cands).any() and not np.isnan(cands).all()


def test_nominal_pose_and_wrist_is_the_chain_s_on_both_threads(monkeypatch):
    """Solver.nominal_pose_and_wrist (threaded by blocks of CHUNK rows) is
    the nominal chain's FK and joint 5's frame origin, bit for bit, and
    that origin is the wrist centre the confdata reads (an independent
    value: the flange pulled back along its z axis by the wrist offset of
    the IRB 140, 65 mm)."""
    monkeypatch.setattr(ik, "side_by_side", lambda: 2)    # (two, whatever the machine has)
    robot = irb140()
    solver = Solver(robot)
    rng = np.random.default_rng(5)
    q = rng.uniform(np.asarray(robot.lower_deg), np.asarray(robot.upper_deg),
                    (2 * ik.CHUNK + 77, 6)) * DEG
    R, p, wrist = solver.nominal_pose_and_wrist(q)
    (R1, p1), (_, ps) = solver.nominal_chain.fk_and_frames(q)
    assert R.tobytes() == R1.tobytes() and p.tobytes() == p1.tobytes()
    assert wrist.tobytes() == np.ascontiguousarray(ps[:, 4]).tobytes()
    assert np.allclose(wrist, p - 65.0 * R[:, :, 2], atol=1e-9)

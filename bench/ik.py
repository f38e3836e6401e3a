"""Benchmark: nominal (closed form) and deformed (Newton) IK on random
reachable targets, batched, against a per-target Pinocchio loop.

    python bench/ik.py [--sizes 100000,1000000] [--loop 2000] [--wrist 10000]

Prints targets/s and the max residual (verified by the batch kernel; the
tests verify it against Pinocchio FK); and the deformed IK of targets
within 3 deg of J5 = 0 with a 150 mm tool, where rows Newton leaves are
solved again with the TCP held exact (the wrist fallback): its rows/s.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from rapidcomp.kinematics.analytic import ArmGeometry
from rapidcomp.kinematics.chain import Chain
from rapidcomp.kinematics.conf import confdata
from rapidcomp.kinematics.frames import DEG
from rapidcomp.kinematics.ik import Solver, solve_deformed_pinocchio
from rapidcomp.kinematics.profile import deform, read_profile
from rapidcomp.kinematics.robot import irb140

ROOT = Path(__file__).resolve().parents[1]
CHUNK = 100_000


def targets(n: int, seed: int = 0):
    robot = irb140()
    rng = np.random.default_rng(seed)
    lo = np.array(robot.lower_deg) + 2
    hi = np.array(robot.upper_deg) - 2
    q = rng.uniform(lo, hi, size=(n, 6))
    q[:, 4] = np.where(np.abs(q[:, 4]) < 10, 10 * np.sign(q[:, 4] + 1e-9), q[:, 4])
    chain = Chain.from_robot(robot)
    phi = ArmGeometry.from_chain(chain).phi
    R = np.empty((n, 3, 3))
    p = np.empty((n, 3))
    conf = np.empty((n, 4), dtype=int)
    for s in range(0, n, CHUNK):
        qq = q[s:s + CHUNK] * DEG
        R[s:s + CHUNK], p[s:s + CHUNK] = chain.fk(qq)
        _, ps = chain.joint_frames(qq)
        conf[s:s + CHUNK] = confdata(qq, ps[:, 4], phi)
    return q, R, p, conf


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="100000,1000000")
    ap.add_argument("--loop", type=int, default=2000, help="targets for the Pinocchio loop")
    ap.add_argument("--wrist", type=int, default=10000, help="targets near J5 = 0")
    args = ap.parse_args()
    robot = irb140()
    deformed = deform(robot, read_profile(ROOT / "fixtures" / "warm.csv"))
    solver = Solver(robot, deformed)
    print(f"{'targets':>9} {'stage':>9} {'seconds':>8} {'targets/s':>11} {'ok':>8} "
          f"{'max residual':>14}")
    for n in (int(s) for s in args.sizes.split(",")):
        q, R, p, conf = targets(n)
        t0 = time.perf_counter()
        nominal_ok = deformed_ok = 0
        worst_nom = worst_def = 0.0
        t_nom = 0.0
        for s in range(0, n, CHUNK):
            a = time.perf_counter()
            nom = solver.solve_nominal(R[s:s + CHUNK], p[s:s + CHUNK], conf[s:s + CHUNK])
            b = time.perf_counter()
            dfm = solver.solve_deformed(R[s:s + CHUNK], p[s:s + CHUNK], nom)
            t_nom += b - a
            nominal_ok += int(nom.success.sum())
            deformed_ok += int(dfm.success.sum())
            worst_nom = max(worst_nom, float(np.nanmax(nom.residual_mm)))
            worst_def = max(worst_def, float(np.nanmax(np.where(dfm.success, dfm.residual_mm, 0))))
        total = time.perf_counter() - t0
        print(f"{n:>9} {'nominal':>9} {t_nom:>8.2f} {n / t_nom:>11.0f} {nominal_ok:>8} "
              f"{worst_nom:>11.2e} mm")
        print(f"{n:>9} {'deformed':>9} {total - t_nom:>8.2f} {n / (total - t_nom):>11.0f} "
              f"{deformed_ok:>8} {worst_def:>11.2e} mm")
        print(f"{n:>9} {'both':>9} {total:>8.2f} {n / total:>11.0f}")
    m = args.loop
    q, R, p, conf = targets(m, seed=1)
    nom = solver.solve_nominal(R, p, conf)
    t = time.perf_counter()
    for i in range(m):
        if nom.success[i]:
            solve_deformed_pinocchio(deformed, R[i], p[i], nom.q_deg[i])
    dt = time.perf_counter() - t
    print(f"{m:>9} {'pin loop':>9} {dt:>8.2f} {m / dt:>11.0f}   (deformed IK, one target "
          "at a time with Pinocchio FK/Jacobian)")
    wrist(solver, args.wrist)


def wrist(solver: Solver, n: int) -> None:
    """n targets within 3 deg of J5 = 0 through a 150 mm tool: the
    deformed IK, and how many rows the wrist fallback took."""
    rng = np.random.default_rng(3)
    sign = rng.choice([-1.0, 1.0], size=(n, 3))
    q = np.stack([sign[:, 0] * rng.uniform(5, 40, n), rng.uniform(0, 45, n),
                  rng.uniform(-20, 35, n), sign[:, 1] * rng.uniform(5, 60, n),
                  rng.uniform(-3, 3, n), sign[:, 2] * rng.uniform(5, 85, n)], axis=1) * DEG
    chain = Chain.from_robot(irb140())
    R, p = chain.fk(q)
    _, ps = chain.joint_frames(q)
    conf = confdata(q, ps[:, 4], ArmGeometry.from_chain(chain).phi)
    tcp = np.tile([0.0, 0.0, 150.0], (n, 1))
    nom = solver.solve_nominal(R, p, conf)
    t = time.perf_counter()
    dfm = solver.solve_deformed(R, p, nom, tcp)
    dt = time.perf_counter() - t
    left = int(((dfm.warnings & 32) > 0).sum())          # Warn.ORIENTATION_LEFT
    print(f"{n:>9} {'J5 ~ 0':>9} {dt:>8.2f} {n / dt:>11.0f} {int(dfm.success.sum()):>8} "
          f"{float(np.nanmax(np.where(dfm.success, dfm.residual_mm, 0))):>11.2e} mm   "
          f"(deformed IK within 3 deg of J5 = 0, 150 mm tool: {left} rows by the wrist "
          "fallback, TCP exact)")


if __name__ == "__main__":
    main()

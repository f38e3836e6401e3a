"""Point sets for measurement campaigns (`rapidcomp simulate --points`).

The paper's 72 test points: the front cube (Table 3, 45 points) and the
side cube (27; its coordinates read from the paper's Table 10 on the
150 mm grid), flange orientation Ry(90) everywhere, on the configuration
branches of Tables 5 (front, cfx 1) and 6 (side, cfx 0). Random poses are
uniform joint vectors inside the limits with the flange above the base.
"""

from __future__ import annotations

import numpy as np

from ..errors import RapidcompError
from ..kinematics.analytic import ArmGeometry, solve_branches
from ..kinematics.chain import Chain
from ..kinematics.frames import DEG, rot_y
from ..kinematics.robot import RobotModel

FRONT = [(400, 300, 250), (400, 150, 250), (400, 0, 250), (400, -150, 250), (400, -300, 250),
         (400, -300, 400), (400, -150, 400), (400, 0, 400), (400, 150, 400), (400, 300, 400),
         (400, 300, 550), (400, 150, 550), (400, 0, 550), (400, -150, 550), (400, -300, 550),
         (550, -300, 550), (550, -150, 550), (550, 0, 550), (550, 150, 550), (550, 300, 550),
         (550, 300, 400), (550, 150, 400), (550, 0, 400), (550, -150, 400), (550, -300, 400),
         (550, -300, 250), (550, -150, 250), (550, 0, 250), (550, 150, 250), (550, 300, 250),
         (700, 300, 250), (700, 150, 250), (700, 0, 250), (700, -150, 250), (700, -300, 250),
         (700, -300, 400), (700, -150, 400), (700, 0, 400), (700, 150, 400), (700, 300, 400),
         (700, 300, 550), (700, 150, 550), (700, 0, 550), (700, -150, 550), (700, -300, 550)]
SIDE = [(150, -700, 600), (0, -700, 600), (-150, -700, 600), (-150, -700, 450), (0, -700, 450),
        (150, -700, 450), (150, -700, 300), (0, -700, 300), (-150, -700, 300),
        (-150, -550, 300), (0, -550, 300), (150, -550, 300), (150, -550, 450), (0, -550, 450),
        (-150, -550, 450), (-150, -550, 600), (0, -550, 600), (150, -550, 600),
        (150, -400, 600), (0, -400, 600), (-150, -400, 600), (-150, -400, 450), (0, -400, 450),
        (150, -400, 450), (150, -400, 300), (0, -400, 300), (-150, -400, 300)]


def cube_points(robot: RobotModel) -> tuple[tuple[str, ...], np.ndarray]:
    """Names P1..P45, S1..S27 and joint angles (deg) of the paper's points."""
    geom = ArmGeometry.from_chain(Chain.from_robot(robot))
    out = []
    for points, cfx, j6_low in ((FRONT, 1, -180.0), (SIDE, 0, 0.0)):
        P = np.array(points, float)
        br = solve_branches(geom, np.broadcast_to(rot_y(np.pi / 2), (len(P), 3, 3)), P)
        q = br.q[:, cfx] / DEG
        if np.isnan(q).any():
            raise RapidcompError(f"{robot.name} cannot reach the paper's cube points")
        q[:, 5] = (q[:, 5] - j6_low) % 360 + j6_low
        out.append(q)
    names = tuple(f"P{i + 1}" for i in range(len(FRONT))) + tuple(
        f"S{i + 1}" for i in range(len(SIDE)))
    return names, np.vstack(out)


def random_points(robot: RobotModel, count: int, seed: int) -> tuple[tuple[str, ...], np.ndarray]:
    """`count` joint vectors (deg), uniform within the limits (J4 and J6
    within +-180), flange at least 100 mm above the base plane; reproducible
    from `seed`."""
    rng = np.random.default_rng(seed)
    lo = np.maximum(np.asarray(robot.lower_deg), -180.0)
    hi = np.minimum(np.asarray(robot.upper_deg), 180.0)
    chain = Chain.from_robot(robot)
    out = np.empty((0, len(lo)))
    while len(out) < count:
        q = rng.uniform(lo, hi, size=(4 * count, len(lo)))
        _, p = chain.fk(q * DEG)
        out = np.vstack([out, q[p[:, 2] >= 100.0]])
    return tuple(f"R{i + 1}" for i in range(count)), out[:count]

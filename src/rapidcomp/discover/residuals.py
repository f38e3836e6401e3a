"""Where simulation and measurement disagree, before anything is fitted:
RMS and max of the 3-D residuals, the worst points, the residual per
workspace region (octants about the median measured position), and the
correlation of the residual with every joint angle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class RegionRow:
    region: str            # e.g. "x+ y- z+": above/below the median
    points: int
    rms_mm: float
    mean_mm: tuple[float, float, float]


@dataclass(frozen=True)
class Correlation:
    joint: str
    with_length: float               # Pearson r of |residual| and the angle
    with_xyz: tuple[float, float, float]


@dataclass(frozen=True)
class Analysis:
    rms_mm: float
    max_mm: float
    max_point: str
    mean_mm: tuple[float, float, float]
    worst: tuple[tuple[str, float, tuple[float, float, float]], ...]  # name, |r|, r
    regions: tuple[RegionRow, ...]
    correlations: tuple[Correlation, ...]


def _pearson(a: np.ndarray, b: np.ndarray) -> float:
    a = a - a.mean()
    b = b - b.mean()
    den = np.sqrt((a @ a) * (b @ b))
    return float(a @ b / den) if den > 0 else 0.0


def analyse(names, q_deg: np.ndarray, xyz_mm: np.ndarray, residuals: np.ndarray,
            joint_names, worst: int = 10) -> Analysis:
    length = np.linalg.norm(residuals, axis=1)
    order = np.argsort(-length, kind="stable")
    rows = tuple((names[i], float(length[i]), tuple(float(x) for x in residuals[i]))
                 for i in order[:worst])
    med = np.median(xyz_mm, axis=0)
    labels = [" ".join(f"{a}{'+' if v > m else '-'}" for a, v, m in zip("xyz", p, med))
              for p in xyz_mm]
    regions = []
    for lab in sorted(set(labels)):
        idx = [i for i, x in enumerate(labels) if x == lab]
        r = residuals[idx]
        regions.append(RegionRow(lab, len(idx), float(np.sqrt(np.mean(np.sum(r ** 2, axis=1)))),
                                 tuple(float(x) for x in r.mean(axis=0))))
    corr = tuple(Correlation(joint_names[k], _pearson(length, q_deg[:, k]),
                             tuple(_pearson(residuals[:, a], q_deg[:, k]) for a in range(3)))
                 for k in range(q_deg.shape[1]))
    return Analysis(float(np.sqrt(np.mean(length ** 2))), float(length.max()),
                    names[int(order[0])], tuple(float(x) for x in residuals.mean(axis=0)),
                    rows, tuple(regions), corr)

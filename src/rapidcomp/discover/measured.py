"""Measured-data files: `point,j1,j2,j3,j4,j5,j6,x,y,z[,approach][,tx,ty,tz]`.

Joints are the commanded angles (deg), x/y/z the measured position (mm, robot
base frame) of the measuring point; rows in the order they were measured
(each joint's direction of approach, for backlash, comes from that order
unless an `approach` column gives it); `tx,ty,tz` give each row's measuring
point in the flange frame (several reflectors per pose: a row each, the
same joints); `t_min` the minutes since a cold start, the robot running, at
which the row was measured (a warm-up campaign; `stood_min` the minutes it
had stood in all by then, each stop following a measurement round), and
`temp_<name>` columns
temperatures read at the same time (deg C, e.g. temp_j2 for a motor).
Lines starting with '#' are comments
(simulate writes its provenance there); extra columns are ignored and
reported; any bad row is a path:line error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..csvtable import header_and_rows, number
from ..errors import InputError
from ..source import not_a_file

JOINT_COLUMNS = ("j1", "j2", "j3", "j4", "j5", "j6")
COLUMNS = ("point",) + JOINT_COLUMNS + ("x", "y", "z")
MIN_POINTS = 3
APPROACH = "approach"
TOOL_COLUMNS = ("tx", "ty", "tz")
TIME = "t_min"
TEMP_PREFIX = "temp_"
STOOD = "stood_min"
MAX_TEMP_C = 500.0
# A warm-up campaign spans hours; beyond a year the column is not minutes.
MAX_T_MIN = 525_600.0
# Values no measurement of a robot has: a joint beyond two turns, a
# position beyond 100 m (wrong units, a corrupt row).
MAX_JOINT_DEG = 720.0
MAX_POSITION_MM = 1e5


@dataclass(frozen=True, eq=False)
class Measurements:
    source: str
    names: tuple[str, ...]
    q_deg: np.ndarray     # (N, 6) commanded joints
    xyz_mm: np.ndarray    # (N, 3) measured positions
    lines: tuple[int, ...]
    ignored_columns: tuple[str, ...] = ()
    # Per pose and joint, the direction it approached the pose from (+1, -1,
    # 0 not known), from an `approach` column; None: from the measuring order.
    approach: np.ndarray | None = None
    # Per row, the measuring point in the flange frame (mm), from `tx,ty,tz`
    # columns (several reflectors: a row each); None: --tool for all.
    tool: np.ndarray | None = None
    # Per row, minutes since a cold start (robot running), from `t_min`.
    t_min: np.ndarray | None = None
    # Temperature columns: name -> (N,) deg C.
    temperatures: tuple[tuple[str, np.ndarray], ...] = ()
    # Per row, minutes stood since the cold start (stops), from `stood_min`.
    stood_min: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.names)


def parse_table(text: str, source: str, columns, numeric, min_rows: int):
    """Rows of a CSV with a header holding `columns` (any order, extra
    columns ignored): (names, values (N, len(numeric)), lines, ignored)."""
    header, body = header_and_rows(text, source, columns)
    ignored = tuple(h for h in header if h and h not in columns)
    index = {c: header.index(c) for c in columns}
    names, values, lines = [], [], []
    seen: dict[str, int] = {}
    for line, row in body:
        # (Empty cells past the header's are a spreadsheet's trailing commas.)
        if len(row) < len(header) or any(c.strip() for c in row[len(header):]):
            raise InputError(source, f"{len(row)} values, expected {len(header)}", line)
        name = row[index["point"]].strip() if "point" in index else str(len(names) + 1)
        if not name:
            raise InputError(source, "the point has no name", line)
        if name in seen:
            raise InputError(source, f"duplicate point {name!r} (first on line {seen[name]})", line)
        seen[name] = line
        vals = []
        for col in numeric:
            cell = row[index[col]].strip()
            try:
                v = number(cell)
            except ValueError:
                raise InputError(source, f"{col} is {cell!r}, expected a number", line) from None
            if not math.isfinite(v):
                raise InputError(source, f"{col} is {cell}, expected a finite number", line)
            if col in JOINT_COLUMNS and abs(v) > MAX_JOINT_DEG:
                raise InputError(source, f"{col} is {cell}, expected a joint angle in degrees "
                                 f"(|{col}| <= {MAX_JOINT_DEG:g})", line)
            if col in ("x", "y", "z") and abs(v) > MAX_POSITION_MM:
                raise InputError(source, f"{col} is {cell}, expected a position in mm "
                                 f"(|{col}| <= {MAX_POSITION_MM:g})", line)
            vals.append(v)
        names.append(name)
        values.append(vals)
        lines.append(line)
    if len(names) < min_rows:
        raise InputError(source, f"{len(names)} point(s), expected at least {min_rows}",
                         body[-1][0] if body else None)
    return tuple(names), np.array(values, float), tuple(lines), ignored


def read_text(path: str | Path) -> str:
    path = Path(path)
    not_a_file(path)
    try:
        return path.read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise InputError(str(path), f"cannot read: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise InputError(str(path), "not UTF-8 text") from None


def parse_measured(text: str, source: str, min_points: int = MIN_POINTS) -> Measurements:
    names, values, lines, ignored = parse_table(text, source, COLUMNS, COLUMNS[1:], min_points)
    approach = None
    if APPROACH in ignored:
        ignored = tuple(c for c in ignored if c != APPROACH)
        approach = _approach(text, source)
    tool = None
    given = [c for c in TOOL_COLUMNS if c in ignored]
    if given:
        if len(given) < len(TOOL_COLUMNS):
            raise InputError(source, f"column(s) {', '.join(given)} without "
                             f"{', '.join(c for c in TOOL_COLUMNS if c not in given)}: the "
                             "measuring point of a row takes tx, ty and tz (mm, flange frame)")
        ignored = tuple(c for c in ignored if c not in TOOL_COLUMNS)
        _, tool, _, _ = parse_table(text, source, ("point",) + COLUMNS[1:] + TOOL_COLUMNS,
                                    TOOL_COLUMNS, min_points)
    t_min = None
    if TIME in ignored:
        ignored = tuple(c for c in ignored if c != TIME)
        t_min = _column(text, source, TIME, min_points, lines, lambda v: 0 <= v <= MAX_T_MIN,
                        f"minutes since a cold start (0 to {MAX_T_MIN:g})")
    temps = []
    # Without t_min a temperature column is an extra column like any other
    # (ignored, with a note): only a warm-up campaign reads it.
    for col in [c for c in ignored if c.startswith(TEMP_PREFIX) and t_min is not None]:
        temps.append((col, _column(text, source, col, min_points, lines,
                                   lambda v: abs(v) <= MAX_TEMP_C, "a temperature in deg C")))
    ignored = tuple(c for c in ignored if t_min is None or not c.startswith(TEMP_PREFIX))
    stood = None
    if STOOD in ignored and t_min is not None:
        ignored = tuple(c for c in ignored if c != STOOD)
        stood = _column(text, source, STOOD, min_points, lines, lambda v: 0 <= v <= MAX_T_MIN,
                        f"the minutes the robot had stood since the cold start (0 to "
                        f"{MAX_T_MIN:g})")
    return Measurements(source, names, values[:, :6], values[:, 6:], lines, ignored, approach,
                        tool, t_min, tuple(temps), stood)


def _column(text: str, source: str, col: str, min_points: int, lines, ok, expected: str):
    """One extra numeric column, every value within `ok`, else a path:line
    error saying what was expected."""
    _, v, _, _ = parse_table(text, source, ("point",) + COLUMNS[1:] + (col,), (col,),
                             min_points)
    bad = [i for i, x in enumerate(v[:, 0]) if not ok(x)]
    if bad:
        raise InputError(source, f"{col} is {v[bad[0], 0]:g}, expected {expected}",
                         lines[bad[0]])
    return v[:, 0]


def _approach(text: str, source: str) -> np.ndarray:
    """The `approach` column: per row six signs, one per joint, `+` (the
    joint last moved in the positive direction before the pose), `-`, or
    `0` (not known), e.g. `+-0++-`."""
    header, body = header_and_rows(text, source, COLUMNS)
    k = header.index(APPROACH)
    out = []
    for line, row in body:
        cell = row[k].strip()
        if len(cell) != len(JOINT_COLUMNS) or any(c not in "+-0" for c in cell):
            raise InputError(source, f"approach is {cell!r}, expected one of + - 0 per joint "
                             f"({len(JOINT_COLUMNS)} characters, e.g. +-0++-)", line)
        out.append([{"+": 1.0, "-": -1.0, "0": 0.0}[c] for c in cell])
    return np.array(out)


def read_measured(path: str | Path, min_points: int = MIN_POINTS) -> Measurements:
    return parse_measured(read_text(path), str(path), min_points)


def read_joints(path: str | Path) -> tuple[tuple[str, ...], np.ndarray]:
    """A point set for simulate: `point,j1..j6`, or `j1..j6` alone (points
    then named by their row number)."""
    text = read_text(path)
    header, _ = header_and_rows(text, str(path), JOINT_COLUMNS)
    columns = (("point",) if "point" in header else ()) + JOINT_COLUMNS
    names, values, _, _ = parse_table(text, str(path), columns, JOINT_COLUMNS, 1)
    return names, values


def format_measured(names, q_deg, xyz_mm, comments=(), t_min=None, temperatures=(),
                    stood=None) -> str:
    extra = ((TIME,) if t_min is not None else ()) + ((STOOD,) if stood is not None else ()) \
        + tuple(c for c, _ in temperatures)
    out = [f"# {c}" for c in comments] + [",".join(COLUMNS + extra)]
    for n, (name, q, x) in enumerate(zip(names, q_deg, xyz_mm)):
        row = [name, *(f"{v:.6f}" for v in q), *(f"{v:.6f}" for v in x)]
        if t_min is not None:
            row.append(f"{t_min[n]:g}")
        if stood is not None:
            row.append(f"{stood[n]:g}")
        row += [f"{v[n]:.3f}" for _, v in temperatures]
        out.append(",".join(row))
    return "\n".join(out) + "\n"

"""One `rapidcomp fix` job per program: load, compensate, render outputs in
memory. Files are written by the caller, all at once (atomic.py), and only
when every job succeeded: bad input anywhere means no output anywhere.

Several programs run in a process pool of two workers (the machine's cores).
"""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from ..errors import RapidcompError
from ..progress import Progress
from . import report
from .fix import FixResult, fix


@dataclass(frozen=True)
class JobSpec:
    program: str
    output: str
    report: str | None
    json: str | None
    profile: str
    robot: str | None
    with_modules: tuple[str, ...]
    mode: str
    force: bool
    limits: tuple[str, ...] = ()
    progress: bool | None = None


@dataclass(frozen=True)
class JobOutcome:
    spec: JobSpec
    result: FixResult
    files: tuple[tuple[str, bytes], ...]   # (path, bytes) to write


def default_output(program: str) -> str:
    p = Path(program)
    return str(p.with_name(p.stem + "_comp" + p.suffix))


def load_robot(robot: str | None, limits=()):
    from ..kinematics.robot import irb140, load_urdf, override_limits
    if robot is None or robot.lower() == "irb140":
        return override_limits(irb140(), limits)
    return override_limits(load_urdf(robot), limits)


def load_solver(profile: str, robot: str | None, force: bool, limits=()):
    from ..kinematics.analytic import UnsupportedGeometry
    from ..kinematics.ik import Solver
    from ..kinematics.profile import deform, read_profile
    nominal = load_robot(robot, limits)
    prof = read_profile(profile, force=force, joint_names=nominal.joint_names)
    try:
        return Solver(nominal, deform(nominal, prof))
    except UnsupportedGeometry as exc:
        raise RapidcompError(f"{robot}: {exc}") from exc


def run(spec: JobSpec) -> JobOutcome:
    from ..rapid.parse import parse_file
    progress = Progress(Path(spec.program).name, spec.progress)
    progress.stage("parsing")
    files = [parse_file(spec.program, Path(spec.program).name)]
    files += [parse_file(m) for m in spec.with_modules]
    solver = load_solver(spec.profile, spec.robot, spec.force, spec.limits)
    progress.stage("compensating")
    result = fix(files, solver, spec.mode, Path(spec.output).name)
    progress.stage("writing")
    meta = {
        "output": Path(spec.output).name,
        "mode": spec.mode,
        "profile": Path(spec.profile).name,
        "robot": Path(spec.robot).name if spec.robot else "irb140",
        "with": ", ".join(Path(m).name for m in spec.with_modules) or "-",
        "joint limits": ", ".join(spec.limits) or "robot defaults",
    }
    out = [(spec.output, files[0].source.encode(result.text))]
    if spec.report:
        out.append((spec.report, report.markdown(result, meta).encode("utf-8")))
    if spec.json:
        out.append((spec.json, report.as_json(result, meta).encode("utf-8")))
    progress.done()
    return JobOutcome(spec, result, tuple(out))


def run_all(specs: list[JobSpec], workers: int = 2) -> list[JobOutcome]:
    """Run jobs (in parallel when there are several); the first bad input
    raises after all jobs ended."""
    if len(specs) == 1 or workers <= 1:
        return [run(s) for s in specs]
    with ProcessPoolExecutor(max_workers=min(workers, len(specs))) as pool:
        futures = [pool.submit(run, s) for s in specs]
        outcomes = []
        error = None
        for f in futures:
            try:
                outcomes.append(f.result())
            except RapidcompError as exc:
                error = error or exc
        if error is not None:
            raise error
        return outcomes

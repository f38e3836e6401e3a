"""Regenerate golden files. Run, then review the diff by eye before committing:

    python tests/regen_golden.py && git diff tests/golden

inspect/: the parser's report of every fixture.
fix/<case>/: before.mod (the input; copied from fixtures/ when the case
names one, else written by hand), after.mod and report.md from
`rapidcomp fix` with the case's options. A task case (a folder of
fixtures/tasks/) has before/ and after/ folders with one file per module.
"""

import shutil
from pathlib import Path

from rapidcomp.compensate import report
from rapidcomp.compensate.fix import fix
from rapidcomp.compensate.load import load_solver
from rapidcomp.compensate.plan import Task
from rapidcomp.rapid.inspect import render_text, report as inspect_report
from rapidcomp.rapid.parse import parse_file

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = ROOT / "tests" / "golden"
PROFILE = ROOT / "fixtures" / "warm.csv"
# case -> (fixture it copies or None, mode, joint limit overrides)
FIX_CASES = {
    "cubes_absj": ("cubes.mod", "absj", ("J5=-120:120",)),
    "cubes_robtarget": ("cubes.mod", "robtarget", ("J5=-120:120",)),
    "paper_front_absj": ("paper_front.mod", "absj", ()),
    "paper_front_robtarget": ("paper_front.mod", "robtarget", ()),
    "refusals": (None, "absj", ()),
    "cam_confoff_robtarget": ("rapid/cam_confoff.mod", "robtarget", ()),
    "robodk_frames_auto": ("rapid/robodk_frames.mod", "auto", ()),
    "robodk_programs_auto": ("rapid/robodk_programs.mod", "auto", ()),
}
# case -> (task folder under fixtures/tasks, mode)
TASK_CASES = {
    "cell_absj": ("cell", "absj"),
    "cell_robtarget": ("cell", "robtarget"),
}


def inspect_golden(path: Path) -> str:
    # Relative display path: goldens must not depend on where the repo lives.
    pf = parse_file(path, display_path=path.relative_to(ROOT).as_posix())
    return render_text(inspect_report(pf))


def fix_golden(case: str) -> tuple[bytes, str]:
    """(after.mod bytes, report.md text) of a case's before.mod."""
    _, mode, limits = FIX_CASES[case]
    pf = parse_file(GOLDEN / "fix" / case / "before.mod", "before.mod")
    result = fix(Task("before.mod", (pf,)), load_solver(str(PROFILE), None, False, limits), mode,
                 output_names={"before.mod": "after.mod"})
    meta = {"output": "after.mod", "mode": mode, "profile": PROFILE.name, "robot": "irb140",
            "with": "-", "joint limits": ", ".join(limits) or "robot defaults"}
    return pf.source.encode(result.modules[0].text), report.markdown(result, meta)


def task_golden(case: str) -> tuple[dict[str, bytes], str]:
    """({module path: after bytes}, report.md text) of a task case."""
    from rapidcomp.compensate.load import load_task
    from rapidcomp.rapid.task import tasks_of
    folder, mode = TASK_CASES[case]
    (source,) = tasks_of(ROOT / "fixtures" / "tasks" / folder)
    task = load_task(source)
    result = fix(task, load_solver(str(PROFILE), None, False, ()), mode)
    meta = {"input": f"folder {folder}", "output": "after/", "mode": mode,
            "profile": PROFILE.name, "robot": "irb140"}
    after = {m.path: pf.source.encode(m.text) for pf, m in zip(task.files, result.modules)}
    return after, report.markdown(result, meta)


def main() -> None:
    out = GOLDEN / "inspect"
    out.mkdir(parents=True, exist_ok=True)
    for path in sorted((ROOT / "fixtures" / "rapid").iterdir()):
        (out / f"{path.name}.txt").write_text(inspect_golden(path), encoding="utf-8")
    for case, (fixture, _, _) in FIX_CASES.items():
        folder = GOLDEN / "fix" / case
        folder.mkdir(parents=True, exist_ok=True)
        if fixture is not None:
            shutil.copyfile(ROOT / "fixtures" / fixture, folder / "before.mod")
        after, rep = fix_golden(case)
        (folder / "after.mod").write_bytes(after)
        (folder / "report.md").write_text(rep, encoding="utf-8", newline="\n")
    for case, (name, _) in TASK_CASES.items():
        folder = GOLDEN / "fix" / case
        shutil.rmtree(folder, ignore_errors=True)
        shutil.copytree(ROOT / "fixtures" / "tasks" / name, folder / "before")
        after, rep = task_golden(case)
        for rel, data in after.items():
            (folder / "after" / rel).parent.mkdir(parents=True, exist_ok=True)
            (folder / "after" / rel).write_bytes(data)
        (folder / "report.md").write_text(rep, encoding="utf-8", newline="\n")


if __name__ == "__main__":
    main()

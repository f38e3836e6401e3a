"""Regenerate golden files. Run, then review the diff by eye before committing:

    python tests/regen_golden.py && git diff tests/golden
"""

from pathlib import Path

from rapidcomp.rapid.inspect import render_text, report
from rapidcomp.rapid.parse import parse_file

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = ROOT / "tests" / "golden"


def inspect_golden(path: Path) -> str:
    # Relative display path: goldens must not depend on where the repo lives.
    pf = parse_file(path, display_path=path.relative_to(ROOT).as_posix())
    return render_text(report(pf))


def main() -> None:
    out = GOLDEN / "inspect"
    out.mkdir(parents=True, exist_ok=True)
    for path in sorted((ROOT / "fixtures" / "rapid").iterdir()):
        (out / f"{path.name}.txt").write_text(inspect_golden(path), encoding="utf-8")


if __name__ == "__main__":
    main()

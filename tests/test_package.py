"""The grammar ships inside the wheel (checked on a real wheel build)."""

import subprocess
import sys
import zipfile

from conftest import ROOT


def test_wheel_contains_grammar(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q",
                           "-w", str(tmp_path), str(ROOT)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    wheel = next(tmp_path.glob("rapidcomp-*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    assert "rapidcomp/grammars/rapid.lark" in names
    packaged = zipfile.ZipFile(wheel).read("rapidcomp/grammars/rapid.lark")
    assert packaged == (ROOT / "grammars" / "rapid.lark").read_bytes()

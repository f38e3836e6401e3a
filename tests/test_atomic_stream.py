"""All-or-nothing output with data given in pieces (a report rendered as
it is written): the pieces joined are the file; a failure while writing
or rendering a piece leaves nothing behind (no output, no temporary
file) and names the file the user asked for. A file name that is not
UTF-8 is written into the reports as the bytes it is (no traceback)."""

import errno
import os
import subprocess
import sys
from pathlib import Path

import pytest

from rapidcomp.atomic import write_all

ROOT = Path(__file__).resolve().parents[1]


class Pieces:
    def __init__(self, pieces, fail=None):
        self.pieces, self.fail = pieces, fail

    def chunks(self):
        for n, p in enumerate(self.pieces):
            if n == self.fail:
                raise self.error
            yield p


def test_pieces_are_written_joined(tmp_path):
    a, b = tmp_path / "a.mod", tmp_path / "sub" / "b.md"
    write_all([(a, b"MODULE"), (b, Pieces([b"# r\n", b"", b"| 1 |\n" * 3]))])
    assert a.read_bytes() == b"MODULE"
    assert b.read_bytes() == b"# r\n" + b"| 1 |\n" * 3


@pytest.mark.parametrize("error", [OSError(errno.ENOSPC, "No space left on device"),
                                   ValueError("a rendering failed")])
def test_a_failure_in_the_middle_of_a_piece_leaves_nothing(tmp_path, error):
    (tmp_path / "old.md").write_bytes(b"kept")
    data = Pieces([b"first piece\n", b"second\n"], fail=1)
    data.error = error
    files = [(tmp_path / "out.mod", b"MODULE"), (tmp_path / "old.md", data)]
    with pytest.raises(type(error)) as got:
        write_all(files)
    if isinstance(error, OSError):
        assert got.value.filename == str(tmp_path / "old.md")
    # Nothing written, nothing left over, the existing file untouched.
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.md"]
    assert (tmp_path / "old.md").read_bytes() == b"kept"


def _run_as(tmp_path, raw_name: bytes, fixture: str, *args: str):
    """rapidcomp run in tmp_path on a copy of a fixture named raw_name (bytes
    that are not UTF-8), the name as the file system decodes it."""
    name = os.fsdecode(raw_name)
    try:
        (tmp_path / name).write_bytes((ROOT / "fixtures" / fixture).read_bytes())
    except (OSError, UnicodeError):
        pytest.skip("this file system does not take such a name")
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    r = subprocess.run([sys.executable, "-m", "rapidcomp", args[0], name, "--profile",
                        str(ROOT / "fixtures" / "warm.csv"), *args[1:]], cwd=tmp_path, env=env,
                       capture_output=True)
    assert r.returncode == 0, r.stderr
    assert b"Traceback" not in r.stderr


def test_a_file_name_that_is_not_utf8_is_written_back_as_its_bytes(tmp_path):
    _run_as(tmp_path, b"caf\xe9.mod", "cubes.mod", "fix", "--limit", "J5=-120:120", "--json",
            "r.json")
    report = (tmp_path / os.fsdecode(b"caf\xe9_comp.md")).read_bytes()
    assert report.startswith(b"# rapidcomp fix: caf\xe9.mod\n")
    assert b'"program": "caf\\udce9.mod"' in (tmp_path / "r.json").read_bytes()
    assert (tmp_path / os.fsdecode(b"caf\xe9_comp.mod")).read_bytes().startswith(b"MODULE Cubes")


def test_discover_reports_a_file_name_that_is_not_utf8_as_its_bytes(tmp_path):
    _run_as(tmp_path, b"m\xe9.csv", "measured.csv", "discover", "--report", "r.md", "-q")
    assert b"- measured: m\xe9.csv\n" in (tmp_path / "r.md").read_bytes()


def test_a_failed_write_leaves_no_folder_it_made(tmp_path):
    """The folders made for the outputs go again when a file cannot be
    written ("nothing written"): none of them is left behind empty; a
    folder that was there before stays."""
    from rapidcomp.atomic import write_all
    (tmp_path / "kept").mkdir()
    (tmp_path / "blocker").write_text("a file, not a folder")
    with pytest.raises(OSError):
        write_all([(tmp_path / "kept" / "new" / "deep" / "o.mod", b"MODULE"),
                   (tmp_path / "blocker" / "r.md", b"# r")])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["blocker", "kept"]
    assert list((tmp_path / "kept").iterdir()) == []


def test_a_reader_that_goes_does_not_stop_the_command(tmp_path):
    """`rapidcomp fix ... | head -c5`: the reader goes after five bytes;
    the command still writes its files and ends with its own exit code
    (click's exit 1 said some targets were not compensated), silently."""
    fixtures = ROOT / "fixtures"
    p = subprocess.Popen([sys.executable, "-m", "rapidcomp", "fix", str(fixtures / "cubes.mod"),
                          "--profile", str(fixtures / "warm.csv"), "--limit", "J5=-120:120",
                          "-o", str(tmp_path / "o.mod")],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    # (Its first line names the input as given.)
    assert p.stdout.read(5) == str(fixtures / "cubes.mod").encode()[:5]
    p.stdout.close()
    err = p.stderr.read()
    assert p.wait() == 0 and err == b"", err
    assert (tmp_path / "o.mod").exists() and (tmp_path / "o.md").exists()

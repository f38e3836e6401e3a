"""A large module's literals decoded by a second process while the parse
runs (rapid/predecode.py, issue #14): the parsed model is the one the parse
makes alone, the child does the work wherever a literal is plain, and no
child is ever left behind, whatever happens to it. Oracle: the same parse
with the child off."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rapidcomp import cpus
from rapidcomp.errors import InputError
from rapidcomp.rapid import predecode as PD
from rapidcomp.rapid.parse import parse_source, parse_text
from rapidcomp.rewrite.names import words
from rapidcomp.source import read_source

import cam_variants
from conftest import FIXTURES

SOURCES = sorted(p for p in FIXTURES.rglob("*")
                 if p.suffix.lower() in (".mod", ".sys", ".modx") and "invalid" not in p.parts)


@pytest.fixture
def children(monkeypatch):
    """Every parse forks its child (any size); the children started and
    what each handed back, in order."""
    monkeypatch.setattr(PD, "PREDECODE_FROM", 0)
    monkeypatch.setattr(PD, "enabled", True)
    out = []
    start, result = PD.start, PD.Ahead.result

    def spy_start(text, children):
        try:
            start(text, children)
        finally:
            out.append([children[-1] if children else None, None])

    def spy_result(self, patience):
        known = result(self, patience)
        out[-1][1] = known
        return known

    monkeypatch.setattr(PD, "start", spy_start)
    monkeypatch.setattr(PD.Ahead, "result", spy_result)
    return out


def _alone(parse, monkeypatch):
    with monkeypatch.context() as m:
        m.setattr(PD, "enabled", False)
        return parse()


def _reaped(ahead) -> bool:
    try:
        os.waitpid(ahead.pid, os.WNOHANG)
    except ChildProcessError:
        return True
    return False


def test_the_model_is_the_one_the_parse_makes_alone(children, monkeypatch):
    texts = [(p.name, read_source(p, p.name)) for p in SOURCES]
    for seed in (1, 2):
        for name, text in (("broken_runs", cam_variants.broken_runs(seed)),
                           ("other_shapes", cam_variants.other_shapes(seed)),
                           ("bench", cam_variants.bench_module(400, seed, "    ConfL\\Off;\n"))):
            texts.append((name, parse_text(text, name).source))
    for name, source in texts:
        alone = _alone(lambda: parse_source(source), monkeypatch)
        got = parse_source(source)
        assert got == alone, name
        # The words new names must not take, found by the child too.
        assert alone.words is None and got.words == words(source.text), name
        ahead, known = children[-1]
        assert ahead is not None and ahead.status == 0 and known is not None, name
        assert _reaped(ahead)
    # The child did the work: every literal of a CAM module was its.
    name, source = texts[-1]
    pf = parse_source(source)
    literals = sum(d.value is not None for d in pf.module.declarations
                   if d.type in ("robtarget", "jointtarget"))
    literals += sum(t.value is not None for m in pf.module.motions for t in m.targets)
    assert literals == 400 and children[-1][1].hits == literals


def test_literals_written_with_blanks_after_their_commas_are_the_childs_too(children,
                                                                           monkeypatch):
    """People write `[[1, 2, 3], [1, 0, 0, 0], ...]`: the child reads those
    literals too (values.spaced_values, as the parse would), and the model
    is the one the parse makes alone; one beyond a num's range is left to
    the parse, which says where."""
    q, ext = "[0.707107, 0, 0.707107, 0]", "[9E+09,\t9E+09, 9E+09, 9E+09, 9E+09, 9E+09]"
    lines = ["MODULE Hand"]
    for i in range(30):
        lines.append(f"  CONST robtarget p{i} := [[{500 + i}.5, {-i}, 300], {q}, "
                     f"[0, 0, -1, 0], {ext}];")
    lines.append("  CONST jointtarget j0 := [[0, 10, 20, 0, 30.5, 0], [9E+09, 9E+09, 9E+09, "
                 "9E+09, 9E+09, 9E+09]];")
    lines.append("  PROC main()")
    for i in range(10):
        lines.append(f"    MoveL [[{400 + i}, 0, 300] , {q},[0, 0, 0, 0], {ext}], v100, z1, "
                     "tool0;")
    lines += ["    MoveAbsJ j0, v100, fine, tool0;", "  ENDPROC", "ENDMODULE", ""]
    text = "\n".join(lines)
    source = parse_text(text, "hand.mod").source
    alone = _alone(lambda: parse_source(source), monkeypatch)
    got = parse_source(source)
    assert got == alone
    assert children[-1][1].hits == 30 + 1 + 10
    # (A number beyond a num's: the same error, the child reading none.)
    bad = text.replace("[[500.5, 0, 300]", "[[5E+39, 0, 300]")
    with pytest.raises(InputError) as alone_error:
        _alone(lambda: parse_text(bad, "hand.mod"), monkeypatch)
    with pytest.raises(InputError) as got_error:
        parse_text(bad, "hand.mod")
    assert str(got_error.value) == str(alone_error.value) and "5E+39" in str(got_error.value)


@pytest.mark.parametrize("trouble", ["raises", "exits early", "hangs"])
def test_a_child_in_trouble_changes_nothing_but_the_time(trouble, children, monkeypatch):
    def raises(text):
        raise RuntimeError("the child's own failure")

    def exits_early(text):
        os._exit(0)

    def hangs(text):
        time.sleep(60)

    how = {"raises": raises, "exits early": exits_early, "hangs": hangs}[trouble]
    monkeypatch.setattr(PD, "_decode_all", how)
    text = cam_variants.bench_module(300, 3, "")
    alone = _alone(lambda: parse_text(text, "cam.mod"), monkeypatch)
    t = time.perf_counter()
    assert parse_text(text, "cam.mod") == alone
    # (A hanging child is stopped a second after the parse, not waited for.)
    assert time.perf_counter() - t < 20
    ahead, known = children[-1]
    assert known is None and _reaped(ahead)
    assert ahead.status == {"raises": 1, "exits early": 0, "hangs": -9}[trouble]


def test_a_syntax_error_stops_the_child(children):
    text = cam_variants.bench_module(300, 4, "").replace("ENDPROC", "ENDPROC PROC", 1)
    with pytest.raises(InputError):
        parse_text(text, "bad.mod")
    ahead, known = children[-1]
    assert known is None and ahead.status is not None and _reaped(ahead)


def test_small_texts_are_decoded_in_process_and_so_is_all_without_a_child(monkeypatch):
    forks = []
    monkeypatch.setattr(os, "fork", lambda: forks.append(1) or (_ for _ in ()).throw(OSError))
    text = cam_variants.bench_module(50, 5, "")
    kids: list = []
    assert len(text) < PD.PREDECODE_FROM
    PD.start(text, kids)
    monkeypatch.setattr(PD, "PREDECODE_FROM", 0)
    monkeypatch.setattr(PD, "enabled", False)
    PD.start(text, kids)
    # (One core: nothing to gain.)
    monkeypatch.setattr(PD, "enabled", True)
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0})
    PD.start(text, kids)
    assert kids == [] and forks == []
    # (A fork that fails: decoded here.)
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1})
    PD.start(text, kids)
    assert kids == [] and forks == [1]


@pytest.mark.parametrize("decl", [
    "CONST robtarget r:=[[1,2,3,4,5,6],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];",
    "CONST jointtarget j:=[[1,2,3],[1,0,0,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];"])
def test_a_literal_of_the_other_shape_is_the_same_error(decl, children, monkeypatch):
    """The child reads a 12-number literal as a jointtarget and a 17-number
    one as a robtarget: declared as the other, the literal is still the
    error it is."""
    text = f"MODULE M\n  {decl}\n  PROC p()\n    WaitTime 1;\n  ENDPROC\nENDMODULE\n"
    with pytest.raises(InputError) as alone:
        _alone(lambda: parse_text(text, "m.mod"), monkeypatch)
    with pytest.raises(InputError) as got:
        parse_text(text, "m.mod")
    assert str(got.value) == str(alone.value) and "components" in str(got.value)
    assert children[-1][1] is not None and children[-1][1].hits == 0


def test_a_ctrl_c_as_the_child_starts_leaves_nothing_behind(children, monkeypatch):
    """A Ctrl-C held back during the fork arrives as the signals are let
    through again: the child is already the caller's to stop."""
    real = PD.signal.pthread_sigmask

    def let_through(how, mask):
        old = real(how, mask)
        if how == PD.signal.SIG_SETMASK:
            raise KeyboardInterrupt
        return old

    monkeypatch.setattr(PD.signal, "pthread_sigmask", let_through)
    with pytest.raises(KeyboardInterrupt):
        parse_text(cam_variants.bench_module(300, 6, ""), "cam.mod")
    ahead, known = children[-1]
    assert ahead is not None and ahead.fd == -1 and ahead.status is not None and _reaped(ahead)


def test_the_result_counts_where_sigchld_is_ignored(children, monkeypatch):
    """Success is the result arriving whole, not an exit status (a process
    that ignores SIGCHLD never sees its children's)."""
    old = signal.signal(signal.SIGCHLD, signal.SIG_IGN)
    try:
        pf = parse_text(cam_variants.bench_module(300, 7, ""), "cam.mod")
    finally:
        signal.signal(signal.SIGCHLD, old)
    ahead, known = children[-1]
    assert ahead.status == -1 and known is not None and known.hits == 300
    assert pf.words is not None


def test_literals_in_comments_are_left_to_the_parse():
    text = ('  ! MoveL [[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]],v1,z1,t;\n'
            '  TPWrite "a!b"; MoveL [[4,5,6],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]],v1,'
            'z1,t;\n  TPWrite "a""!"; ! [[7,8,9],[1,0,0,0],[0,0,0,0],[9,9,9,9,9,9]]\n')
    starts = PD._decode_all(text)[0].tolist()
    assert starts == [text.index("[[4")]


def test_the_child_dies_with_its_parent(tmp_path):
    """A parent killed (a job runner's timeout) takes its child with it:
    nothing keeps running, nor holds the runner's pipes open."""
    script = tmp_path / "parent.py"
    script.write_text(f"""
import sys, time
sys.path[:0] = {[str(Path(__file__).parent)]!r}
import cam_variants
from rapidcomp.rapid import predecode as PD
from rapidcomp.rapid.parse import parse_text
PD.PREDECODE_FROM = 0
PD._decode_all = lambda text: time.sleep(60)
init = PD.Ahead.__init__
def tell(self, pid, fd):
    init(self, pid, fd)
    print(pid, flush=True)
    time.sleep(60)
PD.Ahead.__init__ = tell
parse_text(cam_variants.bench_module(50, 8, ""), "cam.mod")
""")
    proc = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    pid = int(proc.stdout.readline())
    os.kill(pid, 0)                       # (running)
    proc.kill()
    proc.communicate(timeout=10)          # (returns: no child holds the pipes)
    for _ in range(100):
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return
        time.sleep(0.05)
    raise AssertionError("the child outlived its parent")


def test_the_cores_are_those_of_the_cpu_quota_too(tmp_path, monkeypatch):
    """A container's CPU quota (docker --cpus 1) counts like a CPU mask:
    one core, no child."""
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1, 2, 3})
    v2, v1 = tmp_path / "cpu.max", tmp_path / "v1" / "cpu.cfs_quota_us"
    v1.parent.mkdir()
    monkeypatch.setattr(cpus, "_QUOTAS", ((str(v2), "max"), (str(v1), "-1")))
    assert cpus.cores() == 4                      # (no file: no quota)
    v2.write_text("max 100000\n")
    assert cpus.cores() == 4
    v2.write_text("150000 100000\n")
    assert cpus.cores() == 1.5
    v2.unlink()
    v1.write_text("100000\n")
    (v1.parent / "cpu.cfs_period_us").write_text("100000\n")
    assert cpus.cores() == 1
    v1.write_text("-1\n")
    assert cpus.cores() == 4
    v1.write_text("?\n")                         # (unreadable: the mask alone)
    assert cpus.cores() == 4
    v1.write_text("100000\n")
    monkeypatch.setattr(PD, "PREDECODE_FROM", 0)
    monkeypatch.setattr(PD, "enabled", True)
    kids: list = []
    PD.start(cam_variants.bench_module(50, 9, ""), kids)
    assert kids == []

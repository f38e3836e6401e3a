"""process.let_go: in the command's own process (process.own) what a job
lets go of, its parsed program, is kept until the next job starts or the
process ends (not freed object by object just before the process exits);
in a library call it is let go at once. Checked by weak references to the
objects themselves."""

import weakref

import pytest

from rapidcomp import process
from rapidcomp.compensate import job as J
from rapidcomp.compensate.plan import Task
from rapidcomp.rapid.task import tasks_of

FIXTURES = "fixtures"


class _Thing:
    pass


@pytest.mark.parametrize("owned", [False, True])
def test_kept_in_the_command_until_the_next_let_go_else_let_go_at_once(monkeypatch, owned):
    monkeypatch.setattr(process, "_owned", owned)
    monkeypatch.setattr(process, "_kept", None)
    thing = _Thing()
    ref = weakref.ref(thing)
    process.let_go(thing)
    del thing
    assert (ref() is not None) == owned
    process.let_go(None)
    assert ref() is None


def _spec(tmp_path, name: str) -> J.JobSpec:
    src = tasks_of(f"{FIXTURES}/cubes.mod")[0]
    return J.JobSpec(src, str(tmp_path / name), None, None, f"{FIXTURES}/warm.csv", None, (),
                     "auto", False, ("J5=-120:120",))


def test_a_job_keeps_its_parsed_task_and_the_next_job_lets_it_go(monkeypatch, tmp_path):
    monkeypatch.setattr(process, "_owned", True)
    monkeypatch.setattr(process, "_kept", None)
    first = J.run(_spec(tmp_path, "a.mod"))
    kept = process._kept
    assert type(kept) is Task and kept.files[0].source.display_path == "cubes.mod"
    ref = weakref.ref(kept)
    del kept
    # The first job's task is gone before the second one parses (not alive
    # beside it).
    alive_at_parse = []
    load = J.load_task

    def load_task(*args):
        alive_at_parse.append(ref() is not None)
        return load(*args)
    monkeypatch.setattr(J, "load_task", load_task)
    second = J.run(_spec(tmp_path, "b.mod"))
    assert alive_at_parse == [False]
    assert type(process._kept) is Task and process._kept is not None
    # The same job's outputs either way.
    assert first.files[0][1] == second.files[0][1]
    process.let_go(None)


def test_a_job_of_a_library_call_keeps_nothing(monkeypatch, tmp_path):
    monkeypatch.setattr(process, "_owned", False)
    monkeypatch.setattr(process, "_kept", None)
    J.run(_spec(tmp_path, "a.mod"))
    assert process._kept is None


def test_a_worker_lets_go_before_it_renders(monkeypatch, tmp_path):
    """A pool worker (forked from the command, so its own process) renders
    its reports after the job and goes on to its next module: it keeps
    nothing."""
    from rapidcomp import side
    from rapidcomp.rapid import predecode
    monkeypatch.setattr(process, "_owned", True)
    monkeypatch.setattr(process, "_kept", None)
    monkeypatch.setattr(predecode, "enabled", True)
    monkeypatch.setattr(side, "enabled", True)
    spec = J.JobSpec(tasks_of(f"{FIXTURES}/cubes.mod")[0], str(tmp_path / "a.mod"),
                     str(tmp_path / "a.md"), None, f"{FIXTURES}/warm.csv", None, (), "auto",
                     False, ("J5=-120:120",))
    out = J._run_rendered(spec)
    assert process._kept is None
    assert any(path.endswith("a.md") and data.startswith(b"# rapidcomp fix")
               for path, data in out.files)

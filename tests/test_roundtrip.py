"""Round-trip gate: every fixture parses and re-emits byte-identical."""

import pytest

from rapidcomp.edits import OverlappingEdits, SpanEdit, apply_edits
from rapidcomp.rapid.parse import parse_file
from rapidcomp.rapid.values import JointTarget, RobTarget

from conftest import RAPID_FIXTURES

ALL_MODULES = RAPID_FIXTURES + [p for p in (RAPID_FIXTURES[0].parents[1]).glob("*.mod")]


def _fields(pf):
    """Every numeric field of every decoded target in the file."""
    out = []
    for m in pf.modules:
        for d in m.declarations:
            values = d.value if isinstance(d.value, tuple) else (d.value,)
            for v in values:
                if isinstance(v, RobTarget):
                    out += [*v.trans, *v.rot, *v.robconf, *v.extax]
                elif isinstance(v, JointTarget):
                    out += [*v.robax, *v.extax]
        for mo in m.motions:
            for t in mo.targets:
                if isinstance(t.value, RobTarget):
                    out += [*t.value.trans, *t.value.rot, *t.value.robconf, *t.value.extax]
                elif isinstance(t.value, JointTarget):
                    out += [*t.value.robax, *t.value.extax]
    return out


@pytest.mark.parametrize("path", ALL_MODULES, ids=lambda p: p.name)
def test_empty_edit_list_reproduces_bytes(path):
    pf = parse_file(path)
    assert pf.source.encode(apply_edits(pf.source.text, [])) == path.read_bytes()


@pytest.mark.parametrize("path", ALL_MODULES, ids=lambda p: p.name)
def test_rewriting_every_field_with_its_own_text_is_identity(path):
    pf = parse_file(path)
    fields = _fields(pf)
    edits = [SpanEdit(f.span.start, f.span.end, f.text) for f in fields]
    assert pf.source.encode(apply_edits(pf.source.text, edits)) == path.read_bytes()
    for f in fields:  # spans point at exactly the number's characters
        assert pf.source.text[f.span.start:f.span.end] == f.text


def test_field_edit_changes_only_that_field(fixtures_dir):
    path = fixtures_dir / "rapid" / "robotstudio_crlf.mod"
    pf = parse_file(path)
    p_home = next(d for d in pf.module.declarations if d.name == "pHome").value
    x = p_home.trans[0]
    new = pf.source.encode(apply_edits(pf.source.text, [SpanEdit(*x.span, "515.25")]))
    old = path.read_bytes()
    assert new.replace(b"[[515.25,0,712]", b"[[515,0,712]") == old
    assert new.count(b"\r\n") == old.count(b"\r\n")


def test_overlapping_edits_are_refused():
    with pytest.raises(OverlappingEdits):
        apply_edits("abcdef", [SpanEdit(0, 3, "x"), SpanEdit(2, 4, "y")])


def test_encodings_are_detected_and_kept(fixtures_dir):
    cp = parse_file(fixtures_dir / "rapid" / "handwritten_cp1252.mod")
    assert cp.source.encoding == "cp1252"
    assert "Prüfzelle" in cp.source.text
    assert cp.source.newline == "mixed"
    bom = parse_file(fixtures_dir / "rapid" / "system_bom.sys")
    assert bom.source.has_bom and bom.source.encoding == "utf-8"
    assert "Grüße" in bom.source.text
    assert parse_file(fixtures_dir / "rapid" / "robotstudio_crlf.mod").source.newline == "CRLF"

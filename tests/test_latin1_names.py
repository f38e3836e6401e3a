"""Names with ISO 8859-1 letters (the RAPID kernel's character set: a
controller's own backup held `VAR num varÖlcüm;`, `PROC Sensör_Kalibre()`,
`GOTO ölçümolmadan;`, a letter-writing program `PROC Ñ (...)`): read as
names, matched case-blind as RAPID matches names, taken into account when a
new name is made, and alike in the report's lines. Only those letters: the
multiplication and division signs between them, and letters beyond
ISO 8859-1, are refused where they stand."""

import re

import pytest
from click.testing import CliRunner

from rapidcomp.cli import main
from rapidcomp.compensate import report
from rapidcomp.errors import InputError
from rapidcomp.rapid.grammar import engine
from rapidcomp.rapid.parse import parse_text
from rapidcomp.rewrite.names import words

ROOT = __import__("pathlib").Path(__file__).resolve().parents[1]
PROFILE = ROOT / "fixtures" / "warm.csv"

PROGRAM = """MODULE Höhe
    CONST robtarget pHöhe:=[[400,0,400],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];
    CONST robtarget jt_pHöhe:=[[410,0,400],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];
    PERS tooldata tÖl:=[TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,50],[1,0,0,0],0,0,0]];
    VAR num varÖlcüm;
    PROC main()
        varÖlcüm:=0;
        Ölçüm;
        MoveJ PHÖHE, v100, fine, TÖL;
        MoveL jt_pHöhe, v100, fine, tÖl;
    ENDPROC
    PROC Ölçüm()
        GOTO ölçümolmadan;
        ölçümolmadan:
    ENDPROC
ENDMODULE
"""


def test_names_of_latin1_letters_are_names():
    pf = parse_text(PROGRAM, "hoehe.mod")
    m = pf.module
    assert m.name == "Höhe"
    assert [r.name for r in m.routines] == ["main", "Ölçüm"]
    assert {d.name for d in m.declarations} >= {"pHöhe", "jt_pHöhe", "tÖl", "varÖlcüm"}
    body = m.routines[0].node.body
    assert body[1].name == "Ölçüm"
    assert body[2].args[0].value.name == "PHÖHE"


@pytest.mark.parametrize("name,bad", [("p\u00d7q", "\u00d7"), ("p\u00f7q", "\u00f7"),
                                      ("p\u0160", "\u0160"), ("x\u212a", "\u212a"),
                                      ("\u0131f", "\u0131")])
def test_other_characters_in_a_name_are_refused_where_they_stand(name, bad):
    """× and ÷ lie among ISO 8859-1's letters and are none; Š (cp1252's
    0x8A), the Kelvin sign and a dotless i are not ISO 8859-1 (a case-blind
    match of a to z took the last two for K and i)."""
    text = f"MODULE m\n  PROC p()\n    {name} := 1;\n  ENDPROC\nENDMODULE\n"
    with pytest.raises(InputError) as err:
        parse_text(text, "m.mod")
    # (With its code point: the Kelvin sign looks like a K.)
    assert str(err.value).startswith(f"m.mod:3:{5 + name.index(bad)}: unexpected character "
                                     f"{bad!r} (U+{ord(bad):04X}): not part of RAPID")


def test_a_move_naming_one_is_lexed_token_by_token():
    """The one-line tokens keep to a to z: such a move is read as its
    tokens, the name whole (not its a-to-z head)."""
    kinds = [t.type for t in engine().tokens("MoveL pHöhe,v100,z1,tool0;")]
    assert "FAST_CALL" not in kinds and kinds[:2] == ["NAME", "NAME"]
    assert [t.value for t in engine().tokens("MoveL pHöhe,v100,z1,tool0;")][1] == "pHöhe"


def test_a_new_name_takes_none_of_them():
    assert {"jt_phöhe", "varölcüm", "ölçümolmadan"} <= words(PROGRAM)
    assert "jt_ph" not in words(PROGRAM)


def test_reasons_alike_but_for_such_a_name_are_one_line():
    assert (report._alike("pÖa is not declared", "pÖa")
            == report._alike("pÖb is not declared", "pÖb") == "<name> is not declared")


def test_fix_of_a_latin1_module(tmp_path):
    """Compensated as any module: a name matched case-blind (PHÖHE is
    pHöhe, TÖL is tÖl), the new jointtarget named past the one the module
    has (jt_pHöhe), the output ISO 8859-1 as the input, every other byte
    as it was."""
    src = tmp_path / "hoehe.mod"
    data = PROGRAM.encode("latin-1")
    src.write_bytes(data)
    out = tmp_path / "out"
    r = CliRunner().invoke(main, ["fix", str(src), "--profile", str(PROFILE), "--emit", "absj",
                                  "-o", f"{out}/"], catch_exceptions=False)
    assert r.exit_code == 0, r.output
    assert "2 of 2 target uses compensated" in r.output
    assert src.read_bytes() == data
    written = (out / "hoehe.mod").read_bytes().decode("latin-1")
    new = re.findall(r"^    LOCAL CONST jointtarget (\w+):=\[\[[^\]]*\],\[9E9(?:,9E9){5}\]\];\n",
                     written, re.M)
    assert new == ["jt_pHöhe_2", "jt_jt_pHöhe"]
    # (What is left without the new lines and with the moves as they were
    # is the input.)
    back = re.sub(r"^    LOCAL CONST jointtarget .*\n", "", written, flags=re.M)
    back = back.replace("MoveAbsJ jt_pHöhe_2,", "MoveJ PHÖHE,").replace(
        "MoveAbsJ jt_jt_pHöhe,", "MoveL jt_pHöhe,")
    assert back == PROGRAM
    assert CliRunner().invoke(main, ["inspect", str(out / "hoehe.mod")]).exit_code == 0

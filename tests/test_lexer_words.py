"""One-line statements lexed as one token: a declaration with a numeric
aggregate (FAST_DECL) unless its type or its name is a reserved word, a
call (FAST_CALL) unless any word of it is (then each is lexed token by
token). The words are looked for outside the aggregate only (it has none:
the E of 9E+09 follows a digit), a call's arguments after the first once
per distinct text. Oracle: the words the statement was made of, on seeded
random statements."""

import random

from rapidcomp.rapid.grammar import engine


def test_fast_declaration_refused_exactly_when_type_or_name_is_reserved():
    eng = engine()
    kw = eng._keywords
    rnd = random.Random(7)
    words = ["robtarget", "num", "p10", "pE", "e", "E9", "xIF", "iff", "Then", "IF", "FOR",
             "TO", "PROC", "Local", "WHILE", "ENDIF"]
    aggs = ["[1,2E+3,-4.5e-6]", "[[1,2,3],[1,0,0,0],[0,0,0,0],[9E+09,9E+09,1e5,0,0,0]]",
            "[ 1 , 2.E3 ]", "[0]"]
    seen = {True: 0, False: 0}
    for _ in range(3000):
        type_, name = rnd.choice(words), rnd.choice(words)
        scope = rnd.choice(["", "LOCAL ", "task "])
        storage = rnd.choice(["CONST", "pers", "Var"])
        text = f"{scope}{storage} {type_} {name}{rnd.choice(['', ' '])}:={rnd.choice(aggs)};"
        kinds = [t.type for t in eng.tokens(text)]
        fast = not (type_.upper() in kw or name.upper() in kw)
        assert (kinds == ["FAST_DECL", "$END"]) == fast, text
        seen[fast] += 1
    assert min(seen.values()) > 500


def test_fast_call_refused_exactly_when_a_word_is_reserved():
    eng = engine()
    kw = eng._keywords
    rnd = random.Random(8)
    plain = ["MoveL", "Foo", "p10", "v100", "z1", "tool0", "e", "E9", "xIF", "iff", "Then_",
             "TOx", "Local"]
    reserved = ["IF", "for", "Then", "TO", "PROC", "WHILE", "ENDIF", "Return", "not"]

    def word():
        return rnd.choice(reserved if rnd.random() < 0.05 else plain)
    agg = "[[1,2E+3,-4.5e-6],[1,0,0,0],[0,0,0,0],[9E+09,9E+09,1e5,0,0,0]]"
    seen = {True: 0, False: 0}
    seen_no_comma = set()
    for _ in range(6000):
        name = word()
        first = rnd.choice([word(), agg, "func", "-2.5", "7"])
        used = [name] + ([] if first == agg or not first[-1].isalpha() else [first])
        if first == "func":
            # A function of names and aggregates (rcTcR(p10, p10_dq)): its
            # name and names count too.
            # Its optional arguments (RelTool(p, 0, 0, -10 \\Rz:=45)) too.
            parts = [rnd.choice([word(), agg, "-10"]) for _ in range(rnd.randint(1, 3))]
            func = word()
            first = f"{func}({rnd.choice(['', ' ']).join(p + ',' for p in parts)[:-1]}"
            used = [name, func] + [p for p in parts if p[-1].isalpha()]
            if rnd.random() < 0.3:
                w, v = word(), rnd.choice([word(), "45", "-45"])
                first += f"{rnd.choice(['', ' ', ','])}\\{w}:={v}"
                used += [w] + ([v] if v[-1].isalpha() else [])
            first += ")"
        # After the first argument: names after commas and options, in any
        # order (a call without a comma too), spaces or tabs before them.
        # (None: Reset do1; numbers: SetDO do1, 1;)
        after = ""
        for _ in range(rnd.randint(0, 4)):
            pad = rnd.choice(["", "", " ", "\t"])
            kind = rnd.random()
            if kind < 0.1:
                after += f"{pad},{rnd.choice(['', ' '])}{rnd.choice(['1', '-0.5', '+2.'])}"
            elif kind < 0.5:
                w = word()
                after += f"{pad},{rnd.choice(['', ' '])}{w}"
                used.append(w)
            else:
                w = word()
                after += f"{pad}\\{w}"
                used.append(w)
                if kind < 0.75:
                    v = rnd.choice([word(), "100", "1.5"])
                    after += ":=" + v
                    used += [] if v[0].isdigit() else [v]
        text = f"{name} {first}{after};"
        kinds = [t.type for t in eng.tokens(text)]
        fast = not any(w.upper() in kw for w in used)
        assert (kinds == ["FAST_CALL", "$END"]) == fast, text
        seen[fast] += 1
        if "," not in text:
            seen_no_comma.add(fast)
    assert min(seen.values()) > 1000
    # (Calls without a comma were among them, with reserved words and
    # without.)
    assert seen_no_comma == {True, False}

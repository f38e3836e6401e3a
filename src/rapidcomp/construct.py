"""Positional construction of frozen dataclasses, for the places that
make one per target of a CAM program (1e5 and more).

A frozen dataclass's __init__ sets each field through
object.__setattr__ (frozen classes refuse plain assignment): ~0.5 us for
four fields. maker(cls) returns a function that makes the same object by
setting its slots (or its __dict__) directly (~0.3 us): fields by
position, all of them, no defaults and no __post_init__ (maker refuses a
class that has one).
"""

from __future__ import annotations

import dataclasses


def maker(cls):
    """new(*values) -> an instance of cls equal to cls(*values)."""
    params = getattr(cls, "__dataclass_params__", None)
    if params is None or not params.frozen or hasattr(cls, "__post_init__"):
        raise TypeError(f"{cls.__name__}: maker() takes a frozen dataclass without "
                        "__post_init__")
    names = [f.name for f in dataclasses.fields(cls)]
    args = ", ".join(f"v{i}" for i in range(len(names)))
    namespace = {"_new": object.__new__, "_cls": cls}
    if "__slots__" in cls.__dict__:
        namespace.update({f"_set{i}": s for i, s in enumerate(slot_setters(cls))})
        binds = "".join(f", _s{i}=_set{i}" for i in range(len(names)))
        body = "".join(f"    _s{i}(o, v{i})\n" for i in range(len(names)))
    else:
        binds = ""
        body = "    d = o.__dict__\n" + "".join(f"    d[{name!r}] = v{i}\n"
                                            for i, name in enumerate(names))
    source = (f"def new_{cls.__name__}({args}, _n=_new, _c=_cls{binds}):\n"
              f"    o = _n(_c)\n{body}    return o\n")
    exec(source, namespace)
    return namespace[f"new_{cls.__name__}"]


def slot_setters(cls) -> list:
    """The setter of each field of a frozen slots dataclass, in field order
    (setter(o, value) sets it, as maker's functions do; code written for
    one shape of nodes sets them so too: rapid/build.py)."""
    if "__slots__" not in cls.__dict__:
        raise TypeError(f"{cls.__name__}: slot_setters() takes a slots dataclass")
    return [getattr(cls, f.name).__set__ for f in dataclasses.fields(cls)]

"""Positional construction of frozen dataclasses, for the places that
make one per target of a CAM program (1e5 and more).

A frozen dataclass's __init__ sets each field through
object.__setattr__ (frozen classes refuse plain assignment): ~0.5 us for
four fields. maker(cls) returns a function that makes the same object
setting its fields directly: fields by position, all of them, no defaults
and no __post_init__ (maker refuses a class that has one). A class with a
__dict__ gets its fields written there. A slots class is made as its
twin (twin(): the same slots, so the same memory layout, and no frozen
__setattr__), its fields stored by plain assignment, which Python does
for slots at the cost of a store (~15 ns, against ~60 ns a call of the
slot's setter), and then given its class (__class__ assignment, which
Python allows between classes of one layout): Ref ~0.31 -> 0.21 us, a
TargetUse's 20 fields ~1.1 -> 0.34 us. The object is the class's own,
frozen as any other.
"""

from __future__ import annotations

import dataclasses


def maker(cls):
    """new(*values) -> an instance of cls equal to cls(*values)."""
    params = getattr(cls, "__dataclass_params__", None)
    if params is None or not params.frozen or hasattr(cls, "__post_init__"):
        raise TypeError(f"{cls.__name__}: maker() takes a frozen dataclass without "
                        "__post_init__")
    n = len(dataclasses.fields(cls))
    namespace: dict = {}
    body = made_as(cls, "o", [f"v{i}" for i in range(n)], namespace)
    # (What the body names bound as defaults: locals, not globals.)
    binds = "".join(f", {k}={k}" for k in namespace)
    source = (f"def new_{cls.__name__}({', '.join(f'v{i}' for i in range(n))}{binds}):\n"
              + "".join(f"    {line}\n" for line in body) + "    return o\n")
    exec(source, namespace)
    return namespace[f"new_{cls.__name__}"]


def made_as(cls, var: str, values: list[str], namespace: dict) -> list[str]:
    """Lines of Python making `var = cls(*values)` (values: expressions) as
    maker's functions make it, the names they use put in namespace; code
    written for one shape of nodes makes them so too (rapid/build.py)."""
    key = cls.__name__
    namespace["_o"], namespace[f"_{key}"] = object.__new__, cls
    fields = dataclasses.fields(cls)
    if "__slots__" in cls.__dict__:
        namespace[f"_{key}Twin"] = twin(cls)
        return ([f"{var} = _o(_{key}Twin)"]
                + [f"{var}.{f.name} = {v}" for f, v in zip(fields, values)]
                + [f"{var}.__class__ = _{key}"])
    return ([f"{var} = _o(_{key})", f"_d = {var}.__dict__"]
            + [f"_d[{f.name!r}] = {v}" for f, v in zip(fields, values)])


_TWINS: dict = {}


def twin(cls) -> type:
    """A class of cls's memory layout (its bases and its slots) without its
    frozen __setattr__: an instance of it is filled by plain assignment and
    then made cls's (o.__class__ = cls). Its bases must set nothing
    themselves (slots of their own, no __setattr__: values.py's _Numeric)."""
    got = _TWINS.get(cls)
    if got is None:
        if "__slots__" not in cls.__dict__ or any(
                "__slots__" not in b.__dict__ or "__setattr__" in b.__dict__
                for b in cls.__mro__[1:-1]):
            raise TypeError(f"{cls.__name__}: twin() takes a slots class whose bases set "
                            "nothing themselves")
        got = type(f"{cls.__name__}Twin", cls.__bases__,
                   {"__slots__": cls.__dict__["__slots__"], "__module__": cls.__module__})
        probe = object.__new__(got)
        probe.__class__ = cls             # (TypeError here, were the layouts to differ)
        _TWINS[cls] = got
    return got

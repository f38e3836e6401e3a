"""Transient compensation: the correction applied at run time for the
robot's current thermal state s, not only for the warm robot.

Thermal state model (README "Transient compensation"). The deformation at
state s is s . profile (kinematics/profile.scaled): s = 0 cold, s = 1 the
measured steady state. Because the deformation is tiny, the joints the robot
needs at state s are, to first order, q_cold + s . dq with dq = q_warm -
q_cold: every compensated target is written as its cold value and its
correction, and the move's target is rcTcJ(cold, dq), a function of the
generated support module (support_module) that also keeps s up to date:

- clock law: between two compensated moves at most `gap_min` apart the robot
  runs and s rises towards 1 with time constant tau_heat; a longer gap (a
  stop, a pause, power off) is standing and s falls towards 0 with tau_cool.
  The time comes from the controller's calendar clock (CDate/CTime, read
  so that midnight cannot fall between date and time), kept in PERS data,
  so it survives program stops, restarts and power off.
- sensor law: s = clip((T - T_cold) / (T_warm - T_cold), 0, 1), T an analog
  input (AInput).

`state_after` is the Python twin of the clock law; tests execute the
generated RAPID (a small evaluator in tests/) and compare the two.

Verification (fix.py, verify.verify_states): the written program is parsed
again and read at every s in STATES, each rcTcJ/rcTcR(cold, dq) evaluated
as the controller computes it (state_values, float32), and verified as any
output is, on the robot deformed by s . profile.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import RapidcompError
from ..kinematics.frames import row_dots
from ..rapid.parse import parse_text
from ..rewrite import numbers
from ..rewrite.names import NameAllocator

FUNC_J = "rcTcJ"
FUNC_R = "rcTcR"
MODULE = "rcThermal"
MODULE_FILE = "rcThermal.sys"
STATES = (0.0, 0.25, 0.5, 0.75, 1.0)
# Defaults (minutes). Cooling is slower than heating on a standing arm (no
# motor losses, only convection); both are settable and the profile may
# carry them.
DEFAULT_TAU_COOL_FACTOR = 1.0
DEFAULT_GAP_MIN = 2.0
# The shortest time constant or gap the module writes (0.001 min = 60 ms:
# shorter is no warm-up; the number stays plain decimal in RAPID).
MIN_MINUTES = 0.001
MINUTES_PER_DAY = 1440.0


@dataclass(frozen=True)
class Transient:
    """How s is known at run time: the clock law (tau_heat_min, tau_cool_min,
    gap_min) or a temperature sensor (signal, t_cold, t_warm)."""

    tau_heat_min: float | None = None
    tau_cool_min: float | None = None
    gap_min: float = DEFAULT_GAP_MIN
    signal: str | None = None
    t_cold: float = 0.0
    t_warm: float = 0.0
    source: str | None = None        # where tau came from, when not an option

    @property
    def law(self) -> str:
        if self.signal is not None:
            return (f"s from analog input {self.signal}: (T - {self.t_cold:g}) / "
                    f"({self.t_warm:g} - {self.t_cold:g}), clipped to 0..1")
        return (f"clock: heating tau {self.tau_heat_min:g} min while running, cooling tau "
                f"{self.tau_cool_min:g} min after a gap of more than {self.gap_min:g} min"
                + (f" ({self.source})" if self.source else ""))


def make_transient(tau_heat: float | None, tau_cool: float | None, gap: float | None,
                   temperature: str | None, source: str | None = None) -> Transient:
    """The options of `fix --transient`, checked (RapidcompError: exit 2)."""
    if temperature is not None:
        if tau_heat is not None or tau_cool is not None or gap is not None:
            raise RapidcompError("--temperature and --tau-heat/--tau-cool/--gap are two ways to "
                                 "know the thermal state: give one")
        parts = temperature.split(":")
        if len(parts) != 3:
            raise RapidcompError(f"--temperature {temperature}: expected SIGNAL:T_COLD:T_WARM "
                                 "(an analog input and its readings cold and warm)")
        name = parts[0]
        if not _identifier(name):
            raise RapidcompError(f"--temperature {temperature}: {name!r} is not a RAPID signal "
                                 "name (a letter, then letters, digits or _, at most 32)")
        if name.lower() in {n.lower() for n in GLOBAL_NAMES} or not _parses_as_signal(name):
            raise RapidcompError(f"--temperature {temperature}: {name!r} is a RAPID reserved "
                                 "word or a name of the support module, not a signal name")
        _check_signal(name)
        try:
            cold, warm = float(parts[1]), float(parts[2])
        except ValueError:
            raise RapidcompError(f"--temperature {temperature}: T_COLD and T_WARM must be "
                                 "numbers") from None
        if not (math.isfinite(cold) and math.isfinite(warm)) or abs(warm - cold) < 1e-6 \
                or max(abs(cold), abs(warm)) > 1e6:
            raise RapidcompError(f"--temperature {temperature}: T_COLD and T_WARM must be "
                                 "finite, different numbers")
        # (The support module divides by their difference as the controller
        # holds them: the numbers written, as 32-bit floats.)
        if f32(float(_num(cold))) == f32(float(_num(warm))):
            raise RapidcompError(f"--temperature {temperature}: T_COLD and T_WARM are the same "
                                 "number to the controller (a num is a 32-bit float); give "
                                 "readings further apart")
        return Transient(signal=name, t_cold=cold, t_warm=warm)
    if tau_heat is None:
        raise RapidcompError("--transient needs how the thermal state is known: --tau-heat MIN "
                             "[--tau-cool MIN] (clock), --temperature SIGNAL:T_COLD:T_WARM, or "
                             "a profile with tau_heat_min (discover writes it from a warm-up "
                             "campaign)")
    for label, v in (("--tau-heat", tau_heat), ("--tau-cool", tau_cool), ("--gap", gap)):
        if v is not None and not (math.isfinite(v) and MIN_MINUTES <= v <= 100_000):
            raise RapidcompError(f"{label} {v:g}: minutes, from {MIN_MINUTES:g} to 100000")
    return Transient(tau_heat, tau_cool if tau_cool is not None
                     else tau_heat * DEFAULT_TAU_COOL_FACTOR,
                     gap if gap is not None else DEFAULT_GAP_MIN, source=source)


def _parses_as_signal(name: str) -> bool:
    """Whether `name` can stand as AInput's argument (not a reserved word)."""
    try:
        parse_text(f"MODULE m\n  PROC p()\n    x:=AInput({name});\n  ENDPROC\nENDMODULE\n",
                   "<signal>")
    except RapidcompError:
        return False
    return True


def _identifier(name: str) -> bool:
    return (0 < len(name) <= 32 and name[0].isascii() and name[0].isalpha()
            and all(c.isascii() and (c.isalnum() or c == "_") for c in name))


# The support module's global names: a task that has any of them already
# cannot load it (or was compensated with --transient before).
GLOBAL_NAMES = ("rcS", "rcLastDay", "rcLastMin", "rcTauHeat", "rcTauCool", "rcGapMin",
                "rcTCold", "rcTWarm", "rcNow", "rcUpdate", FUNC_J, FUNC_R, "rcThermalSet",
                "rcThermalShow", MODULE)


# The predefined routines the support module calls: a global routine or
# data of the task by one of these names would be called in their place (a
# routine hides the predefined routines of its name).
CALLED = ("CDate", "CTime", "StrToVal", "StrPart", "Exp", "NOrient", "TPWrite", "AInput")
# Predefined data no analog input is named like: tools, loads, the speed
# and zone data every system has, and the system's variables.
_PREDEFINED_DATA = frozenset((
    "tool0", "wobj0", "load0", "pi", "errno", "intno", "fine", "vmax",
    *(f"v{n}" for n in (5, 10, 20, 30, 40, 50, 60, 80, 100, 150, 200, 300, 400, 500, 600, 800,
                        1000, 1500, 2000, 2500, 3000, 4000, 5000, 6000, 7000)),
    *(f"vrot{n}" for n in (1, 2, 5, 10, 20, 50, 100)),
    *(f"vlin{n}" for n in (10, 20, 50, 100, 200, 500, 1000)),
    *(f"z{n}" for n in (0, 1, 5, 10, 15, 20, 30, 40, 50, 60, 80, 100, 150, 200)),
    "inpos20", "inpos50", "inpos100", "stoptime0_5", "stoptime1_0", "stoptime1_5",
    "fllwtime0_5", "fllwtime1_0", "fllwtime1_5"))


def _check_signal(name: str) -> None:
    """RapidcompError where an analog input cannot have this name, past
    _parses_as_signal (which refuses the reserved words a name cannot be):
    TRUE and FALSE (they parse, as values), a predefined data name (v100,
    fine, tool0, pi, ERRNO, ...), a predefined routine's (MoveL, AInput,
    ...): the support module's AInput(name) would not load."""
    from ..rapid.motions import BUILTIN_FUNCTIONS, BUILTIN_INSTRUCTIONS, motion_spec
    lower = name.lower()
    if lower in ("true", "false"):
        what = "a word RAPID reserves"
    elif lower in _PREDEFINED_DATA:
        what = "a predefined data name (speed, zone, tool, load data, a system variable)"
    elif lower in BUILTIN_FUNCTIONS or lower in BUILTIN_INSTRUCTIONS or motion_spec(name):
        what = "a predefined routine's name"
    else:
        return
    raise RapidcompError(f"--temperature {name}: {what}, not an analog input (the support "
                         f"module's AInput({name}) would not load)")


def check_names(task, tr: Transient | None = None) -> None:
    """RapidcompError when the task already declares one of the support
    module's names, or declares globally a routine or data by the name of
    a predefined routine the module calls; with a temperature sensor (tr),
    when its signal's name is the task's routine or data of another type
    than signalai (the module's AInput(signal) would not load)."""
    taken = {n.lower(): n for n in GLOBAL_NAMES}
    for pf in task.files:
        # (A large module's words as its parse found them: predecode.py.)
        clash = sorted(taken[w] for w in NameAllocator([pf.source.text], [pf.words]).taken
                       & set(taken))
        if clash:
            raise RapidcompError(
                f"{pf.source.display_path}: uses {', '.join(clash)}, a name of the transient "
                f"support module {MODULE_FILE}: the task cannot load both (compensated with "
                "--transient already? Compensate the original program)")
    called = {n.lower(): n for n in CALLED}
    signal = tr.signal.lower() if tr is not None and tr.signal else None
    for pf in task.files + task.context:
        for m in pf.modules:
            declared = [(r.node.name, r.node.scope, f"a {r.kind}", r.node.span)
                        for r in m.routines]
            declared += [(d.name, d.scope, f"{d.type} data", d.node.span)
                         for d in m.declarations if d.routine is None]
            for name, scope, what, span in declared:
                key = name.lower()
                if key in called and (scope or "").upper() != "LOCAL":
                    raise RapidcompError(
                        f"{pf.source.display_path}:{pf.line(span)}: {what} named {name} hides "
                        f"the predefined {called[key]} the transient support module "
                        f"{MODULE_FILE} calls: the module would call it instead")
                if key == signal and (scope or "").upper() != "LOCAL" and what != \
                        "signalai data":
                    raise RapidcompError(
                        f"--temperature {tr.signal}: {pf.source.display_path}:{pf.line(span)} "
                        f"declares {name} as {what}, not an analog input (signalai): the "
                        f"support module's AInput({name}) would not load")


# ------------------------------------------------------------- Python twin

def state_after(s: float, dt_min: float, tr: Transient) -> float:
    """The clock law (the generated rcUpdate's twin): the state dt_min
    after a state s."""
    dt = max(0.0, dt_min)
    if dt <= tr.gap_min:
        return 1.0 - (1.0 - s) * math.exp(-dt / tr.tau_heat_min)
    return s * math.exp(-dt / tr.tau_cool_min)


def day_number(year: int, month: int, day: int) -> int:
    """Days since 2000-03-01 (the generated rcNow's formula: a year counted
    from March, so that the leap day is its last)."""
    y, m = (year - 1, month + 12) if month < 3 else (year, month)
    y -= 2000
    return 365 * y + y // 4 - y // 100 + y // 400 + (153 * (m - 3) + 2) // 5 + day - 1


def differs(existing: bytes | None, text: bytes) -> tuple[str, str]:
    """Where the support module `existing` (a file's bytes, None: not
    readable) differs from `text`, the one this run writes, line breaks
    aside: (":line:col", "its line L holds `...` where this run writes
    `...`") of the first line of code that differs (else of the first
    comment), each "" where nothing can be said. The user sees which
    setting differs (most often a time constant) without a diff."""
    if existing is None:
        return "", ""
    have, want = (_lines(t.decode("latin-1")) for t in (existing, text))
    if have == want:
        return "", ""
    other = [i for i, (a, b) in enumerate(zip(have, want)) if a != b]
    if other:
        i = next((i for i in other if not have[i].lstrip().startswith("!")), other[0])
        a, b = have[i], want[i]
        col = next((k for k, (x, y) in enumerate(zip(a, b)) if x != y), min(len(a), len(b)))
        return f":{i + 1}:{col + 1}", (f"its line {i + 1} holds {_quoted(a, col)} where this "
                                       f"run writes {_quoted(b, col)}")
    i = min(len(have), len(want))
    if not have:
        return ":1:1", f"it is empty where this run's begins with {_quoted(want[0])}"
    if len(have) > len(want):
        return f":{i + 1}:1", f"its line {i + 1} holds {_quoted(have[i])} where this run's ends"
    return f":{i}:{len(have[i - 1]) + 1}", (f"it ends at its line {i} where this run's goes "
                                             f"on with {_quoted(want[i])}")


def _lines(text: str) -> list[str]:
    lines = text.replace("\r\n", "\n").split("\n")
    return lines[:-1] if lines[-1] == "" else lines


def _quoted(line: str, col: int = 0) -> str:
    """line in backquotes, its indentation aside; a long one from some way
    before column col (0-based), where it differs."""
    blanks = len(line) - len(line.lstrip())
    line, col = line.strip(), max(col - blanks, 0)
    if len(line) > 72:
        start = max(0, min(col - 36, len(line) - 69))
        line = ("..." if start else "") + line[start:start + 69 - (3 if start else 0)] + (
            "..." if start + 69 < len(line) else "")
    return f"`{line}`"


# ------------------------------------------------------------- the module

def support_module(tr: Transient, nl: str = "\n") -> str:
    """The RAPID support module: s as PERS data, its update, rcTcJ, and the
    operator's routines. Only instructions every IRC5 has (no options)."""
    i1, i2, i3 = "    ", "        ", "            "
    head = [
        f"MODULE {MODULE}(SYSMODULE,NOSTEPIN)",
        f"{i1}! rapidcomp transient thermal compensation, written by `rapidcomp fix --transient`.",
        f"{i1}! A compensated move goes to {FUNC_J}(cold, dq) or {FUNC_R}(cold, dq): the target",
        f"{i1}! the cold robot needs plus rcS times the warm robot's correction (the measured",
        f"{i1}! steady state).",
        f"{i1}! rcS is the thermal state: 0 cold, 1 warm. {tr.law}.",
        f"{i1}! Read it in the program data window or with rcThermalShow"
        + (", set it with rcThermalSet." if tr.signal is None else "; the sensor sets it."),
        f"{i1}! TASK PERS: each motion task (each robot of a MultiMove system) has its own.",
        f"{i1}TASK PERS num rcS:=0;",
    ]
    if tr.signal is None:
        head += [
            f"{i1}! When rcS was last updated: days since 2000-03-01 and minutes of that day.",
            f"{i1}TASK PERS num rcLastDay:=-1;",
            f"{i1}TASK PERS num rcLastMin:=0;",
            f"{i1}CONST num rcTauHeat:={_num(tr.tau_heat_min)};",
            f"{i1}CONST num rcTauCool:={_num(tr.tau_cool_min)};",
            f"{i1}CONST num rcGapMin:={_num(tr.gap_min)};",
            "",
            f"{i1}PROC rcNow(INOUT num day,INOUT num mins)",
            f"{i2}VAR string d1;",
            f"{i2}VAR string d2;",
            f"{i2}VAR string t;",
            f"{i2}VAR num y;",
            f"{i2}VAR num m;",
            f"{i2}VAR num d;",
            f"{i2}VAR num hh;",
            f"{i2}VAR num mm;",
            f"{i2}VAR num ss;",
            f"{i2}VAR bool ok;",
            f"{i2}d1:=CDate();",
            f"{i2}t:=CTime();",
            f"{i2}d2:=CDate();",
            f"{i2}IF d1<>d2 THEN",
            f"{i3}! midnight passed between the readings: read the time of the new day",
            f"{i3}t:=CTime();",
            f"{i2}ENDIF",
            f"{i2}ok:=StrToVal(StrPart(d2,1,4),y);",
            f"{i2}ok:=StrToVal(StrPart(d2,6,2),m);",
            f"{i2}ok:=StrToVal(StrPart(d2,9,2),d);",
            f"{i2}ok:=StrToVal(StrPart(t,1,2),hh);",
            f"{i2}ok:=StrToVal(StrPart(t,4,2),mm);",
            f"{i2}ok:=StrToVal(StrPart(t,7,2),ss);",
            f"{i2}! a year counted from March: the leap day is its last",
            f"{i2}IF m<3 THEN",
            f"{i3}y:=y-1;",
            f"{i3}m:=m+12;",
            f"{i2}ENDIF",
            f"{i2}y:=y-2000;",
            f"{i2}day:=365*y+y DIV 4-y DIV 100+y DIV 400+(153*(m-3)+2) DIV 5+d-1;",
            f"{i2}mins:=hh*60+mm+ss/60;",
            f"{i1}ENDPROC",
            "",
            f"{i1}PROC rcUpdate()",
            f"{i2}VAR num day;",
            f"{i2}VAR num mins;",
            f"{i2}VAR num dt;",
            f"{i2}rcNow day,mins;",
            f"{i2}IF rcLastDay>=0 THEN",
            f"{i3}! days and minutes apart: float32 holds both exactly",
            f"{i3}dt:=(day-rcLastDay)*1440+(mins-rcLastMin);",
            f"{i3}IF dt<0 THEN",
            f"{i3}    ! the clock was set back: nothing is known of the gap",
            f"{i3}    dt:=0;",
            f"{i3}ENDIF",
            f"{i3}IF dt<=rcGapMin THEN",
            f"{i3}    ! running: towards warm",
            f"{i3}    rcS:=1-(1-rcS)*Exp(-dt/rcTauHeat);",
            f"{i3}ELSE",
            f"{i3}    ! a stop, a pause or power off: towards cold",
            f"{i3}    rcS:=rcS*Exp(-dt/rcTauCool);",
            f"{i3}ENDIF",
            f"{i2}ENDIF",
            f"{i2}rcLastDay:=day;",
            f"{i2}rcLastMin:=mins;",
            f"{i1}ENDPROC",
        ]
    else:
        head += [
            f"{i1}CONST num rcTCold:={_num(tr.t_cold)};",
            f"{i1}CONST num rcTWarm:={_num(tr.t_warm)};",
            "",
            f"{i1}PROC rcUpdate()",
            f"{i2}rcS:=(AInput({tr.signal})-rcTCold)/(rcTWarm-rcTCold);",
            f"{i2}IF rcS<0 rcS:=0;",
            f"{i2}IF rcS>1 rcS:=1;",
            f"{i1}ENDPROC",
        ]
    body = [
        "",
        f"{i1}FUNC jointtarget {FUNC_J}(jointtarget cold,jointtarget dq)",
        f"{i2}VAR jointtarget jt;",
        f"{i2}rcUpdate;",
        f"{i2}jt:=cold;",
    ] + [f"{i2}jt.robax.rax_{k}:=cold.robax.rax_{k}+rcS*dq.robax.rax_{k};" for k in range(1, 7)] + [
        f"{i2}RETURN jt;",
        f"{i1}ENDFUNC",
        "",
        f"{i1}! A robtarget move keeps its kind (a MoveL its straight line): the written",
        f"{i1}! robtarget plus rcS times the correction (translation, quaternion difference).",
        f"{i1}FUNC robtarget {FUNC_R}(robtarget cold,pose dq)",
        f"{i2}VAR robtarget rt;",
        f"{i2}rcUpdate;",
        f"{i2}rt:=cold;",
        f"{i2}rt.trans.x:=cold.trans.x+rcS*dq.trans.x;",
        f"{i2}rt.trans.y:=cold.trans.y+rcS*dq.trans.y;",
        f"{i2}rt.trans.z:=cold.trans.z+rcS*dq.trans.z;",
    ] + [f"{i2}rt.rot.q{k}:=cold.rot.q{k}+rcS*dq.rot.q{k};" for k in range(1, 5)] + [
        f"{i2}rt.rot:=NOrient(rt.rot);",
        f"{i2}RETURN rt;",
        f"{i1}ENDFUNC",
        "",
    ] + ([
        f"{i1}PROC rcThermalSet(num s)",
        f"{i2}! what the operator knows: 0 cold (after a long stop), 1 warm",
        f"{i2}rcS:=s;",
        f"{i2}IF rcS<0 rcS:=0;",
        f"{i2}IF rcS>1 rcS:=1;",
        f"{i2}rcNow rcLastDay,rcLastMin;",
        f"{i1}ENDPROC",
        "",
    ] if tr.signal is None else []) + [
        f"{i1}PROC rcThermalShow()",
        f"{i2}rcUpdate;",
        f'{i2}TPWrite "rapidcomp thermal state (0 cold, 1 warm): "\\Num:=rcS;',
        f"{i1}ENDPROC",
        "ENDMODULE",
    ]
    return nl.join(head + body) + nl


def _num(x: float) -> str:
    # Plain decimals (RAPID reads 1e-05 too, but a reviewer reads 0.00001).
    return numbers.fmt(x, 6)


# ------------------------------------------------------------- verification

def f32(x) -> np.ndarray:
    return np.asarray(x, dtype=np.float32)


def state_values(cold, dq, states, joint: bool) -> np.ndarray:
    """rcTcJ(cold, dq) (joint: the 6 joints) or rcTcR's position and
    quaternion (7 numbers: cold and dq a position and a quaternion, RAPID
    order) at each thermal state of `states` (rows), as the controller
    computes them: float32 numbers and float32 arithmetic, cold + s * dq;
    rcTcR's quaternion normalized (NOrient; a spare slot no move reaches
    may hold [0,0,0,0]: left as it is)."""
    return states_values(np.reshape(cold, (1, -1)), np.reshape(dq, (1, -1)), states,
                         joint)[:, 0]


def states_values(cold, dq, states, joint: bool) -> np.ndarray:
    """state_values of each row of cold and dq (n, 6 or 7) at each state:
    (states, n, 6 or 7), the same arithmetic elementwise (a CAM program's
    1e5 calls at once)."""
    s = f32(states).reshape(-1, 1, 1)
    out = (f32(cold)[None] + f32(s * f32(dq)[None])).astype(np.float32)
    if joint:
        return out
    q = out[..., 3:].astype(float)
    # (Each row's norm as np.linalg.norm takes one vector's: its dot
    # product, which a row-wise sum does not round alike: row_dots.)
    norm = np.sqrt(row_dots(q.reshape(-1, 4))).reshape(q.shape[:-1] + (1,))
    out[..., 3:] = f32(np.divide(q, norm, out=q.copy(), where=norm > 0))
    return out

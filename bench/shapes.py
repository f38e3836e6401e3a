"""Benchmark: `rapidcomp fix` end to end on large programs of other shapes
than bench/fix.py's CAM module, as other generators write them.

    python bench/shapes.py [--size 100000] [--shapes a_movec,b_const,...] [--repeat 3]

Each shape has `size` target uses, every target reachable (random joint
vectors in the front workspace through the nominal FK, a 150 mm tool,
3 decimals mm and 6 quaternion, as bench/fix.py's); each runs once through
the command line (`fix --emit absj --allow-partial`, start-up with its
bytecode compiled, as installed), and the table gives its seconds, peak
memory (MiB, ru_maxrss of the command's process), cores, and how many uses
it compensated. Goal of issue #14 (for bench/fix.py's shape): <= 10 s and
<= 954 MiB (1 GB) at 1e5.

  bench_main / bench_nomain  bench/fix.py's module (Path called from main / by nothing)
  a_movec    MoveC only (size/2 moves), each a circle point and an end point, inline
  k_circdecl MoveC only, each a declared circle point and an inline end point
  b_const    Grasshopper: CONST robtarget path{n} := [...]; FOR i ... MoveL path{i}
  b_var      the same, VAR
  b_pers     the same, PERS
  c_robodk   RoboDK's post: 20 PROCs, each assigning rdkTool.tframe/rdkWObj.uframe,
             ConfL\\Off, inline targets
  c_plain    the same 20 PROCs with a declared tool and work object
  d_offs     MoveL Offs(pK, dx, dy, dz): 1 % declared targets, each used 100 times
  h_reltool  the same as RelTool(pK, dx, dy, dz \\Rz:=a), a whole degree in -30..30
  i_datamod  a task folder: the targets in a data module, the moves in another
  j_alldecl  the same in one module: every target declared, each moved to once
  j_alldecl_tr  j_alldecl with `--transient --tau-heat 45` (not --emit absj)
  j_alldecl_tra j_alldecl with `--transient --tau-heat 45 --emit absj` (every move
             MoveAbsJ rcTcJ(jt_pK, jt_pK_dq), two new declarations per target)
  bench_tra  bench_main with `--transient --tau-heat 45 --emit absj` (inline rcTcJ)
  e_confoff  ConfL\\Off, then inline MoveL
  f_tools    10 tools x 10 work objects, half declared, half inline
  g_mixed    MoveJ/MoveL, SetDO and WaitTime every 10 moves
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fix import (PROFILE, cam_module, flange, installed_env, joints,  # noqa: E402
                 literals)

from rapidcomp.kinematics.frames import matrix_to_quat_wxyz, quat_wxyz_to_matrix  # noqa: E402

TOOL = "  PERS tooldata tSpindle:=[TRUE,[[0,0,150],[1,0,0,0]],[2,[0,0,75],[1,0,0,0],0,0,0]];"
WOBJ = "  PERS wobjdata wPart:=[FALSE,TRUE,\"\",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];"
TAIL = ",v100,z1,tSpindle\\WObj:=wPart;"


def targets(n, seed, tool_z=150.0):
    """n reachable robtargets for a tool tool_z mm along flange z, wobj0."""
    R, p, conf = flange(joints(n, np.random.default_rng(seed)))
    return literals(R, p + R[:, :, 2] * tool_z, conf)


def module(name, decl, body_procs, main_body):
    lines = [f"MODULE {name}", *decl]
    for pname, body in body_procs:
        lines += [f"  PROC {pname}()", *("    " + s for s in body), "  ENDPROC"]
    lines += ["  PROC main()", *("    " + s for s in main_body), "  ENDPROC", "ENDMODULE", ""]
    return "\n".join(lines)


def a_movec(n, seed=1):
    t = targets(n, seed)
    body = [f"MoveC {t[2 * k]},{t[2 * k + 1]}{TAIL}" for k in range(n // 2)]
    return module("CAM_MoveC", [TOOL, WOBJ], [("Path", body)], ["Path;"])


def k_circdecl(n, seed=1):
    """MoveC with a declared circle point and an inline end point (size/2
    moves), as a program mixing taught and generated points writes them."""
    t = targets(n, seed)
    decl = [f"  CONST robtarget c{k}:={t[2 * k]};" for k in range(n // 2)]
    body = [f"MoveC c{k},{t[2 * k + 1]}{TAIL}" for k in range(n // 2)]
    return module("CAM_CircDecl", [TOOL, WOBJ, *decl], [("Arcs", body)], ["Arcs;"])


def b_array(n, kind, seed=1):
    t = targets(n, seed)
    decl = [TOOL, WOBJ, f"  {kind} robtarget path{{{n}}}:=["]
    decl += [f"    {x}," for x in t[:-1]] + [f"    {t[-1]}];"]
    body = [f"FOR i FROM 1 TO {n} DO", f"  MoveL path{{i}}{TAIL}", "ENDFOR"]
    return module("GH_Array", decl, [("GhPath", body)], ["GhPath;"])


def c_robodk(n, seed=1, plain=False, procs=20):
    """RoboDK post style: default rdkTool/rdkWObj declared, the real frames
    assigned at the top of each program, ConfJ\\On ConfL\\Off, inline
    targets with ',\\WObj:=' (plain: declared tool, none of that)."""
    t = targets(n, seed)
    per = n // procs
    if plain:
        decl, tail, head = [TOOL, WOBJ], TAIL, []
    else:
        decl = ["  PERS tooldata rdkTool:=[TRUE,[[0,0,0],[1,0,0,0]],[2,[0,0,15],[1,0,0,0],0,0,0.005]];",
                "  PERS wobjdata rdkWObj:=[FALSE,TRUE,\"\",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];",
                "  VAR speeddata rdkSpeed:=[500,500,5000,1000];"]
        tail = ",rdkSpeed,z1,rdkTool,\\WObj:=rdkWObj;"
        head = ["ConfJ \\On;", "ConfL \\Off;",
                "rdkTool.tframe:=[[0.000,0.000,150.000],[1.00000000,0.00000000,0.00000000,0.00000000]];",
                "rdkWObj.uframe:=[[0.000,0.000,0.000],[1.00000000,0.00000000,0.00000000,0.00000000]];"]
    bodies = [(f"Prog{k + 1}", head + [f"MoveL {x}{tail}" for x in t[k * per:(k + 1) * per]])
              for k in range(procs)]
    return module("MOD_RoboDK", decl, bodies, [f"Prog{k + 1};" for k in range(procs)])


def d_offs(n, seed=1, uses=100, reltool=False):
    """n // uses declared pK, each used `uses` times as Offs(pK,dx,dy,dz)
    with distinct offsets (|d| <= 20 mm); each Offs target checked with the
    nominal and warm IK (rapidcomp's own solver), re-drawn until it solves.
    reltool: RelTool(pK,dx,dy,dz \\Rz:=a) instead, a whole degree in
    -30..30 (the displacement along the target's own axes, then the turn
    about its z)."""
    from rapidcomp.compensate.load import load_solver

    solver = load_solver(str(PROFILE), None, False)
    rng = np.random.default_rng(seed)
    k = n // uses
    R, p, conf = flange(joints(k, rng))
    tcp = np.round(p + R[:, :, 2] * 150.0, 3)
    Rr = quat_wxyz_to_matrix(np.round(matrix_to_quat_wxyz(R), 6))   # as written
    ref = np.repeat(np.arange(k), uses)
    off = np.round(rng.uniform(-20, 20, (n, 3)), 1)
    turn = np.round(rng.uniform(-30, 30, n)) if reltool else np.zeros(n)
    bad = np.ones(n, bool)
    while bad.any():
        idx = np.nonzero(bad)[0]
        Rt = Rr[ref[idx]]
        if reltool:
            a = np.radians(turn[idx])
            c, s = np.cos(a), np.sin(a)
            Rz = np.zeros((len(idx), 3, 3))
            Rz[:, 0, 0], Rz[:, 0, 1], Rz[:, 1, 0], Rz[:, 1, 1], Rz[:, 2, 2] = c, -s, s, c, 1
            Rb = Rt @ Rz
            tb = tcp[ref[idx]] + np.einsum("nij,nj->ni", Rt, off[idx])
        else:
            Rb, tb = Rt, tcp[ref[idx]] + off[idx]
        pb = tb - Rb[:, :, 2] * 150.0
        _, comp = solver.compensate(Rb, pb, conf[ref[idx]].astype(float))
        ok = np.asarray(comp.success)
        bad[idx[ok]] = False
        m = int((~ok).sum())
        off[idx[~ok]] = np.round(rng.uniform(-20, 20, (m, 3)), 1)
        if reltool:
            turn[idx[~ok]] = np.round(rng.uniform(-30, 30, m))
    decl = [TOOL, WOBJ] + [f"  CONST robtarget p{j}:={x};" for j, x in
                           enumerate(literals(R, tcp, conf))]
    if reltool:
        body = [f"MoveL RelTool(p{ref[i]},{off[i, 0]:g},{off[i, 1]:g},{off[i, 2]:g} "
                f"\\Rz:={turn[i]:g}){TAIL}" for i in range(n)]
    else:
        body = [f"MoveL Offs(p{ref[i]},{off[i, 0]:g},{off[i, 1]:g},{off[i, 2]:g}){TAIL}"
                for i in range(n)]
    return module("CAM_RelTool" if reltool else "CAM_Offs", decl, [("Path", body)], ["Path;"])


def i_datamod(n, seed=1, folder=True):
    """A task folder as a cell keeps one: the tool, the work object and the
    n targets (CONST, global) in a data module, the moves in another.
    folder=False: all in one module (RobotStudio's own way: every target
    declared, each moved to once)."""
    t = targets(n, seed)
    decl = [f"  CONST robtarget p{i}:={x};" for i, x in enumerate(t)]
    body = [("Path", [f"MoveL p{i}{TAIL}" for i in range(n)])]
    if not folder:
        return module("PathAll", [TOOL, WOBJ, *decl], body, ["Path;"])
    data = "\n".join(["MODULE PathData", TOOL, WOBJ, *decl, "ENDMODULE", ""])
    return {"PathData.mod": data, "PathMain.mod": module("PathMain", [], body, ["Path;"])}


def e_confoff(n, seed=1):
    t = targets(n, seed)
    return module("CAM_ConfOff", [TOOL, WOBJ], [],
                  ["ConfL\\Off;"] + [f"MoveL {x}{TAIL}" for x in t])


def _quat(axis, deg):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    h = np.radians(deg) / 2
    return np.r_[np.cos(h), np.sin(h) * a]


def _qstr(q):
    return ",".join(f"{v:.9f}" for v in q)


def f_tools(n, seed=1, k=10):
    """k tooldata and k wobjdata; move i uses tool i%k, wobj (i//k)%k
    (all 100 pairs); half declared, half inline targets as cam_module."""
    rng = np.random.default_rng(seed)
    q = joints(n, rng)
    Rf, pf, conf = flange(q)
    tools, wobjs, decl = [], [], []
    for j in range(k):
        tt = np.array([rng.uniform(-30, 30), rng.uniform(-30, 30), rng.uniform(100, 220)])
        tq = _quat([rng.uniform(-1, 1), rng.uniform(-1, 1), 0], rng.uniform(0, 25))
        tools.append((quat_wxyz_to_matrix(np.round(tq, 9)), tt))
        decl.append(f"  PERS tooldata tTool{j}:=[TRUE,[[{tt[0]:.3f},{tt[1]:.3f},{tt[2]:.3f}],"
                    f"[{_qstr(tq)}]],[1.5,[0,0,60],[1,0,0,0],0,0,0]];")
    for j in range(k):
        ut = np.array([rng.uniform(-300, 300), rng.uniform(-300, 300), rng.uniform(-100, 200)])
        uq = _quat([0, 0, 1], rng.uniform(-90, 90))
        ot = np.array([rng.uniform(-50, 50), rng.uniform(-50, 50), rng.uniform(0, 50)])
        oq = _quat([0, 0, 1], rng.uniform(-30, 30))
        wobjs.append(((quat_wxyz_to_matrix(np.round(uq, 9)), ut),
                      (quat_wxyz_to_matrix(np.round(oq, 9)), ot)))
        decl.append(f"  TASK PERS wobjdata wCell{j}:=[FALSE,TRUE,\"\",[[{ut[0]:.3f},{ut[1]:.3f},"
                    f"{ut[2]:.3f}],[{_qstr(uq)}]],[[{ot[0]:.3f},{ot[1]:.3f},{ot[2]:.3f}],"
                    f"[{_qstr(oq)}]]];")
    ti = np.arange(n) % k
    wi = (np.arange(n) // k) % k
    Rt = np.empty_like(Rf)
    pt = np.empty_like(pf)
    for j in range(k):
        m = ti == j
        R_t, p_t = tools[j]
        pt[m] = pf[m] + Rf[m] @ p_t
        Rt[m] = Rf[m] @ R_t
    for j in range(k):
        m = wi == j
        (Ru, pu), (Ro, po) = wobjs[j]
        Rw, pw = Ru @ Ro, pu + Ru @ po                        # base_M_object
        pt[m] = (pt[m] - pw) @ Rw                               # Rw^T (p - pw)
        Rt[m] = Rw.T @ Rt[m]
    t = literals(Rt, pt, conf)
    half = n // 2
    decl += [f"  CONST robtarget p{i}:={t[i]};" for i in range(half)]
    tail = [f",v100,z1,tTool{ti[i]}\\WObj:=wCell{wi[i]};" for i in range(n)]
    body = [f"MoveL p{i}{tail[i]}" for i in range(half)]
    body += [f"MoveL {t[i]}{tail[i]}" for i in range(half, n)]
    return module("CAM_Tools", decl, [("Path", body)], ["Path;"])


def g_mixed(n, seed=1):
    """MoveJ / MoveL mixed (every 5th move a MoveJ), SetDO + WaitTime
    between every 10 moves; half declared, half inline."""
    t = targets(n, seed)
    half = n // 2
    decl = [TOOL, WOBJ] + [f"  CONST robtarget p{i}:={t[i]};" for i in range(half)]
    body = []
    for i in range(n):
        if i and i % 10 == 0:
            body += [f"SetDO doSpindle,{(i // 10) % 2};", "WaitTime 0.1;"]
        instr = "MoveJ" if i % 5 == 0 else "MoveL"
        tgt = f"p{i}" if i < half else t[i]
        speed = "v500,z10" if instr == "MoveJ" else "v100,z1"
        body.append(f"{instr} {tgt},{speed},tSpindle\\WObj:=wPart;")
    return module("CAM_Mixed", decl, [("Path", body)], ["Path;"])


SHAPES = {
    "bench_main": lambda n: cam_module(n, main=True),
    "bench_nomain": lambda n: cam_module(n),
    "a_movec": a_movec,
    "k_circdecl": k_circdecl,
    "b_const": lambda n: b_array(n, "CONST"),
    "b_var": lambda n: b_array(n, "VAR"),
    "b_pers": lambda n: b_array(n, "PERS"),
    "c_robodk": c_robodk,
    "c_plain": lambda n: c_robodk(n, plain=True),
    "d_offs": d_offs,
    "h_reltool": lambda n: d_offs(n, reltool=True),
    "i_datamod": i_datamod,
    "j_alldecl": lambda n: i_datamod(n, folder=False),
    "j_alldecl_tr": lambda n: i_datamod(n, folder=False),
    "j_alldecl_tra": lambda n: i_datamod(n, folder=False),
    "bench_tra": lambda n: cam_module(n, main=True),
    "e_confoff": e_confoff,
    "f_tools": f_tools,
    "g_mixed": g_mixed,
}



# Shapes run with other options than `--emit absj`.
MODES = {"j_alldecl_tr": ("--transient", "--tau-heat", "45"),
         "j_alldecl_tra": ("--transient", "--tau-heat", "45", "--emit", "absj"),
         "bench_tra": ("--transient", "--tau-heat", "45", "--emit", "absj")}


def run(path: str, out: str, env: dict, mode: tuple = ("--emit", "absj")) -> dict:
    """`rapidcomp fix` on path, end to end in a process of its own: seconds,
    peak MiB, cores (wait4's CPU time counts the children it reaped), exit
    code and its summary's counts."""
    t = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "rapidcomp", "fix", path, "--profile",
                             str(PROFILE), *mode, "--allow-partial", "-o", out],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    text = proc.stdout.read()
    _, status, usage = os.wait4(proc.pid, 0)
    seconds = time.perf_counter() - t
    m = re.search(r"(\d+) of (\d+) target uses compensated", text)
    if m is None:
        raise SystemExit(f"rapidcomp fix {path} printed no summary:\n{text}")
    return {"s": seconds, "peak_MiB": usage.ru_maxrss / 1024,
            "cores": (usage.ru_utime + usage.ru_stime) / seconds,
            "rc": os.waitstatus_to_exitcode(status), "done": int(m.group(1)),
            "uses": int(m.group(2))}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=int, default=100000)
    ap.add_argument("--shapes", default=",".join(SHAPES))
    # (This machine's speed moves by up to a quarter from one hour to the
    # next: the median of a few runs, with their range, says more of a
    # shape at the goal's edge than one run.)
    ap.add_argument("--repeat", type=int, default=1,
                    help="runs per shape: seconds is their median, with min-max")
    args = ap.parse_args()
    print(f"{'shape':<13} {'uses':>7} {'MB':>6} {'seconds':>8} {'peak MiB':>9} {'cores':>6} "
          f"{'compensated':>12} {'rc':>3}" + ("  seconds min-max" if args.repeat > 1 else ""))
    with tempfile.TemporaryDirectory() as tmp:
        env = installed_env(str(Path(tmp) / "pycache"))
        for name in args.shapes.split(","):
            made = SHAPES[name](args.size)
            if type(made) is dict:
                # (A task folder: its modules, the output a folder too.)
                path = Path(tmp) / name
                path.mkdir()
                for file, text in made.items():
                    (path / file).write_text(text)
                size = sum(f.stat().st_size for f in path.iterdir())
                out = Path(tmp) / f"{name}_comp"
            else:
                path = Path(tmp) / f"{name}.mod"
                path.write_text(made)
                size = path.stat().st_size
                out = Path(tmp) / f"{name}_comp.mod"
            made = None
            runs = sorted((run(str(path), str(out), env, MODES.get(name, ("--emit", "absj")))
                           for _ in range(max(1, args.repeat))), key=lambda r: r["s"])
            r = runs[len(runs) // 2]
            spread = (f"  {runs[0]['s']:.2f}-{runs[-1]['s']:.2f}" if len(runs) > 1 else "")
            print(f"{name:<13} {r['uses']:>7} {size / 1e6:>6.1f} {r['s']:>8.2f} "
                  f"{max(x['peak_MiB'] for x in runs):>9.0f} {r['cores']:>6.2f} {r['done']:>12} "
                  f"{r['rc']:>3}{spread}", flush=True)
            shutil.rmtree(path) if path.is_dir() else path.unlink()


if __name__ == "__main__":
    main()

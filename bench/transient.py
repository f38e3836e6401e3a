"""A shift, simulated (issue #13): the IRB 140 runs the paper's 72 cube
points for 2 h, stands 30 min, runs 2 h more. Its true thermal state
follows the first-order law with a hidden tau (45 min heating, 45 min
cooling) and deforms it by s . profile (fixtures/warm.csv at s = 1). Every
minute of running, the TCP error over the 72 points (max and mean) with

- no compensation (the program's own joints),
- steady-state compensation (`fix`: the joints of the warm robot),
- transient compensation (`fix --transient`: q_cold + s_model . dq in
  float32, s_model from the generated module's law, here its Python twin
  compensate/transient.state_after, tested against the RAPID), with the
  true tau and with the model's tau 20 % too short and too long.

    python bench/transient.py [--plot bench/transient.png]

Prints the worst error per strategy and phase, and seconds per stage.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rapidcomp.compensate.transient import Transient, state_after, state_joints
from rapidcomp.discover.points import cube_points
from rapidcomp.kinematics.chain import Chain
from rapidcomp.kinematics.conf import confdata
from rapidcomp.kinematics.frames import DEG
from rapidcomp.kinematics.ik import Solver
from rapidcomp.kinematics.profile import deform, read_profile, scaled
from rapidcomp.kinematics.robot import irb140, override_limits

TAU_TRUE = 45.0
SCHEDULE = (("run", 120), ("stand", 30), ("run", 120))   # minutes
STEP_MIN = 1.0
MOVE_EVERY_MIN = 10 / 60     # a compensated move every 10 s while running


def true_states(tau: float) -> tuple[np.ndarray, np.ndarray, list]:
    """(t, s) every STEP_MIN of running, and the phase of each sample."""
    law = Transient(tau, tau, 2.0)
    t, s, out_t, out_s, phase = 0.0, 0.0, [], [], []
    for n, (kind, minutes) in enumerate(SCHEDULE):
        steps = int(round(minutes / STEP_MIN))
        for _ in range(steps):
            t += STEP_MIN
            if kind == "run":
                s = 1 - (1 - s) * np.exp(-STEP_MIN / law.tau_heat_min)
                out_t.append(t)
                out_s.append(s)
                phase.append(n)
            else:
                s = s * np.exp(-STEP_MIN / law.tau_cool_min)
    return np.array(out_t), np.array(out_s), phase


def model_states(tau: float, times: np.ndarray) -> np.ndarray:
    """The controller's s at `times`: the generated module's law, updated
    at every compensated move (every MOVE_EVERY_MIN while running); the
    stop is one gap longer than --gap."""
    law = Transient(tau, tau, 2.0)
    s, last, out = 0.0, None, []
    t = 0.0
    clock = []
    for kind, minutes in SCHEDULE:
        if kind == "run":
            n = int(round(minutes / MOVE_EVERY_MIN))
            clock += [t + (k + 1) * MOVE_EVERY_MIN for k in range(n)]
        t += minutes
    clock = np.array(clock)
    k = 0
    for when in times:
        while k < len(clock) and clock[k] <= when + 1e-9:
            if last is not None:
                s = state_after(s, clock[k] - last, law)
            last = clock[k]
            k += 1
        out.append(s)
    return np.array(out)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--plot", default=None, help="write the figure (needs matplotlib)")
    args = ap.parse_args()
    stages = {}
    t0 = time.perf_counter()
    # As the README's quickstart: the paper's side cube needs J5 to 116.9 deg.
    robot = override_limits(irb140(), ["J5=-120:120"])
    profile = read_profile("fixtures/warm.csv")
    _, q_prog = cube_points(robot)
    chain = Chain.from_robot(robot)
    R, p = chain.fk(q_prog * DEG)
    warm = Solver(robot, deform(robot, profile))
    # The program's joints are the nominal solution (its confdata are the
    # joints' own); the deformed one is found from it, as fix does.
    _, ps = chain.joint_frames(q_prog * DEG)
    conf = confdata(q_prog * DEG, ps[:, 4], warm.geometry.phi)
    nominal = warm.solve_nominal(R, p, conf)
    assert np.allclose(nominal.q_deg, q_prog, atol=1e-6), "cube branch"
    compensated = warm.solve_deformed(R, p, nominal)
    assert compensated.success.all()
    q_cold, dq = nominal.q_deg, compensated.q_deg - nominal.q_deg
    stages["solve"] = time.perf_counter() - t0

    t1 = time.perf_counter()
    times, s_true, phase = true_states(TAU_TRUE)
    strategies = {"none": lambda s_model: q_prog,
                  "steady state": lambda s_model: compensated.q_deg}
    taus = {"transient, tau true": TAU_TRUE, "transient, tau -20 %": 0.8 * TAU_TRUE,
            "transient, tau +20 %": 1.2 * TAU_TRUE}
    s_models = {name: model_states(tau, times) for name, tau in taus.items()}
    errors = {name: np.zeros((len(times), 2)) for name in list(strategies) + list(taus)}
    cache = {}
    for n, (t, s) in enumerate(zip(times, s_true)):
        key = round(float(s), 12)
        if key not in cache:
            cache[key] = Chain.from_robot(deform(robot, scaled(profile, s)))
        true_robot = cache[key]
        runs = {name: f(None) for name, f in strategies.items()}
        for name in taus:
            runs[name] = state_joints(q_cold, dq, s_models[name][n]).astype(float)
        for name, q in runs.items():
            _, pp = true_robot.fk(np.asarray(q, float) * DEG)
            d = np.linalg.norm(pp - p, axis=1) * 1000
            errors[name][n] = d.max(), d.mean()
    stages["simulate"] = time.perf_counter() - t1

    print(f"A shift on the IRB 140, the paper's 72 points: run {SCHEDULE[0][1]} min, stand "
          f"{SCHEDULE[1][1]} min, run {SCHEDULE[2][1]} min; true tau {TAU_TRUE:g} min "
          "(heating and cooling)")
    print(f"{'strategy':<24}{'max um':>9}{'first run':>11}{'after stop':>12}{'last hour':>11}")
    last_hour = times > times[-1] - 60
    for name, e in errors.items():
        ph = np.array(phase)
        print(f"{name:<24}{e[:, 0].max():9.1f}{e[ph == 0, 0].max():11.1f}"
              f"{e[ph == 2, 0].max():12.1f}{e[last_hour, 0].max():11.1f}")
    print("seconds: " + ", ".join(f"{k} {v:.2f}" for k, v in stages.items()))
    if args.plot:
        plot(args.plot, times, s_true, errors)


def plot(path: str, times, s_true, errors) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax0, ax1) = plt.subplots(2, 1, figsize=(8, 6), sharex=True,
                                   gridspec_kw={"height_ratios": [1, 3]})
    # The state through the stop too (the law, every minute).
    law = Transient(TAU_TRUE, TAU_TRUE, 2.0)
    tt, ss, t, s = [0.0], [0.0], 0.0, 0.0
    for kind, minutes in SCHEDULE:
        for _ in range(int(round(minutes / STEP_MIN))):
            t += STEP_MIN
            s = (1 - (1 - s) * np.exp(-STEP_MIN / law.tau_heat_min)) if kind == "run" \
                else s * np.exp(-STEP_MIN / law.tau_cool_min)
            tt.append(t)
            ss.append(s)
    ax0.plot(tt, ss, "-", color="black", lw=1.2)
    ax0.set_ylabel("thermal state s")
    ax0.set_ylim(0, 1)
    ax0.axvspan(SCHEDULE[0][1], SCHEDULE[0][1] + SCHEDULE[1][1], color="0.9")
    styles = {"none": ("tab:red", "-"), "steady state": ("tab:orange", "-"),
              "transient, tau true": ("tab:green", "-"),
              "transient, tau -20 %": ("tab:blue", "--"),
              "transient, tau +20 %": ("tab:purple", ":")}
    # No line across the stop: the robot does not work there.
    gap = np.flatnonzero(np.diff(times) > 1.5 * STEP_MIN)
    tx = np.insert(times, gap + 1, np.nan)
    for name, e in errors.items():
        color, ls = styles[name]
        ax1.plot(tx, np.insert(e[:, 0], gap + 1, np.nan), ls, color=color, lw=1.2, label=name)
    ax1.axvspan(SCHEDULE[0][1], SCHEDULE[0][1] + SCHEDULE[1][1], color="0.9")
    ax1.axhline(10, color="0.5", lw=0.8, ls="-.", label="10 um")
    ax1.set_ylabel("max TCP error over the 72 points, um")
    # Log scale: 1 um and 300 um on one figure.
    ax1.set_yscale("log")
    ax1.set_xlabel("minutes since a cold start (grey: the robot stands)")
    ax1.set_ylim(0.1, 3000)
    ax1.legend(fontsize=8, loc="upper center", ncol=3, framealpha=0.9)
    fig.tight_layout()
    fig.savefig(path, dpi=110, metadata={"Software": None})
    print(f"wrote {path}")


if __name__ == "__main__":
    main()

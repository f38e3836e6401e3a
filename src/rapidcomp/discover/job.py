"""`rapidcomp discover` and `rapidcomp simulate` as calls: load, compute,
render every output in memory. The caller writes the files all at once
(atomic.py) so that bad input leaves nothing behind."""

from __future__ import annotations

import os
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..atomic import utf8
from ..errors import InputError, RapidcompError
from ..kinematics.gravity import Payload
from ..progress import Progress
from ..kinematics.profile import ThermalProfile, format_profile, parse_profile, read_profile
from . import plot, report, warmup
from .stats import chi2_ppf
from .effects import THERMAL_KINDS, catalogue, to_profile
from .heldout import held_out
from .measured import format_measured, read_joints, read_measured
from .model import ParamModel
from .plausible import writable
from .points import cube_points, random_points
from .select import Discovery, discover
from .simulate import add_noise, detectability, parse_effect_values, simulate_positions


MIN_DISTINCT_POSES = 6
MAX_RANDOM_POINTS = 100_000
# Rows of one simulated file (a warm-up campaign: points x rounds): as many
# as random:N's most.
MAX_ROWS = MAX_RANDOM_POINTS


@dataclass(frozen=True)
class Outcome:
    summary: tuple[str, ...]
    notes: tuple[str, ...]
    files: tuple[tuple[str, bytes], ...]
    discovery: Discovery | None = None


def _load(robot: str | None, profile: str | None, force: bool, payload):
    from ..compensate.load import load_robot
    nominal = load_robot(robot)
    if profile:
        prof = read_profile(profile, force=force, joint_names=nominal.joint_names)
    else:
        prof = ThermalProfile((), "<none>")
    if payload is not None:
        prof = replace(prof, payload=Payload(payload[0], tuple(payload[1:])))
    return nominal, prof


def _check_outputs(outputs, inputs) -> None:
    seen = set()
    for path in outputs:
        real = os.path.realpath(path)
        if real in seen or any(os.path.realpath(i) == real for i in inputs if i):
            raise RapidcompError(f"{path}: would overwrite an input or another output")
        seen.add(real)


def _payload_text(p: Payload) -> str:
    if p.mass_kg <= 0:
        return "none"
    return f"{p.mass_kg:g} kg at ({', '.join(f'{x:g}' for x in p.com_mm)}) mm in the flange frame"


def run_discover(measured: str, profile: str | None = None, robot: str | None = None,
                 tool=(0.0, 0.0, 0.0), payload=None, sigma: float | None = None,
                 report_path: str | None = None, json_path: str | None = None,
                 plot_path: str | None = None, out_profile: str | None = None,
                 force: bool = False, test: str | None = None,
                 register: bool = False) -> Outcome:
    outputs = [p for p in (report_path, json_path, plot_path, out_profile) if p]
    _check_outputs(outputs, [measured, profile, robot, test])
    if sigma is not None and not sigma > 0:
        raise RapidcompError(f"--sigma {sigma}: expected a positive standard deviation in mm")
    nominal, prof = _load(robot, profile, force, payload)
    # (Fewer rows than the poses it needs: said as that rule, not a smaller.)
    data = read_measured(measured, min_points=MIN_DISTINCT_POSES)
    distinct = len(np.unique(np.round(data.q_deg, 6), axis=0))
    if distinct < MIN_DISTINCT_POSES:
        raise RapidcompError(f"{measured}: {len(data)} rows but {distinct} distinct pose(s); "
                             f"discover needs at least {MIN_DISTINCT_POSES} different poses "
                             "(a base frame alone has 6 parameters)")
    test_data = read_measured(test, min_points=1) if test else None
    for d_ in (data, test_data):
        if d_ is not None and d_.tool is not None and any(tool):
            raise RapidcompError(f"{d_.source}: the measuring point is given per row (tx, ty, "
                                 "tz) and by --tool; give it once")
    notes = []
    if register:
        data, text = registered(nominal, prof, data, tool)
        notes.append(text)
        if test_data is not None:
            test_data, text = registered(nominal, prof, test_data, tool)
            notes.append("test " + text)
    model = ParamModel(nominal, prof, data.q_deg, _tool(data, tool), approach=data.approach)
    effects = catalogue(nominal)
    progress = Progress(Path(measured).name)
    d = discover(model, data, effects, sigma, progress.stage)
    progress.done()
    heldout = None
    if test_data is not None:
        test_model = ParamModel(nominal, prof, test_data.q_deg, _tool(test_data, tool),
                                approach=test_data.approach)
        if d.warmup is not None and d.warmup.tau_min is not None:
            if test_data.t_min is None:
                raise RapidcompError(f"--test {Path(test).name}: the model has thermal effects "
                                     "(the data are a warm-up campaign); the test poses need a "
                                     "t_min column too")
            if d.warmup.state_from is not None and d.warmup.state_from not in dict(
                    test_data.temperatures):
                raise RapidcompError(f"--test {Path(test).name}: the thermal state comes from "
                                     f"{d.warmup.state_from}; the test poses need that column")
            if d.warmup.tau_cool_min is not None and test_data.stood_min is None:
                raise RapidcompError(f"--test {Path(test).name}: the campaign has stops "
                                     "(stood_min); the test poses need that column too")
            test_model = test_model.with_state(d.warmup.states(test_data.t_min,
                                                               test_data.temperatures,
                                                               test_data.stood_min))
        heldout = held_out(test_model, test_data, d.final_fit, d.sigma_mm)
        if not heldout.holds and d.verdict != "unexplained":
            # (Evidence over claims: what the fit called noise is not noise
            # where it was not fitted.)
            d = replace(d, verdict="unexplained", verdict_text=(
                f"{d.verdict_text} But on the {heldout.points} poses of {Path(test).name}, not "
                f"fitted, the final model is off by RMS {heldout.rms_mm * 1000:.1f} um (max "
                f"{heldout.max_mm * 1000:.1f} um), not measurement noise of "
                f"{d.sigma_mm * 1000:.1f} um per axis (chi-square p = {heldout.p:.3g}): the "
                "model does not hold where it was not fitted (poses too few or too alike to tell "
                "the effects apart, or an effect outside the catalogue)."))
    notes += _beyond_limits(data, nominal) + list(d.notes)
    if test_data is not None:
        notes += [f"test {n}" for n in _beyond_limits(test_data, nominal)]
    if data.ignored_columns:
        notes.append(f"{Path(measured).name}: column(s) {', '.join(data.ignored_columns)} "
                     "ignored")
    meta = {"measured": Path(measured).name,
            "model": (f"{Path(robot).name if robot else 'irb140'} + "
                      f"{Path(profile).name if profile else 'no profile'}"),
            "measuring point": (f"({', '.join(f'{x:g}' for x in tool)}) mm in the flange frame"
                                if data.tool is None else
                                f"per row (tx, ty, tz): {len(np.unique(data.tool, axis=0))} "
                                "different points"),
            "payload": _payload_text(prof.payload)}
    files = []
    plot_note = None
    if plot_path:
        if plot.available():
            files.append((plot_path, plot.residual_plot(
                data.xyz_mm[d.kept], d.initial_residuals, d.final_fit.residuals,
                f"{Path(measured).name}: measured - simulated", d.sigma_mm)))
        else:
            plot_note = plot.MISSING
            notes.append(plot.MISSING)
    profile_file = None
    if out_profile and d.far_apart:
        notes.append(f"{Path(out_profile).name} not written: the data and the model are far "
                     "apart (see the verdict); a profile from them would move the robot by what "
                     "the measurement set-up got wrong")
    elif out_profile and d.undetermined:
        notes.append(f"{Path(out_profile).name} not written: these data do not determine "
                     f"{', '.join(eid for eid, _ in d.undetermined)} (see the verdict); a "
                     "profile of its fitted value would move the robot by a guess")
    elif out_profile and heldout is not None and not heldout.holds:
        notes.append(f"{Path(out_profile).name} not written: the final model does not hold on "
                     f"the held-out poses of {Path(test).name} (see the verdict)")
    elif out_profile:
        values = d.named_values()
        warm = d.warmup is not None and d.warmup.tau_min is not None
        # (With --register the data were moved onto the model: a base frame
        # named after it is what the registration left, not the robot's.)
        kept = {e: v for e, v in values.items()
                if writable(e, e.user(v)) and e.kind not in ("backlash", "cyclic")
                and (e.thermal or not warm) and not (register and e.kind == "base_frame")}
        for e in values:
            if warm and not e.thermal and e.kind not in ("backlash", "cyclic"):
                notes.append(f"{e.id} is static (the robot's geometry, not heat): not written "
                             f"into {Path(out_profile).name}, the thermal profile that fix "
                             "--transient scales with the thermal state")
            elif e.kind == "backlash":
                notes.append(f"{e.id} is not written into {Path(out_profile).name}: a profile "
                             "corrects every move alike, backlash depends on the direction each "
                             "move approaches its target from")
            elif e.kind == "cyclic":
                notes.append(f"{e.id} is not written into {Path(out_profile).name}: a profile "
                             "holds no function of a joint's angle")
            elif register and e.kind == "base_frame":
                notes.append(f"{e.id} is not written into {Path(out_profile).name}: --register "
                             "moved the data onto the model, so where the robot's base lies in "
                             "them is what the registration left over, not the robot's")
            elif e not in kept:
                notes.append(f"{e.id} is not written into {Path(out_profile).name}: at "
                             f"{', '.join(f'{k}={x:.4g}' for k, x in e.user(values[e]).items())} "
                             "it is an error of the measurement set-up (frame registration, "
                             "measuring point), not of the robot")
        def comments(kept):
            out = [f"written by rapidcomp discover from {Path(measured).name} "
                   f"(base profile: {Path(profile).name if profile else 'none'})",
                   "effects: " + (", ".join(e.id for e in kept) or "none")]
            if warm:
                out += ["the thermal effects at the steady state (s = 1); fix --transient "
                        "takes tau from the next line",
                        f"tau_heat_min: {d.warmup.tau_min:.4g}"]
                if d.warmup.tau_cool_min is not None:
                    out.append(f"tau_cool_min: {d.warmup.tau_cool_min:.4g}")
                    out.append("cooling time constant, 95% interval: "
                               + warmup.interval_text(*d.warmup.cool_interval, fmt=".4g")
                               + (" (poorly told by the stops: measure longer ones)"
                                  if warmup.LONGER_STOPS in d.warmup.advice else ""))
                for x in d.warmup.sensors:
                    if x.chi_vs_time > chi2_ppf(0.99, 1):
                        continue     # the points follow it worse than time
                    out.append(f"{x.name}: {x.t_cold:.1f} deg C cold, {x.t_warm:.1f} warm: "
                               f"fix --transient --temperature SIGNAL:{x.t_cold:.1f}:"
                               f"{x.t_warm:.1f} reads the state from it")
            if any(e.kind == "tool_offset" for e in kept):
                out.append("tool_offset is written into the flange row; if it is an error of "
                           "the measuring point's mounting, not of the robot, remove it "
                           "before using this profile with fix")
            return out

        campaign = d.warmup is not None
        if warm and not kept:
            notes.append(f"{Path(out_profile).name} not written: the data change over time, but "
                         "no thermal effect is named (nothing for fix --transient to scale)")
        else:
            if warm and not prof.is_zero:
                # The base profile was a static part of the model here: a
                # thermal profile holds the thermal effects alone.
                notes.append(f"the base profile {Path(profile).name} is not written into "
                             f"{Path(out_profile).name}: in this warm-up campaign it was part of "
                             "the static model")
            base = ThermalProfile(()) if warm else prof
            static = campaign and not warm

            def marked(kept):
                return comments(kept) + ([
                    "static: nothing changed over time in the warm-up campaign; fix "
                    "--transient refuses this profile (it would scale geometry with the "
                    "thermal state)"] if static else [])
            if static:
                notes.append(f"{Path(out_profile).name}: nothing changed over time, so its "
                             "effects are static (geometry); marked so, fix --transient refuses "
                             "it")
            text = _loadable_profile(nominal, base, kept, marked, Path(out_profile).name, notes)
            profile_file = (out_profile, utf8(text))
    # (Made once the profile is decided: they say the notes the console
    # says, the profile's among them; written before it, as always.)
    if report_path:
        files.append((report_path, utf8(report.markdown(d, meta, plot_note, heldout,
                                                        tuple(notes)))))
    if json_path:
        files.append((json_path, utf8(report.as_json(d, heldout, tuple(notes)))))
    if profile_file is not None:
        files.append(profile_file)
    return Outcome(tuple(report.summary_lines(d, heldout)), tuple(notes), tuple(files), d)


def _tool(data, tool) -> np.ndarray:
    """The measuring point of every row: the data's own, else --tool."""
    return data.tool if data.tool is not None else np.asarray(tool, float)


def registered(nominal, prof, data, tool):
    """Data measured in the tracker's own frame, moved rigidly onto the
    nominal model's positions (least squares, Kabsch): (the data in the
    robot's base frame, what was done). The base_frame effect then finds
    what is left of the registration."""
    model = ParamModel(nominal, prof, data.q_deg, _tool(data, tool), approach=data.approach)
    target, _ = model.evaluate((), (), jacobian=False)
    src = data.xyz_mm
    a0, b0 = src.mean(axis=0), target.mean(axis=0)
    U, _, Vt = np.linalg.svd((src - a0).T @ (target - b0))
    d = np.sign(np.linalg.det(Vt.T @ U.T))
    R = Vt.T @ np.diag([1.0, 1.0, d]) @ U.T
    t = b0 - R @ a0
    moved = src @ R.T + t
    angle = np.degrees(np.arccos(np.clip((np.trace(R) - 1) / 2, -1.0, 1.0)))
    rms = float(np.sqrt(np.mean(np.sum((moved - target) ** 2, axis=1))))
    text = (f"{Path(data.source).name} registered onto the nominal model: turned {angle:.4g} "
            f"deg, moved ({', '.join(f'{v:.4g}' for v in t)}) mm; {rms * 1000:.1f} um RMS "
            "left for discover")
    return replace(data, xyz_mm=moved), text


def _row_of(e, names) -> str:
    if e.kind == "base_frame":
        return "base"
    if e.kind == "tool_offset" or e.joint is None or e.joint >= len(names):
        return "flange"
    return names[e.joint]


def _loadable_profile(nominal, prof, kept: dict, comments, name: str, notes: list) -> str:
    # comments: the profile's comment lines for the effects written.
    """The profile text with the named effects, every row within what the
    profile reader accepts without --force (what fix and check load): a row
    that the base profile and the effects together take past that loses the
    effects on it, with a note."""
    names = nominal.joint_names
    kept = dict(kept)
    while True:
        text = format_profile(to_profile(nominal, prof, kept), names, comments(kept))
        try:
            parse_profile(text, name, joint_names=names)
            return text
        except InputError as exc:
            row = text.splitlines()[exc.line - 1].split(",")[0] if exc.line else None
            drop = [e for e in kept if _row_of(e, names) == row]
            if not drop:
                notes.append(f"{name}: {exc.message}, as in the base profile: it loads only "
                             "with --force")
                return text
            for e in drop:
                del kept[e]
            notes.append(f"{', '.join(e.id for e in drop)} not written into {name}: with the "
                         f"base profile, row {row} would be beyond what a profile holds "
                         f"({exc.message})")


def _beyond_limits(data, robot) -> list[str]:
    lo, hi = np.asarray(robot.lower_deg), np.asarray(robot.upper_deg)
    # (A pose measured in every round of a campaign is one note, not one a
    # round: a new user read seven of S21.)
    by_joints: dict[tuple, list[str]] = {}
    for name, q in zip(data.names, data.q_deg):
        bad = [f"J{j + 1} {q[j]:g}" for j in range(len(q)) if not lo[j] <= q[j] <= hi[j]]
        if bad:
            by_joints.setdefault((tuple(q.tolist()), ", ".join(bad)), []).append(name)
    out = []
    for (_, bad), names in by_joints.items():
        if len(names) == 1:
            out.append(f"point {names[0]}: {bad} beyond the model's joint limits")
        else:
            shown = ", ".join(names[:2]) + (f" and {len(names) - 2} more" if len(names) > 2
                                            else "")
            out.append(f"points {shown} (the same joints): {bad} beyond the model's joint "
                       "limits")
    if len(out) > 5:
        out = out[:5] + [f"... {len(out) - 5} more points beyond the joint limits"]
    return out


def point_set(spec: str, robot, seed: int):
    """`cube`, `random:N` or a CSV of joints."""
    if spec == "cube":
        return cube_points(robot)
    if spec.startswith("random"):
        try:
            count = int(spec.split(":", 1)[1]) if ":" in spec else 80
        except ValueError:
            count = 0
        if not 1 <= count <= MAX_RANDOM_POINTS:
            raise RapidcompError(f"--points {spec}: expected random:N with 1 <= N <= "
                                 f"{MAX_RANDOM_POINTS} (a campaign measures hundreds of poses)")
        return random_points(robot, count, seed)
    if not os.path.isfile(spec):
        raise RapidcompError(f"--points {spec}: expected cube, random:N or a CSV file of joints "
                             "(point,j1..j6)")
    return read_joints(spec)


# A temperature sensor's noise in a simulated campaign, deg C.
SENSOR_NOISE_C = 0.05


def run_simulate(output: str, points: str = "cube", profile: str | None = None,
                 robot: str | None = None, tool=(0.0, 0.0, 0.0), payload=None,
                 effects=(), noise: float = 0.005, seed: int = 0,
                 table_path: str | None = None, force: bool = False,
                 campaign=None) -> Outcome:
    """campaign: (times, thermal effect specs, tau) for a warm-up campaign:
    the points measured at each time, thermal effects at s(t) times their
    steady-state values."""
    _check_outputs([p for p in (output, table_path) if p],
                   [profile, robot, points if os.path.isfile(points) else None])
    if not noise >= 0:
        raise RapidcompError(f"--noise {noise}: expected a standard deviation >= 0 in mm")
    nominal, prof = _load(robot, profile, force, payload)
    cat = catalogue(nominal)
    values = parse_effect_values(cat, effects, force)
    names, q = point_set(points, nominal, seed)
    t_min = None
    thermal = {}
    if campaign is not None:
        times, thermal_specs, tau, sensors, stands, tau_cool = campaign
        if len(times) * len(q) > MAX_ROWS:
            raise RapidcompError(f"--times: {len(times)} rounds of {len(q)} points make "
                                 f"{len(times) * len(q)} rows; a campaign file holds at most "
                                 f"{MAX_ROWS} (fewer rounds or points)")
        thermal = parse_effect_values(cat, thermal_specs, force, "--thermal-effect")
        for e in thermal:
            if e.kind not in THERMAL_KINDS:
                raise RapidcompError(f"--thermal-effect {e.id}: heat does not change a "
                                     f"{e.kind.replace('_', ' ')}; thermal effects are "
                                     + ", ".join(THERMAL_KINDS))
        rounds = []
        # The law through the rounds: a stop after a round cools (tau_cool),
        # running heats (tau).
        s, last = 0.0, 0.0
        round_s, stood_at = [], []
        total = 0.0
        for t, stand in zip(times, stands):
            s *= np.exp(-stand / (tau_cool or tau))
            total += stand
            s = 1.0 - (1.0 - s) * np.exp(-(t - last) / tau)
            last = t
            round_s.append(s)
            stood_at.append(total)
        for t, s in zip(times, round_s):
            both = dict(values)
            for e, v in thermal.items():
                both[e] = both.get(e, 0.0) + s * np.asarray(v, float)
            rounds.append(simulate_positions(nominal, prof, both, q, tool))
        exact = np.vstack(rounds)
        base = np.vstack([simulate_positions(nominal, prof, {}, q, tool)] * len(times))
        names = tuple(f"{n}_t{t:g}" + (f"_s{S:g}" if S else "")
                      for t, S in zip(times, stood_at) for n in names)
        t_min = np.repeat(np.asarray(times, float), len(q))
        stood = np.repeat(np.asarray(stood_at, float), len(q)) if any(stands) else None
        rng = np.random.default_rng(seed + 1)
        follows = np.repeat(np.asarray(round_s), len(q))
        temperatures = tuple(
            (name, cold + (warm - cold) * (follows if lag is None
                                           else 1.0 - np.exp(-t_min / lag))
             + rng.normal(0.0, SENSOR_NOISE_C, len(t_min)))
            for name, cold, warm, lag in sensors)
        q = np.vstack([q] * len(times))
    else:
        exact = simulate_positions(nominal, prof, values, q, tool)
        base = simulate_positions(nominal, prof, {}, q, tool)
        temperatures = ()
        stood = None
    xyz = add_noise(exact, noise, seed) if noise > 0 else exact
    shift = np.linalg.norm(exact - base, axis=1)
    effect_text = ", ".join(f"{e.id}=" + ",".join(f"{v:g}" for v in e.user(val).values())
                            for e, val in values.items()) or "none"
    if thermal:
        effect_text += "; thermal (steady state, tau " + f"{campaign[2]:g} min): " + ", ".join(
            f"{e.id}=" + ",".join(f"{v:g}" for v in e.user(val).values())
            for e, val in thermal.items())
    comments = [f"simulated by rapidcomp simulate: points {Path(points).name}, model "
                f"{Path(robot).name if robot else 'irb140'} + "
                f"{Path(profile).name if profile else 'no profile'}",
                f"effects: {effect_text}",
                f"measuring point ({', '.join(f'{x:g}' for x in tool)}) mm in the flange "
                f"frame; payload {_payload_text(prof.payload)}",
                f"noise {noise:g} mm per axis, seed {seed}"]
    if campaign is not None:
        comments.append(f"warm-up campaign: the points at {', '.join(f'{t:g}' for t in campaign[0])} "
                        "min of running since a cold start (t_min)" + (
                            f", stops of {', '.join(f'{x:g}' for x in campaign[4] if x)} min "
                            f"(stood_min; cooling tau {campaign[5] or campaign[2]:g} min)"
                            if any(campaign[4]) else "") + "".join(
                            f"; {n} {c:g}..{w:g} deg C (tau {lag or campaign[2]:g} min, noise "
                            f"{SENSOR_NOISE_C:g})" for n, c, w, lag in campaign[3]))
    files = [(output, utf8(format_measured(names, q, xyz, comments, t_min, temperatures,
                                           stood)))]
    rows = detectability(ParamModel(nominal, prof, q, tool), cat, noise if noise > 0 else 0.005)
    meta = {"points": f"{Path(points).name} ({len(names)})",
            "noise": f"{(noise if noise > 0 else 0.005) * 1000:g} um per axis"
                     + ("" if noise > 0 else " (assumed: --noise is 0)"),
            "measuring point": f"({', '.join(f'{x:g}' for x in tool)}) mm in the flange frame"}
    table = report.detectability_markdown(rows, meta)
    if table_path:
        files.append((table_path, utf8(table)))
    summary = (f"{len(names)} points, effects: {effect_text}; TCP shift by the effects max "
               f"{shift.max() * 1000:.1f} um, RMS {np.sqrt(np.mean(shift ** 2)) * 1000:.1f} um; "
               f"noise {noise:g} mm",)
    notes = ()
    if campaign is not None and not thermal:
        notes = ("--times without --thermal-effect: nothing in this campaign changes with time "
                 "(--effect and --profile are static), its rounds are replicates",)
    return Outcome(summary + ("",) + tuple(table.splitlines()), notes, tuple(files))

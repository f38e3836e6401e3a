"""The discover report: Markdown for people (one table per step), JSON with
exactly the keys the issue fixes, and the terminal summary. No timestamps,
no paths beyond base names: the same input gives the same bytes."""

from __future__ import annotations

import json
from pathlib import Path

from .heldout import HeldOut
from .residuals import Analysis
from .select import Discovery
from .simulate import Detectability


def _um(mm: float) -> str:
    text = f"{mm * 1000:.1f}"
    # A value that rounds to zero is 0.0, whatever its sign.
    return "0.0" if text == "-0.0" else text


def _num(x: float) -> str:
    return f"{x:.4g}"


def as_json(d: Discovery, test: HeldOut | None = None, notes: tuple[str, ...] = ()) -> str:
    left_open = {eid for eid, _ in d.undetermined}
    doc = {
        "initial_rms_mm": round(d.initial_rms_mm, 9),
        "final_rms_mm": round(d.final_rms_mm, 9),
        "verdict": d.verdict,
        "sigma_mm": float(f"{d.sigma_mm:.6g}"),
        "sigma_source": d.sigma_source,
        "outliers": [o.point for o in d.outliers],
        "steps": [{"effect": s.effect.base_id,
                   "params": {k: float(f"{v:.9g}") for k, v in s.params.items()},
                   "stderr": {k: float(f"{v:.3g}") for k, v in s.stderr.items()},
                   "rms_before_mm": round(s.rms_before_mm, 9),
                   "rms_after_mm": round(s.rms_after_mm, 9),
                   "alternatives": list(s.alternatives),
                   "thermal": s.effect.thermal,
                   # (Its stated error beyond anything a robot has: the
                   # data leave its value open; the verdict says so.)
                   "determined": s.effect.id not in left_open} for s in d.steps],
        "tau_min": (None if d.warmup is None or d.warmup.tau_min is None
                    else float(f"{d.warmup.tau_min:.6g}")),
        "tau_cool_min": (None if d.warmup is None or d.warmup.tau_cool_min is None
                         else float(f"{d.warmup.tau_cool_min:.6g}")),
        "tau_cool_interval_min": (None if d.warmup is None or d.warmup.cool_interval is None
                                  else [None if d.warmup.cool_interval[2]
                                        else float(f"{d.warmup.cool_interval[0]:.6g}"),
                                        None if d.warmup.cool_interval[3]
                                        else float(f"{d.warmup.cool_interval[1]:.6g}")]),
        "verdict_text": d.verdict_text,
        "notes": list(notes),
    }
    if test is not None:
        doc.update({"test_points": test.points, "test_rms_mm": round(test.rms_mm, 9),
                    "test_max_mm": round(test.max_mm, 9),
                    "test_nominal_rms_mm": round(test.nominal_rms_mm, 9),
                    "test_nominal_max_mm": round(test.nominal_max_mm, 9),
                    "test_p": float(f"{test.p:.3g}"), "test_holds": test.holds})
    return json.dumps(doc, indent=2) + "\n"


def _held_out(test: HeldOut) -> list[str]:
    return ["## Held-out test", "",
            f"{test.points} poses of {Path(test.source).name}, not used for fitting: the error of "
            "each model there (3-D distance, measured - model).", "",
            "| model | RMS um | max um |", "|---|---:|---:|",
            f"| nominal (no effect named) | {_um(test.nominal_rms_mm)} | "
            f"{_um(test.nominal_max_mm)} |",
            f"| final model | {_um(test.rms_mm)} | {_um(test.max_mm)} |", "",
            f"What the final model leaves there against the noise: chi-square p = {test.p:.3g} "
            + ("(it holds)." if test.holds else "(it does not hold: see the verdict)."), ""]


def _outliers(d: Discovery) -> list[str]:
    out = ["## Gross errors (left out of the fit)", "",
           "Points far outside the rest (standardized residual of the whole-catalogue fit "
           "beyond the chi-square(3) quantile at 0.001 / N, robust scale): each is off by its "
           "residual had it not been fitted.", "",
           "| point | line | off by um | robust sigmas |", "|---|---:|---:|---:|"]
    out += [f"| {o.point} | {o.line} | {_um(o.off_mm)} | {o.sigmas:.1f} |" for o in d.outliers]
    return out + [""]


def _analysis(a: Analysis, title: str) -> list[str]:
    out = [f"### {title}", "",
           f"RMS {_um(a.rms_mm)} um, max {_um(a.max_mm)} um (point {a.max_point}), mean vector "
           f"({', '.join(_um(x) for x in a.mean_mm)}) um.", "",
           "| point | residual um | dx um | dy um | dz um |", "|---|---:|---:|---:|---:|"]
    out += [f"| {name} | {_um(length)} | " + " | ".join(_um(x) for x in r) + " |"
            for name, length, r in a.worst]
    out += ["", "Per region (octants about the median measured position):", "",
            "| region | points | RMS um | mean dx um | mean dy um | mean dz um |",
            "|---|---:|---:|---:|---:|---:|"]
    out += [f"| {r.region} | {r.points} | {_um(r.rms_mm)} | "
            + " | ".join(_um(x) for x in r.mean_mm) + " |" for r in a.regions]
    out += ["", "Correlation of the residual with the joint angles (Pearson r; |r| > 0.5 "
            "marked):", "", "| joint | with length | with dx | with dy | with dz |",
            "|---|---:|---:|---:|---:|"]
    for c in a.correlations:
        cells = [c.with_length, *c.with_xyz]
        out.append(f"| {c.joint} | " + " | ".join(
            f"**{x:+.2f}**" if abs(x) > 0.5 else f"{x:+.2f}" for x in cells) + " |")
    return out + [""]


def markdown(d: Discovery, meta: dict, plot_note: str | None = None,
             test: HeldOut | None = None, notes: tuple[str, ...] = ()) -> str:
    """notes: the command's notes, as the console says them."""
    out = ["# rapidcomp discover", ""]
    out += [f"- {k}: {v}" for k, v in meta.items()]
    left = f" ({len(d.outliers)} more left out as gross errors)" if d.outliers else ""
    out += [f"- points: {d.points}{left}",
            f"- noise: {d.sigma_mm * 1000:.2f} um per axis, {d.sigma_source}", "",
            "## Verdict", "", f"**{d.verdict}** — {d.verdict_text}", "",
            f"RMS of the 3-D residuals: {_um(d.initial_rms_mm)} um before, "
            f"{_um(d.final_rms_mm)} um after "
            f"({len(d.steps)} effect{'s' if len(d.steps) != 1 else ''} named).", ""]
    # (The plot's note is said where the plot would be.)
    said = [n for n in notes if n != plot_note]
    if said:
        out += ["## Notes", ""] + [f"- {n}" for n in said] + [""]
    if test is not None:
        out += _held_out(test)
    if d.warmup is not None:
        out += ["## Warm-up", "", d.warmup.text + ".", ""]
        out += [f"- {x.text}." for x in d.warmup.sensors] + ([""] if d.warmup.sensors else [])
        if d.thermal_evidence:
            out += ["| effect | static or thermal, and why |", "|---|---|"]
            out += [f"| {s.effect.base_id} | {d.thermal_evidence.get(s.effect.id, '')} |"
                    for s in d.steps]
            out.append("")
    if d.outliers:
        out += _outliers(d)
    if d.steps:
        out += ["## Final model", "", "| effect | parameter | value | stderr |",
                "|---|---|---:|---:|"]
        errors = d.final_fit.stderr(d.sigma_mm)
        # (The steps' errors where they have them, as the summary and the
        # JSON state them: a warm-up's hold its time constants' uncertainty
        # too, which the final fit's own leave out.)
        stated = {s.effect.id: s.stderr for s in d.steps}
        for e, v, s in zip(d.final_fit.effects, d.final_fit.values, errors):
            errs = stated.get(e.id, e.user(s))
            for name, val in zip(e.params, e.user(v).values()):
                out.append(f"| {e.id} | {name} | {_num(val)} | {_num(errs[name])} |")
        out.append("")
    out += ["## Before fitting", ""] + _analysis(d.initial, "Residuals: measured - simulated")
    for i, s in enumerate(d.steps, 1):
        out += [f"## Step {i}: {s.effect.id}", "",
                "| parameter | final value | stderr | fitted at this step |",
                "|---|---:|---:|---:|"]
        out += [f"| {k} | {_num(v)} | {_num(s.stderr[k])} | {_num(s.at_step[k])} |"
                for k, v in s.params.items()]
        out += ["", "| | all points | held out (leave one point out) |", "|---|---:|---:|",
                f"| RMS before um | {_um(s.rms_before_mm)} | {_um(s.heldout_before_mm)} |",
                f"| RMS after um | {_um(s.rms_after_mm)} | {_um(s.heldout_after_mm)} |", "",
                f"Evidence: chi-square p = {s.p_value:.3g}, BIC change {s.delta_bic:.1f}, "
                f"condition number {s.fit.cond:.3g}.",
                f"Alternatives (explain these data equally): "
                f"{', '.join(s.alternatives) if s.alternatives else 'none'}."]
        if s.note:
            out.append(f"Note: {s.note}")
        out += ["", "Candidates at this step (best five):", "",
                "| effect | params | RMS after um | held out um | p | BIC change | not named "
                "because |", "|---|---:|---:|---:|---:|---:|---|"]
        out += [f"| {c.effect} | {c.nparams} | {_um(c.rms_mm)} | {_um(c.heldout_mm)} | "
                f"{c.p_value:.3g} | {c.delta_bic:.1f} | "
                f"{c.implausible or c.cancelling or _estimated(c)} |" for c in s.candidates[:5]]
        out.append("")
    if d.steps:
        out += _analysis(d.final, "Residuals after the final model")
    if d.not_identifiable:
        out += ["## Not identifiable with these points", ""]
        out += [f"- {eid}: {why}" for eid, why in d.not_identifiable]
        out.append("")
    if plot_note:
        out += [f"Plot: {plot_note}", ""]
    return "\n".join(out)


def summary_lines(d: Discovery, test: HeldOut | None = None) -> list[str]:
    out = [f"residual RMS {_um(d.initial_rms_mm)} um before, {_um(d.final_rms_mm)} um after; "
           f"noise {d.sigma_mm * 1000:.2f} um per axis ({d.sigma_source.split(' (')[0]})"]
    if d.outliers:
        out.append("gross errors left out: " + ", ".join(
            f"{o.point} (line {o.line}, off by {_um(o.off_mm)} um)" for o in d.outliers))
    if d.warmup is not None:
        out.append(d.warmup.text)
        out += [f"temperature {x.text}" for x in d.warmup.sensors]
    for i, s in enumerate(d.steps, 1):
        params = ", ".join(f"{k}={_num(v)}±{_num(s.stderr[k])}" for k, v in s.params.items())
        alt = f"  [alternatives: {', '.join(s.alternatives)}]" if s.alternatives else ""
        out.append(f"step {i}: {s.effect.id}: {params}; RMS {_um(s.rms_before_mm)} -> "
                   f"{_um(s.rms_after_mm)} um{alt}")
    out.append(f"verdict: {d.verdict} — {d.verdict_text}")
    if test is not None:
        out.append(f"held-out test ({test.points} poses): RMS {_um(test.rms_mm)} um, max "
                   f"{_um(test.max_mm)} um (nominal model: RMS {_um(test.nominal_rms_mm)} um, "
                   f"max {_um(test.nominal_max_mm)} um)")
    return out


def detectability_markdown(rows: tuple[Detectability, ...], meta: dict) -> str:
    out = ["# Detectability", ""] + [f"- {k}: {v}" for k, v in meta.items()] + [
        "", "Smallest size of each effect, alone, that discover names with 90 % probability "
        "on this point set and noise, and the largest TCP shift it causes at that size.", "",
        "| effect | parameter | smallest detectable | TCP shift um | note |",
        "|---|---|---:|---:|---|"]
    for r in rows:
        size = "not detectable" if r.smallest is None else f"{r.smallest:.3g}"
        tcp = "-" if r.tcp_um is None else f"{r.tcp_um:.1f}"
        out.append(f"| {r.effect} | {r.param} | {size} | {tcp} | {r.note} |")
    return "\n".join(out) + "\n"


def _estimated(c) -> str:
    return ("not fitted: a linearized step predicts it far from the best (figures are "
            "the prediction)") if c.estimated else ""

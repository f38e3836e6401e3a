"""A warm-up campaign (measured data with a `t_min` column: minutes since a
cold start, the robot running): the thermal time constant, from the data
alone.

Thermal deformations are tiny, so every pose's measured point moves
linearly with the thermal state: x_p(t) = a_p + s(t) b_p, s(t) = 1 -
exp(-t / tau) (README "Transient compensation"), whatever the effects are:
a_p holds the static ones, b_p the thermal ones at the steady state. For a
given tau that is a linear fit per pose; tau is the one-dimensional
minimum of its residual (a log grid, then golden section). No effect model
enters, so tau cannot absorb a model error, and the same fit gives the
noise (each pose's scatter about its own warm-up curve) and the evidence of
any change over time at all (the fit without b, chi-square).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import RapidcompError
from .noise import MIN_SIGMA_MM, replicate_groups
from .stats import chi2_ppf, chi2_sf

TAU_RANGE_MIN = (1.0, 10_000.0)
GRID = 240
ALPHA = 0.001
INTERVAL = 0.95
# A cooling time constant whose interval spans more than this factor is
# poorly told by the campaign's stops.
COOL_WIDE = 3.0
# Its advice then (Warmup.advice; the profile's comment says it too).
LONGER_STOPS = "measure longer stops"
# Fewer distinct times than this cannot tell a curve from a line.
MIN_TIMES = 3


@dataclass(frozen=True)
class Sensor:
    """A temperature column against the warm-up."""

    name: str
    t_cold: float            # its warm-up curve T(t) = T_c + (T_w - T_c) s(t; tau_T)
    t_warm: float
    tau_min: float
    chi_vs_time: float       # (RSS with s from T - RSS with s(t)) / sigma^2: < 0 better
    text: str


@dataclass(frozen=True)
class Warmup:
    poses: int                     # poses measured at MIN_TIMES or more times
    times: int                     # distinct times
    tau_min: float | None          # None: no change over time (or not measurable)
    low_min: float | None          # INTERVAL confidence interval of tau (profile)
    high_min: float | None
    p_value: float                 # of "nothing changes over time"
    sigma_mm: float | None         # scatter about each pose's warm-up curve
    dof: int
    text: str
    sensors: tuple[Sensor, ...] = ()
    state_from: str | None = None  # a temperature column that explains better than time
    tau_cool_min: float | None = None   # campaigns with stops (stood_min)
    # What to measure where tau is poorly known ("measure longer", "measure
    # more often at the start", "measure longer stops"), as the text says.
    advice: tuple[str, ...] = ()
    # tau_cool's INTERVAL interval (low, high, open below, open above), tau
    # held.
    cool_interval: tuple | None = None

    def states(self, t_min, temperatures=(), stood=None) -> np.ndarray:
        """Each row's thermal state: s(t), or from the temperature column
        that explains the warm-up better, (T - T_c) / (T_w - T_c)."""
        if self.state_from is not None:
            sensor = next(x for x in self.sensors if x.name == self.state_from)
            T = dict(temperatures)[self.state_from]
            return (np.asarray(T, float) - sensor.t_cold) / (sensor.t_warm - sensor.t_cold)
        return states(np.asarray(t_min, float), self.tau_min, stood, self.tau_cool_min)


def states(t_min: np.ndarray, tau_min: float, stood=None, tau_cool=None) -> np.ndarray:
    """s of each row: a robot running t_min minutes since a cold start;
    with `stood` (cumulative minutes it stood, a stop following a
    measurement round) the law runs through the rounds in time order:
    cooling over each stop (tau_cool), then heating over the running."""
    t = np.asarray(t_min, float)
    if stood is None or not np.any(np.asarray(stood) > 0):
        return 1.0 - np.exp(-t / tau_min)
    S = np.asarray(stood, float)
    keys, row_key = np.unique(np.round(np.column_stack([t + S, t, S]), 9), axis=0,
                              return_inverse=True)
    s, last_t, last_S = 0.0, 0.0, 0.0
    value = np.empty(len(keys))
    for k, (_, tk, Sk) in enumerate(keys):
        s *= math.exp(-max(Sk - last_S, 0.0) / tau_cool)
        s = 1.0 - (1.0 - s) * math.exp(-max(tk - last_t, 0.0) / tau_min)
        value[k] = s
        last_t, last_S = tk, Sk
    # Rows index their key: a fit's golden search calls this ~850 times, and
    # a dict keyed by each row's rounded pair took 1.4 s of a 2.6 s discover.
    return value[np.reshape(row_key, -1)]


def _poses(q_deg, wall, tool):
    """Rows of each pose (same joints and measuring point) measured at
    MIN_TIMES or more distinct times."""
    out = []
    for rows in replicate_groups(q_deg, tool):
        if len(np.unique(np.round(wall[rows], 9))) >= MIN_TIMES:
            out.append(rows)
    return out


def _rss(groups, t_min, xyz, tau, stood=None, tau_cool=None) -> float:
    return _rss_linear(groups, states(t_min, tau, stood, tau_cool), xyz)


def _rss_linear(groups, x, xyz) -> float:
    """Each pose's points as a + x b (x per row)."""
    total = 0.0
    for rows in groups:
        A = np.column_stack([np.ones(len(rows)), x[rows]])
        coef, *_ = np.linalg.lstsq(A, xyz[rows], rcond=None)
        total += float(np.sum((xyz[rows] - A @ coef) ** 2))
    return total


def _sensor(name, T, t, groups, xyz, rss_time, sigma) -> Sensor:
    """A temperature column: its own warm-up curve, and whether the points
    follow it better than they follow s(t)."""
    grid = np.exp(np.linspace(*np.log(TAU_RANGE_MIN), GRID))

    def curve(tau):
        A = np.column_stack([np.ones(len(t)), states(t, tau)])
        coef, *_ = np.linalg.lstsq(A, T, rcond=None)
        return float(np.sum((T - A @ coef) ** 2)), coef
    k = int(np.argmin([curve(tau)[0] for tau in grid]))
    tau = _golden(lambda x: curve(x)[0], grid[max(k - 1, 0)], grid[min(k + 1, GRID - 1)])
    (t0, rise) = curve(tau)[1]
    t_warm = t0 + rise
    # Cold is what it reads at the cold start (the first time measured),
    # warm its curve's steady state.
    t_cold = float(np.mean(T[t == t.min()]))
    # A sensor still rising past its curve's steady state (a slow second
    # time constant): warm is the highest reading, so that s <= 1 (the
    # generated module clips s to 0..1).
    t_warm = max(t_warm, float(T.max())) if rise > 0 else min(t_warm, float(T.min()))
    chi = (_rss_linear(groups, T, xyz) - rss_time) / sigma ** 2
    tell = chi2_ppf(0.99, 1)
    verdict = ("explains the warm-up better than time does (the heat does not follow one time "
               "constant)" if chi < -tell else
               "explains it as well as time" if chi <= tell else "explains it worse than time")
    return Sensor(name, float(t_cold), float(t_warm), float(tau), float(chi),
                  f"{name}: {t_cold:.1f} deg C cold, {t_warm:.1f} warm (its tau "
                  f"{tau:.1f} min); the points follow it with chi-square {chi:+.1f} against "
                  f"s(t): it {verdict}")


def estimate(q_deg, xyz_mm, t_min, tool=None, sigma_mm: float | None = None,
             temperatures=(), stood=None) -> Warmup:
    """tau, its interval and the evidence of a warm-up, from the poses
    measured at several times (stood: cumulative minutes stood, a campaign
    with stops: tau_cool too)."""
    q_deg, xyz, t = np.asarray(q_deg, float), np.asarray(xyz_mm, float), np.asarray(t_min, float)
    if stood is not None and not np.any(np.asarray(stood) > 0):
        stood = None
    wall = t + (np.asarray(stood, float) if stood is not None else 0.0)
    groups = _poses(q_deg, wall, tool)
    times = len(np.unique(np.round(wall, 9)))
    if not groups:
        raise RapidcompError(
            "t_min: no pose is measured at 3 or more different times; a warm-up campaign "
            "measures the same poses repeatedly from a cold start (rapidcomp simulate --times "
            "makes one)")
    rows = sum(len(g) for g in groups)
    dof = 3 * (rows - 2 * len(groups)) - 1
    if dof < 10:
        raise RapidcompError(f"t_min: {len(groups)} poses at {times} times leave {dof} degrees "
                             "of freedom for the warm-up fit: measure more poses or more times")
    grid = np.exp(np.linspace(*np.log(TAU_RANGE_MIN), GRID))
    tau_cool = None
    if stood is not None:
        # Two constants: a coarse grid with tau_cool = tau_heat, then
        # each refined with the other held (coordinate descent).
        coarse = grid[::8]
        rss0 = [_rss(groups, t, xyz, x, stood, x) for x in coarse]
        tau = tau_cool = float(coarse[int(np.argmin(rss0))])
        for _ in range(4):
            tau_cool = _golden(lambda x: _rss(groups, t, xyz, tau, stood, x),
                               TAU_RANGE_MIN[0], TAU_RANGE_MIN[1])
            tau = _golden(lambda x: _rss(groups, t, xyz, x, stood, tau_cool),
                          TAU_RANGE_MIN[0], TAU_RANGE_MIN[1])
    rss = np.array([_rss(groups, t, xyz, x, stood, tau_cool) for x in grid])
    if stood is None:
        k = int(np.argmin(rss))
        lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, GRID - 1)]
        tau = _golden(lambda x: _rss(groups, t, xyz, x), lo, hi)
    best = _rss(groups, t, xyz, tau, stood, tau_cool)
    # (Tested against no less than the noise any measurement has:
    # noise.MIN_SIGMA_MM; the estimate itself kept, select.py floors it.)
    estimated = math.sqrt(best / dof)
    sigma = sigma_mm if sigma_mm is not None else max(estimated, MIN_SIGMA_MM)
    static = sum(float(np.sum((xyz[g] - xyz[g].mean(axis=0)) ** 2)) for g in groups)
    chi = (static - best) / max(sigma, 1e-12) ** 2
    p = chi2_sf(max(chi, 0.0), 3 * len(groups) + 1)
    span = (float(t.min()), float(t.max()))
    if p >= ALPHA:
        return Warmup(len(groups), times, None, None, None, p, sigma_mm or estimated, dof,
                      f"nothing changes over time (chi-square p = {p:.3g} over {len(groups)} "
                      f"poses at {times} times, {span[0]:g}-{span[1]:g} min): every effect is "
                      "static")
    # Profile interval: the taus whose fit is within the chi-square(1)
    # quantile of the best.
    limit = best + chi2_ppf(INTERVAL, 1) * sigma ** 2

    low, high, low_open, open_end = _interval(
        grid, rss, tau, limit, lambda x: _rss(groups, t, xyz, x, stood, tau_cool) - limit)
    text = (f"warm-up time constant tau = {tau:.1f} min ({INTERVAL:.0%} interval "
            f"{interval_text(low, high, low_open, open_end)}), from {len(groups)} poses "
            f"measured at {times} times ({span[0]:g}-{span[1]:g} min); change over time: "
            f"chi-square p = {p:.3g}")
    advice = []
    cool = None
    if tau_cool is not None:
        # (Its interval as tau's, tau held at its best: how well the stops
        # tell it.)
        rss_cool = np.array([_rss(groups, t, xyz, tau, stood, x) for x in grid])
        cool = _interval(grid, rss_cool, tau_cool, limit,
                         lambda x: _rss(groups, t, xyz, tau, stood, x) - limit)
        c_low, c_high, c_below, c_open = cool
        text += (f"; cooling time constant {tau_cool:.1f} min ({INTERVAL:.0%} interval "
                 f"{interval_text(*cool)}, from the stops, cumulative {float(np.max(stood)):g} min)")
        if c_below or c_open or c_high > COOL_WIDE * c_low:
            advice.append(LONGER_STOPS)
            text += "; the stops tell the cooling time constant poorly: measure longer stops"
    if open_end or tau > 3 * span[1]:
        advice.append("measure longer")
        text += ("; the campaign ends long before the robot is warm: tau is poorly known, "
                 "measure longer")
    first = np.diff(np.unique(np.round(t, 9)))
    if low <= grid[1] or (first.size and tau < first.min()):
        advice.append("measure more often at the start")
        text += ("; the robot warms up faster than the campaign measures (tau below its "
                 "shortest interval, or at the shortest tau searched, 1 min: are the times in "
                 "minutes?): tau is poorly known, measure more often at the start")
    sensors = tuple(_sensor(name, np.asarray(T, float), t, groups, xyz, best, sigma)
                    for name, T in temperatures) if stood is None else ()
    if stood is not None and temperatures:
        text += "; temperature columns are not judged in a campaign with stops (not yet)"
    better = [x for x in sensors if x.chi_vs_time < -chi2_ppf(0.99, 1)
              and abs(x.t_warm - x.t_cold) > 1e-6]
    state_from = min(better, key=lambda x: x.chi_vs_time).name if better else None
    if state_from is not None:
        text += f"; the thermal state comes from {state_from}, which the points follow better"
    return Warmup(len(groups), times, float(tau), low, high, p, sigma_mm or estimated, dof,
                  text, sensors, state_from, tau_cool, tuple(advice), cool)


def interval_text(low: float, high: float, below: bool, above: bool, fmt: str = ".1f") -> str:
    """An interval in words, an end at the search's edge said as open."""
    if below and above:
        return f"any time constant searched, {low:g}-{high:g} min"
    return (f"up to {high:{fmt}} min" if below else
            f"{low:{fmt}}-{'beyond ' if above else ''}{high:{fmt}} min")


def _interval(grid, rss, best: float, limit: float, f) -> tuple[float, float, bool, bool]:
    """(low, high, open below, open above) of the time constants whose fit,
    on the grid's RSS, is within `limit`: where the profile crosses it,
    found on the grid and refined by bisection (log scale, f: RSS - limit)
    between grid points; an end at the grid's edge is open."""
    k = int(np.searchsorted(grid, best))
    lo_i = k - 1
    while lo_i >= 0 and rss[lo_i] <= limit:
        lo_i -= 1
    hi_i = k
    while hi_i < GRID and rss[hi_i] <= limit:
        hi_i += 1
    low = _crossing(f, grid[lo_i], min(best, grid[lo_i + 1])) if lo_i >= 0 else float(grid[0])
    high = _crossing(f, grid[hi_i], max(best, grid[hi_i - 1])) if hi_i < GRID \
        else float(grid[-1])
    return low, high, lo_i < 0, hi_i >= GRID - 1


def _crossing(f, outside: float, inside: float, iterations: int = 40) -> float:
    """Where f changes sign between `outside` (f > 0) and `inside` (f <=
    0), on a log scale."""
    a, b = math.log(outside), math.log(inside)
    for _ in range(iterations):
        m = (a + b) / 2
        if f(math.exp(m)) > 0:
            a = m
        else:
            b = m
    return math.exp((a + b) / 2)


def _golden(f, a: float, b: float, iterations: int = 60) -> float:
    """Minimum of f on [a, b] (log scale)."""
    la, lb = math.log(a), math.log(b)
    g = (math.sqrt(5) - 1) / 2
    c, d = lb - g * (lb - la), la + g * (lb - la)
    fc, fd = f(math.exp(c)), f(math.exp(d))
    for _ in range(iterations):
        if fc < fd:
            lb, d, fd = d, c, fc
            c = lb - g * (lb - la)
            fc = f(math.exp(c))
        else:
            la, c, fc = c, d, fd
            d = la + g * (lb - la)
            fd = f(math.exp(d))
    return math.exp((la + lb) / 2)

"""Chi-square distribution functions (numpy has none, and scipy is not a
dependency): the regularized incomplete gamma function by its series and
continued fraction (Numerical Recipes 6.2), quantiles by bisection, and the
non-central chi-square as a Poisson mixture of central ones.
tests/test_discover_stats.py checks them against printed tables and a
Monte Carlo oracle.
"""

from __future__ import annotations

import math


def _gamma_p(a: float, x: float) -> float:
    """Regularized lower incomplete gamma P(a, x)."""
    if x <= 0:
        return 0.0
    log_front = -x + a * math.log(x) - math.lgamma(a)
    if x < a + 1:
        term = total = 1.0 / a
        ap = a
        for _ in range(10000):
            ap += 1
            term *= x / ap
            total += term
            if abs(term) < abs(total) * 1e-16:
                break
        return min(1.0, total * math.exp(log_front))
    return max(0.0, 1.0 - _gamma_q_fraction(a, x))


def _gamma_q(a: float, x: float) -> float:
    """Regularized upper incomplete gamma Q(a, x) = 1 - P(a, x), computed
    directly in the tail so that tiny p-values keep their digits."""
    if x <= 0:
        return 1.0
    if x < a + 1:
        return 1.0 - _gamma_p(a, x)
    return _gamma_q_fraction(a, x)


def _gamma_q_fraction(a: float, x: float) -> float:
    """Q(a, x) by its continued fraction (modified Lentz), for x >= a + 1."""
    log_front = -x + a * math.log(x) - math.lgamma(a)
    tiny = 1e-300
    b = x + 1 - a
    c = 1 / tiny
    d = 1 / b
    h = d
    for i in range(1, 10000):
        an = -i * (i - a)
        b += 2
        d = an * d + b
        d = tiny if abs(d) < tiny else d
        c = b + an / c
        c = tiny if abs(c) < tiny else c
        d = 1 / d
        step = d * c
        h *= step
        if abs(step - 1) < 1e-16:
            break
    return math.exp(log_front) * h


def chi2_cdf(x: float, k: float) -> float:
    return _gamma_p(k / 2, x / 2)


def chi2_sf(x: float, k: float) -> float:
    """P(X > x) for X ~ chi2(k): the p-value of a chi-square statistic."""
    return _gamma_q(k / 2, x / 2)


def chi2_ppf(p: float, k: float) -> float:
    """x with P(X <= x) = p."""
    lo, hi = 0.0, max(1.0, k)
    while chi2_cdf(hi, k) < p:
        hi *= 2
    for _ in range(200):
        mid = (lo + hi) / 2
        if chi2_cdf(mid, k) < p:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-12 * max(1.0, hi):
            break
    return (lo + hi) / 2


def ncx2_cdf(x: float, k: float, lam: float) -> float:
    """P(X <= x) for a non-central chi-square with k dof and non-centrality lam."""
    if lam <= 0:
        return chi2_cdf(x, k)
    half = lam / 2
    j0 = int(half)
    total = 0.0
    # Sum outwards from the Poisson mode until the weights vanish.
    for direction in (1, -1):
        j = j0 if direction == 1 else j0 - 1
        while j >= 0:
            w = math.exp(-half + j * math.log(half) - math.lgamma(j + 1))
            total += w * chi2_cdf(x, k + 2 * j)
            if w < 1e-16 and abs(j - half) > 5 * math.sqrt(half) + 5:
                break
            j += direction
    return total


def ncx2_lambda_for_power(threshold: float, k: float, power: float) -> float:
    """The non-centrality at which P(X > threshold) = power."""
    lo, hi = 0.0, max(1.0, threshold)
    while 1 - ncx2_cdf(threshold, k, hi) < power:
        hi *= 2
    for _ in range(100):
        mid = (lo + hi) / 2
        if 1 - ncx2_cdf(threshold, k, mid) < power:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2

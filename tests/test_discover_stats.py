"""Chi-square functions against printed tables and a Monte Carlo oracle."""

import numpy as np
import pytest

from rapidcomp.discover.stats import chi2_ppf, chi2_sf, ncx2_cdf, ncx2_lambda_for_power


@pytest.mark.parametrize("p,k,table", [
    (0.95, 1, 3.841459), (0.99, 1, 6.634897), (0.999, 3, 16.266236), (0.95, 10, 18.307038),
    (0.99, 100, 135.806723), (0.01, 5, 0.554298),
])
def test_chi2_quantiles_match_tables(p, k, table):
    assert chi2_ppf(p, k) == pytest.approx(table, abs=2e-6)
    assert chi2_sf(table, k) == pytest.approx(1 - p, rel=1e-5)


def test_tiny_p_values_keep_their_digits():
    # P(chi2(1) > 100) = erfc(sqrt(50)) = 1.5e-23
    from math import erfc, sqrt
    assert chi2_sf(100.0, 1) == pytest.approx(erfc(sqrt(50.0)), rel=1e-9)


@pytest.mark.parametrize("k,lam,x", [(1, 5.0, 6.0), (3, 12.0, 15.0), (6, 40.0, 30.0)])
def test_noncentral_chi2_against_monte_carlo(k, lam, x):
    draws = np.random.default_rng(11).noncentral_chisquare(k, lam, 400_000)
    assert ncx2_cdf(x, k, lam) == pytest.approx(np.mean(draws <= x), abs=0.004)


def test_lambda_for_power():
    t = chi2_ppf(0.99, 2)
    lam = ncx2_lambda_for_power(t, 2, 0.9)
    draws = np.random.default_rng(12).noncentral_chisquare(2, lam, 400_000)
    assert np.mean(draws > t) == pytest.approx(0.9, abs=0.004)

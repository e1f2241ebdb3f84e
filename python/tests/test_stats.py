"""The statistics engine from Python (docs/python.md): Welch, Šidák, Stouffer, binomial, KS.

Closed forms are checked against formulas evaluated here; rejection rates under the null are
checked with the exact binomial test at META_ALPHA, each with a negative control (a real effect,
or a missing correction) whose rate must be rejected. Seeds are fixed.
"""
import math

import numpy as np
import pytest

import testbench as tb

ALPHA = 0.05        # level of the simulated tests
META_ALPHA = 1e-3   # level of the binomial test on their rejection counts
REPS = 2000


def binom_pmf(k, n, p):
    return math.comb(n, k) * p**k * (1.0 - p) ** (n - k)


# --- Welch ----------------------------------------------------------------------------------
def test_welch_matches_the_formula():
    m1, v1, n1, m2, v2, n2 = 1.3, 2.0, 12, 0.4, 0.5, 30
    se2 = v1 / n1 + v2 / n2
    t = (m1 - m2) / math.sqrt(se2)
    dof = se2**2 / ((v1 / n1) ** 2 / (n1 - 1) + (v2 / n2) ** 2 / (n2 - 1))
    r = tb.welch_t_test(m1, v1, n1, m2, v2, n2)
    assert r.statistic == pytest.approx(t, rel=1e-12)
    assert r.dof == pytest.approx(dof, rel=1e-12)
    assert r.p_value == pytest.approx(tb.students_t_two_sided_p(t, dof), rel=1e-12)
    assert tb.welch_t_test(1.0, 1.0, 10, 1.0, 3.0, 20).p_value == pytest.approx(1.0)


def test_welch_of_arrays_uses_unbiased_variances():
    rng = np.random.default_rng(11)
    a, b = rng.normal(0.0, 1.0, 40), rng.normal(0.3, 2.0, 25)
    r = tb.welch_t_test_samples(a, b)
    ref = tb.welch_t_test(a.mean(), a.var(ddof=1), len(a), b.mean(), b.var(ddof=1), len(b))
    assert r.statistic == pytest.approx(ref.statistic, rel=1e-10)
    assert r.dof == pytest.approx(ref.dof, rel=1e-10)


def welch_rejections(shift):
    rng = np.random.default_rng(2024)
    k = 0
    for _ in range(REPS):
        a = rng.normal(0.0, 1.0, 15)
        b = rng.normal(shift, 3.0, 40)  # unequal variances and sizes: where Welch matters
        k += tb.welch_t_test_samples(a, b).rejects(ALPHA)
    return k


def test_welch_null_rejection_rate_is_alpha():
    k = welch_rejections(0.0)
    assert not tb.binomial_test(k, REPS, ALPHA).rejects(META_ALPHA), k


def test_negative_control_welch_detects_a_shift():
    k = welch_rejections(1.5)
    assert tb.binomial_test(k, REPS, ALPHA).rejects(META_ALPHA), k


def test_one_sample_t_of_arrays():
    rng = np.random.default_rng(5)
    x = rng.normal(2.0, 1.0, 500)
    r = tb.one_sample_t_test_samples(x, 2.0)
    assert r.statistic == pytest.approx((x.mean() - 2.0) / (x.std(ddof=1) / math.sqrt(len(x))), rel=1e-10)
    assert r.dof == len(x) - 1
    assert not r.rejects(0.01)
    assert tb.one_sample_t_test_samples(x, 2.3).rejects(0.01)  # negative control: 0.3 = 6.7 SE off


# --- Šidák ------------------------------------------------------------------------------------
def test_sidak_closed_form():
    for alpha, m in [(0.05, 1), (0.05, 20), (0.01, 1000), (1e-9, 10**6)]:
        assert tb.sidak_alpha(alpha, m) == pytest.approx(-math.expm1(math.log1p(-alpha) / m), rel=1e-12)
        assert tb.sidak_adjust(tb.sidak_alpha(alpha, m), m) == pytest.approx(alpha, rel=1e-9)
    assert tb.sidak_alpha(0.05, 1) == pytest.approx(0.05, rel=1e-14)


def familywise_rejections(per_test_alpha, m=20):
    rng = np.random.default_rng(77)
    p = rng.uniform(size=(REPS, m))  # m true nulls per family
    return int((p.min(axis=1) < per_test_alpha).sum())


def test_sidak_keeps_the_familywise_rate():
    k = familywise_rejections(tb.sidak_alpha(ALPHA, 20))
    assert not tb.binomial_test(k, REPS, ALPHA).rejects(META_ALPHA), k


def test_negative_control_uncorrected_familywise_rate():
    k = familywise_rejections(ALPHA)  # 1 - 0.95^20 = 0.64 of families reject
    assert tb.binomial_test(k, REPS, ALPHA).rejects(META_ALPHA), k


# --- Stouffer and sum z^2 ---------------------------------------------------------------------
def test_stouffer_closed_form():
    z = np.array([0.5, -1.2, 2.0, 0.3, 1.1])
    r = tb.stouffer(z)
    big_z = z.sum() / math.sqrt(len(z))
    assert r.statistic == pytest.approx(big_z, rel=1e-12)
    assert r.p_value == pytest.approx(math.erfc(abs(big_z) / math.sqrt(2.0)), rel=1e-10)
    q = tb.sum_z2_test(z)
    assert q.statistic == pytest.approx(float((z**2).sum()), rel=1e-12) and q.dof == len(z)
    assert q.p_value == pytest.approx(tb.chi_squared_sf(float((z**2).sum()), len(z)), rel=1e-12)


def stouffer_rejections(shift):
    rng = np.random.default_rng(99)
    return sum(tb.stouffer(rng.normal(shift, 1.0, 16)).rejects(ALPHA) for _ in range(REPS))


def test_stouffer_null_rejection_rate_is_alpha():
    k = stouffer_rejections(0.0)
    assert not tb.binomial_test(k, REPS, ALPHA).rejects(META_ALPHA), k


def test_negative_control_stouffer_detects_a_common_shift():
    k = stouffer_rejections(0.5)  # combined shift 0.5 * sqrt(16) = 2 SE: power 0.52
    assert tb.binomial_test(k, REPS, ALPHA).rejects(META_ALPHA), k


# --- binomial ---------------------------------------------------------------------------------
def test_binomial_test_is_exact():
    n, p = 20, 0.3
    pmf = [binom_pmf(j, n, p) for j in range(n + 1)]
    for k in range(n + 1):
        expected = sum(q for q in pmf if q <= pmf[k] * (1.0 + 1e-7))
        assert tb.binomial_test(k, n, p).p_value == pytest.approx(min(1.0, expected), rel=1e-9, abs=1e-15)
    # R: binom.test(15, 20) gives p = 0.04139; binom.test(7, 20) gives p = 0.2632.
    assert tb.binomial_test(15, 20, 0.5).p_value == pytest.approx(0.041389, abs=1e-6)
    assert tb.binomial_test(7, 20, 0.5).p_value == pytest.approx(0.263176, abs=1e-6)


def test_clopper_pearson_interval_tails():
    k, n = 5, 20
    lo, hi = tb.binomial_interval(k, n, 0.95)
    assert sum(binom_pmf(j, n, lo) for j in range(k, n + 1)) == pytest.approx(0.025, rel=1e-6)
    assert sum(binom_pmf(j, n, hi) for j in range(0, k + 1)) == pytest.approx(0.025, rel=1e-6)


# --- Kolmogorov-Smirnov -----------------------------------------------------------------------
def test_ks_uniform_and_negative_control():
    rng = np.random.default_rng(3)
    u = rng.uniform(size=2000)
    assert not tb.ks_test(u, lambda x: x).rejects(0.01)
    assert tb.ks_test(u**1.2, lambda x: x).rejects(0.01)  # negative control: a skewed sample

"""The chi-square sampler tester from Python (docs/python.md).

Every statistical test states its level ALPHA, uses fixed seeds, and is paired with a negative
control that must be rejected.
"""
import math

import numpy as np
import pytest

import testbench as tb

ALPHA = 0.01
N = 1_000_000


# --- a researcher's own sampler, written in NumPy: the cosine-power lobe -----------------------
def lobe_sample(n):
    """cos(theta) = u0^(1/(n+1)), phi = 2 pi u1: pdf (n+1)/(2 pi) cos^n(theta) per solid angle."""

    def sample(u):
        cos_t = u[:, 0] ** (1.0 / (n + 1.0))
        sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
        phi = 2.0 * np.pi * u[:, 1]
        return np.stack([sin_t * np.cos(phi), sin_t * np.sin(phi), cos_t], axis=1)

    return sample


def lobe_pdf(n, scale=1.0):
    def pdf(w):
        z = w[:, 2]
        return np.where(z > 0.0, scale * (n + 1.0) / (2.0 * np.pi) * np.maximum(z, 0.0) ** n, 0.0)

    return pdf


def test_lobe_sampler_passes():
    r = tb.chi2_test(tb.Chi2Domain.hemisphere(), lobe_sample(8), lobe_pdf(8), samples=N, seed=1)
    assert r.pdf_integral == pytest.approx(1.0, abs=1e-6)
    assert r.outside == 0 and r.failed == 0
    assert r.observed.shape == (51, 101) and r.observed.sum() == N
    assert r.passed(ALPHA), r.message()


def test_negative_control_pdf_five_percent_high():
    r = tb.chi2_test(tb.Chi2Domain.hemisphere(), lobe_sample(8), lobe_pdf(8, scale=1.05), samples=N, seed=1)
    assert r.pdf_integral == pytest.approx(1.05, abs=1e-6)
    assert not r.passed(ALPHA), r.message()


def test_negative_control_wrong_exponent():
    # Samples from n = 8, pdf of n = 9 (normalised): a shape error, not a scale error.
    r = tb.chi2_test(tb.Chi2Domain.hemisphere(), lobe_sample(8), lobe_pdf(9), samples=N, seed=1)
    assert r.pdf_integral == pytest.approx(1.0, abs=1e-6)
    assert not r.passed(ALPHA), r.message()


# --- agreement with the C++ tester -----------------------------------------------------------
def uniform_sphere_numpy(u):
    z = 1.0 - 2.0 * u[:, 0]
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    phi = 2.0 * np.pi * u[:, 1]
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


@pytest.mark.parametrize(
    "warp, domain, sample, pdf",
    [
        ("uniform_sphere", tb.Chi2Domain.sphere(), uniform_sphere_numpy,
         lambda w: np.full(len(w), 1.0 / (4.0 * np.pi))),
        ("cosine_hemisphere", tb.Chi2Domain.hemisphere(), tb.warps.sample_cosine_hemisphere,
         tb.warps.pdf_cosine_hemisphere),
    ],
)
def test_same_counts_as_cpp_tester(warp, domain, sample, pdf):
    """Sample i uses the stream (seed, key, i) in both testers, so the histograms coincide; the
    pdfs are polynomial in (phi, cos theta), so 7-point Gauss-Legendre and adaptive Gauss-Kronrod
    give the same expected counts."""
    key = tb.hash_string("python." + warp)
    py_result = tb.chi2_test(domain, sample, pdf, samples=200_000, seed=5, key=key)
    cpp_result = tb.chi2_test_builtin(warp, domain, samples=200_000, seed=5, key=key)
    mismatched = np.abs(py_result.observed - cpp_result.observed).sum()
    assert mismatched <= 4, f"{mismatched} samples binned differently"  # NumPy vs libm trig, at cell edges
    np.testing.assert_allclose(py_result.expected, cpp_result.expected, rtol=1e-9, atol=1e-9)
    assert py_result.p_value == pytest.approx(cpp_result.p_value, rel=1e-2, abs=1e-4)
    assert py_result.passed(ALPHA) and cpp_result.passed(ALPHA)


def test_negative_control_numpy_sampler_vs_cpp_pdf():
    # The uniform sphere sampler against the cosine pdf on the sphere: rejected by both testers' logic.
    r = tb.chi2_test(tb.Chi2Domain.sphere(), uniform_sphere_numpy,
                     lambda w: np.maximum(w[:, 2], 0.0) / np.pi, samples=200_000, seed=5)
    assert not r.passed(ALPHA)
    assert r.zero_expected_observed > 0  # samples in the lower hemisphere, where the pdf is 0


# --- interval and rectangle domains -----------------------------------------------------------
def test_interval_linear_density():
    r = tb.chi2_test(tb.Chi2Domain.interval(0.0, 1.0, 50), lambda u: np.sqrt(u[:, 0]), lambda x: 2.0 * x,
                     samples=200_000, seed=2)
    assert r.passed(ALPHA), r.message()
    wrong = tb.chi2_test(tb.Chi2Domain.interval(0.0, 1.0, 50), lambda u: u[:, 0], lambda x: 2.0 * x,
                         samples=200_000, seed=2)
    assert not wrong.passed(ALPHA), wrong.message()


def test_rectangle_product_density():
    # x ~ 2x on [0, 1], y ~ uniform on [0, 2]: pdf = 2x * 1/2 = x.
    def sample(u):
        return np.stack([np.sqrt(u[:, 0]), 2.0 * u[:, 1]], axis=1)

    dom = tb.Chi2Domain.rectangle((0.0, 0.0), (1.0, 2.0), 31, 31)
    r = tb.chi2_test(dom, sample, lambda p: p[:, 0], samples=300_000, seed=3)
    assert r.pdf_integral == pytest.approx(1.0, abs=1e-9)
    assert r.passed(ALPHA), r.message()
    # Negative control: the stated pdf tilted by 10% in y (still normalised): 1 + 0.1 (y - 1).
    wrong = tb.chi2_test(dom, sample, lambda p: p[:, 0] * (1.0 + 0.1 * (p[:, 1] - 1.0)), samples=300_000, seed=3)
    assert wrong.pdf_integral == pytest.approx(1.0, abs=1e-9)
    assert not wrong.passed(ALPHA), wrong.message()


# --- failed samples and samples outside the domain --------------------------------------------
def failing_sampler(u):
    """Uniform on [0, 1], but fails (valid = False) for u1 >= 0.8: a sub-probability density 0.8."""
    return u[:, 0], u[:, 1] < 0.8


def test_failures_matching_the_pdf_deficit_pass():
    r = tb.chi2_test(tb.Chi2Domain.interval(0.0, 1.0, 40), failing_sampler, lambda x: np.full(len(x), 0.8),
                     samples=200_000, seed=4)
    assert r.failed == pytest.approx(0.2 * 200_000, rel=0.02)
    assert r.pdf_integral == pytest.approx(0.8, abs=1e-9)
    assert r.passed(ALPHA), r.message()


def test_negative_control_failures_where_pdf_claims_full_mass():
    r = tb.chi2_test(tb.Chi2Domain.interval(0.0, 1.0, 40), failing_sampler, lambda x: np.ones(len(x)),
                     samples=200_000, seed=4)
    assert not r.passed(ALPHA)
    assert r.p_value == 0.0 and r.zero_expected_observed == r.failed


def test_directions_outside_the_hemisphere_fail_hard():
    pdf = lambda w: np.full(len(w), 1.0 / (4.0 * np.pi))  # noqa: E731
    inside = tb.chi2_test(tb.Chi2Domain.sphere(), uniform_sphere_numpy, pdf, samples=50_000, seed=6)
    assert inside.outside == 0 and inside.passed(ALPHA)
    # Negative control: the same sampler on the hemisphere: half its samples are below it.
    below = tb.chi2_test(tb.Chi2Domain.hemisphere(), uniform_sphere_numpy, pdf, samples=50_000, seed=6)
    assert below.outside > 0 and below.p_value == 0.0 and not below.passed(ALPHA)
    assert "outside the domain" in below.message() and "seed 6" in below.first_outside


def test_non_unit_directions_fail_hard():
    r = tb.chi2_test(tb.Chi2Domain.sphere(), lambda u: 1.01 * uniform_sphere_numpy(u),
                     lambda w: np.full(len(w), 1.0 / (4.0 * np.pi)), samples=10_000, seed=6)
    assert r.outside == 10_000 and not r.passed(ALPHA)


# --- calibration of the p-values under the null -----------------------------------------------
def test_p_values_uniform_under_the_null():
    """40 seeds of a correct sampler: the p-values are uniform (KS at ALPHA); a sampler whose pdf is
    2% off in shape gives p-values that are not (the negative control)."""
    dom = tb.Chi2Domain.interval(0.0, 1.0, 20)
    sample = lambda u: np.sqrt(u[:, 0])  # noqa: E731
    good = [tb.chi2_test(dom, sample, lambda x: 2.0 * x, samples=20_000, seed=s).p_value for s in range(100, 140)]
    bad = [tb.chi2_test(dom, sample, lambda x: 0.98 * 2.0 * x + 0.02, samples=20_000, seed=s).p_value
           for s in range(100, 140)]
    assert not tb.ks_test(np.array(good), lambda p: np.clip(p, 0.0, 1.0)).rejects(ALPHA)
    assert tb.ks_test(np.array(bad), lambda p: np.clip(p, 0.0, 1.0)).rejects(ALPHA)


# --- determinism and argument checking ---------------------------------------------------------
def test_fixed_seed_is_reproducible_and_chunking_does_not_matter():
    dom = tb.Chi2Domain.hemisphere(21, 11)
    a = tb.chi2_test(dom, lobe_sample(3), lobe_pdf(3), samples=30_000, seed=9)
    b = tb.chi2_test(dom, lobe_sample(3), lobe_pdf(3), samples=30_000, seed=9, chunk=777)
    c = tb.chi2_test(dom, lobe_sample(3), lobe_pdf(3), samples=30_000, seed=10)
    np.testing.assert_array_equal(a.observed, b.observed)
    np.testing.assert_allclose(a.expected, b.expected, rtol=1e-12)
    assert not np.array_equal(a.observed, c.observed)


def test_subdivisions_resolve_a_discontinuity():
    # A uniform cone of half-angle 0.3 on the sphere grid: its rim cuts a row of cells, where the
    # fixed Gauss-Legendre rule is inexact; 8 x 8 sub-cells cut the error by about 8, and a cap
    # domain whose edge is the rim integrates it exactly.
    cos_max = math.cos(0.3)

    def pdf(w):
        return np.where(w[:, 2] >= cos_max, 1.0 / (2.0 * np.pi * (1.0 - cos_max)), 0.0)

    def integral_error(domain, subdivisions):
        r = tb.chi2_test(domain, uniform_sphere_numpy, pdf, samples=10, seed=1, subdivisions=subdivisions)
        return abs(1.0 - r.pdf_integral)

    coarse = integral_error(tb.Chi2Domain.sphere(), 1)
    fine = integral_error(tb.Chi2Domain.sphere(), 8)
    assert coarse > 1e-2 and fine < 0.2 * coarse
    assert integral_error(tb.Chi2Domain.spherical_cap(cos_max), 1) < 1e-9


def test_bad_shapes_and_densities_raise():
    dom = tb.Chi2Domain.hemisphere(11, 5)
    with pytest.raises(ValueError, match="shape"):
        tb.chi2_test(dom, lambda u: u, lobe_pdf(1), samples=100)
    with pytest.raises(ValueError, match="must be finite"):
        tb.chi2_test(dom, lobe_sample(1), lambda w: -np.ones(len(w)), samples=100)
    with pytest.raises(ValueError, match="validity mask"):
        tb.chi2_test(dom, lambda u: (lobe_sample(1)(u), np.ones(3, dtype=bool)), lobe_pdf(1), samples=100)

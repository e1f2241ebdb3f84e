"""testbench.render: a scene rendered from Python, compared with the same Welch statistics as
`tb compare` (per-pixel z of the difference of two independent renders, sum z^2 and Stouffer).

Statistical test: alpha = 1e-3 per assertion, seeds fixed; the negative control (one image's
albedo-like scale of 1.05, i.e. a biased renderer) must be rejected at the same alpha.
"""
import os

import numpy as np
import pytest

import testbench as tb

SCENE = os.path.join(os.path.dirname(__file__), "..", "..", "scenes", "cornell-box.json")
ALPHA = 1e-3


def z_image(a, b, scale=1.0):
    d = scale * a["mean"] - b["mean"]
    v = scale * scale * a["variance_of_mean"] + b["variance_of_mean"]
    keep = v > 0
    return d[keep] / np.sqrt(v[keep])


def test_render_returns_mean_and_variance_arrays():
    r = tb.render(SCENE, integrator="pt", spp=16, passes=8, seed=1, resolution="12x8", threads=1)
    assert r["mean"].shape == (8, 12, 3) and r["variance_of_mean"].shape == (8, 12, 3)
    assert np.all(np.isfinite(r["mean"])) and np.all(r["variance_of_mean"] >= 0)
    assert r["mean"].mean() > 0.01
    assert r["passes"] == 8 and r["spp"] == 16 and r["integrator"] == "pt" and r["seconds"] >= 0
    # without spp, the scene's (as tb render): cornell-box.json sets 64
    d = tb.render(SCENE, integrator="pt", passes=2, resolution="4x4", threads=1)
    assert d["spp"] == 64
    # the same seed gives the same image, whatever the thread count
    again = tb.render(SCENE, integrator="pt", spp=16, passes=8, seed=1, resolution="12x8", threads=2)
    np.testing.assert_array_equal(r["mean"], again["mean"])


def test_pt_and_bdpt_agree_and_a_biased_render_is_caught():
    a = tb.render(SCENE, integrator="pt", spp=256, passes=16, seed=11, resolution="16x16")
    b = tb.render(SCENE, integrator="bdpt", spp=64, passes=16, seed=12, resolution="16x16")
    z = z_image(a, b)
    assert z.size > 600
    assert tb.sum_z2_test(z).p_value > ALPHA
    assert tb.stouffer(z).p_value > ALPHA
    # negative control: a 5% bias in one render
    zc = z_image(a, b, scale=1.05)
    assert tb.stouffer(zc).p_value < ALPHA


def test_bad_arguments_are_value_errors_naming_them():
    with pytest.raises(ValueError, match="unknown integrator 'ptt'"):
        tb.render(SCENE, integrator="ptt")
    with pytest.raises(ValueError, match="spp must be"):
        tb.render(SCENE, spp=0)
    with pytest.raises(ValueError, match="passes must be"):
        tb.render(SCENE, passes=0)
    with pytest.raises(ValueError, match="threads must be"):
        tb.render(SCENE, threads=-2)
    with pytest.raises(ValueError, match="bogus"):
        tb.render(SCENE, params={"bogus": 1.0})
    with pytest.raises(Exception, match="resolution"):
        tb.render(SCENE, resolution="0x4")
    with pytest.raises(Exception, match="no_such_scene"):
        tb.render("no_such_scene.json")

"""`tb compare A.exr --reference-mean R.pfm --reference-variance V.pfm`: a render checked against
another renderer's mean image and variance of the mean, written as PFM files by NumPy here (the
standard layout: "PF", width height, scale -1 for little endian, float32 rows bottom to top).

The "other renderer" is this module's bdpt at 16 passes; tb renders pt. alpha = 1e-3 (the
comparison's own level, --alpha), fixed seeds. Negative control: the reference mean scaled by
1.05 must be rejected (exit 1).
"""
import os
import subprocess

import numpy as np
import pytest

import testbench as tb

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
SCENE = os.path.join(ROOT, "scenes", "cornell-box.json")


def tb_program():
    p = os.environ.get("TB_PROGRAM") or os.path.join(ROOT, "build", "tb")
    if not os.path.exists(p):
        pytest.skip("the tb program is not built (CTest sets TB_PROGRAM)")
    return p


def write_pfm(path, rgb):
    h, w, _ = rgb.shape
    with open(path, "wb") as f:
        f.write(f"PF\n{w} {h}\n-1.0\n".encode())
        f.write(np.ascontiguousarray(rgb[::-1], dtype="<f4").tobytes())


def test_tb_compare_against_a_pfm_reference(tmp_path):
    prog = tb_program()
    ref = tb.render(SCENE, integrator="bdpt", spp=256, passes=16, seed=21, resolution="16x16")
    write_pfm(tmp_path / "mean.pfm", ref["mean"])
    write_pfm(tmp_path / "variance.pfm", ref["variance_of_mean"])
    write_pfm(tmp_path / "biased.pfm", 1.05 * ref["mean"])
    a = tmp_path / "pt.exr"
    subprocess.run([prog, "render", SCENE, "--integrator", "pt", "--spp", "512", "--passes", "16",
                    "--resolution", "16x16", "--seed", "22", "--no-progress", "-o", str(a)], check=True,
                   capture_output=True)

    def compare(mean):
        return subprocess.run([prog, "compare", str(a), "--reference-mean", str(tmp_path / mean),
                               "--reference-variance", str(tmp_path / "variance.pfm"), "--alpha", "1e-3"],
                              capture_output=True, text=True)

    same = compare("mean.pfm")
    assert same.returncode == 0, same.stdout + same.stderr
    biased = compare("biased.pfm")
    assert biased.returncode == 1, biased.stdout + biased.stderr
    # a variance image of the wrong size is a usage error naming both files
    write_pfm(tmp_path / "small.pfm", ref["variance_of_mean"][:8])
    bad = subprocess.run([prog, "compare", str(a), "--reference-mean", str(tmp_path / "mean.pfm"),
                          "--reference-variance", str(tmp_path / "small.pfm")], capture_output=True, text=True)
    assert bad.returncode == 2 and "small.pfm" in bad.stderr

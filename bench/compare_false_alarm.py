#!/usr/bin/env python3
"""False-alarm rate of `tb compare` on pairs of correct renders (docs/statistics.md, "Heavy tails").

For each integrator, R independent pairs: A renders S spp, B renders 8 S spp (same number of
passes, so each of B's Welch samples averages 8x the raw samples), with seeds of their own; both
are correct renders of the same scene, so every DIFFERENT verdict is a false alarm. Each pair is
compared with the tiled test (the default) and with the per-pixel test at alpha. Prints the
rejection counts, rates and exact 95% Clopper-Pearson intervals, and writes them as JSON.

  python3 bench/compare_false_alarm.py [--tb build/tb] [--scene scenes/cornell-box.json]
      [--size 24x24] [--alpha 0.01] [--plan pt:64:100,lt:64:100,bdpt:32:60,pssmlt:32:40]
      [--passes 8] [--out reports/out/compare-false-alarm.json]

--plan is integrator:S:R, comma separated.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time


def binom_cdf(k, n, p):
    if k < 0:
        return 0.0
    if k >= n:
        return 1.0
    # sum of pmf via logs
    total = 0.0
    for i in range(0, k + 1):
        total += math.exp(math.lgamma(n + 1) - math.lgamma(i + 1) - math.lgamma(n - i + 1) + i * math.log(p) +
                          (n - i) * math.log1p(-p))
    return min(1.0, total)


def clopper_pearson(k, n, conf=0.95):
    a = (1.0 - conf) / 2.0

    def bisect(f):
        lo, hi = 0.0, 1.0
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            if f(mid):
                hi = mid
            else:
                lo = mid
        return 0.5 * (lo + hi)

    lo = 0.0 if k == 0 else bisect(lambda p: 1.0 - binom_cdf(k - 1, n, p) >= a)
    hi = 1.0 if k == n else bisect(lambda p: binom_cdf(k, n, p) <= a)
    return lo, hi


def run(cmd):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    return r.returncode, r.stdout, r.stderr


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tb", default="build/tb")
    ap.add_argument("--scene", default="scenes/cornell-box.json")
    ap.add_argument("--size", default="24x24")
    ap.add_argument("--alpha", type=float, default=0.01)
    ap.add_argument("--plan", default="pt:64:100,lt:64:100,bdpt:32:60,pssmlt:32:40")
    ap.add_argument("--passes", type=int, default=8)
    ap.add_argument("--ratio", type=int, default=8, help="B's spp / A's spp")
    ap.add_argument("--out", default="reports/out/compare-false-alarm.json")
    args = ap.parse_args()

    results = []
    t0 = time.time()
    with tempfile.TemporaryDirectory() as tmp:
        for item in args.plan.split(","):
            integ, spp, reps = item.split(":")
            spp, reps = int(spp), int(reps)
            counts = {"tiled": 0, "pixel": 0}
            tiles, shifts_pixel, zs = [], [], {"tiled": [], "pixel": []}
            which = {"tiled": {"pixel_or_tile": 0, "stouffer": 0, "sum_z2": 0},
                     "pixel": {"pixel_or_tile": 0, "stouffer": 0, "sum_z2": 0}}
            for r in range(reps):
                paths = []
                for side, s in (("a", spp), ("b", spp * args.ratio)):
                    seed = (r * 2 + (1 if side == "a" else 2)) + 100000 * (sum(map(ord, integ)) % 97)
                    p = os.path.join(tmp, f"{integ}-{r}-{side}.exr")
                    rc, _, err = run([args.tb, "render", args.scene, "--integrator", integ, "--spp", str(s), "--passes",
                                      str(args.passes), "--seed", str(seed), "--resolution", args.size, "-o", p,
                                      "--no-progress"])
                    if rc != 0:
                        sys.exit(f"render failed: {err}")
                    paths.append(p)
                for test in ("tiled", "pixel"):
                    j = os.path.join(tmp, f"{integ}-{r}-{test}.json")
                    rc, out, err = run([args.tb, "compare", paths[0], paths[1], "--alpha", str(args.alpha), "--test", test,
                                        "--json", j])
                    if rc not in (0, 1):
                        sys.exit(f"compare failed: {err}")
                    d = json.load(open(j))
                    counts[test] += int(d["rejects"])
                    if d["rejects"]:  # which of the three tests rejected (each at alpha_each)
                        which[test]["pixel_or_tile"] += int(d["zero_variance_mismatch"] > 0 or
                                                            d["p_pixel_family"] < d["alpha_each"])
                        which[test]["stouffer"] += int(d["stouffer_p"] < d["alpha_each"])
                        which[test]["sum_z2"] += int(d["sum_z2_p"] < d["alpha_each"])
                    zs[test].append(d["stouffer_z"])
                    if test == "tiled":
                        tiles.append(d["tile"])
                        shifts_pixel.append(d["predicted_skew_shift_pixel"])
                for p in paths:
                    os.remove(p)
            row = {"integrator": integ, "spp_a": spp, "spp_b": spp * args.ratio, "pairs": reps}
            for test in ("tiled", "pixel"):
                lo, hi = clopper_pearson(counts[test], reps)
                row[test] = {"rejections": counts[test], "rate": counts[test] / reps, "ci95": [lo, hi],
                             "mean_stouffer_z": sum(zs[test]) / reps, "rejected_by": which[test]}
            row["tiles_chosen"] = sorted(set(tiles))
            row["mean_predicted_shift_pixel"] = sum(shifts_pixel) / reps
            results.append(row)
            print(f"{integ:8s} A {spp} spp, B {spp * args.ratio} spp, {reps} pairs: "
                  f"tiled {counts['tiled']}/{reps} = {row['tiled']['rate']:.3f} "
                  f"[{row['tiled']['ci95'][0]:.3f}, {row['tiled']['ci95'][1]:.3f}] (k {row['tiles_chosen']}, "
                  f"mean Z {row['tiled']['mean_stouffer_z']:+.2f}); "
                  f"pixel {counts['pixel']}/{reps} = {row['pixel']['rate']:.3f} "
                  f"[{row['pixel']['ci95'][0]:.3f}, {row['pixel']['ci95'][1]:.3f}] "
                  f"(mean Z {row['pixel']['mean_stouffer_z']:+.2f}; tiled rejections by {which['tiled']}, predicted skew shift {row['mean_predicted_shift_pixel']:.2f}); "
                  f"{time.time() - t0:.0f} s", flush=True)
    os.makedirs(os.path.dirname(args.out) or ".", exist_ok=True)
    json.dump({"command": " ".join(sys.argv), "scene": args.scene, "size": args.size, "alpha": args.alpha,
               "passes": args.passes, "results": results, "seconds": time.time() - t0}, open(args.out, "w"), indent=1)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Summarises estimators_bench JSON runs (docs/estimators.md, "Benchmark").

For each cost of p(x | t) (the second benchmark argument): the log-log least-squares slope of CPU
time against n = 1, 2, 4, 8, 16 for BM_MmisBudget, BM_MmisEvaluate, BM_MmisWeights and
BM_BarePdfEvals, and the overheads at n = 1 and n = 16: each over the bare pdf evaluations, and the
estimate over all the bare work an estimate must do (N pair draws + N evaluations of f + n·N·T pdf
evaluations, when BM_BareDraws and BM_BareIntegrand are in the file). Then, per benchmark, whether
the target of docs/estimators.md holds: slope 1 ± 0.1 and at most 2x the bare pdf evaluations at
every n. Several files (rounds) are summarised one by one and then by the median over rounds of
each time.

usage: mmis_bench_summary.py run1.json [run2.json ...]
"""
import json
import math
import statistics
import sys

NS = [1, 2, 4, 8, 16]


def load(path):
    with open(path) as f:
        data = json.load(f)
    t = {}
    for b in data["benchmarks"]:
        if b.get("run_type", "iteration") != "iteration":
            continue
        unit = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}[b.get("time_unit", "ns")]
        t[b["name"]] = b["cpu_time"] * unit
    return t


def slope(ys):
    xs = [math.log(n) for n in NS]
    ls = [math.log(y) for y in ys]
    mx, my = sum(xs) / len(xs), sum(ls) / len(ls)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ls)) / sum((x - mx) ** 2 for x in xs)


def summarise(t, label):
    print(f"== {label}")
    for cost in (0, 20, 200):
        row = {}
        for bm in ("BM_MmisBudget", "BM_MmisEvaluate", "BM_MmisWeights", "BM_BarePdfEvals"):
            ys = [t.get(f"{bm}/{n}/{cost}") for n in NS]
            if all(y is not None for y in ys):
                row[bm] = ys
        if "BM_BarePdfEvals" not in row:
            continue
        bare = row["BM_BarePdfEvals"]
        line = f"cost {cost:3d}: bare pdf slope {slope(bare):.3f}, n=1 {bare[0] * 1e6:.2f} us"
        b = row.get("BM_MmisBudget")
        if b:
            line += (f"; budget slope {slope(b):.3f}, budget/bare pdf n=1 {b[0] / bare[0]:.2f}x,"
                     f" n=16 {b[-1] / bare[-1]:.2f}x")
        if "BM_MmisEvaluate" in row:
            e = row["BM_MmisEvaluate"]
            line += (f"; evaluate slope {slope(e):.3f}, evaluate/bare pdf n=1 {e[0] / bare[0]:.2f}x,"
                     f" n=16 {e[-1] / bare[-1]:.2f}x")
        if "BM_MmisWeights" in row:
            w = row["BM_MmisWeights"]
            line += (f"; weights slope {slope(w):.3f}, weights/bare pdf n=1 {w[0] / bare[0]:.2f}x,"
                     f" n=16 {w[-1] / bare[-1]:.2f}x")
        draws, fx = t.get(f"BM_BareDraws/{cost}"), t.get("BM_BareIntegrand")
        if b and draws is not None and fx is not None:
            work = [draws + fx + p for p in bare]
            line += (f"; bare work slope {slope(work):.3f}, budget/bare work n=1 {b[0] / work[0]:.2f}x,"
                     f" n=16 {b[-1] / work[-1]:.2f}x (draws {draws * 1e6:.2f} us, f {fx * 1e6:.2f} us)")
        print(line)
        for bm in ("BM_MmisBudget", "BM_MmisEvaluate", "BM_MmisWeights"):
            if bm in row:
                ys = row[bm]
                worst = max(y / p for y, p in zip(ys, bare))
                ok = abs(slope(ys) - 1.0) <= 0.1 and worst <= 2.0
                print(f"    target {bm} cost {cost}: slope {slope(ys):.3f}, worst ratio to bare pdf {worst:.2f}x"
                      f" -> {'met' if ok else 'MISSED'}")


def main():
    runs = [load(p) for p in sys.argv[1:]]
    for p, t in zip(sys.argv[1:], runs):
        summarise(t, p)
    if len(runs) > 1:
        names = set.intersection(*(set(t) for t in runs))
        summarise({k: statistics.median(t[k] for t in runs) for k in names}, f"median of {len(runs)} rounds")


if __name__ == "__main__":
    main()

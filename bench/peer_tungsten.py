#!/usr/bin/env python3
"""Side-by-side runs of this project's integrators and Tungsten's on one scene, alternating.

Each round renders every (ours, peer) pair once, ours and the peer back to back, so drift of the
machine over a session hits both alike. Per run it records wall and CPU time (user + system of
the whole process, from os.wait4) and the relMSE against a reference image, with `tb compare`:
relMSE = mean over pixels and channels of (x - r)^2 / (r^2 + 0.01). The figure of merit printed is
relMSE x CPU seconds (equal-time error up to the thread count: for an estimator converging as
1/t, relMSE at time T is this product / T), which is less sensitive to a loaded machine than
wall time; wall time is printed too.

Usage (Tungsten built from tunabrain/tungsten, `cmake -G Ninja -DCMAKE_BUILD_TYPE=Release`):
  bench/peer_tungsten.py --tb build/tb --tungsten /path/to/tungsten \
      --peer-scene tungsten-cornell-box.json --scene scenes/cornell-box.json \
      --reference ref.exr --pair mmlt:multiplexed_mlt:64 --rounds 3 --threads 2

--pair OURS:PEER:SPP renders OURS with `tb render --spp SPP` and the peer's integrator type PEER
with spp SPP (Tungsten's MLT integrators count mutations per pixel as spp, as ours do). PEER may
carry integrator fields after a comma, e.g. kelemen_mlt,bidirectional=true. OURS may carry
`--param` settings after a comma, e.g. mmlt,large_step=0.1. The peer writes its image through
renderer.hdr_output_file (its output_buffers miss the light-tracing splats of BDPT and MLT).
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time


def run_timed(cmd, cwd=None, check=True):
    t0 = time.monotonic()
    p = subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    out = p.stdout.read().decode(errors="replace")
    _, status, ru = os.wait4(p.pid, 0)
    wall = time.monotonic() - t0
    if check and os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"failed ({os.waitstatus_to_exitcode(status)}): {' '.join(cmd)}\n{out[-2000:]}")
    return wall, ru.ru_utime + ru.ru_stime, out


def rel_mse(tb, image, reference):
    # tb compare exits 1 when it finds the images different; only its relMSE is read here.
    _, _, out = run_timed([tb, "compare", image, reference], check=False)
    m = re.search(r"relMSE\(eps 0\.01\) ([0-9.eE+-]+)", out)
    if not m:
        sys.exit(f"tb compare printed no relMSE:\n{out}")
    return float(m.group(1))


def split_fields(spec):
    name, *rest = spec.split(",")
    fields = {}
    for kv in rest:
        k, v = kv.split("=", 1)
        try:
            fields[k] = json.loads(v)
        except json.JSONDecodeError:
            fields[k] = v
    return name, fields


def peer_scene(base, integrator, fields, spp, out_file):
    scene = json.loads(json.dumps(base))
    integ = dict(scene.get("integrator", {}))
    integ["type"] = integrator
    integ.update(fields)
    scene["integrator"] = integ
    r = scene.setdefault("renderer", {})
    r["spp"] = spp
    r["spp_step"] = spp
    r["timeout"] = "0"
    r["output_buffers"] = []
    r["output_file"] = out_file + ".png"
    r["hdr_output_file"] = out_file
    r["enable_resume_render"] = False
    return scene


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tb", required=True)
    ap.add_argument("--tungsten", required=True)
    ap.add_argument("--peer-scene", required=True, help="the scene in Tungsten's JSON format")
    ap.add_argument("--scene", required=True, help="the same scene in this project's format")
    ap.add_argument("--reference", required=True, help="reference image (EXR or PFM)")
    ap.add_argument("--pair", action="append", required=True, help="OURS:PEER:SPP")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--resolution", default=None, help="WxH for both renderers (default: the scenes' own)")
    ap.add_argument("--work", default=None, help="folder for the images (default: a temporary one)")
    a = ap.parse_args()

    tb = os.path.abspath(a.tb)
    tungsten = os.path.abspath(a.tungsten)
    with open(a.peer_scene) as f:
        base = json.load(f)
    peer_dir = os.path.dirname(os.path.abspath(a.peer_scene))
    work = os.path.abspath(a.work) if a.work else tempfile.mkdtemp(prefix="peer_tungsten_")
    os.makedirs(work, exist_ok=True)
    rows = []
    for rnd in range(a.rounds):
        for spec in a.pair:
            ours, peer, spp = spec.split(":")
            spp = int(spp)
            our_name, our_params = split_fields(ours)
            peer_name, peer_fields = split_fields(peer)
            seed = 1 + rnd
            # Ours.
            img = os.path.join(work, f"ours-{our_name}-{rnd}.exr")
            cmd = [tb, "render", os.path.abspath(a.scene), "--integrator", our_name, "--spp", str(spp), "--threads",
                   str(a.threads), "--seed", str(seed), "-o", img, "--no-progress"]
            if a.resolution:
                cmd += ["--resolution", a.resolution]
            for k, v in our_params.items():
                cmd += ["--param", f"{k}={v}"]
            wall, cpu, _ = run_timed(cmd)
            rows.append(("ours", ours, spp, rnd, wall, cpu, rel_mse(tb, img, a.reference)))
            print(f"round {rnd} ours {ours:28s} wall {wall:7.2f} s cpu {cpu:7.2f} s relMSE {rows[-1][-1]:.4g} "
                  f"relMSE*cpu {rows[-1][-1] * cpu:.4g}", flush=True)
            # The peer: its scene next to the original, so relative paths (meshes) resolve.
            pimg = os.path.join(work, f"peer-{peer_name}-{rnd}.pfm")
            scene = peer_scene(base, peer_name, peer_fields, spp, pimg)
            if a.resolution:
                w, h = (int(v) for v in a.resolution.split("x"))
                for cam in [scene.get("camera", {})]:
                    cam["resolution"] = [w, h]
            sfile = os.path.join(peer_dir, f".peer_tungsten_{os.getpid()}.json")
            with open(sfile, "w") as f:
                json.dump(scene, f)
            try:
                wall, cpu, _ = run_timed([tungsten, "--threads", str(a.threads), "--seed", str(seed), sfile],
                                         cwd=peer_dir)
            finally:
                os.remove(sfile)
            rows.append(("peer", peer, spp, rnd, wall, cpu, rel_mse(tb, pimg, a.reference)))
            print(f"round {rnd} peer {peer:28s} wall {wall:7.2f} s cpu {cpu:7.2f} s relMSE {rows[-1][-1]:.4g} "
                  f"relMSE*cpu {rows[-1][-1] * cpu:.4g}", flush=True)
    print("\nmeans over rounds (relMSE*cpu: lower is better at equal CPU time)")
    keys = sorted({(r[0], r[1], r[2]) for r in rows}, key=lambda k: (k[2], k[1], k[0]))
    for who, name, spp in keys:
        sel = [r for r in rows if (r[0], r[1], r[2]) == (who, name, spp)]
        n = len(sel)
        wall = sum(r[4] for r in sel) / n
        cpu = sum(r[5] for r in sel) / n
        err = sum(r[6] for r in sel) / n
        print(f"{who:4s} {name:32s} spp {spp:5d}: wall {wall:7.2f} s, cpu {cpu:7.2f} s, relMSE {err:.4g}, "
              f"relMSE*cpu {err * cpu:.4g}")


if __name__ == "__main__":
    main()

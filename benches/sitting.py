#!/usr/bin/env python3
"""One sitting against Embree 3, the figures of PERF.md's sitting tables.

    benches/sitting.py WHITTED EMBREE_BENCH ROUNDS OUTDIR [scene ...]

WHITTED is a `whitted` binary (`cargo build --release`), EMBREE_BENCH the harness of
../shared/peer-embree/ built with its `build.sh` (in a copy: the shared folder is read-only).
Each round runs, scene by scene, `WHITTED bench --scene S --reps 3` and then
`EMBREE_BENCH --scene S --reps 3 --no-build-mt`; every process's rows are kept in OUTDIR.
Scenes: spheres64, spheres4096, torus100k, torus1m (all four by default).

For each kind of ray it prints whitted's best and median Mrays/s over the rounds, Embree's
fastest kernel for that kind (best and median), the ratio of the bests and of the medians, and
both programs' hit counts; for the build, the best and median times and the round-by-round
pairs. Nothing else should run meanwhile.
"""
import os
import statistics
import subprocess
import sys
import time

KINDS = ["primary", "shadow", "mirror", "diffuse"]
SCENES = ["spheres64", "spheres4096", "torus100k", "torus1m"]


def rows(out):
    """`CSV,scene,kernel,rays,hits,ms,rate` rows as {(scene, kernel): (hits, ms, rate)}."""
    found = {}
    for line in out.splitlines():
        if line.startswith("CSV,"):
            _, scene, kernel, _rays, hits, ms, rate = line.split(",")
            found[(scene, kernel)] = (int(hits), float(ms), float(rate))
    return found


def main():
    if len(sys.argv) < 5:
        sys.exit(__doc__)
    whitted, embree = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    rounds, outdir = int(sys.argv[3]), sys.argv[4]
    scenes = sys.argv[5:] or SCENES
    os.makedirs(outdir, exist_ok=True)
    runs = {"whitted": [], "embree": []}
    start = time.strftime("%H:%M:%S", time.gmtime())
    for k in range(rounds):
        for s in scenes:
            for who, cmd in (
                ("whitted", [whitted, "bench", "--scene", s, "--reps", "3"]),
                ("embree", [embree, "--scene", s, "--reps", "3", "--no-build-mt"]),
            ):
                out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
                with open(os.path.join(outdir, f"{who}-{s}-{k}.csv"), "w") as f:
                    f.write(out)
                runs[who].append(rows(out))
    end = time.strftime("%H:%M:%S", time.gmtime())
    print(f"sitting, {rounds} rounds, {start}-{end} UTC")
    med = statistics.median

    def series(who, key):
        return [r[key] for r in runs[who] if key in r]

    for s in scenes:
        print(s)
        for kind in KINDS:
            w = series("whitted", (s, kind))
            kernels = sorted({k[1] for r in runs["embree"] for k in r
                              if k[0] == s and k[1].startswith(kind + "/")})
            best = {k: max(x[2] for x in series("embree", (s, k))) for k in kernels}
            medians = {k: med(x[2] for x in series("embree", (s, k))) for k in kernels}
            fastest = max(best, key=best.get)
            wb, wm = max(x[2] for x in w), med(x[2] for x in w)
            em = max(medians.values())
            hits_w = sorted({x[0] for x in w})
            hits_e = sorted({x[0] for x in series("embree", (s, fastest))})
            others = ", ".join(f"{k} {v:.3f}" for k, v in best.items() if k != fastest)
            print(f"  {kind:8s} whitted {wb:8.3f} (median {wm:8.3f}); Embree {fastest} "
                  f"{best[fastest]:8.3f} (fastest median {em:8.3f}); ratio {wb / best[fastest]:.3f} "
                  f"(medians {wm / em:.3f}); hits {hits_w} / {hits_e}; [{others}]")
        w = [x[1] for x in series("whitted", (s, "build_1t_ms"))]
        e = [x[1] for x in series("embree", (s, "build_1t_ms"))]
        print(f"  build    whitted {min(w):.3f} ms (median {med(w):.3f}); Embree {min(e):.3f} ms "
              f"(median {med(e):.3f}); ratio {min(e) / min(w):.3f} (medians {med(e) / med(w):.3f})")
        print("           rounds, whitted / Embree ms: "
              + ", ".join(f"{a:.3f} / {b:.3f}" for a, b in zip(w, e)))


main()

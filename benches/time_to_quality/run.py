"""Time to quality: luster against Blender Cycles and Mitsuba 3 on three scenes.

For each scene (cornell, hdri, manylights; scenes.py) and renderer, renders a
series of sample counts, one process per render, and records the whole
process's wall and CPU time (user + system of the child, from wait4) and the
image's relative RMSE against that renderer's own high-spp reference. From
the (CPU time, error) points it interpolates, log-log, the CPU time at which
the error falls to 5% and 2%, and prints Markdown tables.

  LUSTER=target/release/luster PYTHON benches/time_to_quality/run.py --quick
  LUSTER=target/release/luster PYTHON benches/time_to_quality/run.py            (full)

PYTHON is a Python with bpy 5.0.1, mitsuba and numpy (README.md). Options:
--work DIR (default /tmp/luster_ttq), --scenes, --renderers, --res, --spp,
--ref-spp, --rounds, --cap, --ref-cap, --check-only, --no-threads; --help.

Renderers (2 threads each): luster (MIS path tracer); Cycles on the CPU with
adaptive sampling on (default noise threshold), denoiser off, light tree on
(`cycles`), and on manylights also with the light tree off (`cycles_nolt`);
Mitsuba 3 `path` in `llvm_ad_rgb` (falls back to `scalar_rgb` where LLVM is
missing). Renders alternate between renderers (A B C A B C ...); with
--rounds > 1 the medians of the times are used.

Error: rel-RMSE = sqrt(mean over pixels and RGB of (x - r)^2 / (r^2 + 0.01)),
r the reference. The reference of a renderer is the mean of two of its own
renders (seeds 1001 and 1002, --ref-spp each, Cycles without adaptive
sampling); the reference's own share of the error, a quarter of the two
halves' rel-MSE against each other, is subtracted from every test image's
rel-MSE. Each renderer is so measured against what it converges to; that the
three converge to the same image is checked first, on the references: mean
luminance and 16 x 16 block means, with z-scores from the halves' noise
(plus 0.1% of the block's mean, so that noise-free sky blocks do not count
a difference of a few 0.01% as significant).
References are cached in WORK/ref under the scene's hash, resolution and spp:
a rerun renders only the series.

Where a series never reaches a threshold, the time is extrapolated from its
last point with error^2 proportional to 1 / time and the figure marked '~';
where its first point is already below, it is marked '<'.
"""
import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
import scenes  # noqa: E402

EPS = 1e-2
THRESHOLDS = (0.05, 0.02)
LUM = np.array([0.2126, 0.7152, 0.0722])
QUICK = {"res": 64, "spp": [16, 64, 256, 1024], "ref_spp": 1024, "cap": 120, "ref_cap": 120, "rounds": 1,
         "thread_spp": 1024, "thread_rounds": 1}
FULL = {"res": 256, "spp": [16, 64, 256, 1024, 4096], "ref_spp": 4096, "cap": 1200, "ref_cap": 1800, "rounds": 1,
        "thread_spp": 256, "thread_rounds": 3}


# ------------------------------------------------------------------ running one render

def run_timed(cmd, env, log):
    """Run cmd to completion; returns (exit code, wall s, CPU s of the process and its children)."""
    t0 = time.time()
    with open(log, "w") as f:
        p = subprocess.Popen(cmd, env=env, stdout=f, stderr=subprocess.STDOUT)
        _, status, ru = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    return p.returncode, time.time() - t0, ru.ru_utime + ru.ru_stime


class Bench:
    def __init__(self, a):
        self.a = a
        self.luster = os.path.abspath(os.environ.get("LUSTER", "target/release/luster"))
        if not os.access(self.luster, os.X_OK):
            sys.exit(f"no luster binary at {self.luster!r}: set LUSTER (cargo build --release)")
        self.luster_oidn = None
        if a.denoise:
            self.luster_oidn = os.path.abspath(os.environ.get("LUSTER_OIDN", self.luster))
            p = subprocess.run([self.luster_oidn, "render", "--help"], capture_output=True, text=True)
            if not os.access(self.luster_oidn, os.X_OK) or "--denoise" not in p.stdout:
                sys.exit(f"--denoise needs a luster built with OIDN at {self.luster_oidn!r}: set LUSTER_OIDN "
                         "(tools/oidn_test.sh, then cargo build --release --features oidn)")
        self.env = dict(os.environ)
        self.env.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")
        self.variant = self.mitsuba_variant()

    def mitsuba_variant(self):
        probe = ("import mitsuba as mi; mi.set_variant('llvm_ad_rgb'); "
                 "mi.render(mi.load_dict({'type': 'scene', 'integrator': {'type': 'path'}, 'sensor': {'type': 'perspective', "
                 "'film': {'type': 'hdrfilm', 'width': 4, 'height': 4}}}), spp=1)")
        p = subprocess.run([sys.executable, "-c", probe], env=self.env, capture_output=True, text=True)
        return "llvm_ad_rgb" if p.returncode == 0 else "scalar_rgb"

    def scene_dir(self, scene, res):
        d = os.path.join(self.a.work, "scenes", f"{scene}_{res}")
        os.makedirs(d, exist_ok=True)
        return d

    def command(self, config, scene, spp, seed, res, out, cap, threads=2):
        """The command line of one render; cap: seconds after which it stops taking samples (0: none)."""
        work = self.scene_dir(scene, res)
        if config.startswith("luster"):
            xml_dir = os.path.join(os.path.dirname(out), "xml")
            os.makedirs(xml_dir, exist_ok=True)
            # the scene file sits beside its shaders and map, named after the image
            xml = scenes.luster_xml(scenes.get(scene), spp, res, os.path.basename(out), work)
            mine = os.path.join(work, os.path.basename(out)[:-4] + ".xml")
            os.replace(xml, mine)
            exe = self.luster_oidn if config == "luster_denoise" else self.luster
            cmd = [exe, "render", "-q", "-t", str(threads), "--seed", str(seed), "--spp", str(spp),
                   "-o", os.path.dirname(out), mine]
            if config == "luster_denoise":
                cmd += ["--denoise"]
            if cap:
                cmd += ["--time", str(cap)]
            return cmd
        base = [sys.executable, os.path.join(HERE, "scenes.py"), "render"]
        if config == "mitsuba":  # a series render: one render call (the cap splits it into passes)
            cap = 0
        opts = ["--spp", str(spp), "--res", str(res), "--seed", str(seed), "--threads", str(threads), "--out", out,
                "--work", work] + (["--time-limit", str(cap)] if cap else [])
        if config.startswith("cycles"):
            ref = config.endswith("_ref")
            return base + ["cycles", scene] + opts + ["--light-tree", "0" if "nolt" in config else "1",
                                                      "--adaptive", "0" if ref else "1",
                                                      "--denoise", "1" if config == "cycles_denoise" else "0"]
        if config.startswith("mitsuba"):
            return base + ["mitsuba", scene] + opts + ["--variant", self.variant]
        raise ValueError(config)

    def render(self, config, scene, spp, seed, res, out, cap, threads=2):
        os.makedirs(os.path.dirname(out), exist_ok=True)
        if os.path.exists(out):
            os.remove(out)
        cmd = self.command(config, scene, spp, seed, res, out, cap, threads)
        rc, wall, cpu = run_timed(cmd, self.env, out + ".log")
        if rc != 0 or not os.path.exists(out):
            sys.stdout.write(open(out + ".log").read()[-3000:])
            sys.exit(f"{config} failed on {scene} ({spp} spp): exit {rc}; log {out}.log")
        return {"config": config, "scene": scene, "spp": spp, "seed": seed, "res": res, "img": out,
                "wall_s": wall, "cpu_s": cpu}


# ------------------------------------------------------------------ metrics

def rel_mse(x, r):
    return float(np.mean((x - r) ** 2 / (r ** 2 + EPS)))


def block_means(y, n=16):
    """Means of an n x n grid of blocks."""
    h, w = y.shape
    return y[: h // n * n, : w // n * n].reshape(n, h // n, n, w // n).mean(axis=(1, 3))


def crossing(points, thr):
    """points: (time, err) sorted by time. Returns (time, mark): mark '' interpolated log-log
    between the bracketing points, '~' extrapolated (err^2 ~ 1/time), '<' already below at the first."""
    if not points:
        return None, ""
    if points[0][1] <= thr:
        return points[0][0], "<"
    for (x0, e0), (x1, e1) in zip(points, points[1:]):
        if e0 > thr >= e1:
            t = (math.log(e0) - math.log(thr)) / (math.log(e0) - math.log(e1))
            return math.exp(math.log(x0) + t * (math.log(x1) - math.log(x0))), ""
    x, e = points[-1]
    return x * (e / thr) ** 2, "~"


# ------------------------------------------------------------------ the steps

def families(scene, renderers, denoise=False):
    """Series configurations of a scene, each with the reference family it is measured against."""
    out = []
    for r in renderers:
        if r == "cycles":
            out.append(("cycles", "cycles"))
            if scene == "manylights":
                out.append(("cycles_nolt", "cycles"))
            if denoise:
                out.append(("cycles_denoise", "cycles"))
        elif r == "luster":
            out.append(("luster", "luster"))
            if denoise:
                out.append(("luster_denoise", "luster"))
        else:
            out.append((r, r))
    return out


def best_ratio(table, scene, cfgs, i, denoised):
    """luster's fastest configuration against the fastest other, among the denoised ones or the others."""
    def pick(mine):
        c = [(table[(scene, k)][i][0], k) for k in cfgs
             if k.startswith("luster") == mine and k.endswith("_denoise") == denoised and table[(scene, k)][i][0]]
        return min(c) if c else None
    lu, other = pick(True), pick(False)
    if not (lu and other):
        return "–"
    return f"{lu[0] / other[0]:.2f} ({lu[1]} / {other[1]})"


def references(b, scene, res, renderers, ref_spp, cap):
    """Two renders per renderer family at ref_spp (cached). Returns {family: (mean image, ref rel-MSE, halves)}."""
    desc = scenes.get(scene)
    key = f"{scene}_{res}_{scenes.digest(desc)}_{ref_spp}"
    d = os.path.join(b.a.work, "ref", key)
    os.makedirs(d, exist_ok=True)
    out = {}
    for fam in renderers:
        cfg = {"cycles": "cycles_ref", "mitsuba": "mitsuba_ref"}.get(fam, fam)
        if fam == "mitsuba":
            fam_key = f"mitsuba_{b.variant}"
        else:
            fam_key = fam
        halves = []
        for seed in (1001, 1002):
            img = os.path.join(d, f"{fam_key}_s{seed}.exr")
            meta = img + ".json"
            if not (os.path.exists(img) and os.path.exists(meta)):
                print(f"  reference {scene} {fam_key} seed {seed}: {ref_spp} spp at {res}x{res} ...", flush=True)
                rec = b.render(cfg, scene, ref_spp, seed, res, img, cap)
                json.dump(rec, open(meta, "w"))
                print(f"    wall {rec['wall_s']:.1f} s, CPU {rec['cpu_s']:.1f} s", flush=True)
            halves.append(scenes.load_exr(img))
        ref = (halves[0] + halves[1]) / 2
        out[fam] = (ref, rel_mse(halves[0], halves[1]) / 4, halves)
    return out


def agreement(scene, refs):
    """Pairwise: mean-luminance difference, 16 x 16 block means (relative), z-scores from the halves."""
    rows = []
    names = list(refs)
    lum = {k: v[0] @ LUM for k, v in refs.items()}
    # per-pixel variance of the reference mean: ((a - b) / 2)^2; of a block mean: sum / n^2
    bvar = {}
    for k, (_, _, (h0, h1)) in refs.items():
        v = (((h0 - h1) @ LUM) / 2) ** 2
        n = (v.shape[0] // 16) * (v.shape[1] // 16)
        bvar[k] = block_means(v) / n
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            p, q = names[i], names[j]
            bp, bq = block_means(lum[p]), block_means(lum[q])
            ok = bq > 0.05 * lum[q].mean()
            d = bp[ok] / bq[ok] - 1
            # 0.1% of the block's mean joins the noise: blocks of sky seen directly have almost none
            z = (bp - bq)[ok] / np.sqrt(bvar[p][ok] + bvar[q][ok] + (1e-3 * bq[ok]) ** 2 + 1e-30)
            rows.append({"scene": scene, "a": p, "b": q, "mean": lum[p].mean() / lum[q].mean() - 1,
                         "block_mean": float(d.mean()), "block_abs": float(np.abs(d).mean()),
                         "block_max": float(np.abs(d).max()), "z2": float(np.mean(z ** 2)),
                         "z4": int(np.sum(np.abs(z) > 4)), "blocks": int(ok.sum())})
    return rows


def series(b, scene, res, confs, spps, rounds, cap, refs, log):
    recs = []
    for k in range(rounds):
        for spp in spps:
            for cfg, fam in confs:
                out = os.path.join(b.a.work, "runs", f"{scene}_{res}", f"{cfg}_{spp}_r{k}.exr")
                rec = b.render(cfg, scene, spp, 1 + k, res, out, cap)
                ref, ref_mse, _ = refs[fam]
                m = rel_mse(scenes.load_exr(out), ref)
                rec.update({"round": k, "family": fam, "relmse_raw": m, "ref_relmse": ref_mse,
                            "err": math.sqrt(max(m - ref_mse, 1e-12))})
                recs.append(rec)
                log.write(json.dumps(rec) + "\n")
                log.flush()
                print(f"  {scene:<10} {cfg:<12} {spp:>5} spp  round {k + 1}: wall {rec['wall_s']:7.2f} s  "
                      f"CPU {rec['cpu_s']:7.2f} s  rel-RMSE {rec['err']:.4f}", flush=True)
    return recs


def summarise(recs):
    """{(scene, config): [(cpu, wall, err, spp)]}: medians over rounds, errors RMS-averaged."""
    g = {}
    for r in recs:
        g.setdefault((r["scene"], r["config"], r["spp"]), []).append(r)
    out = {}
    for (scene, cfg, spp), rs in sorted(g.items(), key=lambda kv: (kv[0][0], kv[0][1], kv[0][2])):
        out.setdefault((scene, cfg), []).append((statistics.median(r["cpu_s"] for r in rs),
                                                 statistics.median(r["wall_s"] for r in rs),
                                                 math.sqrt(statistics.fmean(r["err"] ** 2 for r in rs)), spp))
    return out


def fmt(x, mark=""):
    if x is None:
        return "–"
    return f"{mark}{x:.3g}" if x < 100 else f"{mark}{x:.0f}"


def thread_scaling(b, scene, res, spp, rounds):
    walls = {1: [], 2: []}
    for k in range(rounds):
        for t in (1, 2):
            out = os.path.join(b.a.work, "runs", "threads", f"luster_t{t}_r{k}.exr")
            rec = b.render("luster", scene, spp, 1, res, out, 0, threads=t)
            walls[t].append(rec["wall_s"])
            print(f"  luster -t {t}: wall {rec['wall_s']:.2f} s, CPU {rec['cpu_s']:.2f} s", flush=True)
    return statistics.median(walls[1]), statistics.median(walls[2])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true",
                    help="small and short: {res}x{res}, series {spp} spp, references 2 x {ref_spp} spp (full: "
                         "{fres}x{fres}, {fspp}, 2 x {fref})".format(fres=FULL["res"], fspp=FULL["spp"],
                                                                     fref=FULL["ref_spp"], **QUICK))
    ap.add_argument("--work", default=os.path.join("/tmp", "luster_ttq"), help="work folder (references are cached here)")
    ap.add_argument("--scenes", nargs="+", default=list(scenes.SCENES), choices=scenes.SCENES)
    ap.add_argument("--renderers", nargs="+", default=["luster", "cycles", "mitsuba"],
                    choices=["luster", "cycles", "mitsuba"])
    ap.add_argument("--res", type=int, help="image width and height (quick 64, full 256)")
    ap.add_argument("--spp", type=int, nargs="+", help="the series' samples per pixel")
    ap.add_argument("--ref-spp", type=int, help="samples per pixel of each of a reference's two renders")
    ap.add_argument("--rounds", type=int, help="repetitions of the series (medians of times)")
    ap.add_argument("--cap", type=float, help="seconds after which a series render stops taking samples")
    ap.add_argument("--ref-cap", type=float, help="the same for a reference render")
    ap.add_argument("--check-only", action="store_true", help="references and agreement only")
    ap.add_argument("--no-threads", action="store_true", help="skip luster's 2-threads-against-1 check")
    ap.add_argument("--denoise", action="store_true",
                    help="also luster and Cycles with Open Image Denoise (LUSTER_OIDN: a luster built with OIDN)")
    a = ap.parse_args()
    mode = QUICK if a.quick else FULL
    for k, v in mode.items():
        if getattr(a, k, None) is None:
            setattr(a, k, v)
    a.work = os.path.abspath(a.work)
    os.makedirs(a.work, exist_ok=True)
    b = Bench(a)
    t_start = time.time()
    print(f"# time to quality ({'quick' if a.quick else 'full'}): {a.res}x{a.res}, series {a.spp} spp, "
          f"references 2 x {a.ref_spp} spp, work {a.work}")
    print(f"luster {b.luster}; Mitsuba variant {b.variant}; load {' '.join(open('/proc/loadavg').read().split()[:3])}",
          flush=True)

    print("\n## warm-up (not recorded)", flush=True)
    for scene in a.scenes:
        for cfg, _ in families(scene, a.renderers, a.denoise):
            b.render(cfg, scene, 1, 0, a.res, os.path.join(a.work, "runs", "warmup", f"{scene}_{cfg}.exr"), 0)

    print("\n## references", flush=True)
    refs, agree = {}, []
    for scene in a.scenes:
        refs[scene] = references(b, scene, a.res, a.renderers, a.ref_spp, a.ref_cap)
        agree += agreement(scene, refs[scene])

    print("\n## agreement of the references (luminance; blocks: a 16 x 16 grid, those above 5% of the image mean; "
          "z: block difference over its noise)\n")
    print("| scene | pair | mean | block mean | block mean abs | block max abs | mean z² | abs z > 4 | ref rel-RMSE |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in agree:
        ra, rb = refs[r["scene"]][r["a"]][1], refs[r["scene"]][r["b"]][1]
        print(f"| {r['scene']} | {r['a']} / {r['b']} | {100 * r['mean']:+.2f}% | {100 * r['block_mean']:+.2f}% | "
              f"{100 * r['block_abs']:.2f}% | {100 * r['block_max']:.2f}% | {r['z2']:.2f} | {r['z4']}/{r['blocks']} | "
              f"{math.sqrt(ra):.3f} / {math.sqrt(rb):.3f} |")
    bad = [r for r in agree if abs(r["mean"]) > 0.01]
    if bad:
        print("\nWARNING: mean luminance differs by more than 1%: " +
              ", ".join(f"{r['scene']} {r['a']}/{r['b']} {100 * r['mean']:+.2f}%" for r in bad))
    json.dump(agree, open(os.path.join(a.work, "agreement.json"), "w"), indent=1)
    if a.check_only:
        return

    print("\n## series", flush=True)
    recs = []
    with open(os.path.join(a.work, "series.jsonl"), "w") as log:
        for scene in a.scenes:
            recs += series(b, scene, a.res, families(scene, a.renderers, a.denoise), a.spp, a.rounds, a.cap, refs[scene], log)
    summ = summarise(recs)

    print("\n## points (medians over rounds)\n")
    print("| scene | renderer | spp | CPU s | wall s | rel-RMSE |")
    print("|---|---|---|---|---|---|")
    for (scene, cfg), pts in summ.items():
        for cpu, wall, err, spp in pts:
            print(f"| {scene} | {cfg} | {spp} | {cpu:.2f} | {wall:.2f} | {err:.4f} |")

    print(f"\n## CPU seconds to reach a relative RMSE ({a.res}x{a.res}, 2 threads each)\n")
    hdr = " | ".join(f"CPU s to {100 * t:g}%" for t in THRESHOLDS)
    print(f"| scene | renderer | {hdr} |")
    print("|---|---|" + "---|" * len(THRESHOLDS))
    table = {}
    for (scene, cfg), pts in summ.items():
        table[(scene, cfg)] = [crossing(sorted((p[0], p[2]) for p in pts), t) for t in THRESHOLDS]
    for scene in a.scenes:
        for c, _ in families(scene, a.renderers, a.denoise):
            print(f"| {scene} | {c} | {' | '.join(fmt(x, m) for x, m in table[(scene, c)])} |")
    print("\n## luster's fastest against the fastest other renderer (CPU time to the same error)\n")
    kinds = [False, True] if a.denoise else [False]
    print("| scene | " + " | ".join(f"{'denoised' if d else 'noisy'}, {100 * t:g}%" for d in kinds for t in THRESHOLDS)
          + " |")
    print("|---|" + "---|" * (len(kinds) * len(THRESHOLDS)))
    for scene in a.scenes:
        cfgs = [c for c, _ in families(scene, a.renderers, a.denoise)]
        cells = [best_ratio(table, scene, cfgs, i, d) for d in kinds for i in range(len(THRESHOLDS))]
        print(f"| {scene} | {' | '.join(cells)} |")
    print("\n'~' extrapolated past the last render (error² ∝ 1/time); '<' reached at the first render already.")
    json.dump({f"{s}/{c}": {"points": summ[(s, c)], "cross": {str(t): v for t, v in zip(THRESHOLDS, table[(s, c)])}}
               for (s, c) in summ}, open(os.path.join(a.work, "ttq.json"), "w"), indent=1)

    if not a.no_threads and "luster" in a.renderers:
        scene = "cornell" if "cornell" in a.scenes else a.scenes[0]
        print(f"\n## luster, 2 threads against 1 ({scene}, {a.res}x{a.res}, {a.thread_spp} spp, "
              f"{a.thread_rounds} alternating rounds)", flush=True)
        w1, w2 = thread_scaling(b, scene, a.res, a.thread_spp, a.thread_rounds)
        print(f"\nwall, median: 1 thread {w1:.2f} s, 2 threads {w2:.2f} s: speed-up {w1 / w2:.2f}x (target ≥ 1.9x)")
    print(f"\ntotal {time.time() - t_start:.0f} s wall; load {' '.join(open('/proc/loadavg').read().split()[:3])}")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Embree's primary-ray throughput and BVH build in CPU time, for ratios that hold on a busy machine.

usage: embree_cpu.py MESH.ply [--reps 5] [--threads 1,2] [--script ../shared/bench/embree_rays.py]

The shared `embree_rays.py` times wall-clock seconds, which another process on a 2-core machine
stretches by tens of percent. This script shoots exactly its rays (its own `read_ply` and
`camera_rays`, loaded from the shared file, so the camera cannot drift apart from `luster bench`'s)
and also reads the process's CPU time (`time.process_time`: every thread of the process, Embree's
own build threads included) around each timed call. `luster bench` prints the same figure
("Mrays per CPU-second", from the scheduler's counters), so the two divide into a ratio that a
neighbour's load changes far less than wall time does. Wall figures are printed too.
"""
import argparse
import statistics
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
from embreex import rtcore_scene as rtcs
from embreex.mesh_construction import TriangleMesh


def shared_helpers(script):
    """`read_ply` and `camera_rays` from the shared script, which runs `main()` at import: its last
    call is cut off before the source is executed."""
    src = Path(script).read_text()
    head, sep, _ = src.rpartition("\nmain()")
    if not sep:
        sys.exit(f"{script}: no trailing main() call found; the shared script has changed")
    ns = {"__name__": "embree_rays"}
    exec(compile(head, script, "exec"), ns)
    return ns["read_ply"], ns["camera_rays"]


def timed(f):
    w0, c0 = time.perf_counter(), time.process_time()
    f()
    return time.perf_counter() - w0, time.process_time() - c0


def main():
    here = Path(__file__).resolve().parent
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--script", default=str(here.parent.parent / "shared/bench/embree_rays.py"))
    a = ap.parse_args()
    read_ply, camera_rays = shared_helpers(a.script)
    V, F = read_ply(a.mesh)
    o, d, _, _ = camera_rays(V)
    n = len(o)

    builds = []
    for _ in range(3):
        holder = {}

        def build():
            scene = rtcs.EmbreeScene()
            holder["mesh"] = TriangleMesh(scene, V, F)
            scene.run(o[:1], d[:1])  # the first query commits the scene, as in the shared script
            holder["scene"] = scene

        builds.append(timed(build))
        scene = holder["scene"]
    bw = statistics.median(b[0] for b in builds)
    bc = statistics.median(b[1] for b in builds)
    print(f"== {a.mesh}: {len(F)} tris; BVH build+commit {bw * 1e3:.1f} ms wall, CPU {bc * 1e3:.1f} ms (median of 3)")
    prim = scene.run(o, d, query="INTERSECT")
    print(f"   hit fraction {float((prim >= 0).mean()):.4f}")

    for nt in [int(x) for x in a.threads.split(",")]:
        chunks = np.array_split(np.arange(n), nt)

        def work(idx):
            s, e = idx[0], idx[-1] + 1
            return scene.run(o[s:e], d[s:e], query="INTERSECT")

        walls, cpus = [], []
        with ThreadPoolExecutor(nt) as ex:
            for _ in range(a.reps):
                w, c = timed(lambda: list(ex.map(work, chunks)))
                walls.append(w)
                cpus.append(c)
        w, c = statistics.median(walls), statistics.median(cpus)
        print(
            f"   threads={nt} INTERSECT: median {w * 1e3:.1f} ms -> {n / w / 1e6:.2f} Mrays/s; "
            f"CPU {c * 1e3:.1f} ms -> {n / c / 1e6:.2f} Mrays per CPU-second"
        )


main()

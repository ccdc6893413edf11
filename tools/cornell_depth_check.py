#!/usr/bin/env python3
"""luster's diffuse Cornell box against Mitsuba 3 at every depth, with the
ceiling by the lamp as its own crop.

The scene is the anchors' Scene A (`../shared/bench/anchors/scene_a.py`: the
course's hw7 `cornellbox_jaroslav_path_diffuse.xml` without its point light,
one box-shaped mesh light), rendered by luster's MIS path tracer and by
Mitsuba's `path` integrator (`render_mitsuba.py` there, max_depth = D + 2).
Each renderer runs two seeds; the pixel-by-pixel difference of the seeds gives
the variance, so each mean comes with its standard error and the difference
with a z-score. Prints one line per depth for the whole image and for the
ceiling crop (the top eighth of the image, the middle half of its width).

Setup: a Python with mitsuba and numpy (`pip install mitsuba numpy`; the
`llvm_ad_rgb` variant needs Debian's libllvm19 and
DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1).
Run:   cargo build --release && python tools/cornell_depth_check.py \
           --luster target/release/luster --depths 0 1 2 4 8 --spp 4096
Mitsuba's renders are cached in --work, so a rerun after a luster change only
renders luster.
"""

import argparse
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ANCHORS = os.path.join(HERE, "..", "..", "shared", "bench", "anchors")


def load_exr(path):
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    return np.array(mi.Bitmap(path), dtype=np.float64)[..., :3]


def lum(img):
    return 0.2126 * img[..., 0] + 0.7152 * img[..., 1] + 0.0722 * img[..., 2]


def stats(a, b):
    """Mean of two seeds' luminance and its standard error."""
    a, b = lum(a).ravel(), lum(b).ravel()
    n = a.size
    var = np.sum((a - b) ** 2) / (2 * n)
    return (a.sum() + b.sum()) / (2 * n), np.sqrt(var / (2 * n))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--luster", required=True)
    ap.add_argument("--depths", type=int, nargs="+", default=[0, 1, 2, 4, 8])
    ap.add_argument("--spp", type=int, default=4096)
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--work", default="/tmp/cornell_depth")
    ap.add_argument("--only", choices=["mitsuba", "luster"], default=None)
    ap.add_argument("--epsilon", default=None,
                    help="a <ShadowRayEpsilon> for luster's copy of the scene (e.g. auto; the course's file sets none)")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    sys.path.insert(0, ANCHORS)
    from scene_a import write_luster_xml

    crop = (slice(0, a.res // 8), slice(a.res // 4, 3 * a.res // 4))
    for d in a.depths:
        imgs = {}
        for r in ("mitsuba", "luster"):
            for seed in (1, 2):
                out = os.path.join(a.work, f"{r}_d{d}_s{seed}_{a.spp}_{a.res}.exr")
                if a.only in (None, r) and (r == "luster" or not os.path.exists(out)):
                    if r == "mitsuba":
                        cmd = [sys.executable, os.path.join(ANCHORS, "render_mitsuba.py"), "--variant", a.variant,
                               "--spp", str(a.spp), "--res", str(a.res), "--depth", str(d),
                               "--seed", str(seed), "--out", out]
                        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
                    else:
                        scene = os.path.join(a.work, f"luster_d{d}.xml")
                        write_luster_xml(scene, a.spp, res=a.res, depth=d, image=os.path.basename(out))
                        if a.epsilon:
                            text = open(scene).read().replace(
                                "<Scene>", f"<Scene><ShadowRayEpsilon>{a.epsilon}</ShadowRayEpsilon>", 1)
                            open(scene, "w").write(text)
                        cmd = [a.luster, "render", scene, "-o", a.work, "-q", "-t", "2", "--seed", str(seed)]
                        subprocess.run(cmd, check=True)
                imgs[(r, seed)] = load_exr(out) if os.path.exists(out) else None
        if any(v is None for v in imgs.values()):
            continue
        for name, sl in (("whole", (slice(None), slice(None))), ("ceiling", crop)):
            m, sm = stats(imgs[("mitsuba", 1)][sl], imgs[("mitsuba", 2)][sl])
            l, sl_ = stats(imgs[("luster", 1)][sl], imgs[("luster", 2)][sl])
            diff = (l - m) / m
            z = (l - m) / np.hypot(sm, sl_)
            print(f"depth {d} {name:<8} luster {l:.5f} ± {sl_:.5f}  mitsuba {m:.5f} ± {sm:.5f}  "
                  f"luster/mitsuba − 1 = {100 * diff:+.3f}% (z {z:+.2f})", flush=True)


if __name__ == "__main__":
    main()

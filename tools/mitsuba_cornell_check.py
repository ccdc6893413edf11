#!/usr/bin/env python3
"""Cross-check luster's path tracer against Mitsuba 3 (variant scalar_rgb).

Converts the course's hw7 `cornellbox_jaroslav_path_diffuse.xml` to Mitsuba:
the five walls (OBJ files written here), the two spheres, the box-shaped mesh
light (Radiance 31.831) and the point light (Intensity 3.979 W/sr). Every
material of that scene is a normalized ModifiedPhong with no specular part, so
Lambertian with albedo kd in both. luster renders one camera of its own copy
of the scene with `<RendererParams>MIS</RendererParams>`; Mitsuba uses `path`.

Conventions:
  * Depth. luster's MaxRecursionDepth 3 allows three bounces after the camera
    ray and samples the lights at each of the four hits: paths of up to five
    segments, Mitsuba's max_depth 5. Russian roulette is off in both
    (Mitsuba rr_depth 100).
  * Emission. luster's mesh lights shine from both faces; Mitsuba's area
    emitters from the front one, so every light triangle is wound to face out
    of the light box (its inside is never seen: its open side is flush with
    the ceiling).
  * Camera: lookAt with the course's Gaze as target - position, FovY 45 on
    the vertical axis; box pixel filter in both.

Prints, for the accuracy check (--spp, default 1024): mean HDR-FLIP (NVIDIA's
flip-evaluator) of the linear images, mean LDR-FLIP of the images through the
scene's own display transform (see tone_map), and the relative difference of
the mean luminance; with --floor, the same figures for each renderer against
itself (two seeds) and against a high-count Mitsuba reference; for the
speed check (--time-spp, default 100, 512x512, the same depth): the two
renderers run alternately (luster, Mitsuba, luster, ... --reps times each),
and the medians of each one's wall time and CPU time (user + system: on a
machine shared with other jobs the CPU time is the fairer figure), their
ratios, and luster's Mrays/s as it reports it. Both use every core unless
--threads is given (then Mitsuba too runs on that many threads).

Setup: python3 -m venv /tmp/mi && /tmp/mi/bin/pip install mitsuba numpy flip-evaluator
Run:   cargo build --release && /tmp/mi/bin/python tools/mitsuba_cornell_check.py
Targets (issue 13): mean FLIP <= 0.03, mean luminance within 1%; time ratio
luster/Mitsuba <= 0.5. What the FLIP bar can mean (Mitsuba's own seed-to-seed
figure is 0.042 HDR, 0.027 LDR at 1024 spp): docs/path-tracing.md, Checks.
"""

import argparse
import os
import resource
import statistics
import re
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

import numpy as np

try:
    import mitsuba as mi
except ImportError:
    sys.exit("mitsuba is not installed: pip install mitsuba (see the module doc)")

HERE = os.path.dirname(os.path.abspath(__file__))
SCENE = os.path.join(HERE, "..", "..", "shared", "scenes", "ceng795", "hw7", "xml",
                     "cornellbox_jaroslav_path_diffuse.xml")
W = np.array([0.2126, 0.7152, 0.0722])


def floats(text):
    return [float(x) for x in text.split()]


def vec(el, name):
    return floats(el.find(name).text)


def read_scene(path):
    root = ET.parse(path).getroot()
    verts = np.array(floats(root.find("VertexData").text)).reshape(-1, 3)
    mats = {m.get("id"): vec(m, "DiffuseReflectance") for m in root.find("Materials")}
    cam = root.find("Cameras").find("Camera")
    objs = root.find("Objects")
    meshes, lights, spheres = [], [], []
    for el in objs:
        if el.tag in ("Mesh", "LightMesh"):
            faces = el.find("Faces")
            off = int(faces.get("vertexOffset", "0"))
            idx = (np.array([int(x) for x in faces.text.split()]) + off - 1).reshape(-1, 3)
            kd = mats[el.find("Material").text.strip()]
            if el.tag == "LightMesh":
                lights.append((idx, vec(el, "Radiance")))
            else:
                meshes.append((idx, kd))
        elif el.tag == "Sphere":
            c = verts[int(el.find("Center").text) - 1]
            spheres.append((c, float(el.find("Radius").text), mats[el.find("Material").text.strip()]))
    pl = root.find("Lights").find("PointLight")
    point = (vec(pl, "Position"), vec(pl, "Intensity"))
    return root, verts, cam, meshes, lights, spheres, point


def write_obj(path, verts, idx, outward_from=None):
    tris = []
    for t in idx:
        a, b, c = verts[t]
        if outward_from is not None:
            n = np.cross(b - a, c - a)
            if np.dot(n, (a + b + c) / 3 - outward_from) < 0:
                b, c = c, b
        tris.append((a, b, c))
    with open(path, "w") as f:
        for tri in tris:
            for p in tri:
                f.write("v %.7g %.7g %.7g\n" % tuple(p))
        for i in range(len(tris)):
            f.write("f %d %d %d\n" % (3 * i + 1, 3 * i + 2, 3 * i + 3))


def mitsuba_dict(work, verts, cam, meshes, lights, spheres, point, spp, res, seed=0):
    pos = np.array(vec(cam, "Position"))
    gaze = np.array(vec(cam, "Gaze"))
    up = vec(cam, "Up")
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 5, "rr_depth": 100},
        "sensor": {
            "type": "perspective",
            "fov": float(cam.find("FovY").text),
            "fov_axis": "y",
            "to_world": mi.ScalarTransform4f.look_at(origin=pos.tolist(), target=(pos + gaze).tolist(), up=up),
            "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
            "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"},
                     "pixel_format": "rgb"},
        },
        "point": {"type": "point", "position": point[0], "intensity": {"type": "rgb", "value": point[1]}},
    }
    for i, (idx, kd) in enumerate(meshes):
        p = os.path.join(work, f"wall{i}.obj")
        write_obj(p, verts, idx)
        scene[f"wall{i}"] = {"type": "obj", "filename": p, "face_normals": True,
                             "bsdf": {"type": "twosided", "bsdf": {"type": "diffuse",
                                                                   "reflectance": {"type": "rgb", "value": kd}}}}
    for i, (idx, radiance) in enumerate(lights):
        p = os.path.join(work, f"light{i}.obj")
        write_obj(p, verts, idx, outward_from=verts[np.unique(idx)].mean(axis=0))
        scene[f"light{i}"] = {"type": "obj", "filename": p, "face_normals": True,
                              "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0, 0, 0]}},
                              "emitter": {"type": "area", "radiance": {"type": "rgb", "value": radiance}}}
    for i, (c, r, kd) in enumerate(spheres):
        scene[f"sphere{i}"] = {"type": "sphere", "center": c.tolist(), "radius": r,
                               "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": kd}}}
    return scene


def luster_scene(src, dst, spp, res, params="MIS"):
    """The course file with its first camera only, made luster's MIS path
    tracer (`params`: its RendererParams words)."""
    text = open(src).read()
    cams = re.findall(r"<Camera .*?</Camera>", text, flags=re.S)
    cam = cams[0]
    cam = re.sub(r"<RendererParams>.*?</RendererParams>", f"<RendererParams>{params}</RendererParams>", cam)
    cam = re.sub(r"<NumSamples>\d+</NumSamples>", f"<NumSamples>{spp}</NumSamples>", cam)
    cam = re.sub(r"<ImageResolution>.*?</ImageResolution>", f"<ImageResolution>{res} {res}</ImageResolution>", cam)
    cam = re.sub(r"<ImageName>.*?</ImageName>", "<ImageName>luster.exr</ImageName>", cam)
    body = re.sub(r"<Cameras>.*</Cameras>", "<Cameras>" + cam + "</Cameras>", text, flags=re.S)
    # The glass and mirror materials of the file are unused; their
    # <Transparency> only draws a warning.
    open(dst, "w").write(body)


def cpu(who):
    r = resource.getrusage(who)
    return r.ru_utime + r.ru_stime


def run_luster(luster, scene, work, threads, seed=0):
    cmd = [luster, "render", "-o", work, scene, "--seed", str(seed)]
    if threads:
        cmd += ["-t", str(threads)]
    t, c = time.time(), cpu(resource.RUSAGE_CHILDREN)
    out = subprocess.run(cmd, check=True, capture_output=True, text=True)
    wall, used = time.time() - t, cpu(resource.RUSAGE_CHILDREN) - c
    m = re.search(r"([\d.]+) Mrays/s", out.stdout)
    img = np.array(mi.Bitmap(os.path.join(work, "luster.exr")))[..., :3].astype(np.float64)
    return img, wall, used, float(m.group(1)) if m else float("nan")


def run_mitsuba(d):
    t, c = time.time(), cpu(resource.RUSAGE_SELF)
    scene = mi.load_dict(d)
    img = np.array(mi.render(scene), dtype=np.float64)[..., :3]
    return img, time.time() - t, cpu(resource.RUSAGE_SELF) - c


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--luster", default=os.path.join(HERE, "..", "target", "release", "luster"))
    ap.add_argument("--scene", default=SCENE)
    ap.add_argument("--spp", type=int, default=1024, help="samples per pixel of the accuracy check")
    ap.add_argument("--time-spp", type=int, default=100, help="samples per pixel of the speed check (0: skip)")
    ap.add_argument("--res", type=int, default=512)
    ap.add_argument("--threads", type=int, default=0, help="threads of both renderers (0: all cores)")
    ap.add_argument("--reps", type=int, default=3, help="alternating runs of each renderer in the speed check")
    ap.add_argument("--keep", help="folder to keep both renders in")
    ap.add_argument("--params", default="MIS",
                    help="luster's RendererParams words (default MIS: with this scene's two lights, both are "
                         "sampled at every hit; 'MIS OneLight' takes one per hit, chosen by power, as Mitsuba "
                         "takes one chosen uniformly)")
    ap.add_argument("--floor", type=int, default=None, metavar="REF_SPP",
                    help="instead: the noise floor of the FLIP check at --spp (each renderer against itself "
                         "with two seeds) and both against Mitsuba at REF_SPP (0: no such reference); images "
                         "already in --keep are reused")
    a = ap.parse_args()
    mi.set_variant("scalar_rgb")
    if a.threads:
        import drjit as dr
        dr.set_thread_count(a.threads)
    import flip_evaluator as flip

    _, verts, cam, meshes, lights, spheres, point = read_scene(a.scene)
    work = a.keep or tempfile.mkdtemp(prefix="luster-mi-")
    os.makedirs(work, exist_ok=True)
    if a.floor is not None:
        noise_floor(a, work, verts, cam, meshes, lights, spheres, point, flip)
        return
    for label, spp in (("accuracy", a.spp), ("speed", a.time_spp)):
        if spp <= 0:
            continue
        ls = os.path.join(work, "luster.xml")
        luster_scene(a.scene, ls, spp, a.res, a.params)
        d = mitsuba_dict(work, verts, cam, meshes, lights, spheres, point, spp, a.res)
        reps = a.reps if label == "speed" else 1
        runs = []
        for _ in range(reps):
            ours, t_ours, c_ours, mrays = run_luster(a.luster, ls, work, a.threads)
            theirs, t_theirs, c_theirs = run_mitsuba(d)
            runs.append((t_ours, c_ours, t_theirs, c_theirs))
        t_ours, c_ours, t_theirs, c_theirs = (statistics.median(r[k] for r in runs) for k in range(4))
        if a.keep:
            mi.Bitmap(ours.astype(np.float32)).write(os.path.join(work, f"luster_{label}.exr"))
            mi.Bitmap(theirs.astype(np.float32)).write(os.path.join(work, f"mitsuba_{label}.exr"))
        lo, lt = (ours @ W).mean(), (theirs @ W).mean()
        fl, fl_ldr = flips(flip, theirs, ours)
        print(f"{label}: {a.res}x{a.res}, {spp} spp, depth 5 (MaxRecursionDepth 3)")
        print(f"  mean HDR-FLIP {fl:.4f}, LDR-FLIP {fl_ldr:.4f}   mean luminance luster {lo:.5f} mitsuba {lt:.5f} ({100 * (lo / lt - 1):+.2f}%)")
        print(f"  {reps} alternating runs each, medians: wall time luster {t_ours:.2f} s, mitsuba {t_theirs:.2f} s, "
              f"ratio {t_ours / t_theirs:.3f}; CPU time luster {c_ours:.2f} s, mitsuba {c_theirs:.2f} s, "
              f"ratio {c_ours / c_theirs:.3f}; luster {mrays:.1f} Mrays/s (last run)")
        for k, r in enumerate(runs):
            print(f"    run {k + 1}: luster {r[0]:.2f} s wall / {r[1]:.2f} s CPU, mitsuba {r[2]:.2f} s wall / {r[3]:.2f} s CPU")


def tone_map(img, like, key=0.18, burn=1.0, gamma=2.2):
    """The scene's display transform (Photographic, TMOOptions "0.18 1",
    Saturation 1, Gamma 2.2), clamped and truncated to 8 bits as the course's
    PNGs are, with its log-average and burn-out white taken from `like` (the
    pair's reference) so that both images of a pair go through one curve:
    the course's operator computes them from each noisy image itself."""
    y_like = like @ W
    log_avg = np.exp(np.mean(np.log(1e-5 + y_like)))
    white = np.percentile(key / log_avg * y_like, 100 - burn)
    y = img @ W
    lum = key / log_avg * y
    out = lum * (1 + lum / white ** 2) / (1 + lum)
    rgb = img * (out / np.where(y > 0, y, 1))[..., None]
    rgb = np.clip(rgb, 0, 1) ** (1 / gamma)
    return np.floor(rgb * 255) / 255


def flips(flip, ref, test):
    """Mean HDR-FLIP of the linear images and mean LDR-FLIP of the tone-mapped ones."""
    hdr = flip.evaluate(ref.astype(np.float32), test.astype(np.float32), "HDR")[1]
    ldr = flip.evaluate(tone_map(ref, ref).astype(np.float32), tone_map(test, ref).astype(np.float32), "LDR")[1]
    return hdr, ldr


def noise_floor(a, work, verts, cam, meshes, lights, spheres, point, flip):
    """Mean HDR- and LDR-FLIP of each renderer against itself (seeds 0 and 1)
    at --spp, of the two against each other, and of each against Mitsuba at
    --floor samples: what the 0.03 bar can mean at this sample count. Each
    image is kept in --keep (or the temporary folder) and reused when it is
    already there, so a run can be resumed and the table recomputed."""
    ls = os.path.join(work, "luster.xml")
    luster_scene(a.scene, ls, a.spp, a.res, a.params)
    jobs = [(f"{who}{seed}", who, seed, a.spp) for seed in (0, 1) for who in ("mitsuba", "luster")]
    if a.floor > 0:
        jobs.append(("ref", "mitsuba", 7, a.floor))
    imgs = {}
    for name, who, seed, spp in jobs:
        path = os.path.join(work, f"{name}.exr")
        if os.path.exists(path):
            imgs[name] = np.array(mi.Bitmap(path), dtype=np.float64)[..., :3]
            continue
        if who == "luster":
            imgs[name] = run_luster(a.luster, ls, work, a.threads, seed)[0]
        else:
            imgs[name] = run_mitsuba(mitsuba_dict(work, verts, cam, meshes, lights, spheres, point, spp, a.res,
                                                  seed))[0]
        mi.Bitmap(imgs[name].astype(np.float32)).write(path)
    if imgs["mitsuba0"].shape[0] != a.res:
        sys.exit(f"{work} holds images of another size than --res {a.res}")
    imgs["mitsuba01"] = (imgs["mitsuba0"] + imgs["mitsuba1"]) / 2

    print(f"noise floor: {a.res}x{a.res}, {a.spp} spp, mean FLIP (reference first; LDR: the scene's tone "
          f"mapping, curve from the reference)")
    pairs = [("mitsuba0", "mitsuba1", "Mitsuba seed 0 vs seed 1 (the floor)"),
             ("luster0", "luster1", "luster seed 0 vs seed 1"),
             ("mitsuba0", "luster0", "Mitsuba vs luster, seed 0"),
             ("mitsuba1", "luster1", "Mitsuba vs luster, seed 1"),
             ("mitsuba01", "luster0", f"Mitsuba at {2 * a.spp} (two seeds) vs luster 0"),
             ("mitsuba01", "luster1", f"Mitsuba at {2 * a.spp} (two seeds) vs luster 1")]
    if "ref" in imgs:
        pairs += [("ref", k, f"Mitsuba at {a.floor} vs {k}") for k in ("mitsuba0", "mitsuba1", "luster0", "luster1")]
    print(f"  {'pair':<46} {'HDR-FLIP':>9} {'LDR-FLIP':>9}")
    for ref, test, label in pairs:
        hdr, ldr = flips(flip, imgs[ref], imgs[test])
        print(f"  {label:<46} {hdr:9.4f} {ldr:9.4f}")
    lum = {k: (v @ W).mean() for k, v in imgs.items()}
    print("  mean luminance: " + ", ".join(f"{k} {v:.5f}" for k, v in lum.items()))
    m = (lum["mitsuba0"] + lum["mitsuba1"]) / 2
    print(f"  luster against Mitsuba (two seeds each): {100 * ((lum['luster0'] + lum['luster1']) / 2 / m - 1):+.2f}%"
          f" (seed to seed: Mitsuba {100 * (lum['mitsuba1'] / lum['mitsuba0'] - 1):+.2f}%, "
          f"luster {100 * (lum['luster1'] / lum['luster0'] - 1):+.2f}%)")
    noise_structure(imgs, flip)


def noise_structure(imgs, flip):
    """What sets the seed-to-seed FLIP besides the amount of noise: the
    per-pixel variance of each renderer (from its two seeds), the correlation
    of the noise between horizontal and vertical neighbours, and the FLIP of
    each seed pair again after the noise's sign is flipped at random pixels
    (one ±1 field for both renderers, applied about the pair's mean): that
    keeps every pixel's error and colour and removes only its correlation
    with the neighbours. FLIP filters the images as the eye does (contrast
    sensitivity), so noise that alternates between neighbours is seen less
    than white noise of the same variance."""
    r = np.random.default_rng(7).choice([-1.0, 1.0], size=imgs["mitsuba0"].shape[:2])[..., None]
    var = {}
    print("  noise structure (seed 0 minus seed 1):")
    for who in ("mitsuba", "luster"):
        a, b = imgs[f"{who}0"], imgs[f"{who}1"]
        e = (a - b) @ W
        var[who] = np.mean(e ** 2) / 2
        cx = np.corrcoef(e[:, :-1].ravel(), e[:, 1:].ravel())[0, 1]
        cy = np.corrcoef(e[:-1, :].ravel(), e[1:, :].ravel())[0, 1]
        m = (a + b) / 2
        hdr, ldr = flips(flip, m + (a - m) * r, m + (b - m) * r)
        print(f"    {who:<8} neighbour correlation x {cx:+.3f}, y {cy:+.3f}; with the signs shuffled "
              f"HDR-FLIP {hdr:.4f}, LDR-FLIP {ldr:.4f}")
    print(f"    per-pixel variance of the luminance, luster / Mitsuba: {var['luster'] / var['mitsuba']:.3f}")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Cross-check luster's glTF import against Blender Cycles: one glTF scene, one HDRI.

Blender builds a small scene of Principled BSDF materials (plastic, gold, a
textured cube, glass, a clear-coated paint, sheen cloth, a grey floor) and
exports it as `WORK/scene.glb` with its camera. Cycles renders Blender's own
import of that file under an equirectangular sky (`WORK/sky.exr`); luster
renders the same file with `--env WORK/sky.exr`. Both at two seeds; the
table compares the mean Rec. 709 luminance of the whole image and of a 4×4
grid of blocks, each with its standard error from the two seeds. Pass: the
whole-image means within 3% (`--tol`).

    cargo build --release -p luster
    python3 tools/gltf_crosscheck.py --work target/gltf-xcheck   # --venv target/.venv-xcheck

The venv (CPython 3.11, bpy 5.0.1, numpy) is made and filled on first use, as
`tools/closure_crosscheck.py` does. Output: the table, `WORK/results.json`
and `WORK/side_by_side.png` (Cycles | luster, sRGB-encoded).
"""
import argparse
import json
import math
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from closure_crosscheck import _bitmap, ensure_venv, load_exr, lum, save_exr  # noqa: E402

RES = (480, 320)
THREADS = 2
DEPTH = 8


def make_sky(path, w=512, h=256):
    """A smooth sky with a warm sun, in `--env`'s convention (Blender's
    world with no mapping; docs/environment-light.md): in glTF's axes the
    map's centre faces +x, a quarter across -z, three quarters +z, its top
    row +y."""
    import numpy as np
    v = (np.arange(h) + 0.5) / h
    u = (np.arange(w) + 0.5) / w
    theta = v[:, None] * math.pi
    phi = (u[None, :] - 0.5) * 2 * math.pi
    d = np.stack([np.sin(theta) * np.cos(phi), np.cos(theta) * np.ones_like(phi),
                  np.sin(theta) * np.sin(phi)], -1)
    up = np.clip(d[..., 1], -1, 1)
    sky = np.where(up[..., None] > 0,
                   np.array([0.35, 0.55, 1.0]) * (0.6 + 0.4 * (1 - up[..., None])),
                   np.array([0.25, 0.22, 0.2]) * (0.7 + 0.3 * (1 + up[..., None])))
    sun = np.array([0.5, 0.6, -0.62])
    sun /= np.linalg.norm(sun)
    cosang = np.clip((d * sun).sum(-1), -1, 1)
    blob = np.exp(-((np.degrees(np.arccos(cosang)) / 6.0) ** 2))
    img = sky + blob[..., None] * np.array([40.0, 34.0, 26.0])
    save_exr(path, img.astype(np.float32))


# ---------------------------------------------------------------- Blender


def principled(bpy, name, **inputs):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    p = m.node_tree.nodes["Principled BSDF"]
    for k, v in inputs.items():
        p.inputs[k].default_value = v
    return m, p


def build_scene(work):
    """The scene in Blender, exported as WORK/scene.glb (glTF: +y up)."""
    import bpy
    import numpy as np
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene

    def add(obj, mat):
        obj.data.materials.append(mat)
        for poly in obj.data.polygons:
            poly.use_smooth = True
        return obj

    bpy.ops.mesh.primitive_plane_add(size=12, location=(0, 0, 0))
    add(bpy.context.object, principled(bpy, "floor", **{"Base Color": (0.5, 0.5, 0.5, 1), "Roughness": 0.8})[0])
    for poly in bpy.context.object.data.polygons:
        poly.use_smooth = False
    spheres = [
        ("plastic", (-2.4, 0.6, 0.7), {"Base Color": (0.8, 0.08, 0.06, 1), "Roughness": 0.3}),
        ("gold", (-0.8, 0.6, 0.7), {"Base Color": (1.0, 0.78, 0.34, 1), "Metallic": 1.0, "Roughness": 0.25}),
        ("glass", (0.8, 0.6, 0.7), {"Base Color": (1, 1, 1, 1), "Transmission Weight": 1.0, "IOR": 1.5,
                                    "Roughness": 0.0}),
        ("coat", (2.4, 0.6, 0.7), {"Base Color": (0.05, 0.12, 0.5, 1), "Roughness": 0.5, "Coat Weight": 1.0,
                                   "Coat Roughness": 0.05}),
        ("cloth", (-1.6, -1.0, 0.5), {"Base Color": (0.35, 0.05, 0.1, 1), "Roughness": 0.9,
                                      "Sheen Weight": 1.0, "Sheen Tint": (1.0, 0.7, 0.8, 1),
                                      "Sheen Roughness": 0.4}),
    ]
    for name, loc, inputs in spheres:
        r = 0.5 if name == "cloth" else 0.7
        bpy.ops.mesh.primitive_uv_sphere_add(radius=r, location=loc, segments=64, ring_count=32)
        add(bpy.context.object, principled(bpy, name, **inputs)[0])

    # A cube with an sRGB checker texture as its base colour.
    n = 64
    c = ((np.arange(n)[:, None] // 8 + np.arange(n)[None, :] // 8) % 2).astype(np.float32)
    px = np.zeros((n, n, 4), np.float32)
    px[..., 0] = 0.9 * c + 0.1 * (1 - c)
    px[..., 1] = 0.75 * c + 0.2 * (1 - c)
    px[..., 2] = 0.2 * c + 0.6 * (1 - c)
    px[..., 3] = 1
    img = bpy.data.images.new("checker", n, n, alpha=True)
    img.pixels = px.ravel()
    img.filepath_raw = os.path.join(work, "checker.png")
    img.file_format = "PNG"
    img.save()
    m, p = principled(bpy, "checker", **{"Roughness": 0.5})
    tex = m.node_tree.nodes.new("ShaderNodeTexImage")
    tex.image = bpy.data.images.load(os.path.join(work, "checker.png"))
    tex.interpolation = "Closest"
    m.node_tree.links.new(tex.outputs["Color"], p.inputs["Base Color"])
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(1.4, -1.1, 0.5), rotation=(0, 0, 0.5))
    cube = bpy.context.object
    cube.data.materials.append(m)

    cd = bpy.data.cameras.new("cam")
    cd.sensor_fit = "VERTICAL"
    cd.angle_y = math.radians(35)
    co = bpy.data.objects.new("cam", cd)
    sc.collection.objects.link(co)
    co.location = (0.0, -7.5, 3.0)
    co.rotation_euler = (math.radians(72), 0, 0)
    sc.camera = co
    sc.render.resolution_x, sc.render.resolution_y = RES
    bpy.ops.export_scene.gltf(filepath=os.path.join(work, "scene.glb"), export_format="GLB",
                              export_cameras=True, export_lights=False, export_yup=True)


def render_cycles(work, spp, seed, out):
    """Blender's import of scene.glb under sky.exr, in Cycles."""
    import bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=os.path.join(work, "scene.glb"))
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    cy = sc.cycles
    cy.device = "CPU"
    cy.samples = spp
    cy.use_adaptive_sampling = False
    cy.use_denoising = False
    for k in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
              "transparent_max_bounces"):
        setattr(cy, k, DEPTH)
    cy.sample_clamp_direct = cy.sample_clamp_indirect = 0.0
    cy.blur_glossy = 0.0
    cy.caustics_reflective = cy.caustics_refractive = True
    cy.pixel_filter_type = "BOX"
    cy.seed = seed
    sc.render.threads_mode = "FIXED"
    sc.render.threads = THREADS
    sc.render.resolution_x, sc.render.resolution_y = RES
    sc.render.resolution_percentage = 100
    sc.view_settings.view_transform = "Standard"
    imf = sc.render.image_settings
    imf.file_format, imf.color_depth, imf.color_mode = "OPEN_EXR", "32", "RGB"
    sc.camera = next(o for o in sc.objects if o.type == "CAMERA")

    # `--env` reads the map as Blender's world does with no mapping.
    world = bpy.data.worlds.new("env")
    world.use_nodes = True
    wn, wl = world.node_tree.nodes, world.node_tree.links
    bg = wn["Background"]
    tex = wn.new("ShaderNodeTexEnvironment")
    tex.image = bpy.data.images.load(os.path.join(work, "sky.exr"))
    tex.image.colorspace_settings.name = "Non-Color"
    tex.interpolation = "Closest"
    wl.new(tex.outputs["Color"], bg.inputs["Color"])
    sc.world = world
    t0 = time.time()
    bpy.ops.render.render()
    bpy.data.images["Render Result"].save_render(filepath=out)
    return time.time() - t0


def worker(args):
    if args.step == "build":
        make_sky(os.path.join(args.work, "sky.exr"))
        build_scene(args.work)
    else:
        for seed in (1, 2):
            out = os.path.join(args.work, f"cycles_s{seed}.exr")
            print(f"  cycles seed {seed}: {render_cycles(args.work, args.spp, seed, out):.1f} s", flush=True)


# ---------------------------------------------------------------- luster


def render_luster(args):
    """Both seeds; returns the linear images (film units / 255)."""
    imgs = []
    for seed in (1, 2):
        d = os.path.join(args.work, f"luster_s{seed}")
        os.makedirs(d, exist_ok=True)
        t0 = time.time()
        cmd = [args.luster, "render", "-q", "--threads", str(THREADS), "--seed", str(seed), "--spp", str(args.spp),
               "--size", f"{RES[0]}x{RES[1]}", "--env", os.path.join(args.work, "sky.exr"),
               "--aov", "albedo", "-o", d, os.path.join(args.work, "scene.glb")]
        subprocess.run(cmd, check=True)
        print(f"  luster seed {seed}: {time.time() - t0:.1f} s", flush=True)
        imgs.append(load_luster_beauty(d) / 255.0)
    return imgs


def load_luster_beauty(folder):
    """The beauty layer of the passes file luster wrote (`--aov`), linear
    film units."""
    import numpy as np
    path = next(os.path.join(folder, f) for f in sorted(os.listdir(folder)) if f.endswith(".aov.exr"))
    layers = dict(_bitmap()(path).split())
    return np.array(layers["<root>"], dtype=np.float64)[..., :3]


def stats(pair):
    import numpy as np
    a, b = (lum(x) for x in pair)
    mean = 0.5 * (a.mean() + b.mean())
    se = abs(a.mean() - b.mean()) / 2
    h, w = a.shape
    blocks = []
    for by in range(4):
        for bx in range(4):
            sl = (slice(by * h // 4, (by + 1) * h // 4), slice(bx * w // 4, (bx + 1) * w // 4))
            ma, mb = a[sl].mean(), b[sl].mean()
            blocks.append((0.5 * (ma + mb), abs(ma - mb) / 2))
    return {"mean": float(mean), "se": float(se), "blocks": [(float(m), float(s)) for m, s in blocks]}, \
        np.mean(pair, axis=0)


def side_by_side(path, left, right):
    import numpy as np

    def enc(x):
        x = np.clip(x, 0, 1)
        return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)

    img = np.concatenate([enc(left), np.ones((left.shape[0], 8, 3)), enc(right)], axis=1)
    _bitmap()((img * 255 + 0.5).astype(np.uint8)).write(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--work", default="gltf-xcheck")
    ap.add_argument("--venv", default=".venv-xcheck")
    ap.add_argument("--luster", default=os.path.join(os.path.dirname(HERE), "target", "release", "luster"))
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--tol", type=float, default=0.03)
    ap.add_argument("--step", help=argparse.SUPPRESS)
    args = ap.parse_args()
    args.work = os.path.abspath(args.work)
    if args.step:
        return worker(args)
    py = ensure_venv(args.venv)
    if os.path.abspath(sys.executable) != os.path.abspath(py):
        os.execv(py, [py, os.path.abspath(__file__)] + sys.argv[1:])
    os.makedirs(args.work, exist_ok=True)
    me = [sys.executable, os.path.abspath(__file__), "--work", args.work, "--spp", str(args.spp)]
    subprocess.run(me + ["--step", "build"], check=True)
    subprocess.run(me + ["--step", "cycles"], check=True)
    cyc = [load_exr(os.path.join(args.work, f"cycles_s{s}.exr")) for s in (1, 2)]
    lus = render_luster(args)
    sc, cmean = stats(cyc)
    sl, lmean = stats(lus)
    dev = sl["mean"] / sc["mean"] - 1
    se = math.hypot(sc["se"], sl["se"]) / sc["mean"]
    print(f"{'':<10} {'Cycles':>9} {'luster':>9} {'luster/Cycles-1':>16}")
    print(f"{'image':<10} {sc['mean']:9.4f} {sl['mean']:9.4f} {100 * dev:+9.2f}% ± {100 * se:.2f}%")
    for k, ((mc, ec), (ml, el)) in enumerate(zip(sc["blocks"], sl["blocks"])):
        d = ml / mc - 1 if mc > 0 else float("nan")
        print(f"block {k // 4},{k % 4:<4} {mc:9.4f} {ml:9.4f} {100 * d:+9.2f}% ± {100 * math.hypot(ec, el) / mc:.2f}%")
    ok = abs(dev) <= args.tol
    print("PASS" if ok else "FAIL", f"(whole image within {100 * args.tol:.0f}%)")
    json.dump({"cycles": sc, "luster": sl, "deviation": dev, "se": se, "pass": ok, "spp": args.spp},
              open(os.path.join(args.work, "results.json"), "w"), indent=1)
    side_by_side(os.path.join(args.work, "side_by_side.png"), cmean, lmean)
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()

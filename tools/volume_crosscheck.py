#!/usr/bin/env python3
"""Cross-check luster's volumetric path tracing against Mitsuba 3's `volpath`,
and benchmark the two on the cloud example.

    cargo build --release -p luster --bin luster --example export_volume
    python3 tools/volume_crosscheck.py [--venv .venv-xcheck] [--work volume-xcheck]
    python3 tools/volume_crosscheck.py --bench              # the checks, then the cloud benchmark
    python3 tools/volume_crosscheck.py --bench-only
    python3 tools/volume_crosscheck.py --renderers luster   # Mitsuba from the cache only

Scenes (128x128, pinhole camera at (0, 0, 4) looking down -z, 35 degree
vertical field of view, lit by a uniform environment of radiance 1, all
media grey):

  sphere_env    homogeneous sphere, radius 1, sigma_t 3, albedo 0.8, HG g 0.5
  sphere_point  the same, plus a point light up and to the right
  furnace       albedo 1 (sigma_a 0, sigma_s 3): every pixel should read 1
  grid          three Gaussian blobs written as a Lua density (zero beyond
                0.6 of the centre along each axis) in the box [-0.75, 0.75]^3,
                baked with GridResolution 64 and exported for Mitsuba's
                gridvolume by `export_volume`; sigma_t 8, albedo 0.8,
                isotropic, plus the point light
  grid_absorb   the same grid absorbing only (sigma_a 8): transmittance
                alone, which checks the export's alignment whatever the
                scattering does
  slab          absorption only, sigma_a 2 through a 0.5-thick box: the
                centre reads exp(-1)

Compared (mean luminance over the pixels whose four corners' rays all meet
the medium's bound): luster against Mitsuba (sphere_env, sphere_point, grid,
grid_absorb), against 1 (furnace) and against exp(-sigma_t d) (slab, its central 8x8
pixels). Pass: the mean within --tol (2%) plus two combined standard errors,
and at most 1% of the 8x8 blocks inside the bound with |z| > 4 (z: the
difference of the block means over the two renderers' combined noise, at
least 0.1% of the reference's block mean). Each renderer renders each scene
twice (seeds 1 and 2); the per-pixel variance comes from the two.

Depth: luster `MIS RussianRoulette` (in a scene with media, paths end after
1024 bounces) against Mitsuba volpath max_depth 1026 (1024 + the camera and
emitter vertices) with its roulette; `--depth D` compares a fixed depth instead (luster
MaxRecursionDepth D, `MIS` alone; Mitsuba max_depth D + 2; 0 is single
scattering).

Mitsuba's images are cached in WORK/refs.json (keyed by the scene, spp,
seed and, for the grid, the exported .vol's hash), so a rerun renders luster
only; `--renderers luster` forbids Mitsuba renders. See
tools/volume_crosscheck.md for how the two renderers' settings are aligned.

--bench: the cloud (examples/scenes/cloud.xml, or --cloud) read and
path-traced (MIS RussianRoulette, GridResolution 128) in an axis-aligned Box
copy of its ellipsoid bound (the same transform and script, so the same grid)
against
Mitsuba volpath on the exported grid, at equal samples, 2 threads each,
alternating luster and Mitsuba --bench-runs times (median times), then each
at Density x 1, 2, 4, 8, 16 (--densities); prints a table of times and means.

Exit status: 0 all pass, 1 a case fails, 2 luster or the export could not run.

Internal: `volume_crosscheck.py _worker JOBS.json OUT.json` renders Mitsuba jobs.
"""
import argparse
import hashlib
import json
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
RES = 128
FOVY = 35.0
CAM_Z = 4.0
BLOCK = 8
# luster: <RendererParams>MIS RussianRoulette</RendererParams> ends a path after
# MAX_MEDIUM_BOUNCES = 1024 bounces in a scene with media (MAX_BOUNCES = 64 without;
# crates/render/src/integrator/path/mod.rs, past_limit); Mitsuba's max_depth counts the
# camera vertex and the emitter vertex too: 1024 + 2 (as tools/closure_crosscheck.md).
DEPTH = 64  # MaxRecursionDepth written to the scenes (roulette ignores it)
RR_BOUNCES = 1024
MI_MAX_DEPTH = RR_BOUNCES + 2
MI_RR_DEPTH = 5  # Mitsuba's default; luster's roulette starts at the first bounce
CACHE_VERSION = 1
LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
PACKAGES = ["mitsuba", "numpy"]
TOL = 0.02
# The least noise a block mean is given, relative to the reference's: where nearly every
# sample passes a medium untouched, two seeds can show no difference at all.
NOISE_FLOOR = 1e-3

POINT = {"pos": [2.5, 2.5, 3.0], "intensity": 60.0}
GRID_BOX = 0.75
GRID_LUA = """-- Three Gaussian blobs in the box [-0.75, 0.75]^3, windowed to exactly zero
-- beyond 0.6 of the centre along each axis (tools/volume_crosscheck.py, case grid).
local exp, abs = math.exp, math.abs
local blobs = {
  { 0.22,  0.12,  0.05, 0.20, 1.0},
  {-0.25, -0.15,  0.10, 0.17, 0.9},
  { 0.05, -0.05, -0.25, 0.15, 0.7},
}
local function window(x) return 1 - smoothstep(0.45, 0.6, abs(x)) end
function density(s)
  local p = s.P
  local d = 0
  for i = 1, #blobs do
    local b = blobs[i]
    local dx, dy, dz = p.x - b[1], p.y - b[2], p.z - b[3]
    d = d + b[5] * exp(-(dx * dx + dy * dy + dz * dz) / (2 * b[4] * b[4]))
  end
  return d * window(p.x) * window(p.y) * window(p.z)
end
"""


def case_table():
    """Every scene: its bound, medium, lights and what luster is compared with."""
    sphere = {"sphere": 1.0}
    return [
        dict(name="sphere_env", bound=sphere, sigma_a=0.6, sigma_s=2.4, g=0.5, point=None, ref="mitsuba"),
        dict(name="sphere_point", bound=sphere, sigma_a=0.6, sigma_s=2.4, g=0.5, point=POINT, ref="mitsuba"),
        dict(name="furnace", bound=sphere, sigma_a=0.0, sigma_s=3.0, g=0.5, point=None, ref="one"),
        dict(name="grid", bound={"box": [[-GRID_BOX] * 3, [GRID_BOX] * 3]}, sigma_a=1.6, sigma_s=6.4, g=0.0,
             point=POINT, shader=GRID_LUA, grid=64, ref="mitsuba"),
        dict(name="grid_absorb", bound={"box": [[-GRID_BOX] * 3, [GRID_BOX] * 3]}, sigma_a=8.0, sigma_s=0.0, g=0.0,
             point=None, shader=GRID_LUA, grid=64, ref="mitsuba"),
        dict(name="slab", bound={"box": [[-0.6, -0.6, -0.25], [0.6, 0.6, 0.25]]}, sigma_a=2.0, sigma_s=0.0,
             g=0.0, point=None, ref="analytic"),
    ]


# ---------------------------------------------------------------- geometry

def pixel_rays(res, fovy, sub=None):
    """Unnormalised directions (x, y, -1) of a camera at the origin looking down -z:
    the pixel corners ((res+1)^2), or `sub` x `sub` points per pixel."""
    import numpy as np
    t = math.tan(math.radians(fovy) / 2)
    if sub is None:
        u = np.arange(res + 1) / res
    else:
        u = ((np.arange(res * sub) + 0.5) / sub) / res
    x = (2 * u[None, :] - 1) * t
    y = -(2 * u[:, None] - 1) * t
    return np.broadcast_to(x, (len(u), len(u))), np.broadcast_to(y, (len(u), len(u)))


def bound_mask(bound, res=RES):
    """Pixels whose four corners' rays from (0, 0, CAM_Z) all meet the bound."""
    import numpy as np
    x, y = pixel_rays(res, FOVY)
    if "sphere" in bound:
        r = bound["sphere"] * 0.995
        d2 = CAM_Z ** 2 - CAM_Z ** 2 / (x * x + y * y + 1)  # squared distance of the line from the centre
        hit = d2 < r * r
    else:
        lo, hi = np.array(bound["box"][0]), np.array(bound["box"][1])
        o = np.array([0.0, 0.0, CAM_Z])
        tn, tf = np.full(x.shape, -np.inf), np.full(x.shape, np.inf)
        for k, dk in enumerate((x, y, np.full(x.shape, -1.0))):
            with np.errstate(divide="ignore", invalid="ignore"):
                a, b = (lo[k] - o[k]) / dk, (hi[k] - o[k]) / dk
            a = np.where(dk == 0, np.where((lo[k] <= o[k]) & (o[k] <= hi[k]), -np.inf, np.inf), a)
            b = np.where(dk == 0, np.where((lo[k] <= o[k]) & (o[k] <= hi[k]), np.inf, -np.inf), b)
            tn, tf = np.maximum(tn, np.minimum(a, b)), np.minimum(tf, np.maximum(a, b))
        hit = tn < tf * 0.995
    return hit[:-1, :-1] & hit[1:, :-1] & hit[:-1, 1:] & hit[1:, 1:]


def slab_analytic(case, res=RES, half=4, sub=4):
    """exp(-sigma_t * path length) averaged over the central 2*half pixels square
    (sub x sub points per pixel), and that square's mask."""
    import numpy as np
    lo, hi = case["bound"]["box"]
    thick = hi[2] - lo[2]
    sigma_t = case["sigma_a"] + case["sigma_s"]
    x, y = pixel_rays(res, FOVY, sub)
    tr = np.exp(-sigma_t * thick * np.sqrt(x * x + y * y + 1))
    tr = tr.reshape(res, sub, res, sub).mean(axis=(1, 3))
    m = np.zeros((res, res), bool)
    c = res // 2
    m[c - half:c + half, c - half:c + half] = True
    return float(tr[m].mean()), m


# ---------------------------------------------------------------- luster

def luster_volume(case, density_file=None):
    b = case["bound"]
    if "sphere" in b:
        bound = f"<Sphere><Center>0 0 0</Center><Radius>{b['sphere']}</Radius></Sphere>"
    else:
        lo, hi = b["box"]
        bound = "<Box><Min>%g %g %g</Min><Max>%g %g %g</Max></Box>" % (*lo, *hi)
    extra = ""
    if case.get("shader"):
        extra = f"<Shader>{density_file}</Shader><GridResolution>{case['grid']}</GridResolution>"
    sa, ss = case["sigma_a"], case["sigma_s"]
    return (f'<Volume id="{case["name"]}">{bound}{extra}<Density>1</Density>'
            f"<Absorption>{sa} {sa} {sa}</Absorption><Scattering>{ss} {ss} {ss}</Scattering>"
            f"<Anisotropy>{case['g']}</Anisotropy></Volume>")


def luster_params(depth):
    """luster's MaxRecursionDepth and RendererParams: Russian roulette (depth None), or a fixed depth."""
    return (DEPTH, "MIS RussianRoulette") if depth is None else (depth, "MIS")


def mi_depths(depth):
    """Mitsuba's max_depth and rr_depth matching luster_params(depth)."""
    return (MI_MAX_DEPTH, MI_RR_DEPTH) if depth is None else (depth + 2, depth + 3)


def luster_xml(case, spp, image, depth=None):
    pl = ""
    if case["point"]:
        p, i = case["point"]["pos"], case["point"]["intensity"]
        pl = (f'<PointLight id="2"><Position>{p[0]} {p[1]} {p[2]}</Position>'
              f"<Intensity>{i} {i} {i}</Intensity></PointLight>")
    return f"""<Scene>
  <MaxRecursionDepth>{luster_params(depth)[0]}</MaxRecursionDepth>
  <BackgroundColor>0 0 0</BackgroundColor>
  <ShadowRayEpsilon>1e-5</ShadowRayEpsilon>
  <Cameras><Camera id="1" type="lookAt">
    <Position>0 0 {CAM_Z}</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
    <FovY>{FOVY}</FovY><NearDistance>1</NearDistance>
    <ImageResolution>{RES} {RES}</ImageResolution><NumSamples>{spp}</NumSamples><ImageName>{image}</ImageName>
    <Renderer>PathTracing</Renderer><RendererParams>{luster_params(depth)[1]}</RendererParams></Camera></Cameras>
  <Textures><Images><Image id="1">white.exr</Image></Images></Textures>
  <Lights><AmbientLight>0 0 0</AmbientLight>
    <SphericalDirectionalLight id="1" type="latlong"><ImageId>1</ImageId></SphericalDirectionalLight>{pl}</Lights>
  <Volumes>{luster_volume(case, case['name'] + '.lua')}</Volumes>
</Scene>
"""


def write_luster_scenes(cases, spp, d, depth=None):
    """The scene files, each case's density script and the white environment, in `d`."""
    os.makedirs(d, exist_ok=True)
    import numpy as np
    save_exr(os.path.join(d, "white.exr"), np.ones((32, 64, 3), np.float32))
    paths = {}
    for c in cases:
        if c.get("shader"):
            with open(os.path.join(d, c["name"] + ".lua"), "w") as f:
                f.write(c["shader"])
        for seed in (1, 2):
            xml = os.path.join(d, f"{c['name']}_{spp}_s{seed}.xml")
            with open(xml, "w") as f:
                f.write(luster_xml(c, spp, f"{c['name']}_{spp}_s{seed}.exr", depth))
            paths[(c["name"], seed)] = xml
    return paths


def run_luster(luster, xmls, outdir, seed, threads, quiet=True):
    """One luster process for `xmls` with `seed`; (wall seconds, stdout + stderr, exit code).
    Not quiet, luster ends with a summary line per image: `... X s render (+Y s load and build) ...`."""
    t0 = time.time()
    q = ["-q"] if quiet else []
    p = subprocess.run([luster, "render"] + q + ["-t", str(threads), "--seed", str(seed), "-o", outdir] + xmls,
                       capture_output=True, text=True)
    return time.time() - t0, p.stdout + p.stderr, p.returncode


def export_grid(export, xml, vid, out):
    """Runs export_volume; its JSON line (the Mitsuba box and to_world), or raises with its message."""
    p = subprocess.run([export, xml, vid, out], capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError((p.stderr or p.stdout).strip() or f"export_volume exit {p.returncode}")
    info = json.loads(p.stdout.strip().splitlines()[-1])
    with open(out, "rb") as f:
        info["sha1"] = hashlib.sha1(f.read()).hexdigest()
    info["text"] = p.stdout.strip().splitlines()[:-1]
    return info


# ---------------------------------------------------------------- Mitsuba (worker)

def mi_medium(mi, m):
    """A Mitsuba medium from {sigma_t, albedo, g} and, for a grid, {vol, to_world, scale}."""
    phase = {"type": "hg", "g": m["g"]} if m["g"] != 0 else {"type": "isotropic"}
    albedo = {"type": "rgb", "value": m["albedo"]} if isinstance(m["albedo"], list) else m["albedo"]
    if m.get("vol"):
        return {"type": "heterogeneous", "albedo": albedo, "scale": m["sigma_t"], "phase": phase,
                "sigma_t": {"type": "gridvolume", "filename": m["vol"],
                            "to_world": mi.ScalarTransform4f(m["to_world"])}}
    return {"type": "homogeneous", "albedo": albedo, "sigma_t": m["sigma_t"], "phase": phase}


def mi_cube_to_world(mi, lo, hi):
    c = [(a + b) / 2 for a, b in zip(lo, hi)]
    h = [(b - a) / 2 for a, b in zip(lo, hi)]
    return mi.ScalarTransform4f().translate(c).scale(h)


def mi_scene(mi, j):
    T = mi.ScalarTransform4f
    cam = j["camera"]
    scene = {
        "type": "scene",
        "integrator": {"type": "volpath", "max_depth": j["max_depth"], "rr_depth": j["rr_depth"]},
        "sensor": {"type": "perspective", "fov": cam["fovy"], "fov_axis": "y", "near_clip": 0.01,
                   "far_clip": 10000.0,
                   "to_world": T().look_at(origin=cam["pos"], target=cam["target"], up=cam["up"]),
                   "sampler": {"type": "independent", "sample_count": j["spp"], "seed": j["seed"]},
                   "film": {"type": "hdrfilm", "width": cam["res"], "height": cam["res"], "rfilter": {"type": "box"},
                            "pixel_format": "rgb", "component_format": "float32"}},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": j["env"]}},
    }
    for i, pl in enumerate(j.get("points", [])):
        scene[f"point{i}"] = {"type": "point", "position": pl["pos"],
                              "intensity": {"type": "rgb", "value": pl["intensity"]}}
    med = mi_medium(mi, j["medium"])
    b = j["bound"]
    if "sphere" in b:
        scene["medium_shape"] = {"type": "sphere", "center": [0, 0, 0], "radius": b["sphere"],
                                 "bsdf": {"type": "null"}, "interior": med}
    else:
        scene["medium_shape"] = {"type": "cube", "to_world": mi_cube_to_world(mi, *b["box"]),
                                 "bsdf": {"type": "null"}, "interior": med}
    for i, g in enumerate(j.get("grounds", [])):
        scene[f"ground{i}"] = {"type": "rectangle",
                               "to_world": T().translate([0, g["y"], 0]).rotate([1, 0, 0], -90).scale(g["half"]),
                               "bsdf": {"type": "diffuse",
                                        "reflectance": {"type": "rgb", "value": g["reflectance"]}}}
    return scene


def worker_mitsuba(jobs, out_json):
    t_start = time.time()
    import numpy as np
    import mitsuba as mi
    import drjit as dr
    variant = os.environ.get("XCHECK_MI_VARIANT", "llvm_ad_rgb")
    try:
        mi.set_variant(variant)
    except Exception:
        variant = "scalar_rgb"
        mi.set_variant(variant)
    t_import = time.time() - t_start
    results = []
    for j in jobs:
        dr.set_thread_count(j["threads"])
        t0 = time.time()
        scene = mi.load_dict(mi_scene(mi, j))
        t1 = time.time()
        img = mi.render(scene)
        dr.eval(img)
        img = np.array(img, dtype=np.float32)
        t2 = time.time()
        r = {"out": j["out"], "variant": variant, "load_s": t1 - t0, "render_s": t2 - t1}
        if j.get("again"):  # once more, its kernels compiled: the render alone
            again = mi.render(scene, seed=1)  # another seed: nothing to reuse
            np.array(again)  # waits for the kernels, as the first render's copy did
            r["render_again_s"] = time.time() - t2
        mi.Bitmap(img).write(j["out"])
        results.append(r)
        print(f"  mitsuba[{variant}] {os.path.basename(j['out'])}: {t2 - t0:.1f} s", flush=True)
    with open(out_json, "w") as f:
        json.dump({"variant": variant, "import_s": t_import, "jobs": results}, f)


def run_mitsuba(py, jobs, work, name="jobs", llvm=LLVM):
    """Renders `jobs` in one worker process; (process wall seconds, the worker's report)."""
    path = os.path.join(work, f"{name}_mitsuba.json")
    out = os.path.join(work, f"{name}_mitsuba_done.json")
    with open(path, "w") as f:
        json.dump(jobs, f)
    env = dict(os.environ)
    if os.path.exists(llvm):
        env.setdefault("DRJIT_LIBLLVM_PATH", llvm)
    else:
        env.setdefault("XCHECK_MI_VARIANT", "scalar_rgb")
    t0 = time.time()
    p = subprocess.run([py, os.path.abspath(__file__), "_worker", path, out], env=env)
    wall = time.time() - t0
    if p.returncode != 0:
        sys.exit(f"mitsuba worker failed (exit {p.returncode})")
    with open(out) as f:
        return wall, json.load(f)


def mi_job(case, spp, seed, out, grid_info=None, threads=2, depth=None):
    sa, ss = case["sigma_a"], case["sigma_s"]
    st = sa + ss
    med = {"sigma_t": st, "albedo": ss / st if st > 0 else 0.0, "g": case["g"]}
    if grid_info:
        med.update(vol=grid_info["file"], to_world=grid_info["to_world"])
    bound = case["bound"]
    if grid_info:  # the cube the grid's voxels fill (half a lattice step beyond luster's box)
        bound = {"box": [grid_info["world_box"]["min"], grid_info["world_box"]["max"]]}
    j = {"camera": {"pos": [0, 0, CAM_Z], "target": [0, 0, 0], "up": [0, 1, 0], "fovy": FOVY, "res": RES},
         "max_depth": mi_depths(depth)[0], "rr_depth": mi_depths(depth)[1], "spp": spp, "seed": seed, "out": out,
         "env": [1.0, 1.0, 1.0], "medium": med, "bound": bound, "threads": threads}
    if case["point"]:
        j["points"] = [{"pos": case["point"]["pos"], "intensity": [case["point"]["intensity"]] * 3}]
    return j


# ---------------------------------------------------------------- images and statistics

_MI = None


def _bitmap():
    """Mitsuba's Bitmap (scalar_rgb) reads and writes the EXRs and PNGs."""
    global _MI
    if _MI is None:
        import mitsuba as mi
        mi.set_variant("scalar_rgb")
        _MI = mi
    return _MI.Bitmap


def load_exr(path):
    import numpy as np
    return np.array(_bitmap()(path), dtype=np.float64)[..., :3]


def save_exr(path, img):
    import numpy as np
    _bitmap()(np.asarray(img, dtype=np.float32)).write(path)


def lum(img):
    return img @ [0.2126, 0.7152, 0.0722]


def pair(a, b):
    """Two renders (seeds) of one renderer: the per-pixel mean luminance and its variance estimate."""
    la, lb = lum(a), lum(b)
    return 0.5 * (la + lb), 0.25 * (la - lb) ** 2


def region_stats(y, v, mask):
    n = int(mask.sum())
    return float(y[mask].mean()), float(math.sqrt(v[mask].sum()) / n)


def blocks(y, v, mask, b=BLOCK):
    """Block means, their variances and which blocks lie wholly inside `mask`."""
    h, w = y.shape
    r = lambda a: a[:h // b * b, :w // b * b].reshape(h // b, b, w // b, b)  # noqa: E731
    return r(y).mean(axis=(1, 3)), r(v).sum(axis=(1, 3)) / (b * b) ** 2, r(mask).all(axis=(1, 3))


def compare(lu, ref, mask, tol):
    """luster (y, v) against a reference renderer's (y, v): mean ratio and block z-scores."""
    import numpy as np
    ml, sl = region_stats(*lu, mask)
    mr, sr = region_stats(*ref, mask)
    bl, vl, inside = blocks(*lu, mask)
    br, vr, _ = blocks(*ref, mask)
    sd = np.sqrt(vl + vr + (NOISE_FLOOR * br) ** 2)
    z = np.where(sd > 0, (bl - br) / np.where(sd > 0, sd, 1), 0.0)[inside]
    rel = (bl / np.where(br > 0, br, np.inf) - 1)[inside]
    dev = ml / mr - 1 if mr > 0 else float("inf")
    se = math.hypot(sl / ml if ml > 0 else 0, sr / mr)
    nz = int((np.abs(z) > 4).sum())
    ok = abs(dev) <= tol + 2 * se and nz <= 0.01 * z.size
    return {"luster": ml, "luster_se": sl, "ref_mean": mr, "ref_se": sr, "dev": dev, "dev_se": se,
            "blocks": int(z.size), "mean_z2": float((z ** 2).mean()), "max_abs_z": float(np.abs(z).max()),
            "blocks_z_gt_4": nz, "max_abs_block_dev": float(np.abs(rel).max()), "pass": bool(ok)}


def against_constant(lu, value, mask, tol):
    """luster against a known value everywhere in `mask` (the white furnace)."""
    import numpy as np
    ml, sl = region_stats(*lu, mask)
    bl, vl, inside = blocks(*lu, mask)
    d = (bl - value)[inside]
    sd = np.sqrt(vl[inside] + (NOISE_FLOOR * value) ** 2)
    z = np.where(sd > 0, d / np.where(sd > 0, sd, 1), 0.0)
    worst = int(np.argmax(np.abs(d)))
    dev = ml / value - 1
    ok = abs(dev) <= tol + 2 * sl / value and float(np.abs(d).max()) <= 2 * tol + 4 * float(sd[worst])
    return {"luster": ml, "luster_se": sl, "ref_mean": value, "ref_se": 0.0, "dev": dev, "dev_se": sl / value,
            "blocks": int(d.size), "max_abs_block_dev": float(np.abs(d).max() / value),
            "worst_block_z": float(z[worst]), "mean_z2": float((z ** 2).mean()),
            "max_abs_z": float(np.abs(z).max()), "blocks_z_gt_4": int((np.abs(z) > 4).sum()), "pass": bool(ok)}


def srgb8(img, exposure=1.0):
    import numpy as np
    x = np.clip(img * exposure, 0, 1)
    x = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return (x * 255 + 0.5).astype(np.uint8)


def dev_map(lu, ref, inside, scale=0.2, b=BLOCK):
    """Block relative deviation luster/ref - 1 as colour: red brighter, blue darker, full at +-scale."""
    import numpy as np
    with np.errstate(divide="ignore", invalid="ignore"):
        d = np.where(inside & (ref > 0), lu / ref - 1, 0.0)
    t = np.clip(d / scale, -1, 1)
    c = np.stack([np.where(t > 0, 1.0, 1 + t), 1 - np.abs(t), np.where(t < 0, 1.0, 1 - t)], -1)
    c[~inside] = 0.3
    return (np.kron(c, np.ones((b, b, 1))) * 255 + 0.5).astype(np.uint8)


def write_sheet(path, rows):
    """rows: lists of uint8 images (None: black), same height per row."""
    import numpy as np
    out = []
    for r in rows:
        ims = [x if x is not None else np.zeros((RES, RES, 3), np.uint8) for x in r]
        out.append(np.concatenate(ims, axis=1))
    w = max(r.shape[1] for r in out)
    out = [np.pad(r, ((0, 0), (0, w - r.shape[1]), (0, 0))) for r in out]
    _bitmap()(np.concatenate(out, axis=0)).write(path)


# ---------------------------------------------------------------- the checks

def mi_key(j, extra=""):
    spec = {k: v for k, v in j.items() if k not in ("out", "threads")}
    spec["v"] = CACHE_VERSION
    spec["extra"] = extra
    if spec["medium"].get("vol"):
        spec["medium"] = dict(spec["medium"], vol=os.path.basename(spec["medium"]["vol"]))
    return hashlib.sha1(json.dumps(spec, sort_keys=True).encode()).hexdigest()[:16]


def run_checks(args, cases, work):
    ld = os.path.join(work, "luster")
    idir = os.path.join(work, "img")
    os.makedirs(idir, exist_ok=True)
    xmls = write_luster_scenes(cases, args.spp, ld, args.depth)
    errors = {}
    # the grid, exported from luster's own scene file
    grids = {}
    for c in cases:
        if c.get("shader"):
            vol = os.path.join(work, f"{c['name']}.vol")
            try:
                grids[c["name"]] = export_grid(args.export, xmls[(c["name"], 1)], c["name"], vol)
            except (RuntimeError, OSError) as e:
                errors[c["name"]] = f"export_volume: {e}"
                continue
            for ln in grids[c["name"]]["text"]:
                print(f"  export {c['name']}: {ln}")
    # Mitsuba: cached, or rendered now
    cpath = os.path.join(work, "refs.json")
    cache = json.load(open(cpath)) if os.path.exists(cpath) else {}
    mi_imgs, todo, variant = {}, [], None
    for c in cases:
        if c["name"] in errors:
            continue
        for seed in (1, 2):
            j = mi_job(c, args.spp, seed, "", grids.get(c["name"]), args.threads, args.depth)
            key = mi_key(j, grids[c["name"]]["sha1"] if c["name"] in grids else "")
            j["out"] = os.path.join(idir, f"mitsuba_{c['name']}_{key}.exr")
            if key in cache and os.path.exists(j["out"]):
                mi_imgs[(c["name"], seed)] = j["out"]
                variant = variant or cache[key].get("variant")
            elif "mitsuba" in args.renderers:
                todo.append((c["name"], seed, key, j))
    if todo:
        print(f"mitsuba: {len(todo)} renders", flush=True)
        wall, rep = run_mitsuba(args.python, [t[3] for t in todo], work, "checks", args.llvm)
        variant = rep["variant"]
        print(f"mitsuba[{variant}]: {wall:.1f} s", flush=True)
        for (name, seed, key, j), r in zip(todo, rep["jobs"]):
            cache[key] = {"case": name, "seed": seed, "spp": args.spp, "variant": r["variant"],
                          "render_s": r["render_s"], "file": os.path.basename(j["out"])}
            mi_imgs[(name, seed)] = j["out"]
        with open(cpath, "w") as f:
            json.dump(cache, f, indent=1, sort_keys=True)
    # luster
    lu_imgs, lwall = {}, None
    if "luster" in args.renderers:
        if not os.path.exists(args.luster):
            for c in cases:
                errors.setdefault(c["name"], f"no luster binary at {args.luster}")
        else:
            lwall = 0.0
            for seed in (1, 2):
                todo_l = [xmls[(c["name"], seed)] for c in cases if c["name"] not in errors]
                for c in cases:
                    e = os.path.join(ld, f"{c['name']}_{args.spp}_s{seed}.exr")
                    if os.path.exists(e):
                        os.remove(e)
                w, out, rc = run_luster(args.luster, todo_l, ld, seed, args.threads)
                lwall += w
                print(f"luster seed {seed}: {len(todo_l)} scenes, {w:.1f} s, exit {rc}", flush=True)
                for c in cases:
                    e = os.path.join(ld, f"{c['name']}_{args.spp}_s{seed}.exr")
                    if os.path.exists(e):
                        lu_imgs[(c["name"], seed)] = e
                    elif c["name"] not in errors:
                        lines = [ln for ln in out.splitlines() if c["name"] in ln] or out.strip().splitlines()
                        errors[c["name"]] = (lines or ["no image"])[0][:300]
    # compare
    rows, sheet, worst = [], [], 0
    for c in cases:
        name = c["name"]
        mask = bound_mask(c["bound"])
        mi_pair = [mi_imgs.get((name, s)) for s in (1, 2)]
        lu_pair = [lu_imgs.get((name, s)) for s in (1, 2)]
        mi_yv = pair(*[load_exr(p) for p in mi_pair]) if all(mi_pair) else None
        lu_yv = pair(*[load_exr(p) for p in lu_pair]) if all(lu_pair) else None
        # at a fixed depth a furnace loses what the deeper paths would bring: Mitsuba is its reference
        ref = "mitsuba" if c["ref"] == "one" and args.depth is not None else c["ref"]
        row = {"case": name, "ref": ref, "pixels": int(mask.sum()),
               "medium": {k: c[k] for k in ("sigma_a", "sigma_s", "g")}}
        if mi_yv:
            row["mitsuba"], row["mitsuba_se"] = region_stats(*mi_yv, mask)
        if name in grids:
            row["grid"] = {k: grids[name][k] for k in ("dims", "max", "mean", "world_box", "to_world")}
        res = None
        if lu_yv:
            row["luster"], row["luster_se"] = region_stats(*lu_yv, mask)
            if ref == "mitsuba" and mi_yv:
                res = compare(lu_yv, mi_yv, mask, args.tol)
            elif ref == "one":
                res = against_constant(lu_yv, 1.0, mask, args.tol)
            elif ref == "analytic":
                value, m2 = slab_analytic(c)
                ml, sl = region_stats(*lu_yv, m2)
                res = {"luster": ml, "luster_se": sl, "ref_mean": value, "ref_se": 0.0, "dev": ml / value - 1,
                       "dev_se": sl / value, "pass": abs(ml / value - 1) <= args.tol / 2 + 2 * sl / value,
                       "pixels": int(m2.sum())}
                if mi_yv:
                    row["mitsuba"], row["mitsuba_se"] = region_stats(*mi_yv, m2)
        if res:
            row.update(res)
            worst = max(worst, 0 if res["pass"] else 1)
        elif name in errors:
            row["error"] = errors[name]
            worst = 2
        rows.append(row)
        # previews: Mitsuba | luster | block deviation of luster from Mitsuba (+-20%)
        mi_img = load_exr(mi_pair[0]) if mi_pair[0] else None
        lu_img = load_exr(lu_pair[0]) if lu_pair[0] else None
        dm = None
        if mi_yv and lu_yv:
            bl, _, inside = blocks(*lu_yv, mask)
            br, _, _ = blocks(*mi_yv, mask)
            dm = dev_map(bl, br, inside)
        sheet.append([srgb8(mi_img) if mi_img is not None else None,
                      srgb8(lu_img) if lu_img is not None else None, dm])
        for who, im in (("mitsuba", mi_img), ("luster", lu_img)):
            if im is not None:
                _bitmap()(srgb8(im)).write(os.path.join(work, f"{name}_{who}.png"))
    write_sheet(os.path.join(work, "sheet.png"), sheet)
    return rows, worst, variant, lwall


def print_checks(rows, tol):
    print(f"{'case':<13} {'Mitsuba':>15} {'luster':>15} {'reference':>9} {'luster/ref-1':>16} "
          f"{'blocks':>6} {'mean z2':>8} {'|z|>4':>5} {'max|dev|':>8}  result")
    for r in rows:
        f = lambda m, s: f"{m:8.4f}±{s:.4f}" if m is not None else f"{'-':>15}"  # noqa: E731
        mi = f(r.get("mitsuba"), r.get("mitsuba_se", 0))
        lu = f(r.get("luster"), r.get("luster_se", 0))
        if "dev" not in r:
            why = ("error: " + r["error"] if "error" in r else "no luster image" if r.get("luster") is None
                   else "no reference")
            print(f"{r['case']:<13} {mi} {lu} {'':>9} {'':>16}  {why}")
            continue
        ref = {"mitsuba": "Mitsuba", "one": "1"}.get(r["ref"], "%.4f" % r["ref_mean"])
        dev = f"{100 * r['dev']:+.2f}%±{100 * r['dev_se']:.2f}"
        blk = (f"{r['blocks']:>6} {r['mean_z2']:8.2f} {r['blocks_z_gt_4']:>5} {100 * r['max_abs_block_dev']:7.2f}%"
               if "blocks" in r else f"{'':>6} {'':>8} {'':>5} {'':>8}")
        print(f"{r['case']:<13} {mi} {lu} {ref:>9} {dev:>16} {blk}  {'pass' if r['pass'] else 'FAIL'}")
    print(f"mean luminance over the pixels inside each bound (slab: the central 8x8 pixels, reference "
          f"exp(-sigma_t d)); pass = within {100 * tol:.0f}% + 2 standard errors (slab {50 * tol:.0f}%), and "
          f"|z| > 4 in at most 1% of the {BLOCK}x{BLOCK} blocks (furnace: every block within {200 * tol:.0f}% "
          f"+ 4 sigma of 1)")


# ---------------------------------------------------------------- the cloud benchmark

def _floats(el, what):
    try:
        return [float(x) for x in el.text.split()]
    except (AttributeError, ValueError):
        raise ValueError(f"cannot read {what}")


def read_cloud(path, vid):
    """The parts of a cloud scene (examples/scenes/cloud.xml) the benchmark needs, and its parsed tree.
    It must have a lookAt camera, point lights (and an ambient light) only, planes with normal +y for the
    ground, and the medium `vid` bounded by an unrotated ellipsoid or a box, with no Transformations."""
    import xml.etree.ElementTree as ET
    tree = ET.parse(path)
    root = tree.getroot()
    cam = root.find("Cameras/Camera")
    if cam is None or cam.find("GazePoint") is None:
        raise ValueError("the bench needs a lookAt camera (Position, GazePoint, Up, FovY)")
    spec = {"camera": {"pos": _floats(cam.find("Position"), "Position"),
                       "target": _floats(cam.find("GazePoint"), "GazePoint"),
                       "up": _floats(cam.find("Up"), "Up"), "fovy": _floats(cam.find("FovY"), "FovY")[0]}}
    bg = root.find("BackgroundColor")
    spec["sky"] = _floats(bg, "BackgroundColor") if bg is not None else [0.0, 0.0, 0.0]
    spec["points"] = []
    for light in root.find("Lights") if root.find("Lights") is not None else []:
        if light.tag == "PointLight":
            spec["points"].append({"pos": _floats(light.find("Position"), "a PointLight's Position"),
                                   "intensity": _floats(light.find("Intensity"), "a PointLight's Intensity")})
        elif light.tag != "AmbientLight":
            raise ValueError(f"the bench knows point lights only, not <{light.tag}>")
    verts = _floats(root.find("VertexData"), "VertexData") if root.find("VertexData") is not None else []
    mats = {m.get("id"): m for m in root.iter("Material")}
    spec["planes"] = []
    for obj in root.find("Objects") if root.find("Objects") is not None else []:
        if obj.tag != "Plane":
            raise ValueError(f"the bench knows planes only among the objects, not <{obj.tag}>")
        n = _floats(obj.find("Normal"), "a Plane's Normal")
        i = int(obj.find("Point").text) - 1
        m = mats.get(obj.find("Material").text.strip())
        if n[0] != 0 or n[2] != 0 or n[1] <= 0 or m is None or m.get("BRDF") or m.get("type"):
            raise ValueError("the bench knows ground planes of normal +y with a course material (no BRDF) only")
        spec["planes"].append({"y": verts[3 * i + 1], "kd": _floats(m.find("DiffuseReflectance"), "kd")})
    vol = next((v for v in root.iter("Volume") if v.get("id") == vid), None)
    if vol is None:
        raise ValueError(f"no <Volume id=\"{vid}\">")
    if vol.find("Transformations") is not None:
        raise ValueError("the bench's volume may not have Transformations")
    ell, box = vol.find("Ellipsoid"), vol.find("Box")
    if ell is not None:
        if ell.find("Rotation") is not None:
            raise ValueError("the bench's ellipsoid may not be rotated")
        spec["scale"], spec["center"] = _floats(ell.find("Radii"), "Radii"), _floats(ell.find("Center"), "Center")
    elif box is None:
        raise ValueError("the bench's volume needs an <Ellipsoid> or a <Box> bound")
    shader = vol.find("Shader")
    if shader is None:
        raise ValueError("the bench's volume needs a <Shader> (its density is baked and exported)")
    spec["shader"] = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(path)), shader.text.strip()))
    get = lambda tag, d: _floats(vol.find(tag), tag) if vol.find(tag) is not None else d  # noqa: E731
    spec["density"] = get("Density", [1.0])[0]
    spec["sigma_a"], spec["sigma_s"] = get("Absorption", [1.0] * 3), get("Scattering", [0.0] * 3)
    spec["g"] = get("Anisotropy", [0.0])[0]
    if len(set(spec["sigma_a"])) > 1 or len(set(spec["sigma_s"])) > 1:
        raise ValueError("the bench's medium must be grey (the same σa and σs in every channel)")
    return spec, tree


def cloud_xml(path, vid, res, spp, factor, image):
    """The cloud scene path-traced: MIS RussianRoulette, no ambient light (the path tracer's
    surfaces ignore it, and Mitsuba has none), the ellipsoid replaced by the Box [-1, 1]^3 under
    its radii and centre as Scaling then Translation (the script sees the same s.P, the grid is
    the same, and the medium fills the box as in Mitsuba), the script beside the copy, baked at
    128^3, Density x factor; the camera at `res` and `spp`, writing `image`."""
    import xml.etree.ElementTree as ET
    spec, tree = read_cloud(path, vid)
    root = tree.getroot()

    def put(parent, tag, text, index=None):
        el = parent.find(tag)
        if el is None:
            el = ET.Element(tag)
            parent.insert(len(parent) if index is None else index, el)
        el.text = text
        return el

    put(root, "MaxRecursionDepth", str(DEPTH), 0)
    cam = root.find("Cameras/Camera")
    put(cam, "ImageResolution", f"{res} {res}")
    put(cam, "NumSamples", str(spp))
    put(cam, "ImageName", image)
    for t in cam.findall("Tonemap"):
        cam.remove(t)
    put(cam, "Renderer", "PathTracing")
    put(cam, "RendererParams", "MIS RussianRoulette")
    lights = root.find("Lights")
    if lights is not None and lights.find("AmbientLight") is not None:
        lights.find("AmbientLight").text = "0 0 0"
    vol = next(v for v in root.iter("Volume") if v.get("id") == vid)
    if "scale" in spec:
        ell = vol.find("Ellipsoid")
        i = list(vol).index(ell)
        vol.remove(ell)
        b = ET.Element("Box")
        ET.SubElement(b, "Min").text = "-1 -1 -1"
        ET.SubElement(b, "Max").text = "1 1 1"
        vol.insert(i, b)
        xf = root.find("Transformations")
        if xf is None:
            xf = ET.Element("Transformations")
            root.insert(list(root).index(root.find("Volumes")), xf)
        ET.SubElement(xf, "Scaling", id="901").text = " ".join("%g" % x for x in spec["scale"])
        ET.SubElement(xf, "Translation", id="901").text = " ".join("%g" % x for x in spec["center"])
        put(vol, "Transformations", "s901 t901", i + 1)
    put(vol, "Shader", os.path.basename(spec["shader"]))
    put(vol, "GridResolution", "128")
    put(vol, "Density", "%g" % (spec["density"] * factor))
    return ET.tostring(root, encoding="unicode")


def cloud_mi_job(spec, grid, res, spp, seed, factor, out, threads, again=False):
    sa, ss = spec["sigma_a"][0], spec["sigma_s"][0]
    st = sa + ss
    # The grid holds density x Density (factor 1); sigma_t = grid x factor x (sigma_a + sigma_s).
    med = {"sigma_t": st * factor, "albedo": ss / st if st > 0 else 0.0, "g": spec["g"], "vol": grid["file"],
           "to_world": grid["to_world"]}
    j = {"camera": dict(spec["camera"], res=res), "max_depth": MI_MAX_DEPTH, "rr_depth": MI_RR_DEPTH, "spp": spp,
         "seed": seed, "out": out, "env": spec["sky"], "medium": med,
         "bound": {"box": [grid["world_box"]["min"], grid["world_box"]["max"]]},
         "points": spec["points"], "threads": threads, "again": again}
    # luster's course material without a BRDF reflects kd cos (albedo pi kd) in the path tracer too
    j["grounds"] = [{"y": p["y"], "half": 1000.0, "reflectance": [math.pi * k for k in p["kd"]]}
                    for p in spec["planes"]]
    return j


def run_bench(args, work):
    import numpy as np
    bd = os.path.join(work, "bench")
    os.makedirs(bd, exist_ok=True)
    factors = [float(x) for x in args.densities.split(",")]
    res, spp = args.bench_res, args.bench_spp
    xml = {}
    try:
        spec, _ = read_cloud(args.cloud, args.cloud_volume)
        shutil.copy(spec["shader"], os.path.join(bd, os.path.basename(spec["shader"])))
        for k in sorted(set(factors) | {1.0}):
            xml[k] = os.path.join(bd, f"cloud_x{k:g}.xml")
            with open(xml[k], "w") as f:
                f.write(cloud_xml(args.cloud, args.cloud_volume, res, spp, k, f"cloud_x{k:g}.exr"))
    except (ValueError, OSError) as e:
        print(f"bench: {args.cloud}: {e}")
        return None, 2
    print(f"bench: {args.cloud} (volume {args.cloud_volume}, Density {spec['density']:g}, sigma_a "
          f"{spec['sigma_a'][0]:g}, sigma_s {spec['sigma_s'][0]:g}, g {spec['g']:g}) path-traced in {bd}")
    vol = os.path.join(bd, "cloud.vol")
    t0 = time.time()
    try:
        grid = export_grid(args.export, xml[1.0], args.cloud_volume, vol)
    except (RuntimeError, OSError) as e:
        print(f"bench: export_volume failed: {e}")
        return None, 2
    print(f"bench: exported the cloud's grid in {time.time() - t0:.1f} s (bake included)")
    for ln in grid["text"]:
        print(f"  export cloud: {ln}")
    cpath = os.path.join(bd, "mitsuba_bench.json")
    cache = json.load(open(cpath)) if os.path.exists(cpath) else {}
    do_mi = "mitsuba" in args.renderers
    do_lu = "luster" in args.renderers and os.path.exists(args.luster)

    def mi_run(k, tag, again=False):
        out = os.path.join(bd, f"mitsuba_cloud_x{k:g}.exr")
        j = cloud_mi_job(spec, grid, res, spp, 1, k, out, args.threads, again)
        key = mi_key(j, grid["sha1"]) + f"|{tag}"
        if not do_mi:
            return cache.get(key)
        wall, rep = run_mitsuba(args.python, [j], bd, "bench", args.llvm)
        again_s = rep["jobs"][0].get("render_again_s", 0.0)
        r = {"wall_s": wall - again_s, "render_s": rep["jobs"][0]["render_s"],
             "render_again_s": again_s if again else float("nan"), "load_s": rep["jobs"][0]["load_s"],
             "import_s": rep["import_s"], "variant": rep["variant"], "mean": float(lum(load_exr(out)).mean()),
             "file": os.path.basename(out)}
        cache[key] = r
        with open(cpath, "w") as f:
            json.dump(cache, f, indent=1, sort_keys=True)
        return r

    def lu_run(k):
        if not do_lu:
            return None
        exr = os.path.join(bd, f"cloud_x{k:g}.exr")
        if os.path.exists(exr):
            os.remove(exr)
        wall, out, rc = run_luster(args.luster, [xml[k]], bd, 1, args.threads, quiet=False)
        if rc != 0 or not os.path.exists(exr):
            print(f"  luster cloud x{k:g} failed: {out.strip()[:300]}")
            return None
        m = re.search(r"([0-9.]+) s render \(\+([0-9.]+) s load and build\)", out)
        return {"wall_s": wall, "render_s": float(m.group(1)) if m else float("nan"),
                "load_s": float(m.group(2)) if m else float("nan"), "mean": float(lum(load_exr(exr)).mean())}

    load_before = os.getloadavg()
    if do_mi:
        print("bench: one Mitsuba warm-up render (its JIT kernels are cached on disk after the first)", flush=True)
        mi_run(1.0, "warmup")
    runs = {"luster": [], "mitsuba": []}
    for i in range(args.bench_runs):
        lu = lu_run(1.0)
        mr = mi_run(1.0, f"run{i}", again=True)
        for who, r in (("luster", lu), ("mitsuba", mr)):
            if r:
                runs[who].append(r)
        print(f"  run {i + 1}: luster {lu['wall_s'] if lu else float('nan'):.2f} s, mitsuba "
              f"{mr['wall_s'] if mr else float('nan'):.2f} s (whole process)", flush=True)
    sweep = []
    for k in factors:
        lu = lu_run(k)
        mr = mi_run(k, "sweep")
        sweep.append((k, lu, mr))
        print(f"  density x{k:g}: luster {lu['wall_s'] if lu else float('nan'):.2f} s, mitsuba "
              f"{mr['wall_s'] if mr else float('nan'):.2f} s", flush=True)
    # previews: Mitsuba | luster at each density, exposure 1/255 (luster's 255 = display white)
    rows = []
    for k in factors:
        ims = []
        for p in (os.path.join(bd, f"mitsuba_cloud_x{k:g}.exr"), os.path.join(bd, f"cloud_x{k:g}.exr")):
            ims.append(srgb8(load_exr(p), 1 / 255) if os.path.exists(p) else np.zeros((res, res, 3), np.uint8))
        rows.append(np.concatenate(ims, axis=1))
    _bitmap()(np.concatenate(rows, axis=0)).write(os.path.join(work, "bench_sheet.png"))

    med = lambda rs, f: statistics.median(r[f] for r in rs) if rs else float("nan")  # noqa: E731
    out = {"res": res, "spp": spp, "threads": args.threads, "runs": runs,
           "variant": (runs["mitsuba"] or [{}])[0].get("variant"),
           "median_wall_s": {"luster": med(runs["luster"], "wall_s"), "mitsuba": med(runs["mitsuba"], "wall_s")},
           "median_render_s": {"luster": med(runs["luster"], "render_s"), "mitsuba": med(runs["mitsuba"], "render_s")},
           "median_mitsuba_render_again_s": med(runs["mitsuba"], "render_again_s"),
           "sweep": [{"factor": k, "luster": lu, "mitsuba": mr} for k, lu, mr in sweep],
           "loadavg_before": load_before, "loadavg_after": os.getloadavg(), "cpus": os.cpu_count(),
           "grid": {kk: grid[kk] for kk in ("dims", "max", "mean", "world_box", "to_world")}}
    with open(os.path.join(work, "bench.json"), "w") as f:
        json.dump(out, f, indent=1)
    return out, 0


def print_bench(b, runs_n):
    nan = float("nan")
    g = lambda r, f: r[f] if r else nan  # noqa: E731
    mw, mr = b["median_wall_s"], b["median_render_s"]
    ma = b["median_mitsuba_render_again_s"]
    print(f"cloud {b['res']}x{b['res']}, {b['spp']} spp, {b['threads']} threads each, Mitsuba "
          f"{b['variant']}, {runs_n} alternating runs (A B A B), medians:")
    print(f"  whole process: luster {mw['luster']:.2f} s, Mitsuba {mw['mitsuba']:.2f} s")
    print(f"  render: luster {mr['luster']:.2f} s; Mitsuba {mr['mitsuba']:.2f} s first in its process, "
          f"{ma:.2f} s again (kernels compiled); luster / Mitsuba again {mr['luster'] / ma:.2f}")
    print(f"{'Density x':>9} {'luster wall':>11} {'render':>7} {'growth':>6} {'Mitsuba wall':>12} {'render':>7} "
          f"{'growth':>6} {'luster mean':>11} {'Mitsuba mean':>12} {'lu/mi':>6}")
    base = b["sweep"][0] if b["sweep"] else None
    for s in b["sweep"]:
        lu, mi = s["luster"], s["mitsuba"]
        gl = g(lu, "render_s") / g(base["luster"], "render_s") if base["luster"] and lu else nan
        gm = g(mi, "render_s") / g(base["mitsuba"], "render_s") if base["mitsuba"] and mi else nan
        ratio = g(lu, "mean") / g(mi, "mean") if lu and mi else nan
        print(f"{s['factor']:>9g} {g(lu, 'wall_s'):11.2f} {g(lu, 'render_s'):7.2f} {gl:6.2f} {g(mi, 'wall_s'):12.2f} "
              f"{g(mi, 'render_s'):7.2f} {gm:6.2f} {g(lu, 'mean'):11.2f} "
              f"{g(mi, 'mean'):12.2f} {ratio:6.3f}")
    print(f"load average (1, 5, 15 min) before {' '.join('%.1f' % x for x in b['loadavg_before'])}, after "
          f"{' '.join('%.1f' % x for x in b['loadavg_after'])}, on {b['cpus']} CPUs: above the 2 threads used, "
          "other work shared the machine and the times are noisier")
    print("wall: the whole process (luster: load, bake, render, write; Mitsuba: import, load, JIT, render, write); "
          "render: luster's own figure, Mitsuba's mi.render (the first in its process: tracing and compiling or "
          "loading its kernels; the alternating runs render once more to show what that costs); growth: render "
          "over the first row's; means: whole-image luminance (0-255 units)")


# ---------------------------------------------------------------- driver

def ensure_venv(venv):
    py = os.path.join(venv, "bin", "python")
    if os.path.abspath(sys.prefix) == os.path.abspath(venv):
        return py
    if not os.path.exists(py):
        print(f"creating {venv}", flush=True)
        subprocess.run([sys.executable, "-m", "venv", venv], check=True)
    if subprocess.run([py, "-c", "import mitsuba, numpy"], capture_output=True).returncode != 0:
        print(f"installing {' '.join(PACKAGES)} into {venv}", flush=True)
        subprocess.run([py, "-m", "pip", "install", "-q"] + PACKAGES, check=True)
    return py


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "_worker":
        with open(sys.argv[2]) as f:
            worker_mitsuba(json.load(f), sys.argv[3])
        return 0
    rel = os.path.join("target", "release")
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--venv", default=".venv-xcheck", help="virtual environment with mitsuba and numpy "
                    "(made if missing; default ./.venv-xcheck)")
    ap.add_argument("--work", default="volume-xcheck", help="scratch folder: scenes, images, Mitsuba cache, results")
    ap.add_argument("--luster", default=os.path.join(ROOT, rel, "luster"), help="luster binary")
    ap.add_argument("--export", default=None,
                    help="export_volume binary (default: examples/export_volume beside --luster)")
    ap.add_argument("--llvm", default=LLVM, help="LLVM 19 library for Mitsuba's llvm_ad_rgb (else scalar_rgb)")
    ap.add_argument("--renderers", default="mitsuba,luster")
    ap.add_argument("--cases", default="", help="comma-separated case names (default: all)")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--tol", type=float, default=TOL)
    ap.add_argument("--depth", type=int, default=None,
                    help="a fixed depth instead of Russian roulette: luster MaxRecursionDepth D with MIS alone, "
                         "Mitsuba max_depth D + 2 (0: single scattering)")
    ap.add_argument("--bench", action="store_true", help="the checks, then the cloud benchmark")
    ap.add_argument("--bench-only", action="store_true", help="the cloud benchmark alone")
    ap.add_argument("--cloud", default=os.path.join(ROOT, "examples", "scenes", "cloud.xml"),
                    help="the benchmark's scene (default examples/scenes/cloud.xml)")
    ap.add_argument("--cloud-volume", default="cloud", help="the id of its medium")
    ap.add_argument("--bench-res", type=int, default=128)
    ap.add_argument("--bench-spp", type=int, default=32)
    ap.add_argument("--bench-runs", type=int, default=3, help="alternating runs of each renderer (at least 2)")
    ap.add_argument("--densities", default="1,2,4,8,16", help="Density factors of the sweep")
    args = ap.parse_args()
    if args.export is None:
        args.export = os.path.join(os.path.dirname(os.path.abspath(args.luster)), "examples", "export_volume")
    args.python = ensure_venv(args.venv)
    if os.path.abspath(sys.prefix) != os.path.abspath(args.venv):
        os.execv(args.python, [args.python, os.path.abspath(__file__)] + sys.argv[1:])
    args.renderers = args.renderers.split(",")
    work = os.path.abspath(args.work)
    os.makedirs(work, exist_ok=True)
    if not os.path.exists(args.export):
        print(f"no export_volume at {args.export}: cargo build --release -p luster --example export_volume")
        return 2
    t_start = time.time()
    worst, summary = 0, {}
    if not args.bench_only:
        cases = case_table()
        if args.cases:
            names = args.cases.split(",")
            cases = [c for c in cases if c["name"] in names]
        rows, worst, variant, lwall = run_checks(args, cases, work)
        print_checks(rows, args.tol)
        ld_, lp_ = luster_params(args.depth)
        md_, mr_ = mi_depths(args.depth)
        print(f"luster MaxRecursionDepth {ld_}, {lp_}; Mitsuba volpath max_depth {md_}, rr_depth {mr_}")
        print(f"Mitsuba variant: {variant or 'none rendered or cached'}; luster: {args.luster}"
              + (f" ({lwall:.1f} s for both seeds)" if lwall else ""))
        summary["checks"] = {"spp": args.spp, "res": RES, "variant": variant, "tol": args.tol, "rows": rows,
                             "luster": dict(zip(("MaxRecursionDepth", "RendererParams"), luster_params(args.depth))),
                             "mitsuba": dict(zip(("max_depth", "rr_depth"), mi_depths(args.depth)))}
        with open(os.path.join(work, "results.json"), "w") as f:
            json.dump(summary, f, indent=1)
        print(f"images: {os.path.join(work, 'sheet.png')} (rows: {', '.join(c['name'] for c in cases)}; "
              f"columns: Mitsuba, luster, luster/Mitsuba - 1 per {BLOCK}x{BLOCK} block, +-20%)")
    if args.bench or args.bench_only:
        b, rc = run_bench(args, work)
        worst = max(worst, rc)
        if b:
            print_bench(b, args.bench_runs)
            print(f"bench: {os.path.join(work, 'bench.json')}, previews {os.path.join(work, 'bench_sheet.png')} "
                  f"(rows: Density x {args.densities}; columns: Mitsuba, luster; exposure 1/255)")
    print(f"{time.time() - t_start:.0f} s")
    return worst


if __name__ == "__main__":
    sys.exit(main())

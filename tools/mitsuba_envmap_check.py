#!/usr/bin/env python3
"""Cross-check luster's environment light against Mitsuba 3 (variant scalar_rgb).

Generates a small latitude-longitude EXR (a sky gradient, a darker ground and a
small bright sun), writes three scenes for both renderers -- a diffuse sphere, a
mirror sphere and a glass sphere lit only by that map -- renders both at 256
samples per pixel (or --spp), and prints per scene the mean HDR-FLIP (the
`flip-evaluator` package, NVIDIA's reference implementation) and the relative
error of the mean luminance, luster against Mitsuba.

Setup:  python3 -m venv /tmp/mi && /tmp/mi/bin/pip install mitsuba numpy flip-evaluator
Run:    cargo build --release && /tmp/mi/bin/python tools/mitsuba_envmap_check.py

Output format of luster (--luster-output):
  exr  luster writes `<name>.exr` (linear float). The sun is 100 times the
       zenith sky (--sky-exr, --sun-exr); comparison is in linear HDR.
  png  luster writes the course's 8-bit PNG: radiance clamped to 255 and
       truncated, no gamma. The map is scaled so every pixel stays below 255
       (sky 150, sun 250: a dim sun, the price of 8 bits), and 0.5 is added
       back to undo the truncation's bias. Both images are divided by 255
       before FLIP.
  auto (default) exr if luster accepts an .exr ImageName, else png.

Conventions (documented in docs/environment-light.md):
  * Orientation. luster follows the course (hw5 eqs. 5-6):
        u = (1 + atan2(dx, -dz)/pi) / 2,  v = acos(dy)/pi,
    so -z is the image centre. Mitsuba 3's `envmap` uses
        u = atan2(dx, -dz)/(2 pi) (mod 1),  v = acos(dy)/pi,
    i.e. -z at the left/right edge. The same file therefore needs the
    Mitsuba emitter rotated 180 degrees about +y (to_world), which this script
    does; the mirror sphere would show the sun on the wrong side otherwise.
  * Diffuse scale. The course's diffuse term is kd * cos * E with no 1/pi, so
    under an environment a luster surface reflects pi * kd times the irradiance
    integral's average: Mitsuba albedo rho corresponds to luster kd = rho / pi.
  * Mirror: luster `type="mirror"` with MirrorReflectance 1 and no Blinn-Phong
    terms; Mitsuba `conductor` with material "none" (reflectance 1).
  * Glass: luster `type="dielectric"`, RefractionIndex 1.5, no absorption;
    Mitsuba `dielectric` int_ior 1.5, ext_ior 1.0. luster splits every hit into
    the Fresnel-weighted reflected and refracted rays up to MaxRecursionDepth;
    Mitsuba's path tracer picks one at random, so the two agree in expectation.
  * Pixel filter: box on both (luster's default; Mitsuba `box`).
Targets (issue 12): mean FLIP <= 0.05 and mean luminance within 2% for the
diffuse and mirror spheres; the glass sphere is reported.
"""

import argparse
import math
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

try:
    import mitsuba as mi
except ImportError:
    sys.exit("mitsuba is not installed: pip install mitsuba (see the module doc)")

mi.set_variant("scalar_rgb")

try:
    import flip_evaluator as flip
except ImportError:
    flip = None

SCENES = ("diffuse", "mirror", "glass")
ALBEDO = 0.8


def make_map(width, height, sky_peak, sun_peak):
    """A lat-long sky (row 0 is +y): gradient above the horizon, ground below,
    and a sun a few texels wide at 35 degrees elevation, 60 degrees from -z
    towards +x (so it is off-centre in the map and in the mirror)."""
    v = (np.arange(height) + 0.5) / height
    u = (np.arange(width) + 0.5) / width
    uu, vv = np.meshgrid(u, v)
    theta = np.pi * vv
    phi = np.pi * (2 * uu - 1)
    dy = np.cos(theta)
    dx = np.sin(theta) * np.sin(phi)
    dz = -np.sin(theta) * np.cos(phi)
    sky_t = np.clip(dy, 0, 1)
    sky = np.stack([0.35 + 0.25 * (1 - sky_t), 0.5 + 0.2 * (1 - sky_t), 0.9 + 0.0 * sky_t], axis=-1)
    ground = np.stack([0.18, 0.15, 0.12], axis=-1) * np.ones_like(sky)
    img = np.where((dy > 0)[..., None], sky, ground)
    img = img * (sky_peak / 0.9)
    el, az = math.radians(35), math.radians(60)
    sun = np.array([math.cos(el) * math.sin(az), math.sin(el), -math.cos(el) * math.cos(az)])
    cosang = dx * sun[0] + dy * sun[1] + dz * sun[2]
    disc = cosang > math.cos(math.radians(4.0))
    img[disc] = np.array([1.0, 0.95, 0.85]) * sun_peak
    return img.astype(np.float32)


def luster_scene(kind, spp, res, image_name):
    material = {
        "diffuse": f"""<Material id="1"><DiffuseReflectance>{ALBEDO / math.pi:.9f} {ALBEDO / math.pi:.9f} {ALBEDO / math.pi:.9f}</DiffuseReflectance></Material>""",
        "mirror": """<Material id="1" type="mirror"><MirrorReflectance>1 1 1</MirrorReflectance></Material>""",
        "glass": """<Material id="1" type="dielectric"><RefractionIndex>1.5</RefractionIndex><AbsorptionCoefficient>0 0 0</AbsorptionCoefficient></Material>""",
    }[kind]
    return f"""<Scene>
  <MaxRecursionDepth>16</MaxRecursionDepth>
  <BackgroundColor>0 0 0</BackgroundColor>
  <ShadowRayEpsilon>1e-4</ShadowRayEpsilon>
  <Cameras><Camera id="1" type="lookAt">
    <Position>0 0 4</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
    <FovY>35</FovY><NearDistance>1</NearDistance>
    <ImageResolution>{res} {res}</ImageResolution><NumSamples>{spp}</NumSamples>
    <ImageName>{image_name}</ImageName></Camera></Cameras>
  <Textures><Images><Image id="1">sky.exr</Image></Images></Textures>
  <Lights><SphericalDirectionalLight id="1" type="latlong"><ImageId>1</ImageId></SphericalDirectionalLight></Lights>
  <Materials>{material}</Materials>
  <VertexData>0 0 0</VertexData>
  <Objects><Sphere id="1"><Material>1</Material><Center>1</Center><Radius>1</Radius></Sphere></Objects>
</Scene>
"""


def mitsuba_scene(kind, spp, res, map_path):
    bsdf = {
        "diffuse": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [ALBEDO] * 3}},
        "mirror": {"type": "conductor", "material": "none"},
        "glass": {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0},
    }[kind]
    T = mi.ScalarTransform4f
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 32},
        "sensor": {
            "type": "perspective",
            "fov": 35,
            "fov_axis": "y",
            "to_world": T().look_at(origin=[0, 0, 4], target=[0, 0, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "emitter": {
            "type": "envmap",
            "filename": map_path,
            # Mitsuba's lat-long puts -z at the image edge, the course's at its
            # centre: a half turn about +y maps one onto the other.
            "to_world": T().rotate([0, 1, 0], 180),
        },
        "sphere": {"type": "sphere", "center": [0, 0, 0], "radius": 1.0, "bsdf": bsdf},
    }


def luminance(img):
    return 0.2126 * img[..., 0] + 0.7152 * img[..., 1] + 0.0722 * img[..., 2]


def read_luster(path, fmt):
    bmp = np.array(mi.Bitmap(path), dtype=np.float64)[..., :3]
    if fmt == "png":
        bmp = bmp + 0.5  # the course's PNG truncates; this removes the bias
    return bmp


def luster_accepts_exr(luster, workdir):
    """Whether this luster writes .exr images (helper A's film stage)."""
    d = os.path.join(workdir, "probe")
    os.makedirs(d, exist_ok=True)
    mi.Bitmap(np.ones((2, 4, 3), dtype=np.float32)).write(os.path.join(d, "sky.exr"))
    with open(os.path.join(d, "s.xml"), "w") as f:
        f.write(luster_scene("diffuse", 1, 4, "probe.exr"))
    r = subprocess.run([luster, "render", "-q", "-o", d, os.path.join(d, "s.xml")], capture_output=True)
    return r.returncode == 0 and os.path.exists(os.path.join(d, "probe.exr"))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--luster", default="target/release/luster")
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--map-size", type=int, nargs=2, default=[1024, 512], metavar=("W", "H"))
    ap.add_argument("--luster-output", choices=["auto", "exr", "png"], default="auto")
    ap.add_argument("--sky-exr", type=float, default=1.0, help="zenith sky radiance with EXR output")
    ap.add_argument("--sun-exr", type=float, default=100.0, help="sun radiance with EXR output")
    ap.add_argument("--sky-png", type=float, default=150.0, help="zenith sky radiance with PNG output")
    ap.add_argument("--sun-png", type=float, default=250.0, help="sun radiance with PNG output (below 255)")
    ap.add_argument("--keep", help="folder to keep scenes and images in")
    args = ap.parse_args()

    work = args.keep or tempfile.mkdtemp(prefix="envcheck-")
    os.makedirs(work, exist_ok=True)
    luster = os.path.abspath(args.luster)
    fmt = args.luster_output
    if fmt == "auto":
        fmt = "exr" if luster_accepts_exr(luster, work) else "png"
    sky_peak, sun = (args.sky_exr, args.sun_exr) if fmt == "exr" else (args.sky_png, args.sun_png)
    sky = make_map(args.map_size[0], args.map_size[1], sky_peak, sun)
    map_path = os.path.join(work, "sky.exr")
    mi.Bitmap(sky).write(map_path)
    print(f"map {args.map_size[0]}x{args.map_size[1]}, sky {sky_peak}, sun {sun}; luster output {fmt}; {args.spp} spp, {args.res}x{args.res}")
    if flip is None:
        print("flip-evaluator not installed: FLIP column left out (pip install flip-evaluator)")

    print(f"{'scene':8} {'FLIP':>7} {'lum luster':>11} {'lum mitsuba':>12} {'rel err':>8}  verdict")
    failed = False
    for kind in SCENES:
        name = f"{kind}.{fmt}"
        with open(os.path.join(work, f"{kind}.xml"), "w") as f:
            f.write(luster_scene(kind, args.spp, args.res, name))
        subprocess.run([luster, "render", "-q", "-o", work, os.path.join(work, f"{kind}.xml")], check=True)
        ours = read_luster(os.path.join(work, name), fmt)

        scene = mi.load_dict(mitsuba_scene(kind, args.spp, args.res, map_path))
        ref = np.array(mi.render(scene, seed=1), dtype=np.float64)[..., :3]
        mi.Bitmap(ref.astype(np.float32)).write(os.path.join(work, f"{kind}_mitsuba.exr"))

        scale = 255.0 if fmt == "png" else 1.0
        lo, lm = luminance(ours).mean(), luminance(ref).mean()
        rel = abs(lo - lm) / lm
        mean_flip = float("nan")
        if flip is not None:
            _, mean_flip, _ = flip.evaluate(
                (ref / scale).astype(np.float32), (ours / scale).astype(np.float32), "HDR"
            )
        ok = rel <= 0.02 and (flip is None or mean_flip <= 0.05)
        verdict = "reported" if kind == "glass" else ("ok" if ok else "FAIL")
        failed |= kind != "glass" and not ok
        print(f"{kind:8} {mean_flip:7.4f} {lo:11.4f} {lm:12.4f} {100 * rel:7.2f}%  {verdict}")
    print(f"images in {work}")
    if not args.keep:
        shutil.rmtree(work, ignore_errors=True)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()

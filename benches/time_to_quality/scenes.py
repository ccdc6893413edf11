"""The three time-to-quality scenes, written for luster, Blender Cycles and Mitsuba 3.

Each scene is one renderer-neutral description (geometry, camera, materials,
lights, path depth); this module turns it into a luster XML file, a Mitsuba 3
scene dictionary or a Cycles scene built through bpy, and renders it.

  cornell     the course's hw7 jaroslav Cornell box without its point light:
              five Lambertian walls, two Lambertian spheres, one light box
              (radiance 31.831), depth 3
  hdri        a rough copper-coloured conductor sphere (GGX, roughness 0.2), a smooth
              glass sphere (IOR 1.5) and a grey Lambertian floor, lit only by an
              environment map (examples/scenes/textures/studio.exr, smoothed,
              1/100 of its scale), depth 8
  manylights  a room (floor, ceiling, three walls, open towards the camera)
              with three Lambertian spheres and two boxes, lit by 200 small
              emitting cubes of varied colours and radiances, no environment,
              depth 3

How the renderers were aligned:
  depth     luster MaxRecursionDepth D == Cycles max_bounces D (every per-type
            limit D, min_light_bounces D + 1: no Russian roulette) == Mitsuba
            path max_depth D + 2 (rr_depth 1000)
  pixels    box filter of one pixel in all three; 32-bit linear EXR out
  Lambert   luster ModifiedPhong normalized with ks = 0 (kd/pi); Cycles Diffuse
            BSDF roughness 0; Mitsuba diffuse
  emitters  closed, outward-wound triangle shells: luster LightMesh (emits from
            both faces, the inside is never seen), Cycles Emission (colour / its
            largest channel, strength = largest channel, FRONT sampling),
            Mitsuba area emitter
  metal     luster closure conductor{f0, roughness} (GGX, Schlick Fresnel,
            multiple-scattering compensation); Cycles Metallic BSDF, Multiscatter
            GGX, F82 with a white edge tint (plain Schlick); Mitsuba principled,
            metallic 1 (single scattering: at roughness 0.2 the lost energy is
            a fraction of a percent)
  glass     luster type="dielectric"; Cycles sharp Glass BSDF on a smooth
            256 x 128 UV sphere (Cycles' point spheres are open from inside);
            Mitsuba dielectric
  sky       lat-long in luster's convention; Mitsuba envmap turned 180 degrees
            about +y; Cycles' world looks the map up at (-z, -x, y) with
            Closest interpolation. luster reads texels nearest, Mitsuba
            bilinear, so the map is smoothed until the two agree.

  python scenes.py write OUTDIR [--res R] [--spp N]     luster XML of every scene
  python scenes.py render cycles|mitsuba SCENE --spp N --out IMG.exr [--res R]
        [--seed S] [--threads T] [--light-tree 1|0] [--adaptive 1|0] [--denoise 1|0]
        [--variant llvm_ad_rgb|scalar_rgb] [--time-limit SECONDS] [--work DIR]
The render command prints one line 'RESULT {json}' with the render call's own
wall and CPU seconds and the samples per pixel it took.
"""
import argparse
import hashlib
import json
import math
import os
import resource
import sys
import time
from xml.sax.saxutils import escape

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
STUDIO = os.path.join(REPO, "examples", "scenes", "textures", "studio.exr")
SCENES = ("cornell", "hdri", "manylights")
T0 = time.time()


# ------------------------------------------------------------------ descriptions

def _quad(a, b, c, d):
    return [(a, b, c), (a, c, d)]


def _box_shell(lo, hi):
    """Twelve outward-wound triangles of the axis-aligned box lo..hi."""
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    p = lambda i, j, k: (x1 if i else x0, y1 if j else y0, z1 if k else z0)  # noqa: E731
    faces = [  # each quad counter-clockwise seen from outside
        (p(0, 0, 0), p(0, 1, 0), p(1, 1, 0), p(1, 0, 0)),  # -z
        (p(0, 0, 1), p(1, 0, 1), p(1, 1, 1), p(0, 1, 1)),  # +z
        (p(0, 0, 0), p(1, 0, 0), p(1, 0, 1), p(0, 0, 1)),  # -y
        (p(0, 1, 0), p(0, 1, 1), p(1, 1, 1), p(1, 1, 0)),  # +y
        (p(0, 0, 0), p(0, 0, 1), p(0, 1, 1), p(0, 1, 0)),  # -x
        (p(1, 0, 0), p(1, 1, 0), p(1, 1, 1), p(1, 0, 1)),  # +x
    ]
    tris = []
    for q in faces:
        tris += _quad(*q)
    return tris


def _outward(tris):
    """Wind every triangle of a closed convex shell so its normal faces out."""
    pts = np.array([p for t in tris for p in t], float)
    centre = pts.mean(axis=0)
    out = []
    for a, b, c in tris:
        a, b, c = np.array(a, float), np.array(b, float), np.array(c, float)
        if np.dot(np.cross(b - a, c - a), (a + b + c) / 3 - centre) < 0:
            b, c = c, b
        out.append((tuple(a), tuple(b), tuple(c)))
    return out


def cornell():
    """The course's hw7 jaroslav Cornell box (path_diffuse) without its point light."""
    v = [(-1.27029, 1.30455, -1.28002), (1.28975, 1.30455, -1.28002), (1.28975, 1.30455, 1.28002),
         (-1.27029, 1.30455, 1.28002), (-1.27029, -1.25549, -1.28002), (1.28975, -1.25549, -1.28002),
         (1.28975, -1.25549, 1.28002), (-1.27029, -1.25549, 1.28002)]
    white, green, red = (0.803922,) * 3, (0.156863, 0.803922, 0.172549), (0.803922, 0.152941, 0.152941)
    walls = [((0, 4, 5, 1), white), ((3, 7, 4, 0), green), ((1, 5, 6, 2), red), ((0, 1, 2, 3), white),
             ((2, 6, 7, 3), white)]
    meshes = [{"tris": _quad(*[v[i] for i in q]), "mat": {"type": "diffuse", "kd": kd}} for q, kd in walls]
    # the light box: 0.5 x 0.5 x 0.12 under the ceiling, open at the top (against the ceiling)
    lb = [(-0.25, 0.25, 1.16002), (0.25, 0.25, 1.16002), (0.25, 0.25, 1.28002), (-0.25, 0.25, 1.28002),
          (-0.25, -0.25, 1.16002), (0.25, -0.25, 1.16002), (0.25, -0.25, 1.28002), (-0.25, -0.25, 1.28002)]
    faces = [(0, 2, 1), (2, 0, 3), (3, 4, 7), (4, 3, 0), (1, 6, 5), (6, 1, 2), (4, 5, 6), (6, 7, 4), (0, 5, 4),
             (5, 0, 1)]
    light = _outward([tuple(lb[i] for i in f) for f in faces])
    return {
        "name": "cornell", "depth": 3, "up_axis": "z",
        "camera": {"pos": (-0.0439815, -4.12529, 0.222539),
                   "target": (-0.0439815 + 0.00688625, -4.12529 + 0.998505, 0.222539 - 0.0542161),
                   "up": (3.73896e-4, 0.0542148, 0.998529), "fovy": 45.0},
        "env": None,
        "meshes": meshes,
        "spheres": [{"center": (-0.53885, 0.02453, -0.78002), "radius": 0.5,
                     "mat": {"type": "diffuse", "kd": (0.803922, 0.803922, 0.152941)}},
                    {"center": (0.55831, 0.66454, -0.78002), "radius": 0.5,
                     "mat": {"type": "diffuse", "kd": (0.152941, 0.152941, 0.803922)}}],
        "emitters": [{"tris": light, "radiance": (31.831, 31.831, 31.831)}],
    }


def hdri():
    """Glossy metal, glass and a diffuse floor under the studio map (y up)."""
    f = 12.0
    return {
        "name": "hdri", "depth": 8, "up_axis": "y",
        "camera": {"pos": (0.0, 1.2, 6.5), "target": (0.0, -0.1, 0.0), "up": (0.0, 1.0, 0.0), "fovy": 35.0},
        "env": {"source": STUDIO, "scale": 0.01, "down": 8, "up": 4},
        "meshes": [{"tris": _quad((-f, -1, f), (f, -1, f), (f, -1, -f), (-f, -1, -f)),
                    "mat": {"type": "diffuse", "kd": (0.5, 0.5, 0.5)}}],
        "spheres": [{"center": (-1.15, 0.0, 0.0), "radius": 1.0,
                     "mat": {"type": "conductor", "f0": (0.95, 0.64, 0.54), "roughness": 0.2}},
                    {"center": (1.15, 0.0, 0.0), "radius": 1.0, "mat": {"type": "glass", "ior": 1.5}},
                    {"center": (0.0, -0.55, -2.2), "radius": 0.45,
                     "mat": {"type": "diffuse", "kd": (0.2, 0.35, 0.7)}}],
        "emitters": [],
    }


def manylights(n=200, seed=7):
    """A room lit by n small emitting cubes (z up)."""
    rng = np.random.default_rng(seed)
    W, D, H = 4.0, 4.0, 3.0
    white, warm = (0.7, 0.7, 0.7), (0.75, 0.6, 0.45)
    meshes = [
        {"tris": _quad((-W, -D, 0), (W, -D, 0), (W, D, 0), (-W, D, 0)), "mat": {"type": "diffuse", "kd": white}},
        {"tris": _quad((-W, D, 0), (W, D, 0), (W, D, H), (-W, D, H)), "mat": {"type": "diffuse", "kd": warm}},
        {"tris": _quad((-W, -D, 0), (-W, D, 0), (-W, D, H), (-W, -D, H)),
         "mat": {"type": "diffuse", "kd": (0.3, 0.55, 0.3)}},
        {"tris": _quad((W, -D, 0), (W, -D, H), (W, D, H), (W, D, 0)),
         "mat": {"type": "diffuse", "kd": (0.6, 0.3, 0.3)}},
        {"tris": _quad((-W, -D, H), (-W, D, H), (W, D, H), (W, -D, H)), "mat": {"type": "diffuse", "kd": white}},
    ]
    boxes = [((-2.6, 0.6, 0.0), (-1.4, 1.8, 1.4)), ((1.5, -0.8, 0.0), (2.5, 0.2, 0.8))]
    for lo, hi in boxes:
        meshes.append({"tris": _box_shell(lo, hi), "mat": {"type": "diffuse", "kd": (0.65, 0.65, 0.6)}})
    spheres = [{"center": (0.0, 0.5, 0.8), "radius": 0.8, "mat": {"type": "diffuse", "kd": (0.8, 0.8, 0.8)}},
               {"center": (-1.0, -1.6, 0.45), "radius": 0.45, "mat": {"type": "diffuse", "kd": (0.2, 0.3, 0.75)}},
               {"center": (2.3, 2.0, 0.6), "radius": 0.6, "mat": {"type": "diffuse", "kd": (0.8, 0.7, 0.2)}}]
    emitters = []
    while len(emitters) < n:
        c = rng.uniform((-W + 0.2, -D + 0.4, 0.15), (W - 0.2, D - 0.2, H - 0.1))
        h = rng.uniform(0.03, 0.07)
        if any(np.linalg.norm(c - np.array(s["center"])) < s["radius"] + h + 0.05 for s in spheres):
            continue
        if any(all(lo[k] - h - 0.05 < c[k] < hi[k] + h + 0.05 for k in range(3)) for lo, hi in boxes):
            continue
        hue = rng.uniform(0, 1)
        col = np.clip(np.abs(((hue * 6 + np.array([0, 4, 2])) % 6) - 3) - 1, 0, 1)  # saturated hue
        col = 0.35 + 0.65 * col
        power = math.exp(rng.uniform(math.log(2.0), math.log(40.0)))
        emitters.append({"tris": _box_shell(tuple(c - h), tuple(c + h)),
                         "radiance": tuple(float(x) for x in power * col / col.max())})
    return {
        "name": "manylights", "depth": 3, "up_axis": "z",
        "camera": {"pos": (0.0, -7.8, 2.3), "target": (0.0, 0.0, 0.9), "up": (0.0, 0.0, 1.0), "fovy": 42.0},
        "env": None, "meshes": meshes, "spheres": spheres, "emitters": emitters,
    }


def get(name):
    return {"cornell": cornell, "hdri": hdri, "manylights": manylights}[name]()


def digest(scene):
    """A short hash of a scene's description (references are cached under it)."""
    return hashlib.sha1(json.dumps(scene, sort_keys=True, default=str).encode()).hexdigest()[:12]


# ------------------------------------------------------------------ images

def _mi_bitmap():
    import mitsuba as mi
    if mi.variant() is None:
        mi.set_variant("scalar_rgb")
    return mi


def load_exr(path):
    mi = _mi_bitmap()
    return np.array(mi.Bitmap(path), dtype=np.float64)[..., :3]


def save_exr(path, img):
    mi = _mi_bitmap()
    mi.Bitmap(np.ascontiguousarray(img, dtype=np.float32)).write(path)


def env_map(env, workdir):
    """The environment as a float32 lat-long EXR in workdir: the source box-averaged
    `down` times (energy kept) and bilinearly enlarged `up` times, so neighbouring
    texels differ little and nearest and bilinear look-ups agree; times `scale`."""
    path = os.path.join(workdir, "env.exr")
    if os.path.exists(path):
        return path
    src = load_exr(env["source"])
    d = env["down"]
    h, w = src.shape[0] // d, src.shape[1] // d
    small = src[: h * d, : w * d].reshape(h, d, w, d, 3).mean(axis=(1, 3))
    u = env["up"]
    # bilinear enlargement with texel centres aligned (wrap in longitude, clamp in latitude)
    ys = (np.arange(h * u) + 0.5) / u - 0.5
    xs = (np.arange(w * u) + 0.5) / u - 0.5
    y0 = np.floor(ys).astype(int)
    x0 = np.floor(xs).astype(int)
    fy, fx = (ys - y0)[:, None, None], (xs - x0)[None, :, None]
    yA, yB = np.clip(y0, 0, h - 1), np.clip(y0 + 1, 0, h - 1)
    xA, xB = x0 % w, (x0 + 1) % w
    big = ((1 - fy) * ((1 - fx) * small[yA][:, xA] + fx * small[yA][:, xB])
           + fy * ((1 - fx) * small[yB][:, xA] + fx * small[yB][:, xB]))
    tmp = path + ".tmp.exr"
    save_exr(tmp, big * env["scale"])
    os.replace(tmp, path)
    return path


# ------------------------------------------------------------------ luster

def _v(p):
    return " ".join("%.9g" % x for x in p)


def luster_xml(scene, spp, res, image, workdir):
    """Write SCENE.xml (and what it reads) into workdir; returns its path."""
    os.makedirs(workdir, exist_ok=True)
    verts, mats, objs, tex = [], [], [], []
    images, lights = "", ""

    def vid(p):
        verts.append(_v(p))
        return len(verts)

    def material(m):
        k = len(mats) + 1
        if m["type"] == "diffuse":
            mats.append(f'<Material id="{k}" BRDF="1"><DiffuseReflectance>{_v(m["kd"])}</DiffuseReflectance>'
                        f'<SpecularReflectance>0 0 0</SpecularReflectance></Material>')
        elif m["type"] == "glass":
            mats.append(f'<Material id="{k}" type="dielectric"><RefractionIndex>{m["ior"]}</RefractionIndex>'
                        f'<AbsorptionCoefficient>0 0 0</AbsorptionCoefficient></Material>')
        elif m["type"] == "conductor":
            lua = f"conductor{k}.lua"
            with open(os.path.join(workdir, lua), "w") as f:
                f.write(f"function material(s) return conductor{{f0 = vec3({', '.join(map(str, m['f0']))}), "
                        f"roughness = {m['roughness']}}} end\n")
            mats.append(f'<Material id="{k}"><DiffuseReflectance>0 0 0</DiffuseReflectance>'
                        f'<SpecularReflectance>0 0 0</SpecularReflectance></Material>')
            tex.append(f'<TextureMap id="{len(tex) + 1}" type="shader"><Shader>{escape(lua)}</Shader>'
                       f'<DecalMode>material</DecalMode></TextureMap>')
            return k, len(tex)
        else:
            raise ValueError(m["type"])
        return k, None

    def faces(tris):
        return " ".join(str(vid(p)) for t in tris for p in t)

    for i, m in enumerate(scene["meshes"]):
        k, t = material(m["mat"])
        tx = f"<Textures>{t}</Textures>" if t else ""
        objs.append(f'<Mesh id="{i + 1}"><Material>{k}</Material>{tx}<Faces>{faces(m["tris"])}</Faces></Mesh>')
    for i, s in enumerate(scene["spheres"]):
        k, t = material(s["mat"])
        tx = f"<Textures>{t}</Textures>" if t else ""
        objs.append(f'<Sphere id="{i + 1}"><Material>{k}</Material>{tx}<Center>{vid(s["center"])}</Center>'
                    f'<Radius>{s["radius"]}</Radius></Sphere>')
    if scene["emitters"]:
        mats.append(f'<Material id="{len(mats) + 1}"><DiffuseReflectance>0 0 0</DiffuseReflectance></Material>')
        black = len(mats)
        for i, e in enumerate(scene["emitters"]):
            objs.append(f'<LightMesh id="{len(scene["meshes"]) + i + 1}"><Material>{black}</Material>'
                        f'<Radiance>{_v(e["radiance"])}</Radiance><Faces>{faces(e["tris"])}</Faces></LightMesh>')
    if scene["env"]:
        env = os.path.basename(env_map(scene["env"], workdir))
        images = f'<Images><Image id="1">{escape(env)}</Image></Images>'
        lights = '<SphericalDirectionalLight id="1" type="latlong"><ImageId>1</ImageId></SphericalDirectionalLight>'
    c = scene["camera"]
    xml = f"""<Scene>
  <MaxRecursionDepth>{scene['depth']}</MaxRecursionDepth>
  <BackgroundColor>0 0 0</BackgroundColor>
  <ShadowRayEpsilon>1e-5</ShadowRayEpsilon>
  <Cameras><Camera id="1" type="lookAt">
    <Position>{_v(c['pos'])}</Position><GazePoint>{_v(c['target'])}</GazePoint><Up>{_v(c['up'])}</Up>
    <FovY>{c['fovy']}</FovY><NearDistance>0.01</NearDistance>
    <ImageResolution>{res} {res}</ImageResolution><NumSamples>{spp}</NumSamples><ImageName>{escape(image)}</ImageName>
    <Renderer>PathTracing</Renderer><RendererParams>MIS</RendererParams></Camera></Cameras>
  <Textures>{images}{''.join(tex)}</Textures>
  <Lights>{lights}</Lights>
  <BRDFs><ModifiedPhong id="1" normalized="true"><Exponent>1</Exponent></ModifiedPhong></BRDFs>
  <Materials>{''.join(mats)}</Materials>
  <VertexData>{' '.join(verts)}</VertexData>
  <Objects>{''.join(objs)}</Objects>
</Scene>
"""
    path = os.path.join(workdir, f"{scene['name']}.xml")
    with open(path, "w") as f:
        f.write(xml)
    return path


# ------------------------------------------------------------------ shared camera frame

def camera_basis(c):
    pos = np.array(c["pos"], float)
    f = np.array(c["target"], float) - pos
    f /= np.linalg.norm(f)
    r = np.cross(f, np.array(c["up"], float))
    r /= np.linalg.norm(r)
    return pos, f, r, np.cross(r, f)


def _cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _write_obj(path, tris):
    with open(path, "w") as f:
        for t in tris:
            for p in t:
                f.write("v %.9g %.9g %.9g\n" % tuple(p))
        for i in range(len(tris)):
            f.write("f %d %d %d\n" % (3 * i + 1, 3 * i + 2, 3 * i + 3))


# ------------------------------------------------------------------ Mitsuba 3

def render_mitsuba(scene, a):
    import mitsuba as mi
    import drjit as dr
    mi.set_variant(a.variant)
    dr.set_thread_count(a.threads)
    T = mi.ScalarTransform4f
    objdir = os.path.join(a.work, f"mi_{scene['name']}")
    os.makedirs(objdir, exist_ok=True)
    rgb = lambda c: {"type": "rgb", "value": [float(x) for x in c]}  # noqa: E731

    def bsdf(m):
        if m["type"] == "diffuse":
            return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": rgb(m["kd"])}}
        if m["type"] == "glass":
            return {"type": "dielectric", "int_ior": m["ior"], "ext_ior": 1.0}
        if m["type"] == "conductor":
            return {"type": "principled", "base_color": rgb(m["f0"]), "metallic": 1.0,
                    "roughness": m["roughness"], "specular": 0.5}
        raise ValueError(m["type"])

    c = scene["camera"]
    d = {"type": "scene",
         "integrator": {"type": "path", "max_depth": scene["depth"] + 2, "rr_depth": 1000},
         "sensor": {"type": "perspective", "fov": c["fovy"], "fov_axis": "y", "near_clip": 0.01,
                    "far_clip": 1000.0,
                    "to_world": T().look_at(origin=list(c["pos"]), target=list(c["target"]), up=list(c["up"])),
                    "sampler": {"type": "independent", "sample_count": a.spp, "seed": a.seed},
                    "film": {"type": "hdrfilm", "width": a.res, "height": a.res, "rfilter": {"type": "box"},
                             "pixel_format": "rgb", "component_format": "float32"}}}
    for i, m in enumerate(scene["meshes"]):
        p = os.path.join(objdir, f"mesh{i}.obj")
        _write_obj(p, m["tris"])
        d[f"mesh{i}"] = {"type": "obj", "filename": p, "face_normals": True, "bsdf": bsdf(m["mat"])}
    for i, s in enumerate(scene["spheres"]):
        d[f"sphere{i}"] = {"type": "sphere", "center": list(s["center"]), "radius": s["radius"],
                           "bsdf": bsdf(s["mat"])}
    for i, e in enumerate(scene["emitters"]):
        p = os.path.join(objdir, f"light{i}.obj")
        _write_obj(p, e["tris"])
        d[f"light{i}"] = {"type": "obj", "filename": p, "face_normals": True,
                          "bsdf": {"type": "diffuse", "reflectance": rgb((0, 0, 0))},
                          "emitter": {"type": "area", "radiance": rgb(e["radiance"])}}
    if scene["env"]:
        d["env"] = {"type": "envmap", "filename": env_map(scene["env"], a.work),
                    "to_world": T().rotate([0, 1, 0], 180)}
    t1, c1 = time.time(), _cpu()
    sc = mi.load_dict(d)
    acc, spp_done, k = None, 0, 0
    while spp_done < a.spp:  # passes of at most 256 spp, stopped by --time-limit (references only)
        n = min(a.spp - spp_done, 256 if a.time_limit else a.spp)
        img = np.array(mi.render(sc, spp=n, seed=a.seed * 1000 + k), dtype=np.float64)
        acc = img * n if acc is None else acc + img * n
        spp_done += n
        k += 1
        if a.time_limit and time.time() - t1 > a.time_limit:
            break
    out = acc / spp_done
    rw, rc = time.time() - t1, _cpu() - c1
    save_exr(a.out, out)
    return {"render_wall_s": rw, "render_cpu_s": rc, "spp_done": spp_done, "variant": a.variant}


# ------------------------------------------------------------------ Blender Cycles

def render_cycles(scene, a):
    import bpy
    import mathutils
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    cy = sc.cycles
    cy.device = "CPU"
    cy.samples = a.spp
    cy.use_adaptive_sampling = bool(a.adaptive)
    cy.use_denoising = bool(a.denoise)
    if a.denoise:  # Open Image Denoise on the CPU with albedo and normal, Blender's defaults for a final render
        cy.denoiser = "OPENIMAGEDENOISE"
        cy.denoising_input_passes = "RGB_ALBEDO_NORMAL"
        cy.denoising_prefilter = "ACCURATE"
        cy.denoising_use_gpu = False
    depth = scene["depth"]
    for k in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
              "transparent_max_bounces"):
        setattr(cy, k, depth)
    cy.volume_bounces = 0
    cy.min_light_bounces = depth + 1  # Russian roulette never runs
    cy.min_transparent_bounces = depth + 1
    cy.light_sampling_threshold = 0.0
    cy.sample_clamp_direct = cy.sample_clamp_indirect = 0.0
    cy.blur_glossy = 0.0
    cy.caustics_reflective = cy.caustics_refractive = True
    cy.use_light_tree = bool(a.light_tree)
    cy.pixel_filter_type = "BOX"
    cy.filter_width = 1.0
    cy.seed = a.seed
    cy.use_animated_seed = False
    if a.time_limit:
        cy.time_limit = a.time_limit
    sc.render.threads_mode = "FIXED"
    sc.render.threads = a.threads
    sc.render.resolution_x = sc.render.resolution_y = a.res
    sc.render.resolution_percentage = 100
    sc.render.film_transparent = False
    sc.render.use_persistent_data = False
    sc.view_settings.view_transform = "Standard"
    sc.view_settings.look = "None"
    sc.view_settings.exposure = 0.0
    sc.view_settings.gamma = 1.0
    imf = sc.render.image_settings
    imf.file_format, imf.color_depth, imf.color_mode = "OPEN_EXR", "32", "RGB"

    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    wn, wl = world.node_tree.nodes, world.node_tree.links
    bg = wn["Background"]
    bg.inputs["Strength"].default_value = 1.0
    bg.inputs["Color"].default_value = (0, 0, 0, 1)
    if scene["env"]:
        tc = wn.new("ShaderNodeTexCoord")
        sep = wn.new("ShaderNodeSeparateXYZ")
        neg = [wn.new("ShaderNodeMath") for _ in range(2)]
        comb = wn.new("ShaderNodeCombineXYZ")
        wl.new(tc.outputs["Generated"], sep.inputs[0])
        for n in neg:
            n.operation = "MULTIPLY"
            n.inputs[1].default_value = -1.0
        wl.new(sep.outputs["Z"], neg[0].inputs[0])
        wl.new(sep.outputs["X"], neg[1].inputs[0])
        wl.new(neg[0].outputs[0], comb.inputs["X"])  # Blender x = -luster z (the map's centre)
        wl.new(neg[1].outputs[0], comb.inputs["Y"])  # Blender y = -luster x
        wl.new(sep.outputs["Y"], comb.inputs["Z"])   # Blender z (up) = luster y
        tex = wn.new("ShaderNodeTexEnvironment")
        tex.image = bpy.data.images.load(env_map(scene["env"], a.work))
        tex.image.colorspace_settings.name = "Non-Color"
        tex.interpolation = "Closest"
        wl.new(comb.outputs[0], tex.inputs["Vector"])
        wl.new(tex.outputs["Color"], bg.inputs["Color"])
    else:
        bg.inputs["Strength"].default_value = 0.0
    sc.world = world

    def material(m, name):
        mat = bpy.data.materials.new(name)
        mat.use_nodes = True
        nt = mat.node_tree
        for n in list(nt.nodes):
            nt.nodes.remove(n)
        out = nt.nodes.new("ShaderNodeOutputMaterial")
        if m["type"] == "emission":
            b = nt.nodes.new("ShaderNodeEmission")
            s = max(m["radiance"])
            b.inputs["Color"].default_value = (*[x / s for x in m["radiance"]], 1)
            b.inputs["Strength"].default_value = s
            mat.cycles.emission_sampling = "FRONT"
        elif m["type"] == "diffuse":
            b = nt.nodes.new("ShaderNodeBsdfDiffuse")
            b.inputs["Color"].default_value = (*m["kd"], 1)
            b.inputs["Roughness"].default_value = 0.0
        elif m["type"] == "conductor":
            b = nt.nodes.new("ShaderNodeBsdfMetallic")
            b.distribution = "MULTI_GGX"
            b.fresnel_type = "F82"
            b.inputs["Base Color"].default_value = (*m["f0"], 1)
            b.inputs["Edge Tint"].default_value = (1, 1, 1, 1)
            b.inputs["Roughness"].default_value = m["roughness"]
        elif m["type"] == "glass":
            b = nt.nodes.new("ShaderNodeBsdfGlass")
            b.distribution = "GGX"  # roughness 0: a smooth interface
            b.inputs["Roughness"].default_value = 0.0
            b.inputs["Color"].default_value = (1, 1, 1, 1)
            b.inputs["IOR"].default_value = m["ior"]
        else:
            raise ValueError(m["type"])
        nt.links.new(b.outputs[0], out.inputs["Surface"])
        return mat

    def add_mesh(name, tris, mat):
        verts, faces = [], []
        for t in tris:
            faces.append((len(verts), len(verts) + 1, len(verts) + 2))
            verts.extend(tuple(map(float, p)) for p in t)
        me = bpy.data.meshes.new(name)
        me.from_pydata(verts, [], faces)
        me.update()
        for p in me.polygons:
            p.use_smooth = False
        me.materials.append(mat)
        sc.collection.objects.link(bpy.data.objects.new(name, me))

    for i, m in enumerate(scene["meshes"]):
        add_mesh(f"mesh{i}", m["tris"], material(m["mat"], f"mat{i}"))
    for i, e in enumerate(scene["emitters"]):
        add_mesh(f"light{i}", e["tris"], material({"type": "emission", "radiance": e["radiance"]}, f"light{i}"))
    for i, s in enumerate(scene["spheres"]):
        mat = material(s["mat"], f"sphere{i}")
        if s["mat"]["type"] == "glass":
            bpy.ops.mesh.primitive_uv_sphere_add(segments=256, ring_count=128, radius=s["radius"],
                                                 location=tuple(s["center"]))
            ob = bpy.context.active_object
            bpy.ops.object.shade_smooth()
            ob.data.materials.append(mat)
            continue
        me = bpy.data.meshes.new(f"sphere{i}")
        me.from_pydata([tuple(map(float, s["center"]))], [], [])
        ob = bpy.data.objects.new(f"sphere{i}", me)
        sc.collection.objects.link(ob)
        ng = bpy.data.node_groups.new(f"to_sphere{i}", "GeometryNodeTree")
        ng.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
        ng.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
        gi, go = ng.nodes.new("NodeGroupInput"), ng.nodes.new("NodeGroupOutput")
        m2p = ng.nodes.new("GeometryNodeMeshToPoints")
        m2p.inputs["Radius"].default_value = s["radius"]
        sm = ng.nodes.new("GeometryNodeSetMaterial")
        sm.inputs["Material"].default_value = mat
        ng.links.new(gi.outputs[0], m2p.inputs["Mesh"])
        ng.links.new(m2p.outputs["Points"], sm.inputs["Geometry"])
        ng.links.new(sm.outputs["Geometry"], go.inputs[0])
        ob.modifiers.new("sphere", "NODES").node_group = ng

    pos, f, r, u = camera_basis(scene["camera"])
    cd = bpy.data.cameras.new("cam")
    cd.sensor_fit = "VERTICAL"
    cd.angle_y = math.radians(scene["camera"]["fovy"])
    cd.clip_start, cd.clip_end = 0.01, 1000.0
    co = bpy.data.objects.new("cam", cd)
    sc.collection.objects.link(co)
    co.matrix_world = mathutils.Matrix(((r[0], u[0], -f[0], pos[0]), (r[1], u[1], -f[1], pos[1]),
                                        (r[2], u[2], -f[2], pos[2]), (0, 0, 0, 1)))
    sc.camera = co
    t1, c1 = time.time(), _cpu()
    bpy.ops.render.render()
    rw, rc = time.time() - t1, _cpu() - c1
    bpy.data.images["Render Result"].save_render(filepath=a.out)
    return {"render_wall_s": rw, "render_cpu_s": rc, "spp_done": None}


# ------------------------------------------------------------------ command line

def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    w = sub.add_parser("write", help="write the luster XML of every scene")
    w.add_argument("outdir")
    w.add_argument("--res", type=int, default=256)
    w.add_argument("--spp", type=int, default=64)
    r = sub.add_parser("render", help="render one scene with Cycles or Mitsuba")
    r.add_argument("renderer", choices=("cycles", "mitsuba"))
    r.add_argument("scene", choices=SCENES)
    r.add_argument("--spp", type=int, required=True)
    r.add_argument("--out", required=True)
    r.add_argument("--res", type=int, default=256)
    r.add_argument("--seed", type=int, default=0)
    r.add_argument("--threads", type=int, default=2)
    r.add_argument("--light-tree", type=int, default=1)
    r.add_argument("--adaptive", type=int, default=0)
    r.add_argument("--denoise", type=int, default=0, help="Cycles: Open Image Denoise on the final image")
    r.add_argument("--variant", default="llvm_ad_rgb")
    r.add_argument("--time-limit", type=float, default=0.0, help="stop after about this many seconds (0: none)")
    r.add_argument("--work", default=None, help="folder for meshes and the environment (default: the image's)")
    a = ap.parse_args()
    if a.cmd == "write":
        for name in SCENES:
            print(luster_xml(get(name), a.spp, a.res, f"{name}.exr", os.path.abspath(a.outdir)))
        return
    a.out = os.path.abspath(a.out)
    a.work = os.path.abspath(a.work or os.path.dirname(a.out))
    os.makedirs(a.work, exist_ok=True)
    scene = get(a.scene)
    res = (render_cycles if a.renderer == "cycles" else render_mitsuba)(scene, a)
    res["process_wall_s"] = time.time() - T0
    res["process_cpu_s"] = _cpu()
    print("RESULT " + json.dumps(res), flush=True)


if __name__ == "__main__":
    sys.exit(main())

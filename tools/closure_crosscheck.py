#!/usr/bin/env python3
"""Cross-check luster's shader closures (`material(s)`, docs/closures.md) against
Mitsuba 3 and Blender Cycles: a sphere of radius 1 at the origin, seen by a
pinhole camera from +z (256x256, 35 degree vertical field of view), lit only by
an environment, at a grid of material parameters; compares the mean luminance
(Rec. 709 weights) of the pixels wholly inside the sphere's silhouette.
Pass: luster within 2% (--tol) of every reference renderer of the case.

One command on a fresh machine (Python 3.11, which bpy 5.0.1 needs; the script
makes the venv and installs mitsuba, bpy==5.0.1 and numpy into it, then runs
itself there; `apt-get install -y libllvm19` first makes Mitsuba's fast
llvm_ad_rgb variant work, else scalar_rgb is used):

    cargo build --release -p luster
    python3 tools/closure_crosscheck.py [--venv .venv-xcheck] [--work closure-xcheck]

Reference results (Mitsuba, Cycles) are cached in WORK/refs.json, keyed by the
case's full scene description, the environment, spp and seed: a second run
renders only luster (`--renderers luster` makes that explicit). The table goes
to stdout and WORK/results.json; exit code 1 if a case fails, 2 if luster could
not render a case at all. See tools/closure_crosscheck.md for the alignment
notes (which plugin / node and settings per case) and the measured numbers.

Environments: `white` (uniform radiance 1) and `sky` (a smooth lat-long sky
gradient, a ground, and a soft Gaussian sun up and to the right of the camera,
written as WORK/sky.exr in luster's convention: -z at the map's centre, +y its
top row). Mitsuba's envmap is turned 180 degrees about +y to match
(docs/environment-light.md); in Cycles the world's direction d (luster's
coordinates, y up) is looked up at (-d.z, -d.x, d.y), Blender's equirectangular
convention (+x at the centre, z up). The `orient` line checks the alignment on
the Lambertian sphere: the right/left and top/bottom luminance ratios of its
image must agree between the renderers.

Internal: `closure_crosscheck.py _worker cycles|mitsuba JOBS.json` renders a batch.
"""
import argparse
import hashlib
import json
import math
import os
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
RES = 256
FOVY = 35.0
CAM_Z = 4.0
# luster MaxRecursionDepth == Cycles max_bounces; Mitsuba max_depth = DEPTH + 2. Rough glass traps light
# by total internal reflection: at roughness 0.2 (single scattering) a depth of 16 keeps 97.2%, 64 keeps
# 98.6%, 256 keeps 98.7% (Mitsuba, white environment).
DEPTH = 64
CACHE_VERSION = 2  # part of every cached reference's key: raise it when a scene changes
THREADS = 2
LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
PACKAGES = ["mitsuba", "bpy==5.0.1", "numpy"]
TOL = 0.02
SE_TARGET = 0.003

# OpenPBR's defaults that the Principled BSDFs do not share (Cycles' Principled:
# roughness 0.5, coat IOR 1.5, coat roughness 0.03; OpenPBR: specular_roughness
# 0.3, coat_ior 1.6, fuzz_roughness 0.5).
OPBR_ROUGH, OPBR_COAT_IOR, OPBR_FUZZ_ROUGH, IOR = 0.3, 1.6, 0.5, 1.5
CU = (0.95, 0.64, 0.54)
GOLD = (1.0, 0.78, 0.34)


def v3(c):
    return "vec3(%g, %g, %g)" % tuple(c)


def case_table():
    """Every case: the luster closure, the Cycles and Mitsuba materials, which
    renderers are references (the others are reported only), and notes."""
    C = []
    C.append(dict(name="diffuse", lua="diffuse{albedo = %s}" % v3([0.8] * 3),
                  cycles=dict(node="diffuse", color=[0.8] * 3, roughness=0.0),
                  mitsuba=dict(type="diffuse", reflectance=[0.8] * 3), refs=["cycles", "mitsuba"],
                  legacy=dict(color=[0.8] * 3, specular=[0, 0, 0], roughness=1.0)))
    C.append(dict(name="diffuse_r0.5", lua="diffuse{albedo = %s, roughness = 0.5}" % v3([0.8] * 3),
                  cycles=dict(node="principled", base=[0.8] * 3, diffuse_roughness=0.5, spec_level=0.0),
                  mitsuba=dict(type="diffuse", reflectance=[0.8] * 3), refs=["cycles"],
                  note="Cycles Principled Diffuse Roughness (EON) with Specular IOR Level 0; Mitsuba is Lambert"))
    for r in (0.1, 0.3, 0.6, 1.0):
        C.append(dict(name=f"conductor_r{r}",
                      lua="conductor{f0 = %s, edge = vec3(1, 1, 1), roughness = %g}" % (v3(CU), r),
                      cycles=dict(node="metallic", f0=list(CU), roughness=r),
                      mitsuba=dict(type="principled", base_color=list(CU), metallic=1.0, roughness=r),
                      refs=["cycles"], single_scatter=True,
                      legacy=dict(color=list(CU), metalness=1.0, roughness=r)))
    for r in (0.0, 0.2, 0.5):
        C.append(dict(name=f"dielectric_r{r}", lua="dielectric{ior = 1.5, roughness = %g}" % r,
                      cycles=dict(node="glass", ior=IOR, roughness=r),
                      mitsuba=dict(type="dielectric", ior=IOR, roughness=r),
                      refs=["cycles", "mitsuba"] if r == 0 else ["cycles"], single_scatter=r > 0))
    C.append(dict(name="openpbr_default", lua="openpbr{base_color = %s}" % v3([0.8] * 3),
                  cycles=dict(node="principled", base=[0.8] * 3, roughness=OPBR_ROUGH),
                  mitsuba=dict(type="principled", base_color=[0.8] * 3, roughness=OPBR_ROUGH), refs=["cycles"]))
    C.append(dict(name="openpbr_coat",
                  lua="openpbr{base_color = %s, coat_weight = 1, coat_roughness = 0.1}" % v3((0.6, 0.1, 0.1)),
                  cycles=dict(node="principled", base=[0.6, 0.1, 0.1], roughness=OPBR_ROUGH, coat=1.0,
                              coat_roughness=0.1, coat_ior=OPBR_COAT_IOR),
                  mitsuba=dict(type="principled", base_color=[0.6, 0.1, 0.1], roughness=OPBR_ROUGH, clearcoat=1.0,
                               clearcoat_gloss=(0.1 - 0.1 ** 2) / 0.099),
                  refs=["cycles"]))
    C.append(dict(name="openpbr_metal",
                  lua="openpbr{base_color = %s, base_metalness = 1, specular_roughness = 0.4}" % v3(GOLD),
                  cycles=dict(node="principled", base=list(GOLD), metallic=1.0, roughness=0.4),
                  mitsuba=dict(type="principled", base_color=list(GOLD), metallic=1.0, roughness=0.4),
                  refs=["cycles"]))
    C.append(dict(name="openpbr_fuzz", lua="openpbr{base_color = %s, fuzz_weight = 1}" % v3([0.2] * 3),
                  cycles=dict(node="principled", base=[0.2] * 3, roughness=OPBR_ROUGH, sheen=1.0,
                              sheen_roughness=OPBR_FUZZ_ROUGH),
                  mitsuba=dict(type="principled", base_color=[0.2] * 3, roughness=OPBR_ROUGH, sheen=1.0,
                               sheen_tint=0.0),
                  refs=["cycles"]))
    return C


# ---------------------------------------------------------------- environment

def sun_dir():
    el, az = math.radians(35), math.radians(40)  # above the horizon; from +z (the camera) towards +x
    return (math.cos(el) * math.sin(az), math.sin(el), math.cos(el) * math.cos(az))


def make_sky(w=512, h=256, sun_peak=30.0, sun_sigma_deg=5.0):
    """Lat-long in luster's convention: u = (1 + atan2(dx, -dz)/pi)/2, v = acos(dy)/pi."""
    import numpy as np
    u = (np.arange(w) + 0.5) / w
    v = (np.arange(h) + 0.5) / h
    uu, vv = np.meshgrid(u, v)
    th, ph = np.pi * vv, np.pi * (2 * uu - 1)
    dx, dy, dz = np.sin(th) * np.sin(ph), np.cos(th), -np.sin(th) * np.cos(ph)
    t = np.clip(dy, 0, 1)[..., None]
    sky = np.array([0.6, 0.7, 0.9]) * (1 - t) + np.array([0.2, 0.35, 0.8]) * t
    ground = np.array([0.15, 0.13, 0.10]) * np.ones_like(sky)
    s = np.clip((dy + 0.05) / 0.1, 0, 1)[..., None]
    s = s * s * (3 - 2 * s)  # smooth horizon, 6 degrees wide
    img = ground * (1 - s) + sky * s
    sd = sun_dir()
    cosang = np.clip(dx * sd[0] + dy * sd[1] + dz * sd[2], -1, 1)
    ang = np.arccos(cosang)
    img = img + np.array([1.0, 0.95, 0.85]) * sun_peak * np.exp(-0.5 * (ang / math.radians(sun_sigma_deg)) ** 2)[..., None]
    return img.astype(np.float32)


# ---------------------------------------------------------------- geometry

def sphere_mask(res=RES, margin=0.995):
    """Pixels whose four corners' rays all hit the sphere (shrunk by `margin`)."""
    import numpy as np
    t = math.tan(math.radians(FOVY) / 2)
    edges = (np.arange(res + 1) / res) * 2 - 1
    x = edges[None, :] * t
    y = -edges[:, None] * t
    # ray o=(0,0,CAM_Z), d=(x,y,-1)/|.|; squared distance of the line from the origin
    d2 = CAM_Z ** 2 - CAM_Z ** 2 / (x * x + y * y + 1)
    inside = d2 < margin ** 2
    return inside[:-1, :-1] & inside[1:, :-1] & inside[:-1, 1:] & inside[1:, 1:]


# ---------------------------------------------------------------- luster

def luster_xml(case, env, spp, image, lua_name, legacy):
    # black under the closure, so a luster that ignored material(s) would fail, not pass
    kd = "0.8 0.8 0.8" if legacy else "0 0 0"
    c = f"""<Scene>
  <MaxRecursionDepth>{DEPTH}</MaxRecursionDepth>
  <BackgroundColor>0 0 0</BackgroundColor>
  <ShadowRayEpsilon>1e-5</ShadowRayEpsilon>
  <Cameras><Camera id="1" type="lookAt">
    <Position>0 0 {CAM_Z}</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
    <FovY>{FOVY}</FovY><NearDistance>1</NearDistance>
    <ImageResolution>{RES} {RES}</ImageResolution><NumSamples>{spp}</NumSamples><ImageName>{image}</ImageName>
    <Renderer>PathTracing</Renderer><RendererParams>MIS</RendererParams></Camera></Cameras>
  <Textures><Images><Image id="1">{env}.exr</Image></Images>
    <TextureMap id="1" type="shader"><Shader>{lua_name}</Shader><DecalMode>material</DecalMode></TextureMap></Textures>
  <Lights><SphericalDirectionalLight id="1" type="latlong"><ImageId>1</ImageId></SphericalDirectionalLight></Lights>
  <Materials><Material id="1"><DiffuseReflectance>{kd}</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material></Materials>
  <VertexData>0 0 0</VertexData>
  <Objects><Sphere id="1"><Material>1</Material><Textures>1</Textures><Center>1</Center><Radius>1</Radius></Sphere></Objects>
</Scene>
"""
    return c


def luster_lua(case, legacy):
    if not legacy:
        return f"function material(s) return {case['lua']} end\n"
    g = case["legacy"]  # the pre-closure 'Material outputs' (single-scattering GGX, Lambert base)
    out = f"function color(s) return {v3(g['color'])} end\n"
    if "specular" in g:
        out += f"function specular(s) return {v3(g['specular'])} end\n"
    if "metalness" in g:
        out += f"function metalness(s) return {g['metalness']} end\n"
    out += f"function roughness(s) return {g['roughness']} end\n"
    return out


def render_luster(luster, jobs, work, legacy):
    """jobs: list of (case, env, spp, seed, exr). One luster call per seed and spp."""
    d = os.path.join(work, "luster")
    os.makedirs(d, exist_ok=True)
    errors = {}
    groups = {}
    for case, env, spp, seed, exr in jobs:
        lua = f"{case['name']}.lua"
        open(os.path.join(d, lua), "w").write(luster_lua(case, legacy))
        xml = os.path.join(d, os.path.basename(exr)[:-4] + ".xml")
        open(xml, "w").write(luster_xml(case, env, spp, os.path.basename(exr), lua, legacy))
        if os.path.exists(exr):
            os.remove(exr)
        groups.setdefault(seed, []).append((xml, exr, case["name"], env))
    for seed, g in groups.items():
        t0 = time.time()
        p = subprocess.run([luster, "render", "-q", "-t", str(THREADS), "--seed", str(seed), "-o", d] +
                           [x for x, _, _, _ in g], capture_output=True, text=True)
        print(f"  luster seed {seed}: {len(g)} scenes, {time.time() - t0:.1f} s, exit {p.returncode}", flush=True)
        for xml, exr, name, env in g:
            if not os.path.exists(exr):
                lines = [ln for ln in (p.stderr + p.stdout).splitlines() if os.path.basename(xml) in ln or
                         f"{name}.lua" in ln]
                errors[(name, env)] = (lines or (p.stderr + p.stdout).strip().splitlines() or ["no image"])[0][:300]
    return errors


# ---------------------------------------------------------------- Mitsuba (worker)

def mitsuba_bsdf(m, mi):
    rgb = lambda c: {"type": "rgb", "value": list(c)}  # noqa: E731
    t = m["type"]
    if t == "diffuse":
        return {"type": "diffuse", "reflectance": rgb(m["reflectance"])}
    if t == "dielectric":
        if m["roughness"] == 0:
            return {"type": "dielectric", "int_ior": m["ior"], "ext_ior": 1.0}
        return {"type": "roughdielectric", "distribution": "ggx", "alpha": m["roughness"] ** 2,
                "int_ior": m["ior"], "ext_ior": 1.0}
    if t == "principled":
        b = {"type": "principled", "base_color": rgb(m["base_color"]), "roughness": m["roughness"],
             "metallic": m.get("metallic", 0.0), "specular": 0.5}
        for k in ("clearcoat", "clearcoat_gloss", "sheen", "sheen_tint"):
            if k in m:
                b[k] = m[k]
        return b
    raise ValueError(t)


def worker_mitsuba(jobs):
    import numpy as np
    import mitsuba as mi
    import drjit as dr
    variant = os.environ.get("XCHECK_MI_VARIANT", "llvm_ad_rgb")
    try:
        mi.set_variant(variant)
    except Exception:
        variant = "scalar_rgb"
        mi.set_variant(variant)
    dr.set_thread_count(THREADS)
    T = mi.ScalarTransform4f
    for j in jobs:
        t0 = time.time()
        cam = job_camera(j)
        if j["env"] == "white":
            em = {"type": "constant", "radiance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}}
        else:
            em = {"type": "envmap", "filename": j["env_path"], "to_world": T().rotate([0, 1, 0], 180)}
        scene = {
            "type": "scene",
            "integrator": {"type": "path", "max_depth": DEPTH + 2},
            "sensor": {"type": "perspective", "fov": cam["fovy"], "fov_axis": "y",
                       "to_world": T().look_at(origin=cam["pos"], target=cam["target"], up=cam["up"]),
                       "sampler": {"type": "independent", "sample_count": j["spp"], "seed": j["seed"]},
                       "film": {"type": "hdrfilm", "width": cam["res"], "height": cam["res"], "rfilter": {"type": "box"},
                                "pixel_format": "rgb", "component_format": "float32"}},
            "env": em,
        }
        if j.get("mat"):
            scene["sphere"] = {"type": "sphere", "center": [0, 0, 0], "radius": 1.0, "bsdf": mitsuba_bsdf(j["mat"], mi)}
        img = np.array(mi.render(mi.load_dict(scene)), dtype=np.float32)
        mi.Bitmap(img).write(j["out"])
        print(f"  mitsuba[{variant}] {os.path.basename(j['out'])}: {time.time() - t0:.1f} s", flush=True)


# ---------------------------------------------------------------- Cycles (worker)

def worker_cycles(jobs):
    import bpy
    import mathutils
    import numpy as np
    for j in jobs:
        t0 = time.time()
        cam = job_camera(j)
        bpy.ops.wm.read_factory_settings(use_empty=True)
        sc = bpy.context.scene
        sc.render.engine = "CYCLES"
        cy = sc.cycles
        cy.device = "CPU"
        cy.samples = j["spp"]
        cy.use_adaptive_sampling = False
        cy.use_denoising = False
        for k in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
                  "transparent_max_bounces"):
            setattr(cy, k, DEPTH)
        cy.volume_bounces = 0
        cy.min_light_bounces = DEPTH + 1  # no Russian roulette (unbiased either way)
        cy.light_sampling_threshold = 0.0
        cy.sample_clamp_direct = cy.sample_clamp_indirect = 0.0
        cy.blur_glossy = 0.0
        cy.caustics_reflective = cy.caustics_refractive = True
        cy.pixel_filter_type = "BOX"
        cy.seed = j["seed"]
        cy.use_animated_seed = False
        sc.render.threads_mode = "FIXED"
        sc.render.threads = THREADS
        sc.render.resolution_x = sc.render.resolution_y = cam["res"]
        sc.render.resolution_percentage = 100
        sc.render.film_transparent = False
        sc.view_settings.view_transform = "Standard"
        sc.view_settings.look = "None"
        imf = sc.render.image_settings
        imf.file_format, imf.color_depth, imf.color_mode = "OPEN_EXR", "32", "RGB"

        world = bpy.data.worlds.new("env")
        world.use_nodes = True
        wn, wl = world.node_tree.nodes, world.node_tree.links
        bg = wn["Background"]
        bg.inputs["Strength"].default_value = 1.0
        if j["env"] == "white":
            bg.inputs["Color"].default_value = (1, 1, 1, 1)
        else:
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
            wl.new(neg[0].outputs[0], comb.inputs["X"])  # Blender x = -luster z (map centre)
            wl.new(neg[1].outputs[0], comb.inputs["Y"])  # Blender y = -luster x
            wl.new(sep.outputs["Y"], comb.inputs["Z"])   # Blender z (up) = luster y
            tex = wn.new("ShaderNodeTexEnvironment")
            tex.image = bpy.data.images.load(j["env_path"])
            tex.image.colorspace_settings.name = "Non-Color"
            tex.interpolation = "Closest"  # luster looks texels up nearest
            wl.new(comb.outputs[0], tex.inputs["Vector"])
            wl.new(tex.outputs["Color"], bg.inputs["Color"])
        sc.world = world

        if j.get("mat"):
            add_cycles_sphere(bpy, sc, cycles_material(bpy, j["mat"], j.get("cycles_variant", "ms")),
                              mesh=j["mat"]["node"] == "glass")
        cd = bpy.data.cameras.new("cam")
        cd.sensor_fit = "VERTICAL"
        cd.angle_y = math.radians(cam["fovy"])
        cd.clip_start, cd.clip_end = 0.01, 100.0
        co = bpy.data.objects.new("cam", cd)
        sc.collection.objects.link(co)
        # Blender cameras look down local -z with local +y up
        pos = np.array(cam["pos"], float)
        f = np.array(cam["target"], float) - pos
        f /= np.linalg.norm(f)
        r = np.cross(f, cam["up"])
        r /= np.linalg.norm(r)
        u = np.cross(r, f)
        co.matrix_world = mathutils.Matrix(((r[0], u[0], -f[0], pos[0]), (r[1], u[1], -f[1], pos[1]),
                                            (r[2], u[2], -f[2], pos[2]), (0, 0, 0, 1)))
        sc.camera = co
        bpy.ops.render.render()
        bpy.data.images["Render Result"].save_render(filepath=j["out"])
        print(f"  cycles {os.path.basename(j['out'])}: {time.time() - t0:.1f} s", flush=True)


def job_camera(j):
    """The sphere view unless the job names another (the environment probes)."""
    return j.get("cam") or {"pos": [0, 0, CAM_Z], "target": [0, 0, 0], "up": [0, 1, 0], "fovy": FOVY, "res": RES}


def add_cycles_sphere(bpy, sc, mat, mesh=False):
    """An exact sphere: a one-vertex mesh made a point-cloud point of radius 1
    (Cycles renders points as spheres). A ray inside such a point finds no
    exit (Cycles intersects points from outside only: a smooth glass point
    refracts once and lets the ray escape, 7% brighter than a closed sphere
    under the sky map), so transmissive spheres are a smooth-shaded UV sphere
    of 256 x 128 segments instead (within 0.03% of Mitsuba's analytic sphere)."""
    if mesh:
        bpy.ops.mesh.primitive_uv_sphere_add(segments=256, ring_count=128, radius=1.0)
        ob = bpy.context.active_object
        bpy.ops.object.shade_smooth()
        ob.data.materials.append(mat)
        return
    me = bpy.data.meshes.new("s")
    me.from_pydata([(0.0, 0.0, 0.0)], [], [])
    ob = bpy.data.objects.new("s", me)
    sc.collection.objects.link(ob)
    ng = bpy.data.node_groups.new("pts", "GeometryNodeTree")
    ng.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    ng.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    gi, go = ng.nodes.new("NodeGroupInput"), ng.nodes.new("NodeGroupOutput")
    m2p = ng.nodes.new("GeometryNodeMeshToPoints")
    m2p.inputs["Radius"].default_value = 1.0
    sm = ng.nodes.new("GeometryNodeSetMaterial")
    sm.inputs["Material"].default_value = mat
    ng.links.new(gi.outputs[0], m2p.inputs["Mesh"])
    ng.links.new(m2p.outputs["Points"], sm.inputs["Geometry"])
    ng.links.new(sm.outputs["Geometry"], go.inputs[0])
    ob.modifiers.new("s", "NODES").node_group = ng


def cycles_material(bpy, m, variant):
    dist = "MULTI_GGX" if variant == "ms" else "GGX"
    mat = bpy.data.materials.new("m")
    mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    k = m["node"]
    if k == "diffuse":
        b = nt.nodes.new("ShaderNodeBsdfDiffuse")
        b.inputs["Color"].default_value = (*m["color"], 1)
        b.inputs["Roughness"].default_value = m["roughness"]
    elif k == "metallic":
        b = nt.nodes.new("ShaderNodeBsdfMetallic")
        b.distribution = dist
        b.fresnel_type = "F82"
        b.inputs["Base Color"].default_value = (*m["f0"], 1)
        b.inputs["Edge Tint"].default_value = (1, 1, 1, 1)  # F82 tint white: plain Schlick
        b.inputs["Roughness"].default_value = m["roughness"]
    elif k == "glass":
        b = nt.nodes.new("ShaderNodeBsdfGlass")
        b.distribution = dist
        b.inputs["Color"].default_value = (1, 1, 1, 1)
        b.inputs["IOR"].default_value = m["ior"]
        b.inputs["Roughness"].default_value = m["roughness"]
    elif k == "principled":
        b = nt.nodes.new("ShaderNodeBsdfPrincipled")
        b.distribution = dist
        i = b.inputs
        i["Base Color"].default_value = (*m["base"], 1)
        i["Metallic"].default_value = m.get("metallic", 0.0)
        i["Roughness"].default_value = m.get("roughness", 0.5)
        i["IOR"].default_value = IOR
        i["Specular IOR Level"].default_value = m.get("spec_level", 0.5)
        i["Diffuse Roughness"].default_value = m.get("diffuse_roughness", 0.0)
        i["Coat Weight"].default_value = m.get("coat", 0.0)
        i["Coat Roughness"].default_value = m.get("coat_roughness", 0.0)
        i["Coat IOR"].default_value = m.get("coat_ior", OPBR_COAT_IOR)
        i["Sheen Weight"].default_value = m.get("sheen", 0.0)
        i["Sheen Roughness"].default_value = m.get("sheen_roughness", OPBR_FUZZ_ROUGH)
    else:
        raise ValueError(k)
    nt.links.new(b.outputs[0], out.inputs["Surface"])
    return mat


# ---------------------------------------------------------------- statistics

_MI = None


def _bitmap():
    """Mitsuba's Bitmap (scalar_rgb) reads and writes the EXRs, as ../shared/bench/anchors/imgs.py does."""
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


def pair_stats(a, b, mask):
    """Mean sphere luminance of two independent renders and its standard error,
    from the per-pixel differences (each pixel's variance ~ (a-b)^2 / 2)."""
    import numpy as np
    la, lb = lum(a)[mask], lum(b)[mask]
    n = la.size
    mean = 0.5 * (la.mean() + lb.mean())
    se = float(np.sqrt(np.sum((la - lb) ** 2)) / (2 * n))
    return float(mean), se, float(la.mean()), float(lb.mean())


def orient_stats(img, mask):
    """right/left and top/bottom mean luminance ratios over the sphere."""
    y = lum(img)
    h = RES // 2
    m = mask
    left, right = y[:, :h][m[:, :h]].mean(), y[:, h:][m[:, h:]].mean()
    top, bottom = y[:h][m[:h]].mean(), y[h:][m[h:]].mean()
    return float(right / left) if left > 0 else 0.0, float(top / bottom) if bottom > 0 else 0.0


# ---------------------------------------------------------------- driver

def job_key(renderer, case, env, spp, seed):
    spec = {k: case.get(k) for k in ("cycles", "mitsuba")}
    spec["r"] = renderer
    spec["geo"] = (RES, FOVY, CAM_Z, DEPTH, CACHE_VERSION)
    h = hashlib.sha1(json.dumps(spec, sort_keys=True).encode()).hexdigest()[:10]
    return f"{renderer}|{case['name']}|{env}|{spp}|{seed}|{h}"


def run_worker(py, kind, jobs, work):
    if not jobs:
        return
    path = os.path.join(work, f"jobs_{kind}.json")
    json.dump(jobs, open(path, "w"))
    env = dict(os.environ)
    if kind == "mitsuba" and os.path.exists(LLVM):
        env.setdefault("DRJIT_LIBLLVM_PATH", LLVM)
    elif kind == "mitsuba":
        env.setdefault("XCHECK_MI_VARIANT", "scalar_rgb")
    p = subprocess.run([py, os.path.abspath(__file__), "_worker", kind, path], env=env)
    if p.returncode != 0:
        sys.exit(f"{kind} worker failed (exit {p.returncode})")


def render_refs(args, cases, envs, work, cache, mask):
    """Mitsuba and Cycles (both distribution variants where the case is
    single-scattering-sensitive): render what the cache lacks, raising spp until
    the standard error is below SE_TARGET of the mean."""
    renderers = [("mitsuba", None), ("cycles", "ms"), ("cycles_ss", "ss")]
    todo = [(r, v, c, e) for r, v in renderers for c in cases for e in envs
            if not (r == "cycles_ss" and not c.get("single_scatter"))]
    spp = {t[:1] + (t[2]["name"], t[3]): args.spp for t in todo}
    for attempt in range(4):
        batches = {"mitsuba": [], "cycles": []}
        pending = []
        for r, v, c, e in todo:
            s = spp[(r, c["name"], e)]
            key = job_key(r, c, e, s, 0)
            while key in cache and cache[key]["se"] > SE_TARGET * cache[key]["mean"] and s < args.max_spp:
                s = spp[(r, c["name"], e)] = min(args.max_spp, s * 4)  # too noisy before: go straight on
                key = job_key(r, c, e, s, 0)
            if key in cache or r.split("_")[0] not in args.renderers:  # a renderer not asked for: cache only
                continue
            pending.append((r, v, c, e, s, key))
            for seed in (1, 2):
                out = os.path.join(work, "img", f"{r}_{c['name']}_{e}_{s}_s{seed}.exr")
                j = {"env": e, "env_path": os.path.join(work, "sky.exr"), "spp": s, "seed": seed, "out": out}
                if r == "mitsuba":
                    j["mat"] = c["mitsuba"]
                    batches["mitsuba"].append(j)
                else:
                    j["mat"], j["cycles_variant"] = c["cycles"], v
                    batches["cycles"].append(j)
        if not pending:
            break
        for kind, jobs in batches.items():
            if jobs:
                print(f"{kind}: {len(jobs)} renders", flush=True)
                t0 = time.time()
                run_worker(args.python, kind, jobs, work)
                print(f"{kind}: {time.time() - t0:.0f} s", flush=True)
        for r, v, c, e, s, key in pending:
            imgs = [load_exr(os.path.join(work, "img", f"{r}_{c['name']}_{e}_{s}_s{seed}.exr")) for seed in (1, 2)]
            mean, se, m1, m2 = pair_stats(imgs[0], imgs[1], mask)
            rec = {"mean": mean, "se": se, "spp": s, "seeds": [m1, m2], "orient": orient_stats(imgs[0] + imgs[1], mask)}
            cache[key] = rec
            if se > SE_TARGET * mean and s < args.max_spp:
                spp[(r, c["name"], e)] = min(args.max_spp, s * 4)
                print(f"  {r} {c['name']} {e}: se {100 * se / mean:.2f}% at {s} spp, again at {spp[(r, c['name'], e)]}")
        json.dump(cache, open(os.path.join(work, "refs.json"), "w"), indent=1, sort_keys=True)
    out = {}
    for r, v, c, e in todo:
        key = job_key(r, c, e, spp[(r, c["name"], e)], 0)
        if key in cache:
            out[(r, c["name"], e)] = cache[key]
    return out


def render_luster_all(args, cases, envs, work, mask):
    res, errors = {}, {}
    spp = {(c["name"], e): args.luster_spp or args.spp for c in cases for e in envs}
    todo = [(c, e) for c in cases for e in envs if not args.legacy or "legacy" in c]
    for attempt in range(4):
        jobs = []
        for c, e in todo:
            if (c["name"], e) in res or (c["name"], e) in errors:
                continue
            s = spp[(c["name"], e)]
            for seed in (1, 2):
                jobs.append((c, e, s, seed, os.path.join(work, "luster", f"luster_{c['name']}_{e}_{s}_s{seed}.exr")))
        if not jobs:
            break
        err = render_luster(args.luster, jobs, work, args.legacy)
        for c, e in todo:
            k = (c["name"], e)
            if k in res or k in errors:
                continue
            if k in err:
                errors[k] = err[k]
                continue
            s = spp[k]
            imgs = [load_exr(os.path.join(work, "luster", f"luster_{c['name']}_{e}_{s}_s{seed}.exr")) for seed in (1, 2)]
            mean, se, m1, m2 = pair_stats(imgs[0], imgs[1], mask)
            if mean > 0 and se > SE_TARGET * mean and s < args.max_spp:
                spp[k] = min(args.max_spp, s * 4)
                print(f"  luster {c['name']} {e}: se {100 * se / mean:.2f}% at {s} spp, again at {spp[k]}")
                continue
            res[k] = {"mean": mean, "se": se, "spp": s, "seeds": [m1, m2],
                      "orient": orient_stats(imgs[0] + imgs[1], mask)}
    return res, errors


TAG = {"cycles": "c", "mitsuba": "m", "cycles_ss": "g"}  # the deviation column: against Cycles, Mitsuba, Cycles GGX


def table(cases, envs, refs, lus, lerr, tol, legacy):
    rows, lines = [], []
    hdr = f"{'case':<17} {'env':<5} {'Mitsuba':>8} {'Cycles':>8} {'Cyc.GGX':>8} {'luster':>8} {'luster/ref-1':>16}  result"
    lines.append(hdr)
    worst = 0
    for c in cases:
        for e in envs:
            g = lambda r: refs.get((r, c["name"], e))  # noqa: E731
            mi, cy, ss, lu = g("mitsuba"), g("cycles"), g("cycles_ss"), lus.get((c["name"], e))
            refnames = ["cycles_ss"] if legacy and "legacy" in c and c.get("single_scatter") else c["refs"]
            rv = [(r, g(r)) for r in refnames if g(r)]
            row = {"case": c["name"], "env": e, "refs": refnames,
                   "lua": luster_lua(c, True) if legacy and "legacy" in c else luster_lua(c, False)}
            for n, x in (("mitsuba", mi), ("cycles", cy), ("cycles_ggx", ss), ("luster", lu)):
                row[n] = x
            f = lambda x: f"{x['mean']:8.4f}" if x else f"{'-':>8}"  # noqa: E731
            if lu and rv:
                devs = {r: lu["mean"] / x["mean"] - 1 for r, x in rv}
                # tolerance plus two combined standard errors of noise
                ok = lu["mean"] > 0 and all(
                    abs(d) <= tol + 2 * math.hypot(lu["se"] / lu["mean"], x["se"] / x["mean"])
                    for (r, x), d in zip(rv, devs.values()))
                row["dev"], row["pass"] = devs, ok
                dtxt = " ".join(f"{100 * d:+.2f}%{TAG[r]}" for r, d in devs.items())
                res = "pass" if ok else "FAIL"
                worst = max(worst, 0 if ok else 1)
            elif (c["name"], e) in lerr:
                row["error"], dtxt, res = lerr[(c["name"], e)], "", "luster error"
                worst = 2
            else:
                dtxt, res = "", "no luster" if not lu else "no ref"
            lines.append(f"{c['name']:<17} {e:<5} {f(mi)} {f(cy)} {f(ss)} {f(lu)} {dtxt:>16}  {res}")
            rows.append(row)
    return lines, rows, worst


def orient_lines(refs, lus, envs):
    if "sky" not in envs:
        return [], True
    lines, vals = [], {}
    for r in ("mitsuba", "cycles"):
        x = refs.get((r, "diffuse", "sky"))
        if x:
            vals[r] = x["orient"]
    if ("diffuse", "sky") in lus:
        vals["luster"] = lus[("diffuse", "sky")]["orient"]
    ok = True
    base = next(iter(vals.values()), None)
    for r, (rl, tb) in vals.items():
        lines.append(f"orient {r:<8} right/left {rl:.3f}  top/bottom {tb:.3f}")
        ok &= abs(rl / base[0] - 1) < 0.05 and abs(tb / base[1] - 1) < 0.05
    lines.append("orient " + ("consistent" if ok else "MISMATCH"))
    return lines, ok


def contact_sheet(work, names):
    import numpy as np
    rows = []
    for row in names:
        ims = []
        for p in row:
            im = load_exr(p) if p and os.path.exists(p) else np.zeros((RES, RES, 3))
            x = np.clip(im, 0, 1)
            x = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
            ims.append((x * 255 + 0.5).astype(np.uint8))
        rows.append(np.concatenate(ims, axis=1))
    w = max(r.shape[1] for r in rows)
    rows = [np.pad(r, ((0, 0), (0, w - r.shape[1]), (0, 0))) for r in rows]
    _bitmap()(np.concatenate(rows, axis=0)).write(os.path.join(work, "sheet.png"))


def ensure_llvm(allow_apt):
    """Mitsuba's llvm_ad_rgb needs LLVM 19 (Debian's libllvm19: 14 is too old, 15 aborts with
    'Cannot select: fminimum'); without it the Mitsuba side runs scalar_rgb, slower but the same."""
    if os.path.exists(LLVM) or not allow_apt or not shutil.which("apt-get") or os.geteuid() != 0:
        return os.path.exists(LLVM)
    print("installing libllvm19 (apt-get) for Mitsuba's llvm_ad_rgb variant", flush=True)
    q = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    subprocess.run(["apt-get", "update", "-qq"], **q)
    subprocess.run(["apt-get", "install", "-y", "-qq", "libllvm19"], **q)
    return os.path.exists(LLVM)


def ensure_venv(venv):
    py = os.path.join(venv, "bin", "python")
    if os.path.abspath(sys.prefix) == os.path.abspath(venv):
        return py
    if not os.path.exists(py):
        base = shutil.which("python3.11") or sys.executable
        print(f"creating {venv} with {base} (bpy 5.0.1 needs CPython 3.11)", flush=True)
        subprocess.run([base, "-m", "venv", venv], check=True)
    ok = subprocess.run([py, "-c", "import bpy, mitsuba, numpy; assert bpy.app.version >= (5, 0, 1)"],
                        capture_output=True).returncode == 0
    if not ok:
        print(f"installing {' '.join(PACKAGES)} into {venv} (about 1 GB)", flush=True)
        subprocess.run([py, "-m", "pip", "install", "-q", "--upgrade", "pip"], check=True)
        subprocess.run([py, "-m", "pip", "install", "-q"] + PACKAGES, check=True)
    return py


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "_worker":
        jobs = json.load(open(sys.argv[3]))
        os.makedirs(os.path.dirname(jobs[0]["out"]), exist_ok=True)
        {"cycles": worker_cycles, "mitsuba": worker_mitsuba}[sys.argv[2]](jobs)
        return 0
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--venv", default=".venv-xcheck", help="virtual environment to make and use (default ./.venv-xcheck)")
    ap.add_argument("--work", default="closure-xcheck", help="scratch folder: scenes, images, refs.json, results.json")
    ap.add_argument("--luster", default=os.path.join(os.path.dirname(HERE), "target", "release", "luster"))
    ap.add_argument("--renderers", default="mitsuba,cycles,luster")
    ap.add_argument("--cases", default="", help="comma-separated case names or prefixes (default: all)")
    ap.add_argument("--envs", default="white,sky")
    ap.add_argument("--spp", type=int, default=32, help="first try; raised 4x until the standard error is < 0.3%%")
    ap.add_argument("--luster-spp", type=int, default=0, help="first try for luster (default --spp)")
    ap.add_argument("--max-spp", type=int, default=4096)
    ap.add_argument("--tol", type=float, default=TOL)
    ap.add_argument("--legacy", action="store_true",
                    help="luster with the pre-closure Material outputs (color/metalness/roughness) on the cases that "
                         "have them, against Cycles' single-scattering GGX: checks this tool's luster plumbing")
    ap.add_argument("--lua", help="JSON {case: closure expression} replacing the built-in luster closures "
                    "(the expression `material(s)` returns), should the closure API's spelling differ")
    ap.add_argument("--no-apt", action="store_true", help="do not apt-get install libllvm19 (Mitsuba then runs scalar_rgb)")
    ap.add_argument("--list", action="store_true", help="print the cases and their luster shaders")
    args = ap.parse_args()
    cases = case_table()
    if args.lua:
        over = json.load(open(args.lua))
        for c in cases:
            c["lua"] = over.get(c["name"], c["lua"])
    if args.cases:
        pre = args.cases.split(",")
        cases = [c for c in cases if any(c["name"].startswith(p) for p in pre)]
    if args.list:
        for c in cases:
            print(f"{c['name']:<17} refs {'+'.join(c['refs']):<15} function material(s) return {c['lua']} end")
        return 0
    args.python = ensure_venv(args.venv)
    if os.path.abspath(sys.prefix) != os.path.abspath(args.venv) and "mitsuba" in args.renderers:
        ensure_llvm(not args.no_apt)
    if os.path.abspath(sys.prefix) != os.path.abspath(args.venv):
        os.execv(args.python, [args.python, os.path.abspath(__file__)] + sys.argv[1:])
    args.renderers = args.renderers.split(",")
    envs = args.envs.split(",")
    work = os.path.abspath(args.work)
    os.makedirs(os.path.join(work, "img"), exist_ok=True)
    os.makedirs(os.path.join(work, "luster"), exist_ok=True)
    import numpy as np
    t_start = time.time()
    save_exr(os.path.join(work, "sky.exr"), make_sky())
    shutil.copy(os.path.join(work, "sky.exr"), os.path.join(work, "luster", "sky.exr"))
    save_exr(os.path.join(work, "luster", "white.exr"), np.ones((32, 64, 3), np.float32))
    mask = sphere_mask()
    cpath = os.path.join(work, "refs.json")
    cache = json.load(open(cpath)) if os.path.exists(cpath) else {}
    refs = render_refs(args, cases, envs, work, cache, mask)
    lus, lerr = {}, {}
    if "luster" in args.renderers:
        if not os.path.exists(args.luster):
            lerr = {(c["name"], e): f"no luster binary at {args.luster}" for c in cases for e in envs}
        else:
            lus, lerr = render_luster_all(args, cases, envs, work, mask)
    lines, rows, worst = table(cases, envs, refs, lus, lerr, args.tol, args.legacy)
    ol, ook = orient_lines(refs, lus, envs)
    for ln in lines + ol:
        print(ln)
    for (n, e), m in lerr.items():
        print(f"luster error {n} {e}: {m}")
    print(f"sphere pixels {int(mask.sum())}; mean luminance of the pixels inside the sphere; luster/ref-1 against "
          f"c Cycles, m Mitsuba, g Cycles GGX; pass = within {100 * args.tol:.0f}% (+2 standard errors) of every "
          f"ref; {time.time() - t_start:.0f} s")
    json.dump({"tol": args.tol, "se_target": SE_TARGET, "res": RES, "fovy": FOVY, "depth": DEPTH,
               "sphere_pixels": int(mask.sum()), "legacy": args.legacy, "orient": ol, "rows": rows,
               "refs": {"|".join(k): v for k, v in refs.items()}}, open(os.path.join(work, "results.json"), "w"),
              indent=1)
    sheet = []
    for c in cases:
        for e in envs:
            r = []
            for who in ("mitsuba", "cycles", "luster"):
                x = refs.get((who, c["name"], e)) if who != "luster" else lus.get((c["name"], e))
                if not x:
                    r.append(None)
                elif who == "luster":
                    r.append(os.path.join(work, "luster", f"luster_{c['name']}_{e}_{x['spp']}_s1.exr"))
                else:
                    r.append(os.path.join(work, "img", f"{who}_{c['name']}_{e}_{x['spp']}_s1.exr"))
            sheet.append(r)
    contact_sheet(work, sheet)
    print(f"results: {os.path.join(work, 'results.json')}, images: {os.path.join(work, 'sheet.png')}")
    return worst if ook else max(worst, 1)


if __name__ == "__main__":
    sys.exit(main())

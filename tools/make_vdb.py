#!/usr/bin/env python3
"""Writes the OpenVDB files luster ships: the example smoke plume and the small
grids the VDB tests read.

    examples/scenes/volumes/plume.vdb      `density` and `temperature` float grids
                                           on 48 x 64 x 48 voxels of 1/32 unit
    crates/render/tests-data/grids.vdb     one small grid per case the loader
                                           must read or refuse (listed below)

It needs a Python with the OpenVDB module (`import openvdb`) and numpy. The
module ships inside Blender's `bpy` wheel (`pip install bpy`, Python 3.11); with it in a
virtual environment `.venv`:

    B=.venv/lib/python3.11/site-packages/bpy
    LD_LIBRARY_PATH=$B/lib PYTHONPATH=$B/5.0/python/lib/python3.11/site-packages \\
        .venv/bin/python tools/make_vdb.py

The voxel values are the same on every run (fixed seed); OpenVDB writes a new
random UUID into each file's header, so the bytes are not.
"""

import os
import sys

import numpy as np

try:
    import openvdb as vdb
except ImportError:
    sys.exit("make_vdb.py needs the OpenVDB Python module: see the header of this script")

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
PLUME = os.path.join(ROOT, "examples", "scenes", "volumes", "plume.vdb")
GRIDS = os.path.join(ROOT, "crates", "render", "tests-data", "grids.vdb")


def float_grid(name, values, ijk=(0, 0, 0), transform=None, cls=vdb.FloatGrid):
    """A grid named `name` whose voxel (i, j, k) + ijk holds values[i, j, k];
    zeros (the background) stay inactive."""
    g = cls()
    g.name = name
    g.copyFromArray(values, ijk)
    if transform is not None:
        g.transform = transform
    return g


def scale_translate(scale, translate):
    """A linear transform: index * scale + translate, per axis."""
    sx, sy, sz = scale
    tx, ty, tz = translate
    return vdb.createLinearTransform([[sx, 0, 0, 0], [0, sy, 0, 0], [0, 0, sz, 0], [tx, ty, tz, 1]])


def smooth_noise(rng, shape, cells):
    """Value noise in [0, 1]: a random lattice of `cells` per axis, upsampled
    trilinearly to `shape`."""
    lattice = rng.random((cells + 1,) * 3)
    axes = [np.linspace(0, cells, n) for n in shape]
    i = [np.minimum(a.astype(int), cells - 1) for a in axes]
    f = [a - b for a, b in zip(axes, i)]
    # Smoothstep weights hide the lattice's creases.
    f = [t * t * (3 - 2 * t) for t in f]
    out = np.zeros(shape)
    for dx in (0, 1):
        wx = f[0] if dx else 1 - f[0]
        for dy in (0, 1):
            wy = f[1] if dy else 1 - f[1]
            for dz in (0, 1):
                wz = f[2] if dz else 1 - f[2]
                corner = lattice[np.ix_(i[0] + dx, i[1] + dy, i[2] + dz)]
                out += corner * wx[:, None, None] * wy[None, :, None] * wz[None, None, :]
    return out


def plume():
    """A rising smoke plume: a column that sways and widens with height, broken
    up by fractal noise, hot at its base."""
    nx, ny, nz = 48, 64, 48
    voxel = 1.0 / 32.0
    rng = np.random.default_rng(795)
    # World positions of the voxels: the base at y = 0, centred on x = z = 0.
    x = (np.arange(nx) - (nx - 1) / 2) * voxel
    y = np.arange(ny) * voxel
    z = (np.arange(nz) - (nz - 1) / 2) * voxel
    X, Y, Z = np.meshgrid(x, y, z, indexing="ij")
    h = Y / (ny * voxel)
    cx = 0.12 * np.sin(3.5 * h + 0.4)
    cz = 0.08 * np.sin(2.7 * h + 1.9)
    r = np.hypot(X - cx, Z - cz)
    radius = 0.15 + 0.36 * h**0.8
    # Fractal noise, the fine octaves weighted up so the edge breaks into wisps.
    octaves = [(4, 1.0), (8, 0.7), (16, 0.5), (24, 0.3)]
    noise = sum(w * smooth_noise(rng, (nx, ny, nz), c) for c, w in octaves) / sum(w for _, w in octaves)
    puffs = smooth_noise(rng, (nx, ny, nz), 6)
    # A radial fall-off whose edge the noise pushes in and out; thinner at the
    # foot and fading out at the top.
    edge = 1 - r / radius + 1.1 * (noise - 0.5)
    taper = np.clip(h / 0.05, 0, 1) * np.clip((1 - h) / 0.35, 0, 1)
    # Fading out over the outermost voxels keeps the wisps off the array's sides.
    ix, iz = np.arange(nx), np.arange(nz)
    side = np.minimum(ix, nx - 1 - ix)[:, None, None] * np.minimum(iz, nz - 1 - iz)[None, None, :]
    window = np.clip(side / 9.0, 0, 1)
    density = np.clip(2.5 * edge, 0, 1) * taper * window * (0.3 + 0.9 * puffs)
    density = np.where(density > 0.02, density, 0).astype(np.float32)
    # Temperature: the core of the lowest third, cooling upwards.
    core = np.clip(1 - r / (0.9 * radius), 0, 1) ** 0.5
    temperature = 1.5 * core * np.clip(1 - h / 0.32, 0, 1) ** 1.2 * (0.5 + noise)
    temperature = np.where((temperature > 0.02) & (density > 0), temperature, 0).astype(np.float32)
    # Index (0, 0, 0) is the voxel at world (x[0], 0, z[0]).
    transform = vdb.createLinearTransform(voxel)
    transform.postTranslate((float(x[0]), 0.0, float(z[0])))
    grids = []
    for name, values in (("density", density), ("temperature", temperature)):
        g = float_grid(name, values, transform=transform)
        g.gridClass = vdb.GridClass.FOG_VOLUME
        grids.append(g)
    os.makedirs(os.path.dirname(PLUME), exist_ok=True)
    vdb.write(PLUME, grids)


def test_grids():
    """The grids the loader's tests read, each named for its case."""
    grids = []
    # A few voxels at known places under a per-axis scale and a translation:
    # voxel (i, j, k) is at (1 + 0.5 i, 2 + 0.25 j, 3 + k).
    st = scale_translate((0.5, 0.25, 1.0), (1.0, 2.0, 3.0))
    few = np.zeros((4, 5, 6), np.float32)
    few[0, 0, 0] = 1.0  # voxel (2, 3, 4)
    few[1, 0, 0] = 0.5  # voxel (3, 3, 4)
    few[3, 4, 5] = 0.25  # voxel (5, 7, 9)
    few[2, 2, 2] = -3.0  # voxel (4, 5, 6): negative, read as 0
    grids.append(float_grid("few", few, (2, 3, 4), st))
    # The same lattice's emission: one voxel inside `few`'s box, one beyond it.
    glow = np.zeros((6, 6, 6), np.float32)
    glow[1, 1, 1] = 2.0  # voxel (3, 4, 5)
    glow[5, 5, 5] = 4.0  # voxel (7, 8, 9)
    grids.append(float_grid("glow", glow, (2, 3, 4), st))
    # A constant 8^3 block (voxels 8..15): pruned to a tile, not a leaf.
    block = float_grid("tile", np.full((8, 8, 8), 0.75, np.float32), (8, 8, 8), vdb.createLinearTransform(0.1))
    block.prune()
    grids.append(block)
    # Half floats, as many exporters write them (refused: see volume/vdb.rs).
    half = float_grid("half", few, (2, 3, 4), st)
    half.saveFloatAsHalf = True
    grids.append(half)
    # What must be refused.
    grids.append(float_grid("empty", np.zeros((2, 2, 2), np.float32)))
    far = np.zeros((1, 1, 1), np.float32)
    far[0, 0, 0] = 1.0
    huge = float_grid("huge", far)
    huge.copyFromArray(far, (2000, 2000, 2000))
    grids.append(huge)
    vec = np.zeros((2, 2, 2, 3), np.float32)
    vec[1, 1, 1] = (1, 2, 3)
    grids.append(float_grid("velocity", vec, cls=vdb.Vec3SGrid))
    grids.append(float_grid("double", few.astype(np.float64), cls=vdb.DoubleGrid))
    turned = vdb.createLinearTransform(0.5)
    turned.postRotate(0.3, vdb.Axis.Y)
    grids.append(float_grid("rotated", few, (2, 3, 4), turned))
    grids.append(float_grid("shifted", glow, (2, 3, 4), scale_translate((0.5, 0.25, 1.0), (1.5, 2.0, 3.0))))
    nan = float_grid("nan", few, (2, 3, 4), st)
    nan.getAccessor().setValueOn((3, 4, 5), float("nan"))
    grids.append(nan)
    os.makedirs(os.path.dirname(GRIDS), exist_ok=True)
    vdb.write(GRIDS, grids)


if __name__ == "__main__":
    plume()
    test_grids()
    for path in (PLUME, GRIDS):
        print(f"{os.path.relpath(path, ROOT)}: {os.path.getsize(path)} bytes")

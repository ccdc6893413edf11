#!/usr/bin/env python3
"""How fine the Perlin pattern is on each visible cube face of hw4
`cube_perlin` / `cube_perlin_bump`, in an expected image and in renders.

The course's noise table is its own, so its images cannot be matched pixel
for pixel; their frequency can. Per face (the +x, +y and +z faces of the left
and right cube, inset 15% from the edges, found by casting the scene's camera
rays onto the face planes) this prints f = RMS(pixel gradient) / std(pixel),
which for a stationary pattern is proportional to its spatial frequency, and
the mean and standard deviation of the grey level; then, per image after the
first, the geometric mean over the faces of f(first) / f(image).

    python3 tools/perlin_cube_frequency.py EXPECTED.png RENDER.png [MORE.png ...]

Needs numpy and mitsuba (only to read PNGs): `pip install mitsuba numpy`.
"""
import sys

import numpy as np

W = H = 800
EYE = np.array([3.0, 3.0, 3.0])
_gaze = -EYE / np.linalg.norm(EYE)
_up = np.array([0.0, 1.0, 0.0])
BACK = -_gaze
RIGHT = np.cross(_up, BACK)
RIGHT /= np.linalg.norm(RIGHT)
UP = np.cross(BACK, RIGHT)
HALF = np.tan(np.radians(25 / 2))  # FovY 25, square image


def load(path):
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    bmp = mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True)
    return np.array(bmp).astype(float).mean(2)


def face_mask(cx, axis):
    """Pixels whose camera ray meets face +axis of the cube centred at (cx, 0, 0)
    (half size 0.4: a unit cube scaled by 0.8) within its inner 85%."""
    yy, xx = np.mgrid[0:H, 0:W] + 0.5
    dirs = ((xx / W) * 2 - 1)[..., None] * HALF * RIGHT + (1 - (yy / H) * 2)[..., None] * HALF * UP - BACK
    centre = np.array([cx, 0.0, 0.0])
    n = np.zeros(3)
    n[axis] = 1
    s = ((centre + 0.4 * n) @ n - EYE @ n) / (dirs @ n)
    p = EYE + s[..., None] * dirs
    mask = np.ones((H, W), bool)
    for a in range(3):
        if a != axis:
            mask &= np.abs(p[..., a] - centre[a]) < 0.4 * 0.85
    return mask


def stats(img, mask):
    gx = np.zeros_like(img)
    gy = np.zeros_like(img)
    gx[:, :-1] = img[:, 1:] - img[:, :-1]
    gy[:-1] = img[1:] - img[:-1]
    inner = mask & np.roll(mask, -1, 1) & np.roll(mask, -1, 0)
    inner[:, -1] = False
    inner[-1] = False
    f = np.sqrt((gx[inner] ** 2 + gy[inner] ** 2).mean() / img[mask].var())
    return f, img[mask].mean(), img[mask].std()


def main(paths):
    imgs = [load(p) for p in paths]
    ratios = [[] for _ in imgs]
    for cube, cx in (("left", -0.8), ("right", 0.8)):
        for axis, name in ((0, "+x"), (1, "+y"), (2, "+z")):
            mask = face_mask(cx, axis)
            row = [stats(img, mask) for img in imgs]
            for i, r in enumerate(row):
                ratios[i].append(row[0][0] / r[0])
            cells = "  ".join("f=%.3f mean=%5.1f sd=%4.1f" % r for r in row)
            print(f"{cube:5} {name}  {cells}")
    for path, r in zip(paths[1:], ratios[1:]):
        print(f"{path}: expected is {np.exp(np.mean(np.log(r))):.3f}x as fine (geometric mean of 6 faces)")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1:])

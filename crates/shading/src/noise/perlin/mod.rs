//! Ken Perlin's improved noise ("Improving Noise", SIGGRAPH 2002).
//!
//! The lattice hash is Perlin's own 256-entry permutation, the interpolant his
//! quintic fade `6t⁵ − 15t⁴ + 10t³` (C² continuous, so shading normals built
//! from the gradient do not show lattice creases), and the 3D gradients the
//! twelve cube-edge directions plus four repeats, in the order of his reference
//! code's `grad` function. With those three fixed, [`noise3`] reproduces the
//! reference implementation (`noise(3.14, 42, 7) = 0.13691995878400012`).
//!
//! | function | gradients | measured range |
//! |---|---|---|
//! | [`noise1`] | ±1/4 … ±2 (16 slopes) | [-1, 1], reached at cell centres |
//! | [`noise2`] | 4 axes + 4 diagonals | [-1, 1], reached at cell centres |
//! | [`noise3`], [`pnoise3`] | 12 cube edges + 4 repeats | [-1.0364, 1.0364], off the cell centres |
//! | [`noise4`] | 32 hypercube edges, scaled by 2/3 | ±1 at most at a cell centre; ±0.81 reached in 2·10⁶ cells |
//!
//! The 3D maximum was found by hill-climbing from every cell centre of a
//! 128³ block: the centres themselves reach exactly ±1 when all eight
//! gradients point at them, and the true peak lies slightly off-centre.
//!
//! Every function is 0 at integer lattice points. Coordinates wrap every 256
//! units. Non-finite input never panics: `floor` saturates to an `i32` and the
//! index is masked to 0..=255, and the result is NaN or finite.

/// Ken Perlin's permutation of 0..=255, from the 2002 reference code.
const PERM_256: [u8; 256] = [
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69, 142, 8, 99,
    37, 240, 21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219, 203, 117, 35, 11, 32,
    57, 177, 33, 88, 237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175, 74, 165, 71, 134, 139, 48, 27,
    166, 77, 146, 158, 231, 83, 111, 229, 122, 60, 211, 133, 230, 220, 105, 92, 41, 55, 46, 245, 40, 244,
    102, 143, 54, 65, 25, 63, 161, 1, 216, 80, 73, 209, 76, 132, 187, 208, 89, 18, 169, 200, 196, 135, 130,
    116, 188, 159, 86, 164, 100, 109, 198, 173, 186, 3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147,
    118, 126, 255, 82, 85, 212, 207, 206, 59, 227, 47, 16, 58, 17, 182, 189, 28, 42, 223, 183, 170, 213, 119,
    248, 152, 2, 44, 154, 163, 70, 221, 153, 101, 155, 167, 43, 172, 9, 129, 22, 39, 253, 19, 98, 108, 110,
    79, 113, 224, 232, 178, 185, 112, 104, 218, 246, 97, 228, 251, 34, 242, 193, 238, 210, 144, 12, 191, 179,
    162, 241, 81, 51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31, 181, 199, 106, 157, 184, 84, 204, 176,
    115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243, 141, 128, 195, 78,
    66, 215, 61, 156, 180,
];

/// The permutation written twice, so that `P[P[i] + j]` with `i, j <= 255`
/// (or nested deeper, each level adding at most 256) never needs a modulo.
pub(crate) static P: [u8; 512] = {
    let mut p = [0u8; 512];
    let mut i = 0;
    while i < 512 {
        p[i] = PERM_256[i & 255];
        i += 1;
    }
    p
};

/// The 3D gradients indexed by `hash & 15`, exactly as Perlin's `grad` picks
/// them (his bit tricks unrolled, so the analytic gradient can reuse them).
pub(crate) const GRAD3: [[f32; 3]; 16] = [
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [1.0, -1.0, 0.0],
    [-1.0, -1.0, 0.0],
    [1.0, 0.0, 1.0],
    [-1.0, 0.0, 1.0],
    [1.0, 0.0, -1.0],
    [-1.0, 0.0, -1.0],
    [0.0, 1.0, 1.0],
    [0.0, -1.0, 1.0],
    [0.0, 1.0, -1.0],
    [0.0, -1.0, -1.0],
    [1.0, 1.0, 0.0],
    [1.0, -1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [0.0, -1.0, -1.0],
];

/// 2D gradients: axes and diagonals. The diagonals have length √2, which is
/// what lets the value reach exactly ±1 at a cell centre.
const GRAD2: [[f32; 2]; 8] =
    [[1.0, 1.0], [-1.0, 1.0], [1.0, -1.0], [-1.0, -1.0], [1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]];

/// Perlin's quintic fade: zero first and second derivatives at 0 and 1.
#[inline(always)]
pub(crate) fn fade(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

/// d/dt of [`fade`]: `30t²(t − 1)²`.
#[inline(always)]
pub(crate) fn fade_d(t: f32) -> f32 {
    let s = t * (t - 1.0);
    30.0 * s * s
}

#[inline(always)]
fn lerp(t: f32, a: f32, b: f32) -> f32 {
    a + t * (b - a)
}

/// Splits a coordinate into its lattice cell (masked to 0..=255, so any float,
/// NaN and ±inf included, gives a valid index) and its offset in the cell.
#[inline(always)]
fn lattice(x: f32) -> (usize, f32) {
    let fl = luster_core::math::floor(x);
    ((fl as i32 & 255) as usize, x - fl)
}

/// A 1D slope in ±{1/4, 2/4, …, 8/4}; the steepest pair meeting at a cell
/// centre gives exactly ±1 there, so the range is [-1, 1].
#[inline(always)]
fn grad1(h: u8, x: f32) -> f32 {
    let g = ((h & 7) as f32 + 1.0) * 0.25;
    if h & 8 != 0 {
        -g * x
    } else {
        g * x
    }
}

/// Improved Perlin noise in 1D, in [-1, 1].
#[inline]
pub fn noise1(x: f32) -> f32 {
    let (i, f) = lattice(x);
    lerp(fade(f), grad1(P[i], f), grad1(P[i + 1], f - 1.0))
}

/// Improved Perlin noise in 2D, in [-1, 1].
#[inline]
pub fn noise2(x: f32, y: f32) -> f32 {
    let (xi, fx) = lattice(x);
    let (yi, fy) = lattice(y);
    let g = |h: u8, dx: f32, dy: f32| {
        let g = GRAD2[(h & 7) as usize];
        g[0] * dx + g[1] * dy
    };
    let (a, b) = (P[xi] as usize + yi, P[xi + 1] as usize + yi);
    let u = fade(fx);
    let n0 = lerp(u, g(P[a], fx, fy), g(P[b], fx - 1.0, fy));
    let n1 = lerp(u, g(P[a + 1], fx, fy - 1.0), g(P[b + 1], fx - 1.0, fy - 1.0));
    lerp(fade(fy), n0, n1)
}

/// Improved Perlin noise in 3D, in about [-1.04, 1.04] (see the module table).
///
/// With AVX2 (detected at run time) the eight corners are computed in the
/// lanes of one vector (`super::octaves::noise3_one`), bit for bit the
/// values of [`noise3_scalar`]: the Lua `perlin3` of a bump's three points and
/// the short tails of fractal sums call this one point at a time.
#[inline]
pub fn noise3(x: f32, y: f32, z: f32) -> f32 {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: AVX2 (which implies AVX and SSE4.1) was detected on this CPU.
            return unsafe { super::octaves::noise3_one(x, y, z) };
        }
    }
    noise3_scalar(x, y, z)
}

/// [`noise3`] without SIMD lanes: the reference the lanes must match.
#[inline]
pub fn noise3_scalar(x: f32, y: f32, z: f32) -> f32 {
    let (xi, fx) = lattice(x);
    let (yi, fy) = lattice(y);
    let (zi, fz) = lattice(z);
    let xs = [xi, (xi + 1) & 255];
    let (ys, zs) = ([yi, (yi + 1) & 255], [zi, (zi + 1) & 255]);
    // Its own body rather than `noise3_grad(..).0`: fractal sums call this in
    // a loop, where LLVM keeps `noise3_grad` out of line, so the gradient,
    // half the arithmetic, would be computed and thrown away.
    let corner = |a: usize, b: usize, c: usize| {
        let g = GRAD3[(hash3(xs, ys, zs, a, b, c) & 15) as usize];
        g[0] * (fx - a as f32) + g[1] * (fy - b as f32) + g[2] * (fz - c as f32)
    };
    let n = [
        corner(0, 0, 0),
        corner(1, 0, 0),
        corner(0, 1, 0),
        corner(1, 1, 0),
        corner(0, 0, 1),
        corner(1, 0, 1),
        corner(0, 1, 1),
        corner(1, 1, 1),
    ];
    blend3(ramp_coefficients(n), fade(fx), fade(fy), fade(fz))
}

/// The lattice hash of corner (a, b, c) of the cell spanned by `xs`, `ys`, `zs`.
#[inline(always)]
fn hash3(xs: [usize; 2], ys: [usize; 2], zs: [usize; 2], a: usize, b: usize, c: usize) -> u8 {
    // The masks change nothing (no index exceeds 510) but let LLVM drop bounds checks.
    P[(P[(P[xs[a] & 255] as usize + ys[b]) & 511] as usize + zs[c]) & 511]
}

/// The eight corner ramps (`n[a + 2b + 4c]`) as the coefficients of
/// k0 + k1·u + k2·v + k3·w + k4·uv + k5·vw + k6·wu + k7·uvw, shared by
/// [`noise3`] and [`noise3_grad`] so that both give the same bits.
#[inline(always)]
pub(crate) fn ramp_coefficients(n: [f32; 8]) -> [f32; 8] {
    let [n000, n100, n010, n110, n001, n101, n011, n111] = n;
    [
        n000,
        n100 - n000,
        n010 - n000,
        n001 - n000,
        n000 - n100 - n010 + n110,
        n000 - n010 - n001 + n011,
        n000 - n100 - n001 + n101,
        -n000 + n100 + n010 - n110 + n001 - n101 - n011 + n111,
    ]
}

/// The trilinear blend over the faded offsets, from [`ramp_coefficients`].
#[inline(always)]
pub(crate) fn blend3(k: [f32; 8], u: f32, v: f32, w: f32) -> f32 {
    let [k0, k1, k2, k3, k4, k5, k6, k7] = k;
    k0 + k1 * u + k2 * v + k3 * w + k4 * u * v + k5 * v * w + k6 * w * u + k7 * u * v * w
}

/// [`noise3`] and its exact analytic gradient ∂n/∂(x, y, z).
#[inline]
pub fn noise3_grad(x: f32, y: f32, z: f32) -> (f32, [f32; 3]) {
    let (xi, fx) = lattice(x);
    let (yi, fy) = lattice(y);
    let (zi, fz) = lattice(z);
    core3([xi, (xi + 1) & 255], [yi, (yi + 1) & 255], [zi, (zi + 1) & 255], fx, fy, fz)
}

/// Periodic improved noise: `pnoise3(x + px, y, z, px, py, pz)` equals
/// `pnoise3(x, y, z, px, py, pz)` (likewise for y and z). Periods below 1 are
/// treated as 1. Periods that do not divide 256 are honoured too: the lattice
/// index is reduced modulo the period before it is hashed.
#[inline]
pub fn pnoise3(x: f32, y: f32, z: f32, px: i32, py: i32, pz: i32) -> f32 {
    let wrap = |v: f32, period: i32| {
        let fl = luster_core::math::floor(v);
        let period = period.max(1);
        let i0 = (fl as i32).rem_euclid(period);
        let i1 = if i0 + 1 == period { 0 } else { i0 + 1 };
        ([(i0 & 255) as usize, (i1 & 255) as usize], v - fl)
    };
    let (xs, fx) = wrap(x, px);
    let (ys, fy) = wrap(y, py);
    let (zs, fz) = wrap(z, pz);
    core3(xs, ys, zs, fx, fy, fz).0
}

/// Trilinear blend of the eight corner ramps, with the gradient written as in
/// Quilez's "value noise derivatives": n = k0 + k1·u + k2·v + k3·w + k4·uv +
/// k5·vw + k6·wu + k7·uvw over the faded offsets, plus the blend of the corner
/// gradient vectors themselves (the ramps' own slopes).
#[inline(always)]
fn core3(xs: [usize; 2], ys: [usize; 2], zs: [usize; 2], fx: f32, fy: f32, fz: f32) -> (f32, [f32; 3]) {
    let corner = |a: usize, b: usize, c: usize| {
        let g = GRAD3[(hash3(xs, ys, zs, a, b, c) & 15) as usize];
        let d = [fx - a as f32, fy - b as f32, fz - c as f32];
        (g[0] * d[0] + g[1] * d[1] + g[2] * d[2], g)
    };
    let (n000, g000) = corner(0, 0, 0);
    let (n100, g100) = corner(1, 0, 0);
    let (n010, g010) = corner(0, 1, 0);
    let (n110, g110) = corner(1, 1, 0);
    let (n001, g001) = corner(0, 0, 1);
    let (n101, g101) = corner(1, 0, 1);
    let (n011, g011) = corner(0, 1, 1);
    let (n111, g111) = corner(1, 1, 1);
    let (u, v, w) = (fade(fx), fade(fy), fade(fz));
    let (du, dv, dw) = (fade_d(fx), fade_d(fy), fade_d(fz));

    let k = ramp_coefficients([n000, n100, n010, n110, n001, n101, n011, n111]);
    let [_, k1, k2, k3, k4, k5, k6, k7] = k;
    let value = blend3(k, u, v, w);

    let mut grad = [0.0f32; 3];
    for (axis, g) in grad.iter_mut().enumerate() {
        let x00 = lerp(u, g000[axis], g100[axis]);
        let x10 = lerp(u, g010[axis], g110[axis]);
        let x01 = lerp(u, g001[axis], g101[axis]);
        let x11 = lerp(u, g011[axis], g111[axis]);
        *g = lerp(w, lerp(v, x00, x10), lerp(v, x01, x11));
    }
    grad[0] += du * (k1 + k4 * v + k6 * w + k7 * v * w);
    grad[1] += dv * (k2 + k5 * w + k4 * u + k7 * w * u);
    grad[2] += dw * (k3 + k6 * u + k5 * v + k7 * u * v);
    (value, grad)
}

/// Improved Perlin noise in 4D, within [-1, 1] (measured extremes ±0.81).
///
/// The 32 gradients are the hypercube's edge midpoints (one coordinate 0, the
/// others ±1), as in Perlin's 4D extension. Unscaled they reach ±1.5 at a cell
/// centre, when all sixteen point at it; the factor 2/3 brings that to ±1.
#[inline]
pub fn noise4(x: f32, y: f32, z: f32, w: f32) -> f32 {
    let (xi, fx) = lattice(x);
    let (yi, fy) = lattice(y);
    let (zi, fz) = lattice(z);
    let (wi, fw) = lattice(w);
    let f = [fx, fy, fz, fw];
    let fades = [fade(fx), fade(fy), fade(fz), fade(fw)];
    let mut sum = 0.0;
    for corner in 0..16usize {
        let bit = |k: usize| corner >> k & 1;
        let h = P[P[P[P[xi + bit(0)] as usize + yi + bit(1)] as usize + zi + bit(2)] as usize + wi + bit(3)];
        let mut dot = 0.0;
        let mut weight = 1.0;
        let zero_axis = (h & 3) as usize;
        for k in 0..4 {
            let d = f[k] - bit(k) as f32;
            // One axis is skipped (the zero coordinate); bits 2..5 give the signs.
            if k != zero_axis {
                dot += if h >> (2 + k) & 1 != 0 { -d } else { d };
            }
            weight *= if bit(k) == 1 { fades[k] } else { 1.0 - fades[k] };
        }
        sum += weight * dot;
    }
    sum * (2.0 / 3.0)
}

#[cfg(test)]
mod tests;

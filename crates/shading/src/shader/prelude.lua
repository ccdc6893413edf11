-- The trusted prelude: runs once in every shader Lua state, with the FFI, before
-- any user script. It declares the records shared with Rust (src/shader/ffi.rs
-- must match them field for field), wraps the Rust built-ins in plain Lua
-- functions, defines the pure-Lua helpers, and returns the small API Rust uses
-- to build sandboxes and entry wrappers. Its locals (ffi, the built-in table,
-- the scratch records) are reachable from user code only through the wrapper
-- functions: user scripts get no debug library, no getfenv and no ffi.
local builtins_address, log, images_ctx, image_names, load_module = ...
local ffi = ffi
-- Kept for require (below) before the real globals lose them.
local loadstring, setfenv, pcall = loadstring, setfenv, pcall
local error, type, tostring, select, pairs, ipairs = error, type, tostring, select, pairs, ipairs
local next = next
local setmetatable, tonumber = setmetatable, tonumber
local floor, sqrt, format, abs, min = math.floor, math.sqrt, string.format, math.abs, math.min
local band, bxor, rshift, tobit = bit.band, bit.bxor, bit.rshift, bit.tobit

ffi.cdef [[
typedef struct { double x, y, z; } luster_vec3;
typedef struct { double u, v; } luster_vec2;
typedef struct {
  luster_vec3 P, Pw, Pc, N, Ng, I, V, dPdu, dPdv, dPdx, dPdy;
  luster_vec2 uv;
  double time, filterwidth, random;
  int32_t object_id, instance_id, depth, pixel_x, pixel_y, __luster_pad;
  luster_vec3 dPwdx, dPwdy, dPcdx, dPcdy;
  luster_vec2 duvdx, duvdy;
} luster_shade;
typedef struct { double r, g, b; int32_t bad; } luster_out;
typedef struct { int32_t kind, a, b, thin; double c[3][3]; double x[3]; } luster_node;
typedef struct {
  double color[3], specular[3], emission[3], reflect[3];
  double roughness, metalness;
  int32_t closure_len, closure_root;
  luster_node nodes[32];
} luster_material;
typedef struct { double gen; int32_t index; } luster_closure;
typedef struct { double start, limit; int32_t depth, rays; } luster_clock;
typedef struct { double f1, f2, px, py, pz, id; } luster_cell;
typedef struct { luster_vec3 o, d; double maxdist, time; luster_vec3 ng; } luster_ray;
typedef struct { double t; luster_vec3 P, N, Ng; int32_t object_id, instance_id; } luster_hit;
typedef struct { int32_t redo, offset; } luster_derivs;
typedef struct {
  double (*perlin1)(double);
  double (*perlin2)(double, double);
  double (*perlin3)(double, double, double);
  double (*perlin4)(double, double, double, double);
  double (*perlin3_grad)(double, double, double, luster_vec3 *);
  double (*pperlin3)(double, double, double, int32_t, int32_t, int32_t);
  double (*simplex2)(double, double);
  double (*simplex3)(double, double, double);
  double (*simplex4)(double, double, double, double);
  double (*simplex3_grad)(double, double, double, luster_vec3 *);
  double (*fbm)(double, double, double, int32_t, double, double);
  double (*fbm_grad)(double, double, double, int32_t, double, double, luster_vec3 *);
  double (*turbulence)(double, double, double, int32_t, double, double);
  double (*ridged)(double, double, double, int32_t, double, double, double);
  void (*voronoi3)(double, double, double, uint32_t, double, luster_cell *);
  void (*voronoi2)(double, double, uint32_t, double, luster_cell *);
  int32_t (*find)(const char *, int32_t, int32_t, const char *, int32_t);
  int32_t (*magic)(const char *, int32_t);
  const double *epoch;
  double (*course_noise)(double, double, double);
  int32_t (*texture)(const void *, int32_t, double, double, int32_t, luster_vec3 *);
  double (*course_perlin)(double, double, double, double, int32_t, int32_t);
  int32_t (*trace)(const luster_ray *, luster_hit *);
  double (*occlusion)(const luster_ray *, int32_t);
  int32_t (*bevel)(const luster_ray *, uint32_t, int32_t, int32_t, luster_vec3 *);
  int32_t max_rays;
} luster_builtins;
]]

local B = ffi.cast("const luster_builtins *", builtins_address)
local shade = ffi.new("luster_shade")
-- The second and third shading points of one bump (the first is `shade`):
-- height() at a point and at two steps along the surface, in one call from
-- Rust (see height3_entry).
local shade_b, shade_c = ffi.new("luster_shade"), ffi.new("luster_shade")
local out = ffi.new("luster_out")
local material = ffi.new("luster_material")
local clock = ffi.new("luster_clock")
local grad = ffi.new("luster_vec3")
local cell = ffi.new("luster_cell")

---------------------------------------------------------------------------
-- The deadline. Instrumented user code calls tick() in every loop body and
-- function entry (see instrument.rs). Each tick reads the shader clock, which
-- a watchdog thread advances (ffi.rs), and compares it with the call's start:
-- no count of ticks between reads, so a loop whose every iteration makes a
-- slow library call is stopped as promptly as an empty one. The clock has
-- four copies, read in turn: the JIT would hoist a load from one fixed
-- address out of a compiled loop (it ignores volatile), never to see it
-- change.
---------------------------------------------------------------------------
local epoch = B.epoch
local turn = 0
local STOPPED = "stopped: the shader ran past its time limit"
local function tick()
  turn = band(turn + 1, 3)
  -- Once past, every later tick of this call fails too, even if the script
  -- catches this error with pcall.
  if epoch[turn] - clock.start > clock.limit then error(STOPPED, 2) end
end
-- The same check in the runtime's own loops (sort, gsub, ...), which are not
-- instrumented; the error names the line that called the library function
-- (level 3: the caller of the function that ticks).
local function lib_tick()
  turn = band(turn + 1, 3)
  if epoch[turn] - clock.start > clock.limit then error(STOPPED, 3) end
end

---------------------------------------------------------------------------
-- vec3: a cdata struct with arithmetic metamethods. Inside JIT traces
-- temporaries are allocation-sunk, so vector code costs about what the
-- scalar code costs (benches/shader.rs measures both).
---------------------------------------------------------------------------
local vec3_t
-- A closure (see the closures section below). A vec3 times a closure is a
-- weighted closure, which vec3's own __mul hands over to closure_mul.
local closure_ct = ffi.typeof("luster_closure")
local function is_closure(v) return type(v) == "cdata" and ffi.istype(closure_ct, v) end
-- closure_mul, closure_entry and the emission{} constructor (c_emission).
local closures = {}
local vec3_methods = {}
local vec3_mt = { __index = vec3_methods }
local function isvec(v) return type(v) == "cdata" and ffi.istype(vec3_t, v) end
local shade_t = ffi.typeof("luster_shade")
local vec2_t = ffi.typeof("luster_vec2")
-- Names in the author's terms: LuaJIT calls all three "cdata".
local function typename(v)
  if type(v) ~= "cdata" then return type(v) end
  if isvec(v) then return "vec3" end
  if is_closure(v) then return "closure" end
  if ffi.istype(shade_t, v) then return "shading point" end
  if ffi.istype(vec2_t, v) then return "uv" end
  return "runtime value"
end
local VEC3_FIELDS = "x, y, z and the methods dot, cross, length, normalize, unpack"
setmetatable(vec3_methods, {
  __index = function(_, k)
    error(format("a vec3 has no field '%s' (it has %s)", tostring(k), VEC3_FIELDS), 2)
  end,
})
local SHADE_FIELDS = "P, Pw, Pc, N, Ng, I, V, dPdu, dPdv, dPdx, dPdy, uv, time, filterwidth, random, "
  .. "object_id, instance_id, depth, pixel_x, pixel_y, dPwdx, dPwdy, dPcdx, dPcdy, duvdx, duvdy"
local function no_field(what, fields)
  return function(_, k)
    error(format("%s has no field '%s' (its fields: %s)", what, tostring(k), fields), 2)
  end
end
ffi.metatype(shade_t, {
  __index = no_field("the shading point s", SHADE_FIELDS),
  __newindex = no_field("the shading point s", SHADE_FIELDS),
  __tostring = function(s) return format("shading point at P = (%g, %g, %g)", s.P.x, s.P.y, s.P.z) end,
})
ffi.metatype(vec2_t, {
  __index = no_field("s.uv", "u, v"),
  __newindex = no_field("s.uv", "u, v"),
  __tostring = function(t) return format("uv(%g, %g)", t.u, t.v) end,
})
-- Operands are vec3s or numbers (a number applies to every component). A
-- wrong operand is reported at the script's line, not inside the prelude.
local function operand(v, op)
  if type(v) == "number" or isvec(v) then return end
  error(format("vec3 %s: expected a vec3 or a number, got a %s", op, typename(v)), 3)
end
local function binary(op, f)
  return function(a, b)
    operand(a, op)
    operand(b, op)
    if type(a) == "number" then return vec3_t(f(a, b.x), f(a, b.y), f(a, b.z)) end
    if type(b) == "number" then return vec3_t(f(a.x, b), f(a.y, b), f(a.z, b)) end
    return vec3_t(f(a.x, b.x), f(a.y, b.y), f(a.z, b.z))
  end
end
vec3_mt.__add = binary("+", function(a, b) return a + b end)
vec3_mt.__sub = binary("-", function(a, b) return a - b end)
do
  local vec3_mul = binary("*", function(a, b) return a * b end)
  function vec3_mt.__mul(a, b)
    if is_closure(a) or is_closure(b) then return closures.mul(a, b) end
    return vec3_mul(a, b)
  end
end
vec3_mt.__div = binary("/", function(a, b) return a / b end)
function vec3_mt.__unm(a) return vec3_t(-a.x, -a.y, -a.z) end
function vec3_mt.__tostring(a) return format("vec3(%g, %g, %g)", a.x, a.y, a.z) end
local function dot(a, b) return a.x * b.x + a.y * b.y + a.z * b.z end
local function cross(a, b)
  return vec3_t(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x)
end
local function length(a) return sqrt(a.x * a.x + a.y * a.y + a.z * a.z) end
local function normalize(a)
  local l = length(a)
  if l == 0 then return vec3_t(0, 0, 0) end
  return vec3_t(a.x / l, a.y / l, a.z / l)
end
vec3_methods.dot, vec3_methods.cross = dot, cross
vec3_methods.length, vec3_methods.normalize = length, normalize
function vec3_methods.unpack(a) return a.x, a.y, a.z end
vec3_t = ffi.metatype("luster_vec3", vec3_mt)
local function vec3(x, y, z)
  x = x or 0
  if y == nil and z == nil then return vec3_t(x, x, x) end
  return vec3_t(x, y or 0, z or 0)
end

---------------------------------------------------------------------------
-- Noise: thin wrappers over the Rust built-ins (the JIT inlines them into a
-- direct native call). Defaults match docs/shaders.md.
---------------------------------------------------------------------------
-- Every built-in that takes a point takes x, y, z or one vec3; xyz() turns a
-- vec3 into its numbers (a type test the JIT folds away for numbers).
local function xyz(v, fname)
  if isvec(v) then return v.x, v.y, v.z end
  error(format("%s: expected numbers x, y, z or a vec3, got a %s", fname, typename(v)), 3)
end
local function perlin1(x) return B.perlin1(x) end
local function perlin2(x, y) return B.perlin2(x, y) end
local function perlin3(x, y, z)
  if type(x) ~= "number" then x, y, z = xyz(x, "perlin3") end
  return B.perlin3(x, y, z)
end
local function perlin4(x, y, z, w)
  if type(x) ~= "number" then w = y; x, y, z = xyz(x, "perlin4") end
  return B.perlin4(x, y, z, w)
end
local function course_noise(x, y, z)
  if type(x) ~= "number" then x, y, z = xyz(x, "course_noise") end
  return B.course_noise(x, y, z)
end
-- The course's perlin texture map, octaves and conversion included, in one
-- native call: course_perlin(x, y, z, [scale], [octaves], [conversion]) or
-- course_perlin(p, [scale], [octaves], [conversion]).
local CONVERSIONS = { linear = 0, absval = 1 }
local function course_perlin(x, y, z, scale, octaves, conversion)
  if type(x) ~= "number" then
    scale, octaves, conversion = y, z, scale
    x, y, z = xyz(x, "course_perlin")
  end
  local c = CONVERSIONS[conversion or "linear"]
  if c == nil then
    error(format("course_perlin: unknown conversion %s (use \"linear\" or \"absval\")", tostring(conversion)), 2)
  end
  return B.course_perlin(x, y, z, scale or 1, octaves or 1, c)
end
local function perlin3_grad(x, y, z)
  if type(x) ~= "number" then x, y, z = xyz(x, "perlin3_grad") end
  local v = B.perlin3_grad(x, y, z, grad)
  return v, grad.x, grad.y, grad.z
end
local function pperlin3(x, y, z, px, py, pz)
  if type(x) ~= "number" then
    local per = y
    x, y, z = xyz(x, "pperlin3")
    if isvec(per) then px, py, pz = per.x, per.y, per.z else px, py, pz = per, per, per end
  end
  return B.pperlin3(x, y, z, px, py, pz)
end
local function simplex2(x, y) return B.simplex2(x, y) end
local function simplex3(x, y, z)
  if type(x) ~= "number" then x, y, z = xyz(x, "simplex3") end
  return B.simplex3(x, y, z)
end
local function simplex4(x, y, z, w)
  if type(x) ~= "number" then w = y; x, y, z = xyz(x, "simplex4") end
  return B.simplex4(x, y, z, w)
end
local function simplex3_grad(x, y, z)
  if type(x) ~= "number" then x, y, z = xyz(x, "simplex3_grad") end
  local v = B.simplex3_grad(x, y, z, grad)
  return v, grad.x, grad.y, grad.z
end

-- Antialiasing. An octave of frequency f, seen through a footprint of width
-- fw (in the same units as the point), keeps its full weight while a pixel
-- spans under a quarter of its lattice cell and none once it spans half (the
-- Nyquist limit), with a smooth fade between: the octaves a pixel cannot
-- resolve are replaced by their mean instead of aliasing into noise.
local function octave_weight(fw, f)
  local t = fw * f
  if t <= 0.25 then return 1 end
  if t >= 0.5 then return 0 end
  local u = (t - 0.25) * 4
  return 1 - u * u * (3 - 2 * u)
end
-- The mean of |perlin3| over space (measured in tests.rs): what a faded
-- turbulence octave contributes.
local MEAN_ABS_PERLIN = 0.2209
local function fractal_aa(x, y, z, octaves, lacunarity, gain, fw, fold)
  local sum, amp, f = 0, 1, 1
  for _ = 1, min(octaves, 16) do
    local w = octave_weight(fw, f)
    if w == 0 then
      if fold then sum = sum + amp * MEAN_ABS_PERLIN end
    else
      local n = B.perlin3(x * f, y * f, z * f)
      if fold then n = w * abs(n) + (1 - w) * MEAN_ABS_PERLIN else n = w * n end
      sum = sum + amp * n
    end
    amp, f = amp * gain, f * lacunarity
  end
  return sum
end
-- fbm(x, y, z, [octaves], [lacunarity], [gain], [fw]) or fbm(p, ...): with a
-- filter width fw > 0 the octaves finer than the footprint fade out.
local function fractal_args(fname, x, y, z, a, b, c, d)
  if type(x) ~= "number" then
    a, b, c, d = y, z, a, b
    x, y, z = xyz(x, fname)
  end
  return x, y, z, a or 4, b or 2, c or 0.5, d
end
local function fbm(x, y, z, octaves, lacunarity, gain, fw)
  x, y, z, octaves, lacunarity, gain, fw = fractal_args("fbm", x, y, z, octaves, lacunarity, gain, fw)
  if fw and fw > 0 then return fractal_aa(x, y, z, octaves, lacunarity, gain, fw, false) end
  return B.fbm(x, y, z, octaves, lacunarity, gain)
end
local function fbm_grad(x, y, z, octaves, lacunarity, gain)
  x, y, z, octaves, lacunarity, gain = fractal_args("fbm_grad", x, y, z, octaves, lacunarity, gain)
  local v = B.fbm_grad(x, y, z, octaves, lacunarity, gain, grad)
  return v, grad.x, grad.y, grad.z
end
local function turbulence(x, y, z, octaves, lacunarity, gain, fw)
  x, y, z, octaves, lacunarity, gain, fw =
    fractal_args("turbulence", x, y, z, octaves, lacunarity, gain, fw)
  if fw and fw > 0 then return fractal_aa(x, y, z, octaves, lacunarity, gain, fw, true) end
  return B.turbulence(x, y, z, octaves, lacunarity, gain)
end
local function ridged(x, y, z, octaves, lacunarity, gain, offset)
  if type(x) ~= "number" then
    octaves, lacunarity, gain, offset = y, z, octaves, lacunarity
    x, y, z = xyz(x, "ridged")
  end
  return B.ridged(x, y, z, octaves or 4, lacunarity or 2, gain or 0.5, offset or 1)
end
-- Vector-valued noise: three Perlin noises at far-apart offsets, so the
-- components are uncorrelated (for warping a point, or a random direction).
local function vperlin(x, y, z)
  if type(x) ~= "number" then x, y, z = xyz(x, "vperlin") end
  return vec3_t(B.perlin3(x, y, z), B.perlin3(x + 31.416, y - 47.853, z + 12.679),
    B.perlin3(x - 19.27, y + 33.31, z - 71.13))
end
local function vfbm(x, y, z, octaves, lacunarity, gain, fw)
  x, y, z, octaves, lacunarity, gain, fw = fractal_args("vfbm", x, y, z, octaves, lacunarity, gain, fw)
  local function one(ox, oy, oz)
    if fw and fw > 0 then return fractal_aa(x + ox, y + oy, z + oz, octaves, lacunarity, gain, fw, false) end
    return B.fbm(x + ox, y + oy, z + oz, octaves, lacunarity, gain)
  end
  return vec3_t(one(0, 0, 0), one(31.416, -47.853, 12.679), one(-19.27, 33.31, -71.13))
end
local METRICS = { euclidean = 0, manhattan = 1, chebyshev = 2 }
local function metric_of(m)
  local id = METRICS[m or "euclidean"]
  if id == nil then
    error(format("unknown Voronoi metric %s (use \"euclidean\", \"manhattan\" or \"chebyshev\")", tostring(m)), 3)
  end
  return id
end
local function voronoi(x, y, z, metric, jitter)
  if type(x) ~= "number" then
    jitter, metric = z, y
    x, y, z = xyz(x, "voronoi")
  end
  local m = metric_of(metric)
  B.voronoi3(x, y, z, m, jitter or 1, cell)
  return cell.f1, cell.f2, cell.id, cell.px, cell.py, cell.pz
end
local function voronoi2(x, y, metric, jitter)
  local m = metric_of(metric)
  B.voronoi2(x, y, m, jitter or 1, cell)
  return cell.f1, cell.f2, cell.id, cell.px, cell.py
end
-- The scene's images, by id or file name: bilinear by default, "nearest" on
-- request. Names resolve through a table Rust filled, so a call costs a hash
-- lookup and one native call.
local FILTERS = { nearest = 0, bilinear = 1 }
local texel = ffi.new("luster_vec3")
local function texture(name, u, v, filter)
  if type(u) == "cdata" and ffi.istype(vec2_t, u) then filter = v; u, v = u.u, u.v end
  local index = image_names[name]
  if index == nil and type(name) == "number" then index = image_names[tostring(name)] end
  if index == nil then
    local known = {}
    for k in pairs(image_names) do known[#known + 1] = format("%q", k) end
    table.sort(known)
    local list = #known > 0 and table.concat(known, ", ") or "none"
    error(format("texture: the scene has no image %s (its images: %s)", tostring(name), list), 2)
  end
  if type(u) ~= "number" or type(v) ~= "number" then
    error(format("texture: u and v must be numbers (or one s.uv), got a %s and a %s", typename(u), typename(v)), 2)
  end
  local f = FILTERS[filter or "bilinear"]
  if f == nil then
    error(format("texture: unknown filter %s (use \"nearest\" or \"bilinear\")", tostring(filter)), 2)
  end
  if B.texture(images_ctx, index, u, v, f, texel) ~= 0 then
    error(format("texture: image %s could not be sampled", tostring(name)), 2)
  end
  return texel.x, texel.y, texel.z
end

---------------------------------------------------------------------------
-- Pattern helpers, in plain Lua: the JIT compiles them as well as Rust would.
---------------------------------------------------------------------------
local function clamp(x, lo, hi)
  if x < lo then return lo elseif x > hi then return hi end
  return x
end
local function mix(a, b, t) return a + (b - a) * t end
local function smoothstep(e0, e1, x)
  local t = clamp((x - e0) / (e1 - e0), 0, 1)
  return t * t * (3 - 2 * t)
end
local function step(edge, x) if x < edge then return 0 end return 1 end
local function fract(x) return x - floor(x) end
-- A colour picked on a display (sRGB-encoded, 0 to 1) as the linear value a
-- scene with a display transform renders with: srgb(r, g, b), srgb(grey) or
-- srgb(vec3).
local function srgb_channel(c)
  if c <= 0.04045 then return c / 12.92 end
  return ((c + 0.055) / 1.055) ^ 2.4
end
local function srgb(r, g, b)
  if isvec(r) then r, g, b = r.x, r.y, r.z elseif g == nil and b == nil then g, b = r, r end
  return vec3_t(srgb_channel(r), srgb_channel(g), srgb_channel(b))
end
-- The box-filtered square wave, +1 on [0, 1) and -1 on [1, 2), averaged over
-- [t - w/2, t + w/2]: the difference of its integral, a triangle wave.
local function square_integral(t)
  local h = t / 2 - floor(t / 2)
  return 1 - abs(2 * h - 1)
end
local function filtered_square(t, w)
  if w <= 0 then return (floor(t) % 2 == 0) and 1 or -1 end
  return (square_integral(t + w / 2) - square_integral(t - w / 2)) / w
end
-- checker(x, y, [z], [fw]) or checker(p, [fw]): 0 or 1 on unit cells; with a
-- filter width, the cells' average over the footprint (a box filter per
-- axis). fw is one width or a vec3 of widths per axis (filterwidth_xyz):
-- on a surface the footprint has no depth across it, and a cube-shaped box
-- would blur a plane lying on a cell boundary to grey.
local function checker(x, y, z, fw)
  if type(x) ~= "number" then
    fw = y
    x, y, z = xyz(x, "checker")
  end
  z = z or 0
  if not fw then return (floor(x) + floor(y) + floor(z)) % 2 end
  local wx, wy, wz
  if isvec(fw) then wx, wy, wz = fw.x, fw.y, fw.z else wx, wy, wz = fw, fw, fw end
  if wx <= 0 and wy <= 0 and wz <= 0 then return (floor(x) + floor(y) + floor(z)) % 2 end
  return 0.5 - 0.5 * filtered_square(x, wx) * filtered_square(y, wy) * filtered_square(z, wz)
end
-- aastep(edge, x, [fw]): step(edge, x) box-filtered over a footprint of width
-- fw in the units of x (0 or nil: the hard step).
local function aastep(edge, x, fw)
  if not fw or fw <= 0 then
    if x < edge then return 0 end
    return 1
  end
  return clamp((x - edge) / fw + 0.5, 0, 1)
end
-- filterwidth(s, [scale]): the footprint of s.P scaled by `scale`, the width
-- to give the filtered built-ins for a pattern of `scale * s.P`.
local function filterwidth(s, scale)
  return s.filterwidth * abs(scale or 1)
end
-- filterwidth_xyz(s, [scale]): the footprint's extent along each object
-- axis, |dPdx| + |dPdy| per component, a box that holds the footprint.
local function filterwidth_xyz(s, scale)
  local k, dx, dy = abs(scale or 1), s.dPdx, s.dPdy
  return vec3_t(k * (abs(dx.x) + abs(dy.x)), k * (abs(dx.y) + abs(dy.y)), k * (abs(dx.z) + abs(dy.z)))
end
-- 32-bit integer hashing (the lowbias32 finaliser by Chris Wellons). Lua
-- numbers are doubles, so products are split to stay exact below 2^53.
local function mul32(a, b)
  return tobit(a * band(b, 0xffff) + tobit(a * rshift(b, 16)) * 65536)
end
local function mix32(h)
  h = bxor(h, rshift(h, 16))
  h = mul32(h, 0x7feb352d)
  h = bxor(h, rshift(h, 15))
  h = mul32(h, tobit(0x846ca68b))
  return bxor(h, rshift(h, 16))
end
local function hash_int(a, b, c)
  local h = mix32(tobit(a))
  h = mix32(bxor(h, tobit(b or 0)))
  h = mix32(bxor(h, tobit(c or 0)))
  return band(h, 0x7fffffff)
end
local function hash(a, b, c)
  if isvec(a) then a, b, c = a.x, a.y, a.z end
  return hash_int(floor(a), floor(b or 0), floor(c or 0)) / 0x80000000
end
local function brick(x, y, width, height, mortar)
  width, height, mortar = width or 1, height or 0.5, mortar or 0.05
  local row = floor(y / height)
  local bx = x / width + (row % 2) * 0.5
  local col = floor(bx)
  local bu, bv = bx - col, y / height - row
  local mu, mv = 0.5 * mortar / width, 0.5 * mortar / height
  local m = 0
  if bu < mu or bu > 1 - mu or bv < mv or bv > 1 - mv then m = 1 end
  return m, hash_int(col, row), bu, bv
end
local function ramp(positions, colors)
  if type(positions) ~= "table" or type(colors) ~= "table" then
    error("ramp(positions, colors) takes two lists", 2)
  end
  local n = #positions
  if n == 0 or #colors ~= n then
    error(format("ramp: %d positions but %d colors", n, #colors), 2)
  end
  local ps, rs, gs, bs = {}, {}, {}, {}
  for i = 1, n do
    local c = colors[i]
    ps[i] = positions[i]
    if isvec(c) then
      rs[i], gs[i], bs[i] = c.x, c.y, c.z
    elseif type(c) == "table" then
      rs[i], gs[i], bs[i] = c[1], c[2], c[3]
    else
      rs[i], gs[i], bs[i] = c, c, c
    end
    if type(ps[i]) ~= "number" or type(rs[i]) ~= "number" or type(gs[i]) ~= "number" or type(bs[i]) ~= "number" then
      error(format("ramp: entry %d is not a number position with an {r, g, b} color", i), 2)
    end
    if i > 1 and ps[i] < ps[i - 1] then error("ramp: positions must not decrease", 2) end
  end
  return function(t)
    if not (t > ps[1]) then return rs[1], gs[1], bs[1] end
    for i = 2, n do
      if t < ps[i] then
        local f = (t - ps[i - 1]) / (ps[i] - ps[i - 1])
        return rs[i - 1] + (rs[i] - rs[i - 1]) * f, gs[i - 1] + (gs[i] - gs[i - 1]) * f,
          bs[i - 1] + (bs[i] - bs[i - 1]) * f
      end
    end
    return rs[n], gs[n], bs[n]
  end
end

---------------------------------------------------------------------------
-- The sandbox. The real string table is reachable from any string through
-- its metatable, so it is cleaned in place; everything else a script sees
-- is a copy made per shader, so one shader cannot change another's library.
---------------------------------------------------------------------------
-- What the rest of the prelude uses from the sandbox; its helpers live in a
-- function of their own, as the main chunk may have only 200 locals.
local safe_sort, safe_move, safe_foreachi, safe_foreach, safe_concat, safe_resume, safe_wrap
;(function()
local MAX_REP = 16 * 1024 * 1024
local rep = string.rep
local function safe_rep(s, n, sep)
  local count = tonumber(n)
  local len = #tostring(s) + (sep and #tostring(sep) or 0)
  if count and count > 0 and len * count > MAX_REP then
    error(format("string.rep: result of %.0f bytes is over the %d-byte limit", len * count, MAX_REP), 2)
  end
  return rep(s, n, sep)
end
-- Lua patterns backtrack inside C, where the time limit cannot reach:
-- string.find(string.rep("a", 1e5), ".-.-.-.-b") runs for hours. So the
-- pattern functions take only literal patterns (no magic character), and
-- search with a linear-time substring search in Rust (B.find): LuaJIT's own
-- search of literal text compares the whole pattern at every occurrence of
-- its first byte, quadratic on "aaaa...". gsub is Lua here too, so that a
-- replacement function is called from Lua (its recursion is bounded by Lua's
-- stack, not the native one) and a long replacement is checked against the
-- clock. See docs/shaders.md.
local real_find = string.find
local sub, byte = string.sub, string.byte
local concat = table.concat
local find_c, magic_c = B.find, B.magic
local function literal(fname, pattern)
  if type(pattern) == "string" and magic_c(pattern, #pattern) ~= 0 then
    error(format("string.%s: patterns with magic characters (^$*+?.()[]%%-) are not available in shaders, "
      .. "since matching them can run unboundedly long; use a literal pattern or string.find(s, p, 1, true)",
      fname), 3)
  end
end
-- LuaJIT takes a number where a string is expected (as tostring writes it),
-- and a numeric string where a number is.
local function as_text(v)
  if type(v) == "number" then return tostring(v) end
  return v
end
local function as_number(v)
  if type(v) == "string" then return tonumber(v) or v end
  return v
end
-- A number as LuaJIT's library functions read an integer argument: a C
-- cast to int32_t, which the vendored build compiles to a 64-bit truncation
-- keeping the low 32 bits (NaN and magnitudes from 2^63 up give 0).
local function to_int(x)
  if not (x > -9223372036854775808 and x < 9223372036854775808) then return 0 end
  local t = (x >= 0 and floor(x) or -floor(-x)) % 4294967296
  if t >= 2147483648 then t = t - 4294967296 end
  return t
end
-- The 0-based byte where a search of a string of n bytes starts, from `init`
-- as LuaJIT reads it: 1-based, negative counting from the end, clamped to
-- the string.
local function start_of(init, n)
  if init == nil then return 0 end
  local st = to_int(init)
  if st < 0 then st = st + n else st = st - 1 end
  if st < 0 then return 0 end
  if st > n then return n end
  return st
end
-- LuaJIT's pattern matcher (match, gmatch, gsub; not find) ends a pattern at
-- its first zero byte, as Lua 5.1 did.
local function to_nul(p)
  local z = find_c(p, 0, #p, "\0", 1)
  if z < 0 then return p end
  return sub(p, 1, z)
end
local function find_text(s, p, init)
  local m = #p
  local q = find_c(s, start_of(init, #s), #s, p, m)
  if q < 0 then return nil end
  return q + 1, q + m
end
local real_match, real_gmatch, real_gsub = string.match, string.gmatch, string.gsub
string.find = function(s, pattern, init, plain)
  s, pattern, init = as_text(s), as_text(pattern), as_number(init)
  if not plain then literal("find", pattern) end
  if type(s) == "string" and type(pattern) == "string" and (init == nil or type(init) == "number") then
    return find_text(s, pattern, init)
  end
  -- LuaJIT's own function reports the bad argument.
  return real_find(s, pattern, init, plain)
end
string.match = function(s, pattern, init)
  s, pattern, init = as_text(s), as_text(pattern), as_number(init)
  literal("match", pattern)
  if type(s) == "string" and type(pattern) == "string" and (init == nil or type(init) == "number") then
    -- A literal pattern has no captures: the match is the pattern itself.
    pattern = to_nul(pattern)
    if find_text(s, pattern, init) then return pattern end
    return nil
  end
  return real_match(s, pattern, init)
end
string.gmatch = function(s, pattern)
  s, pattern = as_text(s), as_text(pattern)
  literal("gmatch", pattern)
  if type(s) ~= "string" or type(pattern) ~= "string" then return real_gmatch(s, pattern) end
  pattern = to_nul(pattern)
  local n, m, pos = #s, #pattern, 0
  return function()
    if pos > n then return nil end
    local q = find_c(s, pos, n, pattern, m)
    if q < 0 then
      pos = n + 1
      return nil
    end
    -- After an empty match, the next search starts one byte further.
    pos = q + (m == 0 and 1 or m)
    return pattern
  end
end
-- A replacement string cut at its escapes: text, and WHOLE for "%0" or
-- "%1" (the whole match: a literal pattern has no captures), or BAD_CAPTURE
-- for "%2" to "%9". "%x" is x; a final "%" is a zero byte, as in LuaJIT.
local WHOLE, BAD_CAPTURE = {}, {}
local function parse_replacement(r)
  local parts, n, i = {}, #r, 0
  while true do
    local q = find_c(r, i, n, "%", 1)
    if q < 0 then
      parts[#parts + 1] = sub(r, i + 1, n)
      return parts
    end
    parts[#parts + 1] = sub(r, i + 1, q)
    local c = byte(r, q + 2)
    if c == nil then
      parts[#parts + 1] = "\0"
    elseif c == 48 or c == 49 then
      parts[#parts + 1] = WHOLE
    elseif c >= 50 and c <= 57 then
      parts[#parts + 1] = BAD_CAPTURE
    else
      parts[#parts + 1] = string.char(c)
    end
    i = q + 2
  end
end
string.gsub = function(s, pattern, repl, max_n)
  s, pattern, max_n = as_text(s), as_text(pattern), as_number(max_n)
  literal("gsub", pattern)
  local kind = type(repl)
  if type(s) ~= "string" or type(pattern) ~= "string" or (max_n ~= nil and type(max_n) ~= "number")
    or (kind ~= "string" and kind ~= "number" and kind ~= "table" and kind ~= "function") then
    -- LuaJIT's own function reports the bad argument.
    return real_gsub(s, pattern, repl, max_n)
  end
  pattern = to_nul(pattern)
  local n, m = #s, #pattern
  local limit = max_n == nil and n + 1 or to_int(max_n)
  local parts = (kind == "string" or kind == "number") and parse_replacement(as_text(repl))
  -- The result in pieces; every 4096 pieces are joined into one chunk, so the
  -- pieces never outnumber the result's bytes by much.
  local pieces, np, chunks = {}, 0, {}
  local function add(piece)
    np = np + 1
    pieces[np] = piece
    if np == 4096 then
      chunks[#chunks + 1] = concat(pieces, "", 1, np)
      np = 0
    end
  end
  local src, count = 0, 0
  while count < limit do
    lib_tick()
    local q = find_c(s, src, n, pattern, m)
    if q < 0 then break end
    if q > src then add(sub(s, src + 1, q)) end
    count = count + 1
    local whole = sub(s, q + 1, q + m)
    if parts then
      for i = 1, #parts do
        local part = parts[i]
        if part == WHOLE then
          add(whole)
        elseif part == BAD_CAPTURE then
          error("invalid capture index", 2)
        else
          add(part)
        end
      end
    else
      local v
      if kind == "table" then v = repl[whole] else v = repl(whole) end
      if not v then
        v = whole
      elseif type(v) == "number" then
        v = tostring(v)
      elseif type(v) ~= "string" then
        error(format("invalid replacement value (a %s)", type(v)), 2)
      end
      add(v)
    end
    if m > 0 then
      src = q + m
    elseif q < n then
      -- An empty match: the byte after it is kept, and the search moves on.
      add(sub(s, q + 1, q + 1))
      src = q + 1
    else
      src = n
      break
    end
  end
  add(sub(s, src + 1, n))
  chunks[#chunks + 1] = concat(pieces, "", 1, np)
  return concat(chunks), count
end
-- %s of a table or an FFI value calls its __tostring from C, where a
-- __tostring that formats itself would recurse on the native stack, which no
-- Lua limit bounds. Such arguments go through tostring first, in Lua, where
-- the recursion is Lua's own (a stack overflow error).
local real_format = string.format
local function plain_value(v)
  local t = type(v)
  return t == "string" or t == "number"
end
string.format = function(fmt, ...)
  local n = select("#", ...)
  local args
  for i = 1, n do
    local v = select(i, ...)
    if not plain_value(v) then
      args = { ... }
      break
    end
    if i >= 8 then
      args = { ... }
      break
    end
  end
  if not args then return real_format(fmt, ...) end
  for i = 1, n do
    if not plain_value(args[i]) then args[i] = tostring(args[i]) end
  end
  return real_format(fmt, unpack(args, 1, n))
end
string.dump = nil
string.rep = safe_rep

-- table.sort: LuaJIT's quicksort is quadratic on adversarial input and runs
-- in C, beyond the clock; its comparator (or __lt) is called from C, so a
-- comparator that sorts recurses on the native stack. This heap sort is
-- O(n log n) whatever the input, checks the clock, and calls the comparator
-- from Lua. Like LuaJIT's, it reads and writes the table raw and is not stable.
local function less(a, b)
  local ta, tb = type(a), type(b)
  if ta == tb and (ta == "number" or ta == "string") then return a < b end
  -- Level 4: the line that called table.sort (less <- sift <- sort).
  if ta ~= tb then error(format("attempt to compare %s with %s", ta, tb), 4) end
  if ta ~= "table" and ta ~= "cdata" and ta ~= "userdata" then
    error(format("attempt to compare two %s values", ta), 4)
  end
  return a < b
end
local function sift(t, i, n, lt)
  local v = rawget(t, i)
  while true do
    local c = 2 * i
    if c > n then break end
    local cv = rawget(t, c)
    if c < n then
      local right = rawget(t, c + 1)
      if lt(cv, right) then c, cv = c + 1, right end
    end
    if not lt(v, cv) then break end
    rawset(t, i, cv)
    i = c
  end
  rawset(t, i, v)
end
function safe_sort(t, comp)
  if type(t) ~= "table" then
    error(format("bad argument #1 to 'sort' (table expected, got %s)", typename(t)), 2)
  end
  if comp ~= nil and type(comp) ~= "function" then
    error(format("bad argument #2 to 'sort' (function expected, got %s)", typename(comp)), 2)
  end
  local lt, n = comp or less, #t
  for i = floor(n / 2), 1, -1 do
    lib_tick()
    sift(t, i, n, lt)
  end
  for last = n, 2, -1 do
    lib_tick()
    local top = rawget(t, 1)
    rawset(t, 1, rawget(t, last))
    rawset(t, last, top)
    sift(t, 1, last - 1, lt)
  end
end
-- table.move, foreach and foreachi are Lua inside LuaJIT but not
-- instrumented: table.move({}, 1, 2^31 - 2, 1) would copy nils for seconds.
-- These check the clock at every element.
local function int_arg(fname, k, v)
  local x = as_number(v)
  if type(x) ~= "number" then
    error(format("bad argument #%d to '%s' (number expected, got %s)", k, fname, typename(v)), 3)
  end
  return to_int(x)
end
local function table_arg(fname, k, v)
  if type(v) ~= "table" then
    error(format("bad argument #%d to '%s' (table expected, got %s)", k, fname, typename(v)), 3)
  end
end
function safe_move(a1, f, e, t, a2)
  table_arg("move", 1, a1)
  f, e, t = int_arg("move", 2, f), int_arg("move", 3, e), int_arg("move", 4, t)
  if a2 == nil then a2 = a1 end
  table_arg("move", 5, a2)
  if e >= f then
    local d = t - f
    if t > e or t <= f or a2 ~= a1 then
      for i = f, e do
        lib_tick()
        a2[i + d] = a1[i]
      end
    else
      for i = e, f, -1 do
        lib_tick()
        a2[i + d] = a1[i]
      end
    end
  end
  return a2
end
function safe_foreachi(t, f)
  table_arg("foreachi", 1, t)
  for i = 1, #t do
    lib_tick()
    local r = f(i, t[i])
    if r ~= nil then return r end
  end
end
function safe_foreach(t, f)
  table_arg("foreach", 1, t)
  for k, v in next, t do
    lib_tick()
    local r = f(k, v)
    if r ~= nil then return r end
  end
end
-- table.concat converts numbers one by one in C: 2^22 items take well under
-- a second; more is refused.
local MAX_CONCAT = 4 * 1024 * 1024
function safe_concat(t, sep, i, j)
  if type(t) == "table" then
    local first = tonumber(i) or 1
    local last = tonumber(j) or #t
    if last - first >= MAX_CONCAT then
      error(format("table.concat: %.0f items are over the limit of %d", last - first + 1, MAX_CONCAT), 2)
    end
  end
  return concat(t, sep, i, j)
end
-- Coroutines: every resume nests a native call frame (LuaJIT's vm_resume),
-- and every coroutine has a Lua stack of its own, so no Lua limit bounds
-- coroutines resumed inside one another. The clock record counts them per
-- call (Rust resets it), up to Lua 5.1's C call limit.
local MAX_NESTED_COROUTINES = 200
local real_resume, real_create = coroutine.resume, coroutine.create
local function nest(level)
  local d = clock.depth
  if d >= MAX_NESTED_COROUTINES then
    error(format("coroutines nested too deep: more than %d resumed inside one another (Lua's C call limit)",
      MAX_NESTED_COROUTINES), level + 1)
  end
  clock.depth = d + 1
end
local function unnest(...)
  clock.depth = clock.depth - 1
  return ...
end
function safe_resume(co, ...)
  -- A bad argument is LuaJIT's error, raised before anything nests.
  if type(co) ~= "thread" then return real_resume(co, ...) end
  nest(2)
  return unnest(real_resume(co, ...))
end
local function rethrow(ok, ...)
  if not ok then error((...), 0) end
  return ...
end
function safe_wrap(f)
  if type(f) ~= "function" then
    error(format("bad argument #1 to 'wrap' (function expected, got %s)", typename(f)), 2)
  end
  local co = real_create(f)
  return function(...)
    nest(2)
    return rethrow(unnest(real_resume(co, ...)))
  end
end
end)()
getmetatable("").__metatable = false

local function copy(t, drop)
  local c = {}
  for k, v in pairs(t) do
    if not (drop and drop[k]) then c[k] = v end
  end
  return c
end
local real_collectgarbage = collectgarbage
local function safe_collectgarbage(opt)
  if opt == "count" then return real_collectgarbage("count") end
  error("collectgarbage: shaders may only ask for \"count\"", 2)
end
local SAFE_GLOBALS = {
  "assert", "error", "ipairs", "next", "pairs", "pcall", "xpcall", "select", "tonumber", "tostring",
  "type", "unpack", "rawequal", "rawget", "rawset", "setmetatable", "getmetatable", "_VERSION",
}
local real_globals = _G
local BUILTINS = {
  vec3 = vec3, dot = dot, cross = cross, length = length, normalize = normalize,
  perlin1 = perlin1, perlin2 = perlin2, perlin3 = perlin3, perlin4 = perlin4,
  perlin3_grad = perlin3_grad, pperlin3 = pperlin3, course_noise = course_noise,
  course_perlin = course_perlin,
  simplex2 = simplex2, simplex3 = simplex3, simplex4 = simplex4, simplex3_grad = simplex3_grad,
  fbm = fbm, fbm_grad = fbm_grad, turbulence = turbulence, ridged = ridged,
  voronoi = voronoi, voronoi2 = voronoi2, texture = texture, vperlin = vperlin, vfbm = vfbm,
  clamp = clamp, mix = mix, lerp = mix, smoothstep = smoothstep, step = step, fract = fract,
  aastep = aastep, filterwidth = filterwidth, filterwidth_xyz = filterwidth_xyz,
  checker = checker, brick = brick, ramp = ramp, hash = hash, srgb = srgb,
  collectgarbage = safe_collectgarbage,
}

---------------------------------------------------------------------------
-- Rays from shaders (docs/tracing.md): trace(), occlusion(), edgewear() and
-- bevel(). Rust casts them into the scene the renderer installed for this
-- thread (trace.rs), or finds nothing when none is. clock.rays counts a
-- call's rays (Rust clears it when the call starts); past B.max_rays the
-- call fails at the script's line. Rays leave the current point's surface
-- (the record `shade`, whose Ng and time they take) on the side they head.
---------------------------------------------------------------------------
-- A function of its own: a function may have only 200 locals.
local function tracing()
  local ray_in, hit_out, bevel_out = ffi.new("luster_ray"), ffi.new("luster_hit"), ffi.new("luster_vec3")
  local function finite_number(v) return type(v) == "number" and v - v == 0 end
  -- The checks below raise their errors at `level` (default 3: the script's
  -- line that called the built-in that checks).
  local function spend(n, fname, level)
    local used = clock.rays + n
    if used > B.max_rays then
      error(format("%s: the call would cast %d rays, over the cap of %d rays per shader call "
        .. "(fewer samples, or fewer calls per point)", fname, used, B.max_rays), level or 3)
    end
    clock.rays = used
  end
  local function vec_arg(v, fname, what, level)
    if not isvec(v) then error(format("%s: %s must be a vec3, got a %s", fname, what, typename(v)), level or 3) end
    if not (finite_number(v.x) and finite_number(v.y) and finite_number(v.z)) then
      error(format("%s: %s must be finite, got %s", fname, what, tostring(v)), level or 3)
    end
  end
  local function positive_arg(v, default, fname, what)
    if v == nil then return default end
    if type(v) ~= "number" or not (v > 0) then
      error(format("%s: %s must be a positive number, got %s", fname, what, tostring(v)), 3)
    end
    return v
  end
  local function samples_arg(v, default, fname)
    if v == nil then return default end
    if type(v) ~= "number" or v ~= floor(v) or v < 1 or v > B.max_rays then
      error(format("%s: samples must be a whole number from 1 to %d, got %s", fname, B.max_rays, tostring(v)), 3)
    end
    return v
  end
  local function set_vec(dst, v) dst.x, dst.y, dst.z = v.x, v.y, v.z end
  -- The ray record for a ray from `o` along `d` (a direction or an axis).
  local function ray_from(o, d, maxdist)
    set_vec(ray_in.o, o)
    set_vec(ray_in.d, d)
    ray_in.maxdist = maxdist
    ray_in.time = shade.time
    set_vec(ray_in.ng, shade.Ng)
  end
  -- trace(origin, dir, [maxdist]): the nearest surface along the ray, as
  -- { t, P, N, Ng, object_id, instance_id }, or nil.
  local function trace(origin, dir, maxdist)
    vec_arg(origin, "trace", "origin")
    vec_arg(dir, "trace", "dir")
    maxdist = positive_arg(maxdist, math.huge, "trace", "maxdist")
    local l = length(dir)
    if l == 0 then error("trace: dir must not be the zero vector", 2) end
    spend(1, "trace")
    ray_from(origin, dir / l, maxdist)
    local found = B.trace(ray_in, hit_out)
    if found < 0 then error("trace: the renderer failed to trace the ray", 2) end
    if found == 0 then return nil end
    local h = hit_out
    return {
      t = h.t,
      P = vec3_t(h.P.x, h.P.y, h.P.z),
      N = vec3_t(h.N.x, h.N.y, h.N.z),
      Ng = vec3_t(h.Ng.x, h.Ng.y, h.Ng.z),
      object_id = h.object_id,
      instance_id = h.instance_id,
    }
  end
  local function is_shade(v) return type(v) == "cdata" and ffi.istype(shade_t, v) end
  -- The shared half of occlusion and edgewear: the fraction of `samples`
  -- cosine-weighted directions around `axis` blocked within `reach`.
  -- Errors at level 3 from here are the script's line (the callers below
  -- call it in no tail call).
  local function blocked(fname, P, axis, samples, reach)
    vec_arg(P, fname, "P", 4)
    vec_arg(axis, fname, "N", 4)
    if length(axis) == 0 then error(format("%s: N must not be the zero vector", fname), 3) end
    spend(samples, fname, 4)
    ray_from(P, axis, reach)
    local f = B.occlusion(ray_in, samples)
    if f ~= f then error(format("%s: the renderer failed to trace the rays", fname), 3) end
    return f
  end
  -- occlusion(P, N, [samples], [maxdist]) or occlusion(s, [samples], [maxdist]):
  -- ambient occlusion, 0 (open) to 1 (enclosed).
  local function occlusion(P, N, samples, maxdist)
    if is_shade(P) then P, N, samples, maxdist = P.Pw, P.N, N, samples end
    samples = samples_arg(samples, 16, "occlusion")
    maxdist = positive_arg(maxdist, math.huge, "occlusion", "maxdist")
    local f = blocked("occlusion", P, N, samples, maxdist)
    return f
  end
  -- edgewear(P, N, radius, [samples]) or edgewear(s, radius, [samples]): the
  -- fraction of rays into the object that leave it within radius, 0 on a flat
  -- face of a thick object, rising towards a convex edge or corner.
  local function edgewear(P, N, radius, samples)
    if is_shade(P) then P, N, radius, samples = P.Pw, P.N, N, radius end
    if radius == nil then error("edgewear: the radius is missing (edgewear(P, N, radius, [samples]))", 2) end
    radius = positive_arg(radius, nil, "edgewear", "radius")
    samples = samples_arg(samples, 16, "edgewear")
    vec_arg(N, "edgewear", "N")
    local f = blocked("edgewear", P, -N, samples, radius)
    return f
  end
  -- bevel(radius, [samples]) or bevel(s, radius, [samples]): the shading
  -- normal rounded over radius at the current point, as Cycles' Bevel node.
  local function bevel(s, radius, samples)
    if not is_shade(s) then s, radius, samples = shade, s, radius end
    if radius == nil then error("bevel: the radius is missing (bevel(radius, [samples]))", 2) end
    radius = positive_arg(radius, nil, "bevel", "radius")
    samples = samples_arg(samples, 8, "bevel")
    ray_from(s.Pw, s.N, radius)
    set_vec(ray_in.ng, s.Ng)
    local budget = B.max_rays - clock.rays
    local rays = B.bevel(ray_in, s.instance_id, samples, budget, bevel_out)
    if rays == -1 then spend(budget + 1, "bevel") end
    if rays < 0 then error("bevel: the renderer failed to trace the rays", 2) end
    spend(rays, "bevel")
    return vec3_t(bevel_out.x, bevel_out.y, bevel_out.z)
  end
  return trace, occlusion, edgewear, bevel
end
BUILTINS.trace, BUILTINS.occlusion, BUILTINS.edgewear, BUILTINS.bevel = tracing()

-- What a script gets instead of a removed global or library function: an
-- error saying it was removed on purpose, and why.
local REMOVED = {
  io = "shaders cannot read or write files",
  os = "shaders cannot reach the operating system, and its clock would make images differ between runs",
  debug = "it would reach past the sandbox",
  ffi = "it would reach past the sandbox",
  jit = "it would reach past the sandbox",
  package = "modules are loaded with require \"name\" only",
  module = "a module returns its table instead (see require in docs/shaders.md)",
  load = "shaders cannot compile code while they run",
  loadstring = "shaders cannot compile code while they run",
  loadfile = "shaders cannot read files",
  dofile = "shaders cannot read files",
  getfenv = "it would reach past the sandbox",
  setfenv = "it would reach past the sandbox",
  newproxy = "it would reach past the sandbox",
}
local RANDOM_WHY = "images must not depend on which thread shades which pixel; "
  .. "use hash(...) or the noise functions for repeatable randomness"
local function removed(lib, why)
  return {
    __index = function(_, k)
      local reason = why[k]
      if reason then error(format("%s%s was removed from shaders: %s", lib, tostring(k), reason), 2) end
      return nil
    end,
    __metatable = false,
  }
end

-- Declared parameters: params{ name = default, ... } at the top level. The
-- default's kind is the parameter's type; rgb() and image() mark the kinds a
-- plain value cannot show.
local KIND_MARK = {}
local function rgb(r, g, b)
  local v
  if isvec(r) then v = r elseif g == nil and b == nil then v = vec3(r) else v = vec3_t(r, g, b) end
  return { [KIND_MARK] = "rgb", value = v }
end
local function image_param(name)
  if type(name) ~= "string" and type(name) ~= "number" then
    error(format("image(name): expected the name of one of the scene's images, got a %s", typename(name)), 2)
  end
  return { [KIND_MARK] = "image", value = tostring(name) }
end
local function kind_of(v)
  if type(v) == "table" and v[KIND_MARK] then return v[KIND_MARK], v.value end
  if type(v) == "number" then return "number", v end
  if type(v) == "string" then return "string", v end
  if isvec(v) then return "vec3", v end
  return nil
end
local function show(kind, v)
  if kind == "rgb" or kind == "vec3" then return format("(%g, %g, %g)", v.x, v.y, v.z) end
  if kind == "string" or kind == "image" then return format("%q", v) end
  return tostring(v)
end
local function image_list()
  local known = {}
  for k in pairs(image_names) do known[#known + 1] = format("%q", k) end
  table.sort(known)
  return #known > 0 and table.concat(known, ", ") or "none"
end
-- What the scene gave, as the scene gave it: "number", "vec3" or "string".
local function scene_kind(v)
  if type(v) == "table" then return "vec3" end
  return type(v)
end
-- The scene's value converted to the declared kind, or nil and the reason.
local function convert(kind, v)
  local given = scene_kind(v)
  if kind == "number" then
    if given == "number" then return v end
  elseif kind == "rgb" then
    if given == "vec3" then return vec3_t(v[1], v[2], v[3]) end
    if given == "number" then return vec3(v) end
  elseif kind == "vec3" then
    if given == "vec3" then return vec3_t(v[1], v[2], v[3]) end
  elseif kind == "string" then
    if given == "string" or given == "number" then return tostring(v) end
  elseif kind == "image" then
    if given == "string" or given == "number" then
      local name = tostring(v)
      if image_names[name] == nil then
        return nil, format("names no image of the scene (its images: %s)", image_list())
      end
      return name
    end
  end
  local want = { number = "one number", rgb = "an rgb colour (three numbers, or one for grey)",
    vec3 = "a vec3 (three numbers)", string = "text", image = "an image's name" }
  local got = { number = "a number", vec3 = "three numbers", string = "text" }
  return nil, format("is %s, but the script declares %s", got[given] or given, want[kind])
end

---------------------------------------------------------------------------
-- range(default, min, max) inside params{}: a number parameter whose
-- slider in the watch page's editor spans min..max; the script sees a plain
-- number. declaration_of() lists what params{} declared for Rust
-- (ShaderSet::declared): name, kind, default and range of each.
---------------------------------------------------------------------------
local function range_param(default, lo, hi)
  for i, v in ipairs({ default, lo, hi }) do
    if type(v) ~= "number" or v ~= v or v == math.huge or v == -math.huge then
      error(format("range(default, min, max): argument %d must be a finite number, got %s", i,
        type(v) == "number" and tostring(v) or typename(v)), 2)
    end
  end
  if not (lo < hi) or default < lo or default > hi then
    error(format("range(%g, %g, %g): expected min < max and the default between them", default, lo, hi), 2)
  end
  return { [KIND_MARK] = "number", value = default, min = lo, max = hi }
end
local function declaration_of(names, decl, kinds)
  local out = {}
  for i, name in ipairs(names) do
    local kind, v = kinds[name][1], kinds[name][2]
    if kind == "rgb" or kind == "vec3" then v = { v.x, v.y, v.z } end
    local d = decl[name]
    local ranged = type(d) == "table" and d.min ~= nil
    out[i] = { name = name, kind = kind, value = v, min = ranged and d.min or nil, max = ranged and d.max or nil }
  end
  return out
end

local require_module
-- The derivatives' record (see the Derivatives section): `offset` is set
-- during an offset run, where print stays quiet, so a call prints once.
local derivs = ffi.new("luster_derivs")
local function make_env(shader_name, params)
  local env = {}
  env.require = require_module
  for _, k in ipairs(SAFE_GLOBALS) do env[k] = real_globals[k] end
  for k, v in pairs(BUILTINS) do env[k] = v end
  env.math = copy(math, { random = true, randomseed = true })
  setmetatable(env.math, removed("math.", { random = RANDOM_WHY, randomseed = RANDOM_WHY }))
  env.string = copy(string)
  setmetatable(env.string, removed("string.", { dump = "it would expose compiled code" }))
  env.table = copy(table)
  env.table.sort, env.table.move, env.table.concat = safe_sort, safe_move, safe_concat
  env.table.foreach, env.table.foreachi = safe_foreach, safe_foreachi
  env.bit = copy(bit)
  env.coroutine = copy(coroutine)
  env.coroutine.resume, env.coroutine.wrap = safe_resume, safe_wrap
  env.print = function(...)
    if derivs.offset ~= 0 then return end
    local n = select("#", ...)
    local parts = { ... }
    for i = 1, n do parts[i] = tostring(parts[i]) end
    log(shader_name, table.concat(parts, "\t", 1, n), shade.pixel_x, shade.pixel_y)
  end
  local param = {}
  for k, v in pairs(params) do
    if type(v) == "table" then v = vec3_t(v[1], v[2], v[3]) end
    param[k] = v
  end
  env.param = param
  env.rgb = rgb
  env.image = image_param
  env.range = range_param
  local declared, declaration = false, {}
  env.params = function(decl)
    if declared then error("params{...} may be called only once", 2) end
    if type(decl) ~= "table" then error("params{...} takes a table of name = default", 2) end
    declared = true
    local names, kinds = {}, {}
    for name, default in pairs(decl) do
      local kind, value = kind_of(default)
      if type(name) ~= "string" or kind == nil then
        error(format("params: '%s' has a default of type %s; use a number, rgb(r, g, b), vec3(x, y, z), "
          .. "image(\"name\") or a string", tostring(name), typename(default)), 2)
      end
      names[#names + 1] = name
      kinds[name] = { kind, value }
    end
    table.sort(names)
    declaration = declaration_of(names, decl, kinds)
    local listed = {}
    for i, name in ipairs(names) do
      local k = kinds[name]
      listed[i] = format("%s (%s, default %s)", name, k[1], show(k[1], k[2]))
    end
    local declares = #listed > 0 and table.concat(listed, ", ") or "none"
    local given = {}
    for name in pairs(params) do given[#given + 1] = name end
    table.sort(given)
    for _, name in ipairs(given) do
      if kinds[name] == nil then
        error(format("the scene's parameter '%s' is not one the script declares; it declares: %s",
          name, declares), 2)
      end
    end
    for _, name in ipairs(names) do
      local kind, default = kinds[name][1], kinds[name][2]
      if params[name] == nil then
        param[name] = default
      else
        local v, why = convert(kind, params[name])
        if v == nil then
          error(format("the scene's parameter '%s' %s; the script declares: %s", name, why, declares), 2)
        end
        param[name] = v
      end
    end
    setmetatable(param, {
      __index = function(_, k)
        error(format("param.%s is not declared; the script declares: %s", tostring(k), declares), 2)
      end,
    })
  end
  env._G = env
  setmetatable(env, removed("", REMOVED))
  return env, function() return declared, declaration end
end

---------------------------------------------------------------------------
-- require "name": Rust finds and reads the file inside the allowed folders
-- (modules.rs) and instruments it for the time limit; here it runs once per
-- state, in its own sandboxed environment, and its result is cached. A
-- module being loaded that is required again is a cycle, an error.
---------------------------------------------------------------------------
-- Results by name, and by file: "lib.wood" and "lib/wood" are one module.
local by_name, by_file, module_loading, loading_chain = {}, {}, {}, {}
require_module = function(name)
  if type(name) ~= "string" then
    error(format("require: expected a module name (a string), got a %s", typename(name)), 2)
  end
  local cached = by_name[name]
  if cached ~= nil then return cached end
  local file, code, key = load_module(name)
  if not file then error(code, 2) end
  cached = by_file[key]
  if cached ~= nil then
    by_name[name] = cached
    return cached
  end
  if module_loading[key] then
    local chain = {}
    for i, n in ipairs(loading_chain) do chain[i] = format("'%s'", n) end
    chain[#chain + 1] = format("'%s'", name)
    error(format("require: modules require each other in a cycle: %s", table.concat(chain, " -> ")), 2)
  end
  local f, err = loadstring(code, "@" .. file)
  if not f then error(err, 0) end
  setfenv(f, (make_env("module " .. name, {})))
  module_loading[key] = true
  loading_chain[#loading_chain + 1] = name
  local ok, result = pcall(f, tick)
  loading_chain[#loading_chain] = nil
  module_loading[key] = nil
  if not ok then error(result, 0) end
  if result == nil then result = true end
  by_name[name], by_file[key] = result, result
  return result
end

---------------------------------------------------------------------------
-- Derivatives (docs/derivatives.md): Dx(v), Dy(v) and filterwidth(v) of any
-- number or vec3 an entry function computes. A function that asks for one
-- runs three times per call: at the point moved one pixel right (P + dPdx,
-- Pw + dPwdx, Pc + dPcdx, uv + duvdx; everything else unchanged), one pixel
-- down, and at the point itself. The two offset runs record the values
-- handed to the derivative functions, in call order (a tape); in the main
-- run the k-th call returns the k-th taped value minus its own. Only the
-- main run's result counts. Until a function first asks, it runs once per
-- call; the call in which it first asks raises REDO, and Rust starts that
-- call again (`derivs.redo`), now in triple mode, so that a point's result
-- never depends on which calls came before it. A script that catches REDO
-- with pcall is redone all the same: Rust reads the flag, not the error.
---------------------------------------------------------------------------
local derivs_wrap
-- A function of its own: a function may have only 200 locals.
;(function()
local D_SINGLE, D_RECORD, D_MAIN = 0, 1, 2
local dmode = D_SINGLE
-- The wrapped entry function running in single mode (its triple flag).
local dcurrent = nil
local REDO = "luster: derivatives need the call again"
-- A cap on the derivative calls of one run, so that a loop cannot grow the
-- tape without bound.
local MAX_TAPE = 65536
-- Two tapes (the x and the y offset), each as four arrays: kind (1 a number,
-- 3 a vec3) and the components; na, nb: their lengths in this call.
local tka, ta1, ta2, ta3 = {}, {}, {}, {}
local tkb, tb1, tb2, tb3 = {}, {}, {}, {}
local na, nb = 0, 0
-- The tape being recorded, its length, and the main run's count.
local rk, r1, r2, r3 = tka, ta1, ta2, ta3
local nrec, kmain = 0, 0

local function need_triple(fname, level)
  local st = dcurrent
  if st == nil then
    error(format("%s works only while an entry function such as color(s) runs", fname), level + 1)
  end
  st.triple = true
  derivs.redo = 1
  error(REDO, 0)
end
-- A difference that is not finite (the value is undefined at an offset
-- point) counts as no change.
local function fin(d) if d - d == 0 then return d end return 0 end
-- The derivative call of `fname` with value v, whose caller's caller is
-- the user's code at `level` from here: v's kind and its change along x
-- and along y (all 0 in an offset run).
local function delta(fname, v, level)
  local kind, a, b, c
  if type(v) == "number" then
    kind, a, b, c = 1, v, 0, 0
  elseif isvec(v) then
    kind, a, b, c = 3, v.x, v.y, v.z
  else
    error(format("%s: expected a number or a vec3, got a %s", fname, typename(v)), level)
  end
  local m = dmode
  if m == D_MAIN then
    local k = kmain + 1
    kmain = k
    local x1, x2, x3, y1, y2, y3 = 0, 0, 0, 0, 0, 0
    -- A tape that is shorter, or holds another kind here, took another
    -- branch: no derivative.
    if k <= na and tka[k] == kind then x1, x2, x3 = fin(ta1[k] - a), fin(ta2[k] - b), fin(ta3[k] - c) end
    if k <= nb and tkb[k] == kind then y1, y2, y3 = fin(tb1[k] - a), fin(tb2[k] - b), fin(tb3[k] - c) end
    return kind, x1, x2, x3, y1, y2, y3
  elseif m == D_RECORD then
    local k = nrec + 1
    if k > MAX_TAPE then
      error(format("%s: more than %d derivative calls in one call of the shader", fname, MAX_TAPE), level)
    end
    nrec = k
    rk[k], r1[k], r2[k], r3[k] = kind, a, b, c
    return kind, 0, 0, 0, 0, 0, 0
  end
  need_triple(fname, level)
end

-- Dx(v), Dy(v): the change of v to the next pixel right (down), a number
-- or a vec3 like v.
local function Dx(v)
  local kind, x1, x2, x3 = delta("Dx", v, 3)
  if kind == 1 then return x1 end
  return vec3_t(x1, x2, x3)
end
local function Dy(v)
  local kind, _, _, _, y1, y2, y3 = delta("Dy", v, 3)
  if kind == 1 then return y1 end
  return vec3_t(y1, y2, y3)
end
local function width(x, y) return sqrt(x * x + y * y) end
-- filterwidth(v): OSL's, sqrt(Dx(v)^2 + Dy(v)^2), per component of a vec3.
-- filterwidth(s, [scale]) of the shading point keeps its meaning.
local function filterwidth_any(v, scale)
  if type(v) == "cdata" and ffi.istype(shade_t, v) then return filterwidth(v, scale) end
  if scale ~= nil then
    error("filterwidth(v) takes one value (filterwidth(s, scale) takes the shading point s)", 2)
  end
  local kind, x1, x2, x3, y1, y2, y3 = delta("filterwidth", v, 3)
  if kind == 1 then return width(x1, y1) end
  return vec3_t(width(x1, y1), width(x2, y2), width(x3, y3))
end
-- aastep(edge, x, [fw]): without fw, the width is filterwidth(x - edge) (an
-- edge that varies too is filtered right); a given fw wins, 0 is the hard
-- step.
local function aastep_auto(edge, x, fw)
  if fw == nil then
    if type(x) ~= "number" or type(edge) ~= "number" then
      error(format("aastep: expected numbers for edge and x, got a %s and a %s", typename(edge),
        typename(x)), 2)
    end
    local _, x1, _, _, y1 = delta("aastep", x - edge, 3)
    fw = width(x1, y1)
  end
  return aastep(edge, x, fw)
end
BUILTINS.Dx, BUILTINS.Dy = Dx, Dy
BUILTINS.filterwidth, BUILTINS.aastep = filterwidth_any, aastep_auto

-- The offset points of one call (offset runs never nest: entry functions
-- are wrapped only where Rust calls them).
local sx, sy = ffi.new("luster_shade"), ffi.new("luster_shade")
local SHADE_BYTES = ffi.sizeof("luster_shade")
local function moved(dst, s, dP, dPw, dPc, duv)
  ffi.copy(dst, s, SHADE_BYTES)
  dst.P.x, dst.P.y, dst.P.z = s.P.x + dP.x, s.P.y + dP.y, s.P.z + dP.z
  dst.Pw.x, dst.Pw.y, dst.Pw.z = s.Pw.x + dPw.x, s.Pw.y + dPw.y, s.Pw.z + dPw.z
  dst.Pc.x, dst.Pc.y, dst.Pc.z = s.Pc.x + dPc.x, s.Pc.y + dPc.y, s.Pc.z + dPc.z
  dst.uv.u, dst.uv.v = s.uv.u + duv.u, s.uv.v + duv.v
end
local function zero3(v) return v.x == 0 and v.y == 0 and v.z == 0 end
-- A point with no footprint (a volume, a baked grid) has no derivatives:
-- its offset runs would see the point itself.
local function still(s)
  return zero3(s.dPdx) and zero3(s.dPdy) and zero3(s.dPwdx) and zero3(s.dPwdy) and zero3(s.dPcdx)
    and zero3(s.dPcdy) and s.duvdx.u == 0 and s.duvdx.v == 0 and s.duvdy.u == 0 and s.duvdy.v == 0
end
-- One offset run: its result is dropped, and so is an error it raises (the
-- main run reports what is wrong at the point itself; a timeout stops the
-- main run too). The tape's length.
local function offset_pass(f, p, fresh)
  if fresh then fresh() end
  nrec, dmode, derivs.offset = 0, D_RECORD, 1
  -- Each run may cast the whole per-call ray budget (trace()).
  clock.rays = 0
  pcall(f, p)
  derivs.offset = 0
  return nrec
end
local function triple(f, s, fresh)
  if still(s) then
    na, nb = 0, 0
  else
    moved(sx, s, s.dPdx, s.dPwdx, s.dPcdx, s.duvdx)
    moved(sy, s, s.dPdy, s.dPwdy, s.dPcdy, s.duvdy)
    rk, r1, r2, r3 = tka, ta1, ta2, ta3
    na = offset_pass(f, sx, fresh)
    rk, r1, r2, r3 = tkb, tb1, tb2, tb3
    nb = offset_pass(f, sy, fresh)
  end
  if fresh then fresh() end
  dmode, kmain, clock.rays = D_MAIN, 0, 0
  return f(s)
end
-- An entry function as the wrappers below call it: once per call until it
-- asks for a derivative, then three times. `fresh` (for material(s))
-- clears what a run leaves behind before the next.
derivs_wrap = function(f, fresh)
  if f == nil then return nil end
  local st = { triple = false }
  return function(s)
    if st.triple then return triple(f, s, fresh) end
    dmode, dcurrent = D_SINGLE, st
    return f(s)
  end
end
end)()

---------------------------------------------------------------------------
-- Entry wrappers: Rust writes the shading point into `shade`, calls the
-- wrapper with no arguments, and reads `out`. Results are checked here, where
-- their Lua types are still known.
---------------------------------------------------------------------------
-- NaN and the infinities fail `v - v == 0`; every other number passes.
local function finite(v)
  return type(v) == "number" and v - v == 0
end
local function describe(v)
  if v ~= v then return "NaN" end
  if v == math.huge then return "inf" end
  if v == -math.huge then return "-inf" end
  if v == nil then return "nothing (nil)" end
  if type(v) == "number" then return tostring(v) end
  return "a " .. typename(v)
end
local function bad(shader_name, entry, what)
  out.bad = 1
  error(format("shader '%s': %s() returned %s", shader_name, entry, what), 0)
end
local channel_names = { "red", "green", "blue" }
-- A colour entry's result (r, g, b numbers or a vec3) as three numbers; a
-- value that is not finite is an error naming its channel.
local function finite_rgb(shader_name, entry, r, g, b)
  if isvec(r) and g == nil then r, g, b = r.x, r.y, r.z end
  if finite(r) and finite(g) and finite(b) then return r, g, b end
  for i = 1, 3 do
    local v = select(i, r, g, b)
    if not finite(v) then
      bad(shader_name, entry, format("%s as its %s value (expected finite r, g, b numbers or a vec3)", describe(v), channel_names[i]))
    end
  end
end
local function color_entry(f, shader_name, entry)
  return function()
    out.r, out.g, out.b = finite_rgb(shader_name, entry, f(shade))
  end
end
-- Entry points that return one number: height, density.
local function scalar_entry(f, shader_name, entry)
  return function()
    local h = f(shade)
    if finite(h) then
      out.r = h
      return
    end
    bad(shader_name, entry, describe(h) .. " (expected a finite number)")
  end
end
-- The bump wrapper: height() at the three points shade, shade_b and shade_c,
-- into out.r, g, b. One call from Rust instead of three cuts the call overhead
-- of bump mapping to a third. Each point has its own record, all written by
-- Rust before the call, so a script that writes to s cannot change the next
-- point (and no record is copied: a 344-byte ffi.copy is a memcpy call).
local function height3_entry(f, shader_name)
  local function one(s)
    local v = f(s)
    if not finite(v) then
      bad(shader_name, "height", describe(v) .. " (expected a finite number)")
    end
    return v
  end
  return function()
    out.r = one(shade)
    out.g = one(shade_b)
    out.b = one(shade_c)
  end
end
local function make_height3(env, shader_name)
  local f = env.height
  if type(f) ~= "function" then return nil end
  return height3_entry(derivs_wrap(f), shader_name)
end
local function make_entry(env, entry, shader_name)
  local f = env[entry]
  -- A built-in of the same name (the emission{} constructor) is no entry
  -- point, and material(s) is called through make_material alone.
  if type(f) ~= "function" or f == BUILTINS[entry] or entry == "material" then return nil end
  f = derivs_wrap(f)
  if entry == "height" or entry == "density" or entry == "roughness" or entry == "metalness" then
    return scalar_entry(f, shader_name, entry)
  end
  return color_entry(f, shader_name, entry)
end

---------------------------------------------------------------------------
-- Closures (docs/closures.md): material(s) returns a tree of BSDF nodes that
-- the constructors below write straight into the `material` record, children
-- before parents, as they run. A closure value is a small cdata holding its
-- node's index and the call it was built in (`gen`): it costs no Lua table,
-- its + and * are metamethods, and one kept from an earlier call is refused
-- (its node has been overwritten since). The kind numbers are NodeKind's
-- order in closure.rs.
---------------------------------------------------------------------------
-- A function of its own: a function may have only 200 locals.
;(function()
local closure_mul
local MAX_NODES = 32
local K_DIFFUSE, K_CONDUCTOR, K_DIELECTRIC, K_SHEEN, K_EMISSION = 0, 1, 2, 3, 4
local K_TRANSPARENT, K_ADD, K_SCALE, K_LAYER = 5, 6, 7, 8
local KIND_NAMES = { [0] = "diffuse", "conductor", "dielectric", "sheen", "emission", "transparent",
  "add", "scale", "layer" }
local FLT_MAX = 3.4028234663852886e38
local nodes = material.nodes
-- The current call of a material wrapper, and whether one is running: a
-- closure built at the top level or in another entry point would be stale
-- before any call could return it.
local gen, building = 0, false
local closure_t
local EMPTY = {}
local CLOSURE_EXAMPLE = "a closure such as diffuse{...}"

-- Every check helper below is called by a constructor or operator, which
-- the user's code called: level 4 from here is the user's line. `extra`
-- counts further prelude frames in between.
local function fail(msg, extra)
  error(msg, 4 + (extra or 0))
end
local function a_type(v)
  if v == nil then return "nothing (nil)" end
  return "a " .. typename(v)
end
local function unknown_key(who, fname, k, list)
  fail(format("%s: unknown parameter '%s' (%s takes %s)", who, tostring(k), fname, list), 1)
end
-- Unknown names are the likeliest mistake (a misspelt parameter would
-- otherwise silently take its default).
local function check_keys(t, who, fname, known, list)
  if type(t) ~= "table" or t[KIND_MARK] ~= nil then
    fail(format("%s takes one table of named parameters (%s), got %s", who, list, a_type(t)))
  end
  -- The first keys one next() at a time, without a loop: a loop here
  -- (pairs or counted) would be a trace of its own, entered and left on
  -- every call, costing more than the rest of the constructor.
  local k = next(t)
  if k == nil then return end
  if not known[k] then unknown_key(who, fname, k, list) end
  k = next(t, k)
  if k == nil then return end
  if not known[k] then unknown_key(who, fname, k, list) end
  k = next(t, k)
  if k == nil then return end
  if not known[k] then unknown_key(who, fname, k, list) end
  k = next(t, k)
  if k == nil then return end
  if not known[k] then unknown_key(who, fname, k, list) end
  k = next(t, k)
  if k == nil then return end
  if not known[k] then unknown_key(who, fname, k, list) end
  k = next(t, k)
  if k == nil then return end
  if not known[k] then unknown_key(who, fname, k, list) end
  k = next(t, k)
  if k == nil then return end
  if not known[k] then unknown_key(who, fname, k, list) end
  k = next(t, k)
  if k == nil then return end
  if not known[k] then unknown_key(who, fname, k, list) end
  -- More than eight (openpbr{} with many parameters).
  k = next(t, k)
  while k ~= nil do
    if not known[k] then unknown_key(who, fname, k, list) end
    k = next(t, k)
  end
end
local function range_text(lo, hi)
  if hi == FLT_MAX then return "a finite number, 0 or more" end
  return format("a number from %g to %g", lo, hi)
end
local function num_arg(v, default, who, pname, lo, hi)
  if v == nil then return default end
  if type(v) == "number" and v >= lo and v <= hi then return v end
  local what = type(v) == "number" and describe(v) or a_type(v)
  fail(format("%s: %s is %s (expected %s)", who, pname, what, range_text(lo, hi)))
end
local function bool_arg(v, default, who, pname)
  if v == nil then return default end
  if v == true or v == false then return v end
  fail(format("%s: %s is %s (expected true or false)", who, pname, a_type(v)))
end
local function color_expected(hi)
  return format("%s, or a colour: rgb(r, g, b), vec3(r, g, b) or {r, g, b} with each value %s",
    range_text(0, hi), hi == FLT_MAX and "finite and 0 or more" or format("from 0 to %g", hi))
end
local function color_range_msg(who, pname, r, g, b, hi)
  for i = 1, 3 do
    local v = select(i, r, g, b)
    if not (v >= 0 and v <= hi) then
      local expect = hi == FLT_MAX and "finite, 0 or more" or format("0 to %g", hi)
      return format("%s: %s's %s value is %s (expected %s)", who, pname, channel_names[i], describe(v), expect)
    end
  end
end
-- A colour parameter: a number (grey), a vec3, rgb(...) or {r, g, b}, each
-- value from 0 to hi (FLT_MAX: any finite value f32 holds). nil takes the
-- default grey.
local function color_arg(v, default, who, pname, hi)
  local r, g, b
  if type(v) == "number" then
    if v >= 0 and v <= hi then return v, v, v end
    fail(format("%s: %s is %s (expected %s)", who, pname, describe(v), color_expected(hi)))
  elseif v == nil then
    return default, default, default
  elseif isvec(v) then
    r, g, b = v.x, v.y, v.z
  elseif type(v) == "table" then
    local mark = v[KIND_MARK]
    if mark == "rgb" then
      local c = v.value
      r, g, b = c.x, c.y, c.z
    elseif mark == nil then
      r, g, b = v[1], v[2], v[3]
      if r == nil and g == nil and b == nil then r, g, b = v.r, v.g, v.b end
    end
    if type(r) ~= "number" or type(g) ~= "number" or type(b) ~= "number" then
      fail(format("%s: %s is a table without three numbers (expected %s)", who, pname, color_expected(hi)))
    end
  else
    fail(format("%s: %s is %s (expected %s)", who, pname, a_type(v), color_expected(hi)))
  end
  if r >= 0 and r <= hi and g >= 0 and g <= hi and b >= 0 and b <= hi then return r, g, b end
  fail(color_range_msg(who, pname, r, g, b, hi))
end
local STALE = "a closure from an earlier call of material(s) (a closure lasts for the call that built it: "
  .. "build closures inside material(s) on every call)"
-- A closure operand's node index.
local function closure_arg(v, who, pname)
  if is_closure(v) then
    if v.gen == gen then return v.index end
    fail(format("%s: %s is %s", who, pname, STALE))
  end
  local what = v == nil and "missing" or a_type(v)
  fail(format("%s: %s is %s (expected %s)", who, pname, what, CLOSURE_EXAMPLE))
end
-- Appends one node; its index. Every field is written: the record is not
-- cleared between calls.
local function emit(extra, who, kind, a, b, thin, r0, g0, b0, r1, g1, b1, x0, x1, x2)
  local n = material.closure_len
  if not building then
    fail(format("%s: closures can be built only while material(s) runs (not at the top level or in "
      .. "another function's call)", who), extra)
  end
  if n >= MAX_NODES then
    fail(format("%s: the closure would have more than %d nodes (each constructor, + and layer adds one, "
      .. "a weight other than 1 one, mix three)", who, MAX_NODES), extra)
  end
  local node = nodes[n]
  node.kind, node.a, node.b, node.thin = kind, a, b, thin
  local c = node.c
  c[0][0], c[0][1], c[0][2] = r0, g0, b0
  c[1][0], c[1][1], c[1][2] = r1, g1, b1
  c[2][0], c[2][1], c[2][2] = 0, 0, 0
  local x = node.x
  x[0], x[1], x[2] = x0, x1, x2
  material.closure_len = n + 1
  return n
end
-- (1 - t) a + t b, as two Scale nodes and an Add.
local function mix_nodes(extra, who, ia, ib, r, g, b)
  local sa = emit(extra + 1, who, K_SCALE, ia, 0, 0, 1 - r, 1 - g, 1 - b, 0, 0, 0, 0, 0, 0)
  local sb = emit(extra + 1, who, K_SCALE, ib, 0, 0, r, g, b, 0, 0, 0, 0, 0, 0)
  -- Not a tail call: fail's levels count this frame.
  local n = emit(extra + 1, who, K_ADD, sa, sb, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0)
  return n
end

local DIFFUSE = { albedo = true, roughness = true }
local function c_diffuse(t)
  local W = "diffuse{}"
  t = t or EMPTY
  check_keys(t, W, "diffuse", DIFFUSE, "albedo, roughness")
  local r, g, b = color_arg(t.albedo, 0.8, W, "albedo", 1)
  local rough = num_arg(t.roughness, 0, W, "roughness", 0, 1)
  return closure_t(gen, emit(0, W, K_DIFFUSE, 0, 0, 0, r, g, b, 0, 0, 0, rough, 0, 0))
end
local CONDUCTOR = { f0 = true, edge = true, roughness = true, anisotropy = true }
local function c_conductor(t)
  local W = "conductor{}"
  t = t or EMPTY
  check_keys(t, W, "conductor", CONDUCTOR, "f0, edge, roughness, anisotropy")
  local fr, fg, fb = color_arg(t.f0, 1, W, "f0", 1)
  local er, eg, eb = color_arg(t.edge, 1, W, "edge", 1)
  local rough = num_arg(t.roughness, 0, W, "roughness", 0, 1)
  local aniso = num_arg(t.anisotropy, 0, W, "anisotropy", 0, 1)
  return closure_t(gen, emit(0, W, K_CONDUCTOR, 0, 0, 0, fr, fg, fb, er, eg, eb, rough, aniso, 0))
end
local DIELECTRIC = { ior = true, roughness = true, anisotropy = true, tint = true, specular = true, thin = true }
local function c_dielectric(t)
  local W = "dielectric{}"
  t = t or EMPTY
  check_keys(t, W, "dielectric", DIELECTRIC, "ior, roughness, anisotropy, tint, specular, thin")
  local ior = num_arg(t.ior, 1.5, W, "ior", 1, 5)
  local rough = num_arg(t.roughness, 0, W, "roughness", 0, 1)
  local aniso = num_arg(t.anisotropy, 0, W, "anisotropy", 0, 1)
  local tr, tg, tb = color_arg(t.tint, 1, W, "tint", 1)
  local sr, sg, sb = color_arg(t.specular, 1, W, "specular", 1)
  local thin = bool_arg(t.thin, false, W, "thin") and 1 or 0
  return closure_t(gen, emit(0, W, K_DIELECTRIC, 0, 0, thin, tr, tg, tb, sr, sg, sb, ior, rough, aniso))
end
local SHEEN = { color = true, roughness = true }
local function c_sheen(t)
  local W = "sheen{}"
  t = t or EMPTY
  check_keys(t, W, "sheen", SHEEN, "color, roughness")
  local r, g, b = color_arg(t.color, 1, W, "color", 1)
  local rough = num_arg(t.roughness, 0.3, W, "roughness", 0, 1)
  return closure_t(gen, emit(0, W, K_SHEEN, 0, 0, 0, r, g, b, 0, 0, 0, rough, 0, 0))
end
local EMISSION = { radiance = true }
local function c_emission(t)
  local W = "emission{}"
  t = t or EMPTY
  check_keys(t, W, "emission", EMISSION, "radiance")
  local r, g, b = color_arg(t.radiance, 1, W, "radiance", FLT_MAX)
  return closure_t(gen, emit(0, W, K_EMISSION, 0, 0, 0, r, g, b, 0, 0, 0, 0, 0, 0))
end
local TRANSPARENT = { color = true }
local function c_transparent(t)
  local W = "transparent{}"
  t = t or EMPTY
  check_keys(t, W, "transparent", TRANSPARENT, "color")
  local r, g, b = color_arg(t.color, 1, W, "color", 1)
  return closure_t(gen, emit(0, W, K_TRANSPARENT, 0, 0, 0, r, g, b, 0, 0, 0, 0, 0, 0))
end
local LAYER = { top = true, base = true }
local function c_layer(t)
  local W = "layer{}"
  t = t or EMPTY
  check_keys(t, W, "layer", LAYER, "top, base")
  local top = closure_arg(t.top, W, "top")
  local base = closure_arg(t.base, W, "base")
  return closure_t(gen, emit(0, W, K_LAYER, top, base, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0))
end
local function closure_add(a, b)
  local W = "closure +"
  local ia = closure_arg(a, W, "the left operand")
  local ib = closure_arg(b, W, "the right operand")
  return closure_t(gen, emit(0, W, K_ADD, ia, ib, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0))
end
local function no_weight(who, pname)
  fail(format("%s: %s is missing (expected %s)", who, pname, color_expected(1)))
end
-- w * a or a * w; a weight of exactly 1 adds no node.
closure_mul = function(a, b)
  local W = "closure *"
  local c, w = a, b
  if not is_closure(a) then c, w = b, a end
  if is_closure(w) then
    fail("closure *: both operands are closures (expected a closure and a weight: a number or a colour "
      .. "from 0 to 1)", -1)
  end
  local ic = closure_arg(c, W, "the closure")
  if w == nil then no_weight(W, "the weight") end
  local r, g, bb = color_arg(w, 1, W, "the weight", 1)
  if r == 1 and g == 1 and bb == 1 then return c end
  return closure_t(gen, emit(0, W, K_SCALE, ic, 0, 0, r, g, bb, 0, 0, 0, 0, 0, 0))
end
-- (1 - t) a + t b; t of exactly 0 or 1 is a or b itself, adding no node.
local function closure_mix(a, b, t)
  local W = "mix()"
  local ia = closure_arg(a, W, "the first closure")
  local ib = closure_arg(b, W, "the second closure")
  if t == nil then no_weight(W, "t") end
  local r, g, bb = color_arg(t, 1, W, "t", 1)
  if r == 0 and g == 0 and bb == 0 then return a end
  if r == 1 and g == 1 and bb == 1 then return b end
  return closure_t(gen, mix_nodes(0, W, ia, ib, r, g, bb))
end
-- mix() of numbers and vec3s as before; of closures, closure_mix.
local function mix_any(a, b, t)
  if is_closure(a) or is_closure(b) then return closure_mix(a, b, t) end
  return a + (b - a) * t
end

local CLOSURE_OPS = "closures are added (a + b), weighted (w * a) and mixed (mix(a, b, t))"
local function closure_no_op(op)
  return function() fail(format("closure %s: not defined: %s", op, CLOSURE_OPS), -1) end
end
closure_t = ffi.metatype("luster_closure", {
  __add = closure_add,
  __mul = closure_mul,
  __sub = closure_no_op("-"),
  __div = closure_no_op("/"),
  __unm = closure_no_op("-"),
  __pow = closure_no_op("^"),
  __mod = closure_no_op("%"),
  __concat = closure_no_op(".."),
  __index = function(_, k)
    error(format("a closure has no field '%s' (%s)", tostring(k), CLOSURE_OPS), 2)
  end,
  __newindex = function(_, k)
    error(format("a closure has no field '%s' (%s)", tostring(k), CLOSURE_OPS), 2)
  end,
  __tostring = function(c)
    if c.gen ~= gen then return "closure (from an earlier call)" end
    return format("closure #%d (%s)", c.index, KIND_NAMES[nodes[c.index].kind])
  end,
})

-- openpbr{...}: OpenPBR Surface 1.1's parameters on the constructors above
-- (docs/closures.md has the mapping). A branch whose weight is 0 builds no
-- nodes.
local OPENPBR_NAMES = { "base_weight", "base_color", "base_metalness", "base_diffuse_roughness",
  "specular_weight", "specular_color", "specular_roughness", "specular_ior", "specular_anisotropy",
  "transmission_weight", "transmission_color", "coat_weight", "coat_color", "coat_roughness", "coat_ior",
  "fuzz_weight", "fuzz_color", "fuzz_roughness", "emission_luminance", "emission_color",
  "subsurface_weight", "subsurface_color", "geometry_opacity", "geometry_thin_walled", "thin_walled" }
local OPENPBR = {}
for _, k in ipairs(OPENPBR_NAMES) do OPENPBR[k] = true end
local OPENPBR_LIST = table.concat(OPENPBR_NAMES, ", ")
-- OpenPBR's specular_weight scales the dielectric's F0 = ((ior - 1) / (ior
-- + 1))^2; the ior with that F0.
local function weighted_ior(ior, w)
  if w == 1 then return ior end
  local s = (ior - 1) / (ior + 1)
  local r = sqrt(min(w * s * s, 1))
  if r >= 1 then return 5 end
  return min((1 + r) / (1 - r), 5)
end
local function c_openpbr(t)
  local W = "openpbr{}"
  t = t or EMPTY
  check_keys(t, W, "openpbr", OPENPBR, OPENPBR_LIST)
  local bw = num_arg(t.base_weight, 1, W, "base_weight", 0, 1)
  local bcr, bcg, bcb = color_arg(t.base_color, 0.8, W, "base_color", 1)
  local metal = num_arg(t.base_metalness, 0, W, "base_metalness", 0, 1)
  local bdr = num_arg(t.base_diffuse_roughness, 0, W, "base_diffuse_roughness", 0, 1)
  local sw = num_arg(t.specular_weight, 1, W, "specular_weight", 0, 1)
  local scr, scg, scb = color_arg(t.specular_color, 1, W, "specular_color", 1)
  local sr = num_arg(t.specular_roughness, 0.3, W, "specular_roughness", 0, 1)
  local sior = num_arg(t.specular_ior, 1.5, W, "specular_ior", 1, 5)
  local sa = num_arg(t.specular_anisotropy, 0, W, "specular_anisotropy", 0, 1)
  local tw = num_arg(t.transmission_weight, 0, W, "transmission_weight", 0, 1)
  local tcr, tcg, tcb = color_arg(t.transmission_color, 1, W, "transmission_color", 1)
  local cw = num_arg(t.coat_weight, 0, W, "coat_weight", 0, 1)
  local ccr, ccg, ccb = color_arg(t.coat_color, 1, W, "coat_color", 1)
  local cr = num_arg(t.coat_roughness, 0, W, "coat_roughness", 0, 1)
  local cior = num_arg(t.coat_ior, 1.6, W, "coat_ior", 1, 5)
  local fw = num_arg(t.fuzz_weight, 0, W, "fuzz_weight", 0, 1)
  local fcr, fcg, fcb = color_arg(t.fuzz_color, 1, W, "fuzz_color", 1)
  local fr = num_arg(t.fuzz_roughness, 0.5, W, "fuzz_roughness", 0, 1)
  local el = num_arg(t.emission_luminance, 0, W, "emission_luminance", 0, FLT_MAX)
  local ecr, ecg, ecb = color_arg(t.emission_color, 1, W, "emission_color", 1)
  local ssw = num_arg(t.subsurface_weight, 0, W, "subsurface_weight", 0, 1)
  local sscr, sscg, sscb = color_arg(t.subsurface_color, 0.8, W, "subsurface_color", 1)
  local op = num_arg(t.geometry_opacity, 1, W, "geometry_opacity", 0, 1)
  local thin = (bool_arg(t.geometry_thin_walled, false, W, "geometry_thin_walled")
    or bool_arg(t.thin_walled, false, W, "thin_walled")) and 1 or 0

  local top
  if metal < 1 then
    local ior = weighted_ior(sior, sw)
    if tw < 1 then
      -- Subsurface until luster has it: the diffuse albedo leans towards
      -- subsurface_color.
      local ar, ag, ab = bcr + (sscr - bcr) * ssw, bcg + (sscg - bcg) * ssw, bcb + (sscb - bcb) * ssw
      local d = emit(0, W, K_DIFFUSE, 0, 0, 0, bw * ar, bw * ag, bw * ab, 0, 0, 0, bdr, 0, 0)
      local gloss = emit(0, W, K_DIELECTRIC, 0, 0, thin, 1, 1, 1, scr, scg, scb, ior, sr, sa)
      top = emit(0, W, K_LAYER, gloss, d, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0)
    end
    if tw > 0 then
      local clear = emit(0, W, K_DIELECTRIC, 0, 0, thin, tcr, tcg, tcb, scr, scg, scb, ior, sr, sa)
      if top then top = mix_nodes(0, W, top, clear, tw, tw, tw) else top = clear end
    end
  end
  if metal > 0 then
    local m = emit(0, W, K_CONDUCTOR, 0, 0, 0, bw * bcr, bw * bcg, bw * bcb, sw * scr, sw * scg, sw * scb,
      sr, sa, 0)
    if top then top = mix_nodes(0, W, top, m, metal, metal, metal) else top = m end
  end
  if cw > 0 then
    -- The layer passes the base what the weighted coat lets through:
    -- the same as mixing the coated and uncoated substrate, in fewer nodes.
    local coat = emit(0, W, K_DIELECTRIC, 0, 0, 0, ccr, ccg, ccb, 1, 1, 1, cior, cr, 0)
    if cw < 1 then coat = emit(0, W, K_SCALE, coat, 0, 0, cw, cw, cw, 0, 0, 0, 0, 0, 0) end
    top = emit(0, W, K_LAYER, coat, top, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0)
  end
  if fw > 0 then
    local fuzz = emit(0, W, K_SHEEN, 0, 0, 0, fcr, fcg, fcb, 0, 0, 0, fr, 0, 0)
    if fw < 1 then fuzz = emit(0, W, K_SCALE, fuzz, 0, 0, fw, fw, fw, 0, 0, 0, 0, 0, 0) end
    top = emit(0, W, K_LAYER, fuzz, top, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0)
  end
  if el > 0 then
    local e = emit(0, W, K_EMISSION, 0, 0, 0, el * ecr, el * ecg, el * ecb, 0, 0, 0, 0, 0, 0)
    top = emit(0, W, K_ADD, top, e, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0)
  end
  if op < 1 then
    local clear = emit(0, W, K_TRANSPARENT, 0, 0, 0, 1, 1, 1, 0, 0, 0, 0, 0, 0)
    if op > 0 then top = mix_nodes(0, W, clear, top, op, op, op) else top = clear end
  end
  return closure_t(gen, top)
end
BUILTINS.diffuse, BUILTINS.conductor, BUILTINS.dielectric = c_diffuse, c_conductor, c_dielectric
BUILTINS.sheen, BUILTINS.emission, BUILTINS.transparent = c_sheen, c_emission, c_transparent
BUILTINS.layer, BUILTINS.openpbr = c_layer, c_openpbr
BUILTINS.mix, BUILTINS.lerp = mix_any, mix_any
closures.mul, closures.emission = closure_mul, c_emission

-- The material(s) wrapper: a fresh node list per call.
local function closure_entry(f, shader_name)
  return function()
    gen = gen + 1
    material.closure_len = 0
    building = true
    local c = f(shade)
    building = false
    if is_closure(c) and c.gen == gen then
      material.closure_root = c.index
      return
    end
    if is_closure(c) then bad(shader_name, "material", STALE) end
    bad(shader_name, "material", format("%s (expected %s)", a_type(c), CLOSURE_EXAMPLE))
  end
end
closures.entry = closure_entry
-- A fresh node list for each run of a material(s) that takes derivatives:
-- the offset runs' nodes are dropped, and their closures are stale.
closures.fresh = function()
  gen = gen + 1
  material.closure_len = 0
  building = true
end
end)()

-- DecalMode material: every material output the script defines, in one call
-- from Rust, checked against its range (docs/shaders.md, "Material outputs").
-- hi == nil: no upper bound (emitted radiance).
local function material_color(f, shader_name, entry, dst, hi)
  local r, g, b = finite_rgb(shader_name, entry, f(shade))
  for i = 1, 3 do
    local v = select(i, r, g, b)
    if v < 0 or (hi and v > hi) then
      local range = hi and "0 to 1: a reflectance" or "0 or more: a radiance"
      bad(shader_name, entry, format("%s as its %s value (expected %s)", describe(v), channel_names[i], range))
    end
  end
  dst[0], dst[1], dst[2] = r, g, b
end
local function material_scalar(f, shader_name, entry)
  local v = f(shade)
  if not finite(v) then bad(shader_name, entry, describe(v) .. " (expected a finite number from 0 to 1)") end
  if v < 0 or v > 1 then bad(shader_name, entry, describe(v) .. " (expected a number from 0 to 1)") end
  return v
end
local function make_material(env, shader_name)
  -- A script that defines material(s) gives its closure alone.
  if type(env.material) == "function" then
    return closures.entry(derivs_wrap(env.material, closures.fresh), shader_name)
  end
  local color, specular, emission, reflect = env.color, env.specular, env.emission, env.reflect
  local roughness, metalness = env.roughness, env.metalness
  -- emission is also the closure constructor, which is no output.
  local function fn(f)
    if type(f) == "function" and f ~= closures.emission then return derivs_wrap(f) end
    return nil
  end
  color, specular, emission, reflect = fn(color), fn(specular), fn(emission), fn(reflect)
  roughness, metalness = fn(roughness), fn(metalness)
  if not (color or specular or emission or reflect or roughness or metalness) then return nil end
  return function()
    if color then material_color(color, shader_name, "color", material.color, 1) end
    if specular then material_color(specular, shader_name, "specular", material.specular, 1) end
    if reflect then material_color(reflect, shader_name, "reflect", material.reflect, 1) end
    if emission then material_color(emission, shader_name, "emission", material.emission, nil) end
    if roughness then material.roughness = material_scalar(roughness, shader_name, "roughness") end
    if metalness then material.metalness = material_scalar(metalness, shader_name, "metalness") end
  end
end

-- Rust calls each wrapper through a trampoline of its own. A trace that
-- starts in a function and reads an immutable upvalue of it (as a wrapper
-- reads f and the shader's name) is specialized to that closure, and on
-- leaving it stores the closure back into its frame slot as two 32-bit
-- halves, which the interpreter then reads as one 64-bit value: a load the
-- store buffer cannot forward, so it waits for every pending store (the
-- shading point Rust just wrote among them) to reach the cache: most of the time
-- of an empty call. The trampoline reaches the wrapper through a table,
-- which LuaJIT never makes a constant, so its own slot is left alone; a
-- chunk of its own gives each wrapper its own prototype, hence its own
-- root trace rather than one shared by all wrappers and dispatched by guards.
local TRAMPOLINE = "local t = ... return function() t[1]() end"
local function trampoline(wrapper)
  if wrapper == nil then return nil end
  local chunk, err = loadstring(TRAMPOLINE, "=luster")
  if not chunk then error(err, 0) end
  return chunk({ wrapper })
end

---------------------------------------------------------------------------
-- Attributes (attributes.rs): getattribute("name" [, default]) reads the
-- scene's user data for the object being shaded: the instance's own table,
-- then its geometry's, by the ids in the shading point (`shade`, or the s
-- passed first: getattribute(s, "name" [, default])). Rust hands the tables
-- over once per state (set_attributes), so a lookup is two table reads.
---------------------------------------------------------------------------
local set_attributes
-- A function of its own: the main chunk is near its 200 locals.
;(function()
  local by_instance, by_object, name_of = {}, {}, function() return nil end
  -- object:name, fetched from Rust on first use, by instance id (false: none).
  local names = {}
  local function object_name(s)
    local id = s.instance_id
    local n = names[id]
    if n == nil then
      n = name_of(id) or false
      names[id] = n
    end
    return n or nil
  end
  local KIND_NAMES = { number = "a number", string = "text" }
  local function kind_name(v)
    if isvec(v) then return "a vec3" end
    return KIND_NAMES[type(v)] or "a " .. typename(v)
  end
  local function getattribute(a, b, c)
    local s, name, default = shade, a, b
    if type(a) == "cdata" and ffi.istype(shade_t, a) then s, name, default = a, b, c end
    -- rgb(r, g, b), which marks a declared parameter's kind, is a colour here.
    if type(default) == "table" and default[KIND_MARK] then default = default.value end
    if type(name) ~= "string" then
      error(format("getattribute: expected an attribute name (a string), got %s", kind_name(name)), 2)
    end
    local v
    local t = by_instance[s.instance_id]
    if t then v = t[name] end
    if v == nil then
      t = by_object[s.object_id]
      if t then v = t[name] end
      if v == nil then
        if name == "object:name" then v = object_name(s) end
        if v == nil then return default end
      end
    end
    -- A copy: a script that changes the vector must not change what the
    -- next point (on any thread) reads.
    if isvec(v) then v = vec3_t(v.x, v.y, v.z) end
    -- The default's kind is the kind the script wants; a number serves as
    -- a grey vec3 or as text, anything else that differs is an error.
    if default == nil or (type(default) ~= "number" and type(default) ~= "string" and not isvec(default)) then
      return v
    end
    if type(v) == type(default) and isvec(v) == isvec(default) then return v end
    if type(v) == "number" then
      if isvec(default) then return vec3_t(v, v, v) end
      if type(default) == "string" then return tostring(v) end
    end
    error(format("getattribute: attribute '%s' of this object is %s, but the default is %s", name,
      kind_name(v), kind_name(default)), 2)
  end
  set_attributes = function(instances, objects, fetch_name)
    for _, tables in ipairs({ instances, objects }) do
      for _, t in pairs(tables) do
        for k, v in pairs(t) do
          if type(v) == "table" then t[k] = vec3_t(v[1], v[2], v[3]) end
        end
      end
    end
    by_instance, by_object, name_of, names = instances, objects, fetch_name, {}
  end
  BUILTINS.getattribute = getattribute
end)()

-- Scripts run in their own environments, but the real globals lose the
-- dangerous libraries too, as a second line of defence.
for _, k in ipairs({ "ffi", "jit", "debug", "require", "package", "io", "os", "load", "loadstring",
  "loadfile", "dofile", "getfenv", "setfenv", "newproxy", "module" }) do
  real_globals[k] = nil
end
-- Rust gets the record addresses as numbers (exact: addresses fit in 53 bits).
local function address(p) return tonumber(ffi.cast("uintptr_t", ffi.cast("void *", p))) end
return {
  make_env = make_env,
  make_entry = function(env, entry, name) return trampoline(make_entry(env, entry, name)) end,
  make_height3 = function(env, name) return trampoline(make_height3(env, name)) end,
  make_material = function(env, name) return trampoline(make_material(env, name)) end,
  tick = tick,
  -- LuaJIT's messages name the records by number ('struct 97'): the names
  -- the author knows them by.
  ctypes = { vec3 = tostring(ffi.typeof("luster_vec3")), ["shading point"] = tostring(shade_t),
    uv = tostring(vec2_t), closure = tostring(closure_ct) },
  shade = address(shade),
  shade_b = address(shade_b),
  shade_c = address(shade_c),
  out = address(out),
  material = address(material),
  clock = address(clock),
  sizes = { shade = ffi.sizeof("luster_shade"), out = ffi.sizeof("luster_out"),
    material = ffi.sizeof("luster_material"), node = ffi.sizeof("luster_node"),
    clock = ffi.sizeof("luster_clock"), cell = ffi.sizeof("luster_cell"),
    ray = ffi.sizeof("luster_ray"), hit = ffi.sizeof("luster_hit"),
    derivs = ffi.sizeof("luster_derivs") },
  set_attributes = set_attributes,
  derivs = address(derivs),
}

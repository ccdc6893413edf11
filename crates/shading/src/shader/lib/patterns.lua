-- patterns: POV-Ray's best-known patterns and warps under their POV-Ray
-- names, each with a filtered (antialiased) form. Built into luster: any
-- shader can `require "patterns"`, and a patterns.lua of the scene's own
-- folders takes its place. docs/patterns.md is the reference.
--
-- Every pattern is patterns.NAME(p, [fw], [options]): p a vec3, fw the
-- footprint's width around p (a number, or a vec3 of widths per axis such as
-- filterwidth_xyz(s, scale) gives), options a table. fw nil or 0 gives the
-- pattern itself; a width gives its average over the footprint: in closed
-- form where the pattern has one, for noise by weighting each octave by what
-- a box of that size keeps of it, otherwise from a few samples, with detail
-- finer than the footprint replaced by its mean.
local M = {}

local floor, abs, sqrt, sin, cos = math.floor, math.abs, math.sqrt, math.sin, math.cos
local asin, acos, atan2, max, min = math.asin, math.acos, math.atan2, math.max, math.min
local pi, huge = math.pi, math.huge
local format, concat, sort = string.format, table.concat, table.sort
local TAU = 2 * pi
-- Widths past this are "everything": averages stay finite.
local MAX_WIDTH = 1e9
-- The variance of perlin3 over space (measured in tests_patterns.rs), which
-- dents' filtered form needs: the mean of a cube is not the cube of the mean.
local PERLIN_VARIANCE = 0.0736
local NONE = {}

local function clamp01(v)
  if v < 0 then return 0 elseif v > 1 then return 1 end
  if v ~= v then return 0 end
  return v
end

-- sin(x)/x: the average of a sinusoid over a box, relative to its value.
local function sinc(x)
  if abs(x) < 1e-4 then return 1 - x * x / 6 end
  return sin(x) / x
end

-- How much of the few samples to keep of a cellular pattern of frequency f
-- under a footprint of width w: all while the footprint spans under a
-- quarter of a cell, none from half (where four samples would alias), a
-- smooth fade between; the rest is the pattern's mean.
local function fade(w, f)
  local t = w * f
  if t <= 0.25 then return 1 end
  if t >= 0.5 then return 0 end
  local u = (t - 0.25) * 4
  return 1 - u * u * (3 - 2 * u)
end

local function geometric(omega, n)
  if omega == 1 then return n end
  return (1 - omega ^ n) / (1 - omega)
end

---------------------------------------------------------------------------
-- Wave types: POV-Ray reshapes a pattern's value v as shape(fract(v *
-- frequency + phase)). Each shape comes with its integral over [0, s] so that
-- a footprint spanning a width of v averages it exactly.
---------------------------------------------------------------------------
local SHAPES = {
  ramp = { f = function(s) return s end, F = function(s) return s * s / 2 end,
    mean = function() return 0.5 end },
  triangle = {
    f = function(s) if s < 0.5 then return 2 * s end return 2 - 2 * s end,
    F = function(s) if s < 0.5 then return s * s end return 2 * s - s * s - 0.5 end,
    mean = function() return 0.5 end,
  },
  sine = { f = function(s) return 0.5 + 0.5 * sin(TAU * s) end,
    F = function(s) return s / 2 + (1 - cos(TAU * s)) / (2 * TAU) end,
    mean = function() return 0.5 end },
  scallop = { f = function(s) return abs(sin(pi * s)) end,
    F = function(s) return (1 - cos(pi * s)) / pi end,
    mean = function() return 2 / pi end },
  cubic = { f = function(s) return s * s * (3 - 2 * s) end,
    F = function(s) return s * s * s - s * s * s * s / 2 end,
    mean = function() return 0.5 end },
  poly = { f = function(s, e) return s ^ e end,
    F = function(s, e) return s ^ (e + 1) / (e + 1) end,
    mean = function(e) return 1 / (e + 1) end },
}
local WAVE_NAMES = '"ramp", "triangle", "sine", "scallop", "cubic" or "poly"'

-- Agate's own profile, ((1 + sin 2πs) / 2)^0.77, has no closed-form
-- integral: it is tabulated (Simpson's rule per interval) once.
local AGATE
do
  local N = 512
  local function f(s) return ((1 + sin(TAU * s)) / 2) ^ 0.77 end
  local cum = { [0] = 0 }
  for i = 1, N do
    local a, b = (i - 1) / N, i / N
    cum[i] = cum[i - 1] + (b - a) / 6 * (f(a) + 4 * f((a + b) / 2) + f(b))
  end
  AGATE = {
    f = f,
    -- Within an interval, the trapezoid from its start to s.
    F = function(s)
      local i = min(floor(s * N), N - 1)
      local a = i / N
      return cum[i] + (s - a) * (f(a) + f(s)) / 2
    end,
    mean = function() return cum[N] end,
  }
end

-- The average of a periodic shape over [t - w/2, t + w/2], w > 0. The
-- interval is moved next to 0 first, so that a tiny width loses no precision.
local function periodic_average(sh, e, t, w)
  local lo = t - w / 2
  lo = lo - floor(lo)
  local hi = lo + w
  local k = floor(hi)
  return (k * sh.mean(e) + sh.F(hi - k, e) - sh.F(lo, e)) / w
end

-- shape(v * frequency + phase), averaged over a width vw of v. clipped: v
-- never leaves [0, 1] (a pattern clamped there), so the part of the box
-- beyond an end takes that end's value instead of wrapping round.
local function wave_value(sh, e, v, vw, freq, phase, clipped)
  if freq == 0 then
    -- No repetition: the shape of v itself, held at its ends.
    if vw <= 0 then return sh.f(clamp01(v), e) end
    local a, b = v - vw / 2, v + vw / 2
    local total = sh.F(clamp01(b), e) - sh.F(clamp01(a), e)
    if a < 0 then total = total + (min(b, 0) - a) * sh.f(0, e) end
    if b > 1 then total = total + (b - max(a, 1)) * sh.f(1, e) end
    return total / vw
  end
  local function at(u)
    local t = u * freq + phase
    return sh.f(t - floor(t), e)
  end
  if vw <= 0 then return at(v) end
  local a, b = v - vw / 2, v + vw / 2
  if not clipped or (a >= 0 and b <= 1) then
    return periodic_average(sh, e, v * freq + phase, vw * abs(freq))
  end
  local ca, cb = max(a, 0), min(b, 1)
  local total = 0
  if cb > ca then total = periodic_average(sh, e, (ca + cb) / 2 * freq + phase, (cb - ca) * abs(freq)) * (cb - ca) end
  if a < 0 then total = total + (min(b, 0) - a) * at(0) end
  if b > 1 then total = total + (b - max(a, 1)) * at(1) end
  return total / vw
end

---------------------------------------------------------------------------
-- Arguments and options. Errors name the caller's line (level 3: the
-- script that called a pattern, through its public function).
---------------------------------------------------------------------------
local function widths(who, fw)
  if fw == nil then return 0, 0, 0 end
  local wx, wy, wz
  if type(fw) == "number" then
    wx, wy, wz = fw, fw, fw
  elseif type(fw) == "cdata" then
    wx, wy, wz = fw.x, fw.y, fw.z
  else
    error(format("patterns.%s: the footprint width fw must be a number or a vec3 of widths "
      .. "(filterwidth_xyz(s, scale)), got a %s", who, type(fw)), 3)
  end
  -- A degenerate footprint (NaN) filters nothing; an infinite one averages all.
  wx, wy, wz = abs(wx), abs(wy), abs(wz)
  if wx ~= wx then wx = 0 end
  if wy ~= wy then wy = 0 end
  if wz ~= wz then wz = 0 end
  return min(wx, MAX_WIDTH), min(wy, MAX_WIDTH), min(wz, MAX_WIDTH)
end

local KINDS = {
  number = { "a finite number", function(v) return type(v) == "number" and v - v == 0 end },
  positive = { "a number above 0", function(v) return type(v) == "number" and v > 0 and v - v == 0 end },
  octaves = { "a whole number from 1 to 16",
    function(v) return type(v) == "number" and v >= 1 and v <= 16 and v == floor(v) end },
  vec3 = { "a vec3", function(v) return type(v) == "cdata" end },
  scalar_or_vec3 = { "a number or a vec3",
    function(v) return (type(v) == "number" and v - v == 0) or type(v) == "cdata" end },
  boolean = { "true or false", function(v) return type(v) == "boolean" end },
  wave = { "one of " .. WAVE_NAMES, function(v) return SHAPES[v] ~= nil end },
}
local function describe(v)
  if type(v) == "number" or type(v) == "boolean" then return tostring(v) end
  if type(v) == "string" then return "a string" end
  return "a " .. type(v)
end
local function check_options(who, o, spec, names)
  if o == nil then return NONE end
  if type(o) ~= "table" then
    error(format("patterns.%s: options must be a table such as {frequency = 2}, got a %s", who, type(o)), 3)
  end
  for k, v in pairs(o) do
    local kind = spec[k]
    if kind == nil then
      error(format("patterns.%s: no option '%s' (its options: %s)", who, tostring(k), names), 3)
    end
    if not KINDS[kind][2](v) then
      error(format("patterns.%s: option %s must be %s, got %s", who, k, KINDS[kind][1], describe(v)), 3)
    end
  end
  return o
end
local function option_list(spec)
  local names = {}
  for k in pairs(spec) do names[#names + 1] = k end
  sort(names)
  if #names == 0 then return "none" end
  return concat(names, ", ")
end
local function merged(...)
  local all = {}
  for i = 1, select("#", ...) do
    for k, v in pairs((select(i, ...))) do all[k] = v end
  end
  return all
end

local WAVE_OPTIONS = { wave = "wave", frequency = "number", phase = "number", exponent = "positive" }
local TURBULENCE_OPTIONS = { octaves = "octaves", omega = "number", lambda = "number" }

-- The width a value spans over the footprint, from how much it changes
-- along each of the box's axes: the width of the uniform spread with the
-- same variance as the value over the box, sqrt(Σ dᵢ²) (a sum of uniform
-- variables is narrower than the sum of their widths).
local function width_of(dx, dy, dz)
  return sqrt(dx * dx + dy * dy + dz * dz)
end
-- The width of a pattern's value with no closed form: its changes as p
-- moves by each width in turn.
local function spread(raw, p, v, wx, wy, wz, o)
  local dx, dy, dz = 0, 0, 0
  if wx > 0 then dx = raw(p + vec3(wx, 0, 0), wx, wy, wz, o) - v end
  if wy > 0 then dy = raw(p + vec3(0, wy, 0), wx, wy, wz, o) - v end
  if wz > 0 then dz = raw(p + vec3(0, 0, wz), wx, wy, wz, o) - v end
  return width_of(dx, dy, dz)
end

M.names = {}

-- A continuous pattern. raw(p, wx, wy, wz, o, waved) gives its value
-- (filtered when widths are given) and, where known, the width vw its value
-- spans over the footprint, which a wave then averages over. waved tells raw
-- a wave follows, so it returns the value before filtering and its width.
-- default_wave: POV-Ray's wave for it (nil: the value is used as it is, in
-- [0, 1]). own_frequency: the pattern uses frequency and phase itself.
local function continuous(name, spec, default_wave, raw, own_frequency, clipped)
  local all = merged(WAVE_OPTIONS, spec)
  local names = option_list(all)
  M.names[#M.names + 1] = name
  M[name] = function(p, fw, o)
    if type(p) ~= "cdata" then
      error(format("patterns.%s(p, [fw], [options]): p must be a vec3, got a %s", name, type(p)), 2)
    end
    local wx, wy, wz = widths(name, fw)
    o = check_options(name, o, all, names)
    local wave = o.wave or default_wave
    local freq, phase = o.frequency, o.phase
    if own_frequency then freq, phase = nil, nil end
    if wave == nil and freq == nil and phase == nil then
      return clamp01(raw(p, wx, wy, wz, o, false))
    end
    local v, vw = raw(p, wx, wy, wz, o, true)
    if vw == nil then
      vw = 0
      if wx + wy + wz > 0 then vw = spread(raw, p, v, wx, wy, wz, o) end
    end
    return clamp01(wave_value(SHAPES[wave or "ramp"], o.exponent or 1, v, vw, freq or 1, phase or 0, clipped))
  end
end

-- A pattern of a few values (no waves).
local function discrete(name, spec, f)
  local names = option_list(spec)
  M.names[#M.names + 1] = name
  M[name] = function(p, fw, o)
    if type(p) ~= "cdata" then
      error(format("patterns.%s(p, [fw], [options]): p must be a vec3, got a %s", name, type(p)), 2)
    end
    local wx, wy, wz = widths(name, fw)
    o = check_options(name, o, spec, names)
    return f(p, wx, wy, wz, o)
  end
end

-- Four points of a 2x2x2 stratified grid over the box of widths (w): every
-- pair of axes sees all four combinations, so a footprint lying in a plane
-- gets a full 2x2 grid.
local SIGNS = { { 1, 1, 1 }, { 1, -1, -1 }, { -1, 1, -1 }, { -1, -1, 1 } }
local function supersample4(f, p, wx, wy, wz, o)
  local sum = 0
  for i = 1, 4 do
    local s = SIGNS[i]
    sum = sum + f(vec3(p.x + s[1] * wx / 4, p.y + s[2] * wy / 4, p.z + s[3] * wz / 4), o)
  end
  return sum / 4
end

---------------------------------------------------------------------------
-- Noise. POV-Ray's Noise is 0 to 1 around 0.5: here 0.5 + 0.5 perlin3.
--
-- Filtering noise: what the average of perlin3 over a box is expected to be,
-- knowing its value at the centre, is that value times
-- exp(-0.287 f² Σ wᵢ²) for lattice frequency f and box widths wᵢ (the
-- regression measured over many boxes: a cube of side w keeps
-- exp(-0.86 (f w)²), a square exp(-0.57 (f w)²); tests_patterns.rs checks
-- the result against supersampled boxes). Each octave of a sum is weighted
-- so, fading to its mean, and the variance it lost is kept for patterns
-- that bend the sum through a curve.
---------------------------------------------------------------------------
local exp = math.exp
-- The mean of |perlin3| over space (the prelude's turbulence uses it too).
local MEAN_ABS_PERLIN = 0.2209
local function octave_weight(f, ww)
  if ww <= 0 then return 1 end
  return exp(-0.287 * f * f * ww)
end
-- Σ ωⁱ kᵢ n(λⁱ p), n = perlin3 (fold: kᵢ |n| + (1 - kᵢ) mean |n|), i <
-- octaves, kᵢ the octave's weight for ww = Σ wᵢ²; and the variance the
-- weights took out of it (unfolded).
local function noise_sum(x, y, z, octaves, lambda, omega, ww, fold)
  local sum, lost, amp, f = 0, 0, 1, 1
  for _ = 1, octaves do
    local k = octave_weight(f, ww)
    if k < 1e-6 then
      if fold then sum = sum + amp * MEAN_ABS_PERLIN end
      lost = lost + amp * amp
    else
      local n = perlin3(x * f, y * f, z * f)
      if fold then n = k * abs(n) + (1 - k) * MEAN_ABS_PERLIN else n = k * n end
      sum = sum + amp * n
      lost = lost + amp * amp * (1 - k * k)
    end
    amp, f = amp * omega, f * lambda
  end
  return sum, lost * PERLIN_VARIANCE
end
-- POV-Ray's scalar turbulence Σ ωⁱ Noise(λⁱ p), i < octaves: a constant
-- plus half a noise_sum; and the variance its weighting lost.
local function pov_turbulence(p, octaves, omega, lambda, ww)
  local n, lost = noise_sum(p.x, p.y, p.z, octaves, lambda, omega, ww, false)
  return 0.5 * geometric(omega, octaves) + 0.5 * n, 0.25 * lost
end
-- A vector of three uncorrelated noise_sums (the offsets of the prelude's
-- vfbm): the displacement of warps and wood.
local function vector_noise(p, octaves, lambda, omega, ww)
  local x, y, z = p.x, p.y, p.z
  return vec3(noise_sum(x, y, z, octaves, lambda, omega, ww, false),
    noise_sum(x + 31.416, y - 47.853, z + 12.679, octaves, lambda, omega, ww, false),
    noise_sum(x - 19.27, y + 33.31, z - 71.13, octaves, lambda, omega, ww, false))
end
local function turbulence_args(o)
  return o.octaves or 6, o.omega or 0.5, o.lambda or 2
end
-- The width a*turbulence spans over the footprint, as the width of a uniform
-- spread with the variance of its changes along each axis (dx, dy, dz, the
-- caller's own added in) and of what the weighting lost (12 σ² = width²).
local function turbulence_width(dx, dy, dz, a, lost)
  return sqrt(dx * dx + dy * dy + dz * dz + 12 * a * a * lost)
end
-- How pov_turbulence changes across the footprint along each axis.
local function turbulence_deltas(p, t, wx, wy, wz, octaves, omega, lambda, ww)
  local dx, dy, dz = 0, 0, 0
  if wx > 0 then dx = pov_turbulence(p + vec3(wx, 0, 0), octaves, omega, lambda, ww) - t end
  if wy > 0 then dy = pov_turbulence(p + vec3(0, wy, 0), octaves, omega, lambda, ww) - t end
  if wz > 0 then dz = pov_turbulence(p + vec3(0, 0, wz), octaves, omega, lambda, ww) - t end
  return dx, dy, dz
end
local function amount_x(a)
  if a == nil then return 0 end
  if type(a) == "number" then return a end
  return a.x
end

-- bozo (= spotted = bumps): smooth noise.
local function bozo(p, wx, wy, wz)
  return 0.5 + 0.5 * octave_weight(1, wx * wx + wy * wy + wz * wz) * perlin3(p)
end
continuous("bozo", {}, nil, bozo)
continuous("spotted", {}, nil, bozo)
continuous("bumps", {}, nil, bozo)

-- dents: Noise³. Filtered: the faded noise c, plus what the faded part's
-- variance adds to the mean of a cube (E[(c + r)³] = c³ + 3c E[r²]).
continuous("dents", {}, nil, function(p, wx, wy, wz)
  local k = octave_weight(1, wx * wx + wy * wy + wz * wz)
  local c = 0.5 + 0.5 * k * perlin3(p)
  return c * c * c + 0.75 * c * (1 - k * k) * PERLIN_VARIANCE
end)

-- granite: Σ |0.5 - Noise(4·2ⁱ p)| / 2ⁱ over 6 octaves, i.e. half the
-- turbulence (Σ |perlin3|) of 4p.
continuous("granite", {}, nil, function(p, wx, wy, wz)
  return 0.5 * noise_sum(4 * p.x, 4 * p.y, 4 * p.z, 6, 2, 0.5, 16 * (wx * wx + wy * wy + wz * wz), true)
end)

-- wrinkles: (Σ 0.5ⁱ Noise(2ⁱ p), i < 10) / 2.
continuous("wrinkles", {}, nil, function(p, wx, wy, wz)
  return 0.25 * geometric(0.5, 10)
    + 0.25 * noise_sum(p.x, p.y, p.z, 10, 2, 0.5, wx * wx + wy * wy + wz * wz, false)
end)

-- agate: ((1 + sin 2π(1.3 t + 1.1 z)) / 2)^0.77, t = agate_turb ·
-- turbulence(p). Filtered: the profile averaged over the width of its
-- argument (z's and the turbulence's slope), with the turbulence faded.
continuous("agate", merged(TURBULENCE_OPTIONS, { agate_turb = "number" }), nil, function(p, wx, wy, wz, o)
  local a = o.agate_turb or 1
  local octaves, omega, lambda = turbulence_args(o)
  local ww = wx * wx + wy * wy + wz * wz
  local t, lost = pov_turbulence(p, octaves, omega, lambda, ww)
  local u = 1.3 * a * t + 1.1 * p.z
  if ww <= 0 then return AGATE.f(u - floor(u)) end
  local dx, dy, dz = turbulence_deltas(p, t, wx, wy, wz, octaves, omega, lambda, ww)
  local c = 1.3 * a
  local uw = turbulence_width(c * dx, c * dy, c * dz + 1.1 * wz, c, lost)
  if uw <= 0 then return AGATE.f(u - floor(u)) end
  return periodic_average(AGATE, 0, u, uw)
end)

-- leopard: ((sin x + sin y + sin z) / 3)². Its box average is exact: the
-- mean of a square is the sum of the means of sin² and of the cross
-- products, and the box is separable (E[sin] = sin · sinc(w/2), E[sin²] =
-- (1 - cos 2x · sinc w) / 2).
continuous("leopard", {}, nil, function(p, wx, wy, wz)
  local x, y, z = p.x, p.y, p.z
  if wx + wy + wz <= 0 then
    local s = (sin(x) + sin(y) + sin(z)) / 3
    return s * s
  end
  local mx, my, mz = sin(x) * sinc(wx / 2), sin(y) * sinc(wy / 2), sin(z) * sinc(wz / 2)
  local qx = 0.5 - 0.5 * cos(2 * x) * sinc(wx)
  local qy = 0.5 - 0.5 * cos(2 * y) * sinc(wy)
  local qz = 0.5 - 0.5 * cos(2 * z) * sinc(wz)
  return (qx + qy + qz + 2 * (mx * my + mx * mz + my * mz)) / 9
end)

-- marble: x + turbulence · turbulence(p), through a triangle wave.
continuous("marble", merged(TURBULENCE_OPTIONS, { turbulence = "scalar_or_vec3" }), "triangle",
  function(p, wx, wy, wz, o)
    local a = amount_x(o.turbulence)
    if a == 0 then return p.x, wx end
    local octaves, omega, lambda = turbulence_args(o)
    local ww = wx * wx + wy * wy + wz * wz
    local t, lost = pov_turbulence(p, octaves, omega, lambda, ww)
    local dx, dy, dz = turbulence_deltas(p, t, wx, wy, wz, octaves, omega, lambda, ww)
    return p.x + a * t, turbulence_width(wx + a * dx, a * dy, a * dz, a, lost)
  end)

-- wood: rings round the z axis, the distance from it through a triangle
-- wave; turbulence bends x and y as POV-Ray does (x + sin 2π(x + dx)·a).
local function wood_radius(x, y, dx, dy, ax, ay)
  if ax ~= 0 then x = x + sin(TAU * (x + dx) * ax) end
  if ay ~= 0 then y = y + sin(TAU * (y + dy) * ay) end
  return sqrt(x * x + y * y)
end
continuous("wood", merged(TURBULENCE_OPTIONS, { turbulence = "scalar_or_vec3" }), "triangle",
  function(p, wx, wy, wz, o)
    local a = o.turbulence or 0
    local ax, ay
    if type(a) == "number" then ax, ay = a, a else ax, ay = a.x, a.y end
    local dx, dy = 0, 0
    if ax ~= 0 or ay ~= 0 then
      local octaves, omega, lambda = turbulence_args(o)
      local d = vector_noise(p, octaves, lambda, omega, wx * wx + wy * wy + wz * wz)
      dx, dy = d.x, d.y
    end
    local x, y = p.x, p.y
    local r = wood_radius(x, y, dx, dy, ax, ay)
    -- The bend varies slowly: its slope across the footprint, at this bend.
    return r, width_of(wood_radius(x + wx, y, dx, dy, ax, ay) - r, wood_radius(x, y + wy, dx, dy, ax, ay) - r, 0)
  end)

-- onion: concentric spheres, the distance from the origin through a ramp.
continuous("onion", {}, "ramp", function(p, wx, wy, wz)
  local r = sqrt(p.x * p.x + p.y * p.y + p.z * p.z)
  if r <= 0 then return 0, max(wx, wy, wz) end
  return r, width_of(p.x * wx, p.y * wy, p.z * wz) / r
end)

-- gradient: the position along a direction, through a ramp.
local X_AXIS = vec3(1, 0, 0)
continuous("gradient", { direction = "vec3" }, "ramp", function(p, wx, wy, wz, o)
  local d = o.direction or X_AXIS
  return p.x * d.x + p.y * d.y + p.z * d.z, width_of(d.x * wx, d.y * wy, d.z * wz)
end)

-- radial: the angle round the y axis, 0 to 1 from the -z axis (as
-- POV-Ray's 0.25 + (atan2(x, z) + π) / 2π), through a ramp.
continuous("radial", {}, "ramp", function(p, wx, wy, wz)
  local x, z = p.x, p.z
  local rr = x * x + z * z
  if abs(x) < 0.001 and abs(z) < 0.001 then
    -- The axis: every angle at once.
    if wx + wz > 0 then return 0.25, MAX_WIDTH end
    return 0.25, 0
  end
  return 0.25 + (atan2(x, z) + pi) / TAU, width_of(z * wx, x * wz, 0) / (TAU * rr)
end)

-- spiral1: arms winding round the z axis, z + r + arms · φ/2π (φ measured as
-- POV-Ray does), through a triangle wave; spiral2: two such spirals winding
-- the other way, triangle(r) + triangle(z + r + arms · φ/2π).
local SPIRAL_OPTIONS = merged(TURBULENCE_OPTIONS, { arms = "number", turbulence = "scalar_or_vec3" })
-- Returns the value, its changes across the footprint along each axis, and r.
local function spiral(p, wx, wy, wz, o)
  local x, y, z = p.x, p.y, p.z
  local k = (o.arms or 1) / TAU
  local r = sqrt(x * x + y * y)
  local phi, dx, dy = 0, 0, 0
  if r > 0 then
    local s = min(max(y / r, -1), 1)
    if x < 0 then phi = 1.5 * pi - asin(s) else phi = 0.5 * pi + asin(s) end
    -- ∇(r + kφ) = (x/r - k y/r², y/r + k x/r², 0)
    dx, dy = (x / r - k * y / (r * r)) * wx, (y / r + k * x / (r * r)) * wy
  elseif wx + wy > 0 then
    -- The axis: every angle at once.
    dx = MAX_WIDTH
  end
  local v, dz, lost = z + r + k * phi, wz, 0
  local a = amount_x(o.turbulence)
  if a ~= 0 then
    local octaves, omega, lambda = turbulence_args(o)
    local ww = wx * wx + wy * wy + wz * wz
    local t, tlost = pov_turbulence(p, octaves, omega, lambda, ww)
    v = v + a * t
    if ww > 0 then
      local tx, ty, tz = turbulence_deltas(p, t, wx, wy, wz, octaves, omega, lambda, ww)
      dx, dy, dz = dx + a * tx, dy + a * ty, dz + a * tz
      lost = 12 * a * a * tlost
    end
  end
  -- lost: the faded octaves' share of the width², added to the changes'.
  return v, dx, dy, dz, r, lost
end
continuous("spiral1", SPIRAL_OPTIONS, "triangle", function(p, wx, wy, wz, o)
  local v, dx, dy, dz, _, lost = spiral(p, wx, wy, wz, o)
  return v, sqrt(dx * dx + dy * dy + dz * dz + lost)
end)
local triangle = SHAPES.triangle.f
continuous("spiral2", SPIRAL_OPTIONS, "triangle", function(p, wx, wy, wz, o)
  local u, dx, dy, dz, r, lost = spiral(p, wx, wy, wz, o)
  -- A triangle wave's slope is ±2: each axis's change is at most twice
  -- the changes of r and u.
  local rx, ry = 0, 0
  if r > 0 then rx, ry = p.x / r * wx, p.y / r * wy end
  local v = triangle(r - floor(r)) + triangle(u - floor(u))
  local ex, ey = abs(rx) + abs(dx), abs(ry) + abs(dy)
  return v, 2 * sqrt(ex * ex + ey * ey + dz * dz + lost)
end)

-- waves and ripples: ten wave fronts spreading from fixed points a unit from
-- the origin. waves: 0.2 (2.5 + mean of sin 2π(r fᵢ F + phase) / fᵢ), each
-- source with its own frequency fᵢ in [0.5, 1.5); ripples: 0.5 (1 + mean of
-- sin 2π(r F + phase)). frequency F and phase are the fronts' own. Filtered:
-- each front averaged over the box (r is nearly linear across it: a sinc
-- per axis).
local SOURCES, SOURCE_FREQUENCY = {}, {}
for i = 1, 10 do
  SOURCES[i] = normalize(vec3(hash(i, 1) - 0.5, hash(i, 2) - 0.5, hash(i, 3) - 0.5))
  SOURCE_FREQUENCY[i] = 0.5 + hash(i, 4)
end
local function fronts(p, wx, wy, wz, frequency, phase, own)
  local sum = 0
  local filtered = wx + wy + wz > 0
  for i = 1, 10 do
    local s = SOURCES[i]
    local dx, dy, dz = p.x - s.x, p.y - s.y, p.z - s.z
    local r = sqrt(dx * dx + dy * dy + dz * dz)
    if r == 0 then r = 1 end
    local f = frequency
    if own then f = f * SOURCE_FREQUENCY[i] end
    local term = sin(TAU * (r * f + phase))
    if filtered then
      local k = pi * f / r
      term = term * sinc(k * dx * wx) * sinc(k * dy * wy) * sinc(k * dz * wz)
    end
    if own then term = term / SOURCE_FREQUENCY[i] end
    sum = sum + term
  end
  return sum / 10
end
continuous("waves", {}, nil, function(p, wx, wy, wz, o)
  return 0.2 * (2.5 + fronts(p, wx, wy, wz, o.frequency or 1, o.phase or 0, true))
end, true)
continuous("ripples", {}, nil, function(p, wx, wy, wz, o)
  return 0.5 * (1 + fronts(p, wx, wy, wz, o.frequency or 1, o.phase or 0, false))
end, true)

-- spherical, cylindrical, boxed, planar: 1 at the centre (the origin, the y
-- axis, the origin, the y = 0 plane) falling linearly to 0 at a distance of
-- 1 (POV-Ray's clipped density). Filtered: four samples over the footprint;
-- under a wave, the wave averaged over the width of the distance.
local function clipped_density(name, distance)
  local function at(q) return max(1 - distance(q), 0) end
  continuous(name, {}, nil, function(p, wx, wy, wz, o, waved)
    if waved then
      local d, g = distance(p)
      if d >= 1 then return 0, 0 end
      local gx, gy, gz = g(p)
      return 1 - d, width_of(gx * wx, gy * wy, gz * wz)
    end
    if wx + wy + wz <= 0 then return at(p) end
    return supersample4(at, p, wx, wy, wz, o)
  end, false, true)
end
clipped_density("spherical", function(p)
  local r = sqrt(p.x * p.x + p.y * p.y + p.z * p.z)
  return r, function(q)
    if r <= 0 then return 1, 1, 1 end
    return abs(q.x) / r, abs(q.y) / r, abs(q.z) / r
  end
end)
clipped_density("cylindrical", function(p)
  local r = sqrt(p.x * p.x + p.z * p.z)
  return r, function(q)
    if r <= 0 then return 1, 0, 1 end
    return abs(q.x) / r, 0, abs(q.z) / r
  end
end)
clipped_density("boxed", function(p)
  local ax, ay, az = abs(p.x), abs(p.y), abs(p.z)
  local d = max(ax, ay, az)
  return d, function()
    if d == ax then return 1, 0, 0 elseif d == ay then return 0, 1, 0 end
    return 0, 0, 1
  end
end)
clipped_density("planar", function(p)
  return abs(p.y), function() return 0, 1, 0 end
end)

---------------------------------------------------------------------------
-- Cellular patterns.
---------------------------------------------------------------------------
-- One feature point ("nucleus") per unit cube, anywhere in it.
local function nucleus(i, j, k)
  local h1 = hash(i, j, k)
  local h2 = hash(h1 * 2147483648, j, k)
  local h3 = hash(h2 * 2147483648, i, k)
  return i + h1, j + h2, k + h3
end
-- The cubes whose nuclei can be among the three nearest: the 3x3x3 block
-- round the point and the nine cubes beyond each of its faces (as POV-Ray).
local NEIGHBOURS = {}
for i = -1, 1 do
  for j = -1, 1 do
    for k = -1, 1 do NEIGHBOURS[#NEIGHBOURS + 1] = { i, j, k } end
  end
end
for _, a in ipairs({ -2, 2 }) do
  for i = -1, 1 do
    for j = -1, 1 do
      NEIGHBOURS[#NEIGHBOURS + 1] = { a, i, j }
      NEIGHBOURS[#NEIGHBOURS + 1] = { i, a, j }
      NEIGHBOURS[#NEIGHBOURS + 1] = { i, j, a }
    end
  end
end

-- crackle: form · (F1, F2, F3), the distances to the three nearest nuclei in
-- the metric (Σ|dᵢ|^metric)^(1/metric), each raised by offset; solid: every
-- cell one value (noise at its nucleus). The default form <-1, 1, 0> is
-- F2 - F1: cells with dark cracks between them.
local DEFAULT_FORM = vec3(-1, 1, 0)
local function crackle_at(q, o)
  local metric, offset, form = o.metric or 2, o.offset or 0, o.form or DEFAULT_FORM
  local x, y, z = q.x, q.y, q.z
  local fx, fy, fz = floor(x), floor(y), floor(z)
  local d1, d2, d3 = huge, huge, huge
  local n1x, n1y, n1z = 0, 0, 0
  for c = 1, #NEIGHBOURS do
    local off = NEIGHBOURS[c]
    local nx, ny, nz = nucleus(fx + off[1], fy + off[2], fz + off[3])
    local dx, dy, dz = abs(nx - x), abs(ny - y), abs(nz - z)
    local d
    if metric == 2 then
      d = dx * dx + dy * dy + dz * dz
    elseif metric == 1 then
      d = dx + dy + dz
    else
      d = dx ^ metric + dy ^ metric + dz ^ metric
    end
    if d < d1 then
      d1, d2, d3 = d, d1, d2
      n1x, n1y, n1z = nx, ny, nz
    elseif d < d2 then
      d2, d3 = d, d2
    elseif d < d3 then
      d3 = d
    end
  end
  if o.solid then return clamp01(0.5 + 0.5 * perlin3(n1x, n1y, n1z)) end
  if metric == 2 then
    local o2 = offset * offset
    d1, d2, d3 = sqrt(d1 + o2), sqrt(d2 + o2), sqrt(d3 + o2)
  elseif metric == 1 then
    d1, d2, d3 = d1 + offset, d2 + offset, d3 + offset
  else
    local om, inv = offset ^ metric, 1 / metric
    d1, d2, d3 = (d1 + om) ^ inv, (d2 + om) ^ inv, (d3 + om) ^ inv
  end
  return clamp01(form.x * d1 + form.y * d2 + form.z * d3)
end
-- crackle's mean for one set of options, estimated once per state from
-- fixed points (the same in every state, so images stay repeatable).
local crackle_means, crackle_mean_count = {}, 0
local function crackle_mean(o)
  local form = o.form or DEFAULT_FORM
  local key = format("%.17g %.17g %.17g %.17g %.17g %s", form.x, form.y, form.z, o.metric or 2, o.offset or 0,
    tostring(o.solid or false))
  local m = crackle_means[key]
  if m then return m end
  local sum, n = 0, 1024
  for i = 1, n do
    sum = sum + crackle_at(vec3(hash(i, 11) * 97, hash(i, 12) * 97, hash(i, 13) * 97), o)
  end
  m = sum / n
  -- Options that change from call to call would grow the cache without end.
  if crackle_mean_count >= 64 then crackle_means, crackle_mean_count = {}, 0 end
  crackle_means[key], crackle_mean_count = m, crackle_mean_count + 1
  return m
end
continuous("crackle", { form = "vec3", metric = "positive", offset = "number", solid = "boolean" }, nil,
  function(p, wx, wy, wz, o)
    if wx + wy + wz <= 0 then return crackle_at(p, o) end
    -- Cells are a unit across: four samples while the footprint is well
    -- under a cell, the mean once it spans half of one.
    local k = fade(max(wx, wy, wz), 1)
    local m = 0
    if k < 1 then m = crackle_mean(o) end
    if k <= 0 then return m end
    return k * supersample4(crackle_at, p, wx, wy, wz, o) + (1 - k) * m
  end)

-- The unit cells a box [t - w/2, t + w/2] (w < 1) covers: the first, and
-- the share of the box in it (the rest is in the next).
local function cover(t, w)
  local lo = t - w / 2
  local i = floor(lo)
  if w <= 0 then return floor(t), 1 end
  return i, min((i + 1 - lo) / w, 1)
end
-- cells: each unit cube one random value. Filtered: the exact average of the
-- (at most eight) cubes the box covers, fading to 0.5 once it spans half a cube.
continuous("cells", {}, nil, function(p, wx, wy, wz)
  if wx + wy + wz <= 0 then return hash(p) end
  local k = fade(max(wx, wy, wz), 1)
  if k <= 0 then return 0.5 end
  local i, a = cover(p.x, wx)
  local j, b = cover(p.y, wy)
  local l, c = cover(p.z, wz)
  local sum = 0
  for di = 0, 1 do
    local ea = di == 0 and a or 1 - a
    if ea > 0 then
      for dj = 0, 1 do
        local eb = dj == 0 and b or 1 - b
        if eb > 0 then
          for dl = 0, 1 do
            local ec = dl == 0 and c or 1 - c
            if ec > 0 then sum = sum + ea * eb * ec * hash(i + di, j + dj, l + dl) end
          end
        end
      end
    end
  end
  return k * sum + (1 - k) * 0.5
end)

---------------------------------------------------------------------------
-- Block patterns: a few values, no waves.
---------------------------------------------------------------------------
-- checker: the built-in (0 or 1 on unit cubes; filtered exactly).
M.names[#M.names + 1] = "checker"
M.checker = function(p, fw, o)
  if type(p) ~= "cdata" then
    error(format("patterns.checker(p, [fw]): p must be a vec3, got a %s", type(p)), 2)
  end
  if o ~= nil then error("patterns.checker: it takes no options", 2) end
  local wx, wy, wz = widths("checker", fw)
  if wx + wy + wz <= 0 then return checker(p) end
  return clamp01(checker(p, vec3(wx, wy, wz)))
end

-- hexagon: hexagons of side 1 in the x-z plane, coloured 0, 1 and 2 so that
-- no two neighbours match; the one round the origin is 0. Returns the value
-- and the weights of the three colours (one of them 1, unfiltered).
-- Filtered: four samples over the footprint, fading to a third each once it
-- spans half a hexagon.
local SQRT3 = sqrt(3)
local function hexagon_at(x, z)
  -- Axial coordinates of flat-topped hexagons, rounded to the nearest centre.
  local q = 2 / 3 * x
  local r = -1 / 3 * x + SQRT3 / 3 * z
  local cx, cz, cy = q, r, -q - r
  local rx, rz, ry = floor(cx + 0.5), floor(cz + 0.5), floor(cy + 0.5)
  local ex, ez, ey = abs(rx - cx), abs(rz - cz), abs(ry - cy)
  if ex > ez and ex > ey then
    rx = -rz - ry
  elseif ez > ey then
    rz = -rx - ry
  end
  local v = (rx - rz) % 3
  if v ~= v then return 0 end
  return v
end
discrete("hexagon", {}, function(p, wx, wy, wz)
  if wx + wz <= 0 then
    local v = hexagon_at(p.x, p.z)
    return v, v == 0 and 1 or 0, v == 1 and 1 or 0, v == 2 and 1 or 0
  end
  local c = { 0, 0, 0 }
  for i = 1, 4 do
    local s = SIGNS[i]
    local v = hexagon_at(p.x + s[1] * wx / 4, p.z + s[2] * wz / 4)
    c[v + 1] = c[v + 1] + 0.25
  end
  local k = fade(max(wx, wz), 1 / SQRT3)
  local w0, w1, w2 = k * c[1] + (1 - k) / 3, k * c[2] + (1 - k) / 3, k * c[3] + (1 - k) / 3
  return w1 + 2 * w2, w0, w1, w2
end)

-- brick: 1 in a brick, 0 in the mortar; bricks of size (x, y, z), courses
-- offset by half a brick in x and z in turn (as POV-Ray). Filtered exactly:
-- the course, the joints across x and the joints across z are separable
-- within each of the two kinds of course.
local DEFAULT_BRICK = vec3(8, 3, 4.5)
-- The share of [t - w/2, t + w/2] where t mod period lies in (a, period).
local function solid_share(t, w, period, a)
  if w <= 0 then
    local u = t - floor(t / period) * period
    return u > a and 1 or 0
  end
  local lo = t - w / 2
  lo = lo - floor(lo / period) * period
  local hi = lo + w
  local function integral(u)
    local n = floor(u / period)
    return n * (period - a) + max(u - n * period - a, 0)
  end
  return (integral(hi) - integral(lo)) / w
end
-- The share of [y - w/2, y + w/2] in the brick part of courses of one kind
-- (0: even courses, 1: odd), with courses of height h and mortar m.
local function course_share(y, w, h, m, kind)
  local period = 2 * h
  local function integral(u)
    local n = floor(u / period)
    local r = u - n * period - kind * h
    return n * (h - m) + min(max(r - m, 0), h - m)
  end
  if w <= 0 then
    local r = y - floor(y / period) * period - kind * h
    return (r > m and r < h) and 1 or 0
  end
  local lo = y - w / 2
  lo = lo - floor(lo / period) * period
  return (integral(lo + w) - integral(lo)) / w
end
discrete("brick", { size = "vec3", mortar = "number" }, function(p, wx, wy, wz, o)
  local size, m = o.size or DEFAULT_BRICK, o.mortar or 0.5
  local bw, bh, bd = size.x, size.y, size.z
  -- POV-Ray moves the mortar off the origin by its own width.
  local x, y, z = p.x + m, p.y + m, p.z + m
  local even = course_share(y, wy, bh, m, 0)
  local odd = course_share(y, wy, bh, m, 1)
  local v = 0
  if even > 0 then v = v + even * solid_share(x, wx, bw, m) * solid_share(z + bd / 2, wz, bd, m) end
  if odd > 0 then v = v + odd * solid_share(x + bw / 2, wx, bw, m) * solid_share(z, wz, bd, m) end
  return v
end)

---------------------------------------------------------------------------
-- Waves as functions of their own: patterns.wave(v, [vw], [options]) and
-- patterns.NAME_wave(v, [vw]), vw the width v spans over the footprint.
---------------------------------------------------------------------------
local WAVE_NAMES_LIST = option_list(WAVE_OPTIONS)
function M.wave(v, vw, o)
  if type(v) ~= "number" then error(format("patterns.wave: v must be a number, got a %s", type(v)), 2) end
  if vw ~= nil and type(vw) ~= "number" then
    error(format("patterns.wave: the width vw must be a number, got a %s", type(vw)), 2)
  end
  o = check_options("wave", o, WAVE_OPTIONS, WAVE_NAMES_LIST)
  local w = abs(vw or 0)
  if w ~= w then w = 0 end
  return wave_value(SHAPES[o.wave or "ramp"], o.exponent or 1, v, min(w, MAX_WIDTH), o.frequency or 1,
    o.phase or 0, false)
end
for _, name in ipairs({ "ramp", "triangle", "sine", "scallop", "cubic" }) do
  local sh = SHAPES[name]
  M[name .. "_wave"] = function(v, vw)
    if type(v) ~= "number" or (vw ~= nil and type(vw) ~= "number") then
      error(format("patterns.%s_wave(v, [vw]): expected numbers, got a %s and a %s", name, type(v), type(vw)), 2)
    end
    local w = abs(vw or 0)
    if w ~= w then w = 0 end
    return wave_value(sh, 1, v, min(w, MAX_WIDTH), 1, 0, false)
  end
end
function M.poly_wave(v, exponent, vw)
  if type(v) ~= "number" or type(exponent) ~= "number" or not (exponent > 0)
    or (vw ~= nil and type(vw) ~= "number") then
    error("patterns.poly_wave(v, exponent, [vw]): expected numbers, the exponent above 0", 2)
  end
  local w = abs(vw or 0)
  if w ~= w then w = 0 end
  return wave_value(SHAPES.poly, exponent, v, min(w, MAX_WIDTH), 1, 0, false)
end

---------------------------------------------------------------------------
-- color_map: POV-Ray's colour_map, a list of {value, colour} entries with
-- values that do not decrease; a colour is a vec3, {r, g, b} or a grey
-- number. Returns a function of a value giving a vec3, interpolating
-- linearly between entries and holding the end colours beyond them; two
-- entries at one value make a sharp edge.
---------------------------------------------------------------------------
local MAX_ENTRIES = 256
function M.color_map(entries)
  local USAGE = "(a list of {value, colour} entries such as {{0, vec3(0)}, {1, vec3(1)}})"
  if type(entries) ~= "table" or #entries == 0 then
    error("patterns.color_map: expected " .. USAGE, 2)
  end
  local n = #entries
  if n > MAX_ENTRIES then
    error(format("patterns.color_map: %d entries, over the limit of %d", n, MAX_ENTRIES), 2)
  end
  local vs, rs, gs, bs = {}, {}, {}, {}
  for i = 1, n do
    local e = entries[i]
    local v, c = nil, nil
    if type(e) == "table" then v, c = e[1], e[2] end
    if type(v) ~= "number" or v - v ~= 0 then
      error(format("patterns.color_map: entry %d has no finite value first %s", i, USAGE), 2)
    end
    if i > 1 and v < vs[i - 1] then
      error(format("patterns.color_map: entry %d's value %g is below the entry before it (values must not "
        .. "decrease)", i, v), 2)
    end
    local r, g, b
    if type(c) == "number" then
      r, g, b = c, c, c
    elseif type(c) == "cdata" then
      r, g, b = c.x, c.y, c.z
    elseif type(c) == "table" then
      r, g, b = c[1], c[2], c[3]
    end
    if type(r) ~= "number" or type(g) ~= "number" or type(b) ~= "number" then
      error(format("patterns.color_map: entry %d has no colour second (a vec3, {r, g, b} or a grey number)", i), 2)
    end
    vs[i], rs[i], gs[i], bs[i] = v, r, g, b
  end
  return function(v)
    if type(v) ~= "number" then
      error(format("color_map: expected a number, got a %s", type(v)), 2)
    end
    if not (v > vs[1]) then return vec3(rs[1], gs[1], bs[1]) end
    for i = 2, n do
      if v < vs[i] then
        local f = (v - vs[i - 1]) / (vs[i] - vs[i - 1])
        return vec3(rs[i - 1] + (rs[i] - rs[i - 1]) * f, gs[i - 1] + (gs[i] - gs[i - 1]) * f,
          bs[i - 1] + (bs[i] - bs[i - 1]) * f)
      end
    end
    return vec3(rs[n], gs[n], bs[n])
  end
end

---------------------------------------------------------------------------
-- Warps: patterns.warp.NAME(p, [fw], [options]) returns the moved point and,
-- given a footprint, the footprint's widths there (a vec3).
---------------------------------------------------------------------------
M.warp = {}
-- The widths of f's result over the footprint: Σⱼ |∂f/∂pⱼ| wⱼ, the
-- derivatives by forward differences.
local function warped_widths(f, p, q, wx, wy, wz, o)
  local h = 1e-6 * (1 + max(abs(p.x), abs(p.y), abs(p.z)))
  local ox, oy, oz = 0, 0, 0
  local function axis(dp, w)
    if w <= 0 then return end
    local d = (f(p + dp, o) - q) / h
    ox, oy, oz = ox + abs(d.x) * w, oy + abs(d.y) * w, oz + abs(d.z) * w
  end
  axis(vec3(h, 0, 0), wx)
  axis(vec3(0, h, 0), wy)
  axis(vec3(0, 0, h), wz)
  return vec3(min(ox, MAX_WIDTH), min(oy, MAX_WIDTH), min(oz, MAX_WIDTH))
end
-- check(o) returns nil or why the options cannot work together.
-- stretches: the warp changes widths (else they pass through).
local function warp(name, spec, f, stretches, check)
  local names = option_list(spec)
  M.warp[name] = function(p, fw, o)
    if type(p) ~= "cdata" then
      error(format("patterns.warp.%s(p, [fw], [options]): p must be a vec3, got a %s", name, type(p)), 2)
    end
    local wx, wy, wz = widths("warp." .. name, fw)
    o = check_options("warp." .. name, o, spec, names)
    if check then
      local why = check(o)
      if why then error(format("patterns.warp.%s: %s", name, why), 2) end
    end
    local q = f(p, o, wx * wx + wy * wy + wz * wz)
    if fw == nil then return q end
    if not stretches then return q, vec3(wx, wy, wz) end
    return q, warped_widths(f, p, q, wx, wy, wz, o)
  end
end

-- turbulence: p moved by amount · (a vector fBm of octaves, lambda, omega),
-- its finer octaves fading under a footprint; widths pass through.
warp("turbulence", merged(TURBULENCE_OPTIONS, { amount = "scalar_or_vec3" }), function(p, o, ww)
  local octaves, omega, lambda = turbulence_args(o)
  return p + vector_noise(p, octaves, lambda, omega, ww) * (o.amount or 1)
end, false)

-- black_hole: points within radius of center pushed out from it (pulling
-- the pattern in) by strength · ((radius - d) / radius)^falloff of their
-- distance (at most all of it), or pulled in with inverse; repeat_ repeats
-- the hole every repeat_.x, .y, .z along each axis (0: not along it).
local ORIGIN = vec3(0, 0, 0)
warp("black_hole", { center = "vec3", radius = "positive", strength = "number", falloff = "number",
  inverse = "boolean", repeat_ = "vec3", ["repeat"] = "vec3" }, function(p, o)
  local c = o.center or ORIGIN
  local rep = o.repeat_ or o["repeat"]
  if rep then
    local cx, cy, cz = c.x, c.y, c.z
    if rep.x > 0 then cx = cx + rep.x * floor(p.x / rep.x) end
    if rep.y > 0 then cy = cy + rep.y * floor(p.y / rep.y) end
    if rep.z > 0 then cz = cz + rep.z * floor(p.z / rep.z) end
    c = vec3(cx, cy, cz)
  end
  local radius = o.radius or 1
  local d = p - c
  local l = sqrt(d.x * d.x + d.y * d.y + d.z * d.z)
  if l >= radius then return p end
  local s = min(((radius - l) / radius) ^ (o.falloff or 2) * (o.strength or 1), 1)
  if o.inverse then s = -s end
  return p + d * s
end, true)

-- repeat: space cut into slabs direction's length wide along its one axis,
-- each a copy of the first moved by offset per slab; flip mirrors odd
-- slabs along each axis where flip is non-zero. (repeat is a Lua keyword:
-- patterns.warp.repeat_, or patterns.warp["repeat"].)
local ZERO = vec3(0, 0, 0)
warp("repeat_", { direction = "vec3", offset = "vec3", flip = "vec3" }, function(p, o)
  local d = o.direction
  local axis, width = "x", abs(d.x)
  if d.y ~= 0 then axis, width = "y", abs(d.y) elseif d.z ~= 0 then axis, width = "z", abs(d.z) end
  local t = p[axis]
  local n = floor(t / width)
  local c = { x = p.x, y = p.y, z = p.z }
  c[axis] = t - n * width
  local flip = o.flip or ZERO
  if n % 2 == 1 then
    for _, k in ipairs({ "x", "y", "z" }) do
      if flip[k] ~= 0 then
        c[k] = -c[k]
        if k == axis then c[k] = c[k] + width end
      end
    end
  end
  local off = o.offset or ZERO
  return vec3(c.x + n * off.x, c.y + n * off.y, c.z + n * off.z)
end, false, function(o)
  local d = o.direction
  if d == nil then return "it needs a direction, such as {direction = vec3(2, 0, 0)}" end
  local nonzero = (d.x ~= 0 and 1 or 0) + (d.y ~= 0 and 1 or 0) + (d.z ~= 0 and 1 or 0)
  if nonzero ~= 1 or d.x ~= d.x or d.y ~= d.y or d.z ~= d.z then
    return "direction must have exactly one non-zero component, the width of the slabs along that axis"
  end
  return nil
end)
M.warp["repeat"] = M.warp.repeat_

-- cylindrical, spherical, toroidal: wrap the x-y plane round a cylinder (the
-- y axis), a sphere or a torus (major_radius round the y axis), so that a
-- pattern made for a plane covers them. The result is (angle round the y
-- axis / 2π, height or the second angle / 2π, distance), the angles scaled
-- by distance^dist_exp; orientation turns the result as POV-Ray does.
local Z_AXIS = vec3(0, 0, 1)
local function orient(x, y, z, o)
  local v = o.orientation or Z_AXIS
  if v.x == 0 and v.y == 0 and v.z == 1 then return vec3(x, y, z) end
  return vec3(v.x * z + v.y * x + v.z * x, v.x * y - v.y * z + v.z * y, -v.x * x + v.y * y + v.z * z)
end
-- The angle round the y axis, 0 to 1 from +x towards +z.
local function turn(x, z, len)
  local theta
  if z == 0 then
    theta = x > 0 and 0 or pi
  else
    theta = acos(min(max(x / len, -1), 1))
    if z < 0 then theta = TAU - theta end
  end
  return theta
end
local function scaled(a, len, e)
  if e == 0 then return a end
  if e == 1 then return a * len end
  return a * len ^ e
end
local MAPPING = { orientation = "vec3", dist_exp = "number" }
warp("cylindrical", MAPPING, function(p, o)
  local x, y, z = p.x, p.y, p.z
  local len = sqrt(x * x + z * z)
  if len == 0 then return p end
  return orient(scaled(turn(x, z, len) / TAU, len, o.dist_exp or 0), y, len, o)
end, true)
warp("spherical", MAPPING, function(p, o)
  local dist = sqrt(p.x * p.x + p.y * p.y + p.z * p.z)
  if dist == 0 then return p end
  local x, y, z = p.x / dist, p.y / dist, p.z / dist
  local phi = 0.5 + asin(min(max(y, -1), 1)) / pi
  local len = sqrt(x * x + z * z)
  local theta = 0
  if len > 0 then theta = turn(x, z, len) / TAU end
  local e = o.dist_exp or 0
  return orient(scaled(theta, dist, e), scaled(phi, dist, e), dist, o)
end, true)
warp("toroidal", merged(MAPPING, { major_radius = "number" }), function(p, o)
  local x, y, z = p.x, p.y, p.z
  local len = sqrt(x * x + z * z)
  if len == 0 then return p end
  local theta = turn(x, z, len) / TAU
  x = len - (o.major_radius or 1)
  len = sqrt(x * x + y * y)
  if len == 0 then return orient(theta, 0, 0, o) end
  local phi = acos(min(max(-x / len, -1), 1))
  if y > 0 then phi = TAU - phi end
  local e = o.dist_exp or 0
  return orient(scaled(theta, len, e), scaled(phi / TAU, len, e), len, o)
end, true)

sort(M.names)
return M

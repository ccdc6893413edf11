-- Hammered copper with verdigris: the height is dents (Voronoi cells) plus
-- fine fBm; color() calls height() so corrosion collects in the pits, and
-- reflect() makes the bare metal a mirror and the verdigris matte.
-- Parameters: scale (dents per unit, 5), tint (the bare metal's colour).
-- The parameters a scene's <Parameter> may set, with their defaults.
params {
  scale = 5,
  tint = rgb(0.85, 0.45, 0.28),
}
local sc = param.scale
-- Colours (tint too) are display values; srgb() makes them linear.
local copper = srgb(param.tint)
local patina = ramp({ 0, 0.5, 1 }, { srgb(0.30, 0.55, 0.45), srgb(0.35, 0.70, 0.58), srgb(0.55, 0.80, 0.70) })

function height(s)
  local x, y, z = s.P.x * sc, s.P.y * sc, s.P.z * sc
  local f1 = voronoi(x, y, z)
  -- A dent is a bowl around each feature point; fBm roughens it.
  return -0.04 * (1 - f1 * f1) + 0.006 * fbm(x * 6, y * 6, z * 6, 4)
end

-- How corroded a point is, 0 to 1: deep points and a blotchy noise.
local function corrosion(s)
  local depth = -height(s) / 0.04
  local blotch = fbm(s.P.x * 3 + 11, s.P.y * 3, s.P.z * 3, 4)
  return smoothstep(0.75, 1.05, depth + 0.4 * blotch)
end

function color(s)
  local c = corrosion(s)
  local pr, pg, pb = patina(fbm(s.P.x * 9, s.P.y * 9, s.P.z * 9, 3) * 0.5 + 0.5)
  local m = 0.35 * (1 - c)
  return mix(copper * m, vec3(pr, pg, pb), c):unpack()
end

function reflect(s)
  local k = 1 - corrosion(s)
  return (copper * (0.9 * k)):unpack()
end

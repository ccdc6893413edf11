-- The shading tour (examples/scenes/tour.xml): one script, three maps.
-- color: tiles from the filtered checker, each tile its own shade (hash of
--   its cell), and on instanced objects a hue per instance (s.random).
-- reflect: Fresnel from the view direction s.V (Schlick), wet tiles.
-- height: rounded tile edges, antialiased with aastep.
params {
  scale = 2,                      -- tiles per unit
  light = rgb(0.85, 0.82, 0.76),
  dark = rgb(0.18, 0.2, 0.26),
  wet = 0.04,                     -- reflectance seen head-on
  mode = "tiles",                 -- or "instances"
}
local floor, cos, abs, max = math.floor, math.cos, math.abs, math.max
local f = param.scale

function color(s)
  if param.mode == "instances" then
    local a = 6.2832 * s.random
    return srgb(0.55 + 0.35 * cos(a), 0.55 + 0.35 * cos(a + 2.1), 0.55 + 0.35 * cos(a + 4.2))
  end
  local p = s.P * f
  -- A 2D checker on the floor: y is held mid-cell, away from the cell
  -- boundary the floor lies on (where rounding would flip cells at random).
  local c = checker(vec3(p.x, 0.5, p.z), filterwidth_xyz(s, f))
  local shade = 0.85 + 0.3 * hash(floor(p.x), floor(p.z))
  -- The colours are display values; srgb() makes them linear.
  return mix(srgb(param.dark), srgb(param.light), c) * shade
end

function reflect(s)
  local cosv = max(dot(s.N, s.V), 0)
  local r = param.wet + (1 - param.wet) * (1 - cosv) ^ 5
  return r, r, r
end

function height(s)
  local p = s.P * f
  local fw = filterwidth(s, f)
  local u, v = p.x - floor(p.x), p.z - floor(p.z)
  local edge = math.min(u, 1 - u, v, 1 - v)
  return 0.02 * aastep(0.04, edge, fw)
end

-- Wood: growth rings around the y axis, wobbled by low-frequency noise, with
-- fine grain streaks along the trunk. Parameters: rings (per unit, 6),
-- light and dark (vec3 colours of early and late wood).
local sqrt, floor = math.sqrt, math.floor
-- The parameters a scene's <Parameter> may set, with their defaults.
params {
  rings = 6,
  light = rgb(0.80, 0.58, 0.34),
  dark = rgb(0.45, 0.26, 0.12),
}
local rings = param.rings
-- The colours are display values; srgb() makes them linear.
local light = srgb(param.light)
local dark = srgb(param.dark)

function color(s)
  local x, y, z = s.P.x, s.P.y, s.P.z
  -- The trunk's axis wanders a little, so rings are not perfect circles.
  local wx = x + 0.15 * perlin3(y * 0.8, 1.3, z * 0.5)
  local wz = z + 0.15 * perlin3(x * 0.5, 4.7, y * 0.8)
  local r = sqrt(wx * wx + wz * wz) * rings + 0.6 * fbm(x * 2, y * 0.4, z * 2, 3)
  local ring = r - floor(r)
  -- Late wood: a sharp dark edge at the end of each year's ring.
  local late = smoothstep(0.55, 0.95, ring)
  local grain = 0.85 + 0.15 * perlin3(x * 40, y * 2, z * 40)
  local c = mix(light, dark, late) * grain
  return c.x, c.y, c.z
end

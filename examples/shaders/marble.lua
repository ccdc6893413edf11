-- Marble: layers along x, bent by 4-octave turbulence; the zero crossings of
-- the sine become thin veins. Parameters: frequency (layers per unit, 4),
-- warp (how far turbulence bends them, 3), stone and vein (vec3 colours).
local sin, abs = math.sin, math.abs
-- The parameters a scene's <Parameter> may set, with their defaults.
params {
  frequency = 4,
  warp = 3,
  stone = rgb(0.92, 0.90, 0.86),
  vein = rgb(0.30, 0.26, 0.28),
}
local f = param.frequency
local warp = param.warp
-- The colours are display values; srgb() makes them linear.
local stone = srgb(param.stone)
local vein = srgb(param.vein)
local body = ramp({ 0, 0.25, 1 }, { vein, mix(vein, stone, 0.7), stone })

function color(s)
  local x, y, z = s.P.x * f, s.P.y * f, s.P.z * f
  local t = turbulence(x, y, z, 4)
  local w = abs(sin(x + warp * t))
  -- Clouding: a low-frequency tint so the stone is not flat between veins.
  local cloud = 0.9 + 0.1 * fbm(x * 0.5 + 7, y * 0.5, z * 0.5, 3)
  local r, g, b = body(w ^ 0.4)
  return r * cloud, g * cloud, b * cloud
end

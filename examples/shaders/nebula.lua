-- A nebula: glowing gas whose brightness and colour follow one noise field
-- through a colour ramp, with ridged filaments and dark dust where the
-- field is thin. Parameters: scale (features per unit, 1.6), brightness
-- (emission multiplier, 1).
-- The parameters a scene's <Parameter> may set, with their defaults.
params {
  scale = 1.6,
  brightness = 1,
}
local scale = param.scale
local brightness = param.brightness
local glow = ramp({ 0, 0.3, 0.55, 0.8, 1 }, {
  vec3(0, 0, 0), vec3(40, 8, 70), vec3(170, 30, 90), vec3(255, 140, 70), vec3(255, 235, 190),
})

local function gas(p)
  local x, y, z = p.x * scale, p.y * scale, p.z * scale
  local body = 1 - length(p) + 0.7 * fbm(x, y, z, 5)
  local filaments = ridged(x * 1.7 + 3.1, y * 1.7, z * 1.7, 4)
  return clamp(body, 0, 1) * filaments
end

function density(s)
  return gas(s.P)
end

function emission(s)
  local d = gas(s.P)
  local r, g, b = glow(clamp(d * 1.4, 0, 1))
  local k = d * brightness
  return r * k, g * k, b * k
end

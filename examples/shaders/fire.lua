-- A flame: heat rising from the bottom of its bound (s.P.y from -1 to 1),
-- narrowing as it rises and torn by turbulence that drifts upwards, glowing
-- through a black-body-like ramp. Parameters: scale (turbulence features,
-- 3), brightness (emission multiplier, 1), rise (how fast the turbulence
-- drifts over the shutter, 0).
-- The parameters a scene's <Parameter> may set, with their defaults.
params {
  scale = 3,
  brightness = 1,
  rise = 0,
}
local scale = param.scale
local brightness = param.brightness
local rise = param.rise
local glow = ramp({ 0, 0.15, 0.4, 0.7, 1 }, {
  vec3(0, 0, 0), vec3(90, 10, 0), vec3(255, 70, 5), vec3(255, 170, 40), vec3(255, 245, 210),
})

local function heat(s)
  local p = s.P
  local h = clamp((p.y + 1) * 0.5, 0, 1)
  local y = p.y * scale - rise * s.time
  local t = turbulence(p.x * scale, y, p.z * scale, 4)
  local r = math.sqrt(p.x * p.x + p.z * p.z)
  local width = 0.5 * (1 - h) ^ 0.8 + 0.04
  local q = clamp(1 - r / width + 0.5 * t - 0.3 * h, 0, 1)
  return q * q
end

function density(s)
  return heat(s)
end

function emission(s)
  local q = heat(s)
  local r, g, b = glow(q)
  local k = q * brightness
  return r * k, g * k, b * k
end

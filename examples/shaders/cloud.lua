-- A cumulus-like cloud: fBm noise shaped by a soft ball, so the density
-- fades to nothing at the bound. Parameters: scale (noise features per unit,
-- 2.5), octaves (5), coverage (how much of the ball is cloud, 0.55).
-- The parameters a scene's <Parameter> may set, with their defaults.
params {
  scale = 2.5,
  octaves = 5,
  coverage = 0.55,
}
local scale = param.scale
local octaves = param.octaves
local coverage = param.coverage

function density(s)
  local p = s.P
  local r = length(p)
  -- A flattened base: clouds sit on a level.
  local shape = 1 - smoothstep(0.35, 1.0, r) - smoothstep(0.1, -0.5, p.y)
  local n = fbm(p.x * scale, p.y * scale, p.z * scale, octaves)
  -- Noise alone may poke out of the ball: fade it out at the bound.
  local edge = 1 - smoothstep(0.9, 1.0, r)
  return clamp((shape + n * 0.8) - (1 - coverage), 0, 1) * 2 * edge
end

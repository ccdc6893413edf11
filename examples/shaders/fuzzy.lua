-- Perlin & Hoffert's fuzzy ball: a sphere's falloff disturbed by turbulence,
-- thresholded into a surface (a hypertexture). Parameters: scale (2.5),
-- amount (how far turbulence pushes the surface, 0.45).
-- The parameters a scene's <Parameter> may set, with their defaults.
params {
  scale = 2.5,
  amount = 0.45,
}
local scale = param.scale
local amount = param.amount

function density(s)
  local p = s.P
  local t = turbulence(p.x * scale, p.y * scale, p.z * scale, 5)
  return 1 - length(p) + amount * t
end

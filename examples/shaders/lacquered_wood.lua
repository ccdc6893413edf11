-- lacquered_wood.lua: wood grain under a clear lacquer coat (docs/closures.md).
-- The grain is a diffuse albedo; layer{} puts a glossy dielectric over it, so
-- the highlight is white and sharp while the wood below stays matte.
params { frequency = 16, lacquer_roughness = 0.04 }
local grain = ramp({ 0, 0.5, 0.8, 1 },
  { srgb(0.80, 0.55, 0.32), srgb(0.70, 0.45, 0.24), srgb(0.45, 0.24, 0.10), srgb(0.35, 0.17, 0.07) })

function material(s)
  local p = s.P
  -- Growth rings around the y axis, warped; fine fibres stretched along y.
  local r = math.sqrt(p.x * p.x + p.z * p.z) * param.frequency + 3 * fbm(p.x * 2, p.y * 0.5, p.z * 2, 3)
  local fibre = 0.2 * fbm(p.x * 60, p.y * 3, p.z * 60, 2, 2, 0.5, filterwidth(s, 60))
  local wood = diffuse{albedo = vec3(grain(clamp(fract(r) + fibre, 0, 1))), roughness = 0.3}
  local lacquer = dielectric{ior = 1.5, roughness = param.lacquer_roughness}
  local c = layer{top = lacquer, base = wood}
  return c
end

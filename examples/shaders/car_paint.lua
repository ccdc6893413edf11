-- car_paint.lua: metallic car paint. The base mixes a coloured diffuse with a
-- conductor by a per-flake weight (each Voronoi cell is one flake; whether it
-- is metal, how much, and how rough come from hash(id)), and a smooth clear
-- coat covers it all.
params { paint = rgb(0.01, 0.03, 0.16), flake = rgb(0.55, 0.7, 1.0), flakes_per_unit = 140, density = 0.35 }

function material(s)
  local _, _, id = voronoi(s.P * param.flakes_per_unit)
  local on = step(hash(id), param.density)             -- 1 for a flake, 0 for pigment
  local w = on * (0.2 + 0.4 * hash(id, 17))            -- how metallic this cell is
  local metal = conductor{f0 = param.flake, roughness = 0.08 + 0.25 * hash(id, 31)}
  local base = mix(diffuse{albedo = param.paint}, metal, w)
  local c = layer{top = dielectric{ior = 1.5, roughness = 0.02}, base = base}
  return c
end

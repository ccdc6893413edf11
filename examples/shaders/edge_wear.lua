-- edge_wear.lua: red paint worn through to the steel underneath along the
-- edges and corners. edgewear() measures how exposed the point is: the
-- fraction of rays into the object that leave it within `radius` (0 on a
-- face, 0.5 on a right-angled edge, more at a corner, fading over `radius`).
-- Noise breaks the worn band into chips; indirect rays take fewer samples.
params { paint = rgb(0.5, 0.05, 0.03), radius = 0.12, threshold = 0.22 }

function material(s)
  local e = edgewear(s, param.radius, s.depth == 0 and 16 or 4)
  local chips = 0.3 * fbm(s.P * 6, 4) + 0.12 * fbm(s.P * 40, 2)
  local worn = smoothstep(param.threshold - 0.03, param.threshold + 0.03, e + chips)
  local paint = layer{top = dielectric{ior = 1.5, roughness = 0.2}, base = diffuse{albedo = param.paint}}
  local steel = conductor{f0 = srgb(0.72, 0.72, 0.74), roughness = 0.3 + 0.2 * (1 - worn)}
  local c = mix(paint, steel, worn)
  return c
end

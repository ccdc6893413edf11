-- rusty_paint.lua: painted steel rusting through. mix() blends two whole
-- materials by an fbm mask: a glossy coated paint, and a rough orange-brown
-- rust whose colour varies; the paint darkens where it starts to lift.
params { paint = rgb(0.05, 0.3, 0.22), scale = 2.5, rust_amount = 0.55 }
local rust_ramp = ramp({ 0, 0.5, 1 }, { srgb(0.25, 0.09, 0.03), srgb(0.5, 0.2, 0.06), srgb(0.68, 0.36, 0.12) })

function material(s)
  local n = fbm(s.P * param.scale, 6) + 0.3 * fbm(s.P * 25, 2)
  local mask = smoothstep(0.05, 0.12, n + param.rust_amount - 0.5)
  local edge = 1 - 0.6 * smoothstep(-0.1, 0.05, n + param.rust_amount - 0.5)   -- dark rim in the paint
  local paint = layer{top = dielectric{ior = 1.5, roughness = 0.15}, base = diffuse{albedo = param.paint * edge}}
  local rust = diffuse{albedo = vec3(rust_ramp(0.5 + 0.5 * fbm(s.P * 30, 3))), roughness = 0.9}
  local c = mix(paint, rust, mask)
  return c
end

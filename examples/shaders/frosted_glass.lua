-- frosted_glass.lua: an etched thin glass globe with clear bands left unetched. One
-- dielectric whose roughness the shader varies: rough (frosted: what is
-- behind is blurred) over most of the surface, polished (sharp) in the bands.
params { roughness = 0.5, bands_per_unit = 3, band_width = 0.12, thin = 1 }

function material(s)
  local f = param.bands_per_unit
  local d = math.abs(fract(s.P.y * f + 0.5) - 0.5)                -- 0 on a band's centre line
  local frosted = aastep(param.band_width / 2, d, filterwidth(s, f))
  local c = dielectric{ior = 1.5, roughness = 0.02 + (param.roughness - 0.02) * frosted, thin = param.thin > 0}
  return c
end

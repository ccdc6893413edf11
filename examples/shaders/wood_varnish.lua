-- wood_varnish.lua: a varnished wood as a physically based material
-- (DecalMode material): rougher and darker in the late-wood rings.
local wood = require "lib.wood"
params { frequency = 6 }

function color(s)
  return mix(wood.light, wood.dark, wood.rings(s.P, param.frequency))
end
function specular(s) return 0.04, 0.04, 0.04 end
function roughness(s) return 0.15 + 0.35 * wood.rings(s.P, param.frequency) end

-- wood_color.lua: the colour of wood, from the shared module lib/wood.lua.
local wood = require "lib.wood"
params { frequency = 6 }

function color(s)
  return mix(wood.light, wood.dark, wood.rings(s.P, param.frequency))
end

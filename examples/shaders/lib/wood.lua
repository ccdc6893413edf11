-- lib/wood.lua: a wood-ring pattern shared by several shaders with
-- require "lib.wood" (see docs/shaders.md, "Modules").
local M = {}

-- Rings around the object's y axis, warped by noise: 0 in early wood,
-- 1 in the dark late wood.
function M.rings(p, frequency)
  local r = math.sqrt(p.x * p.x + p.z * p.z) * frequency + 2 * fbm(p * 1.5, 3)
  return smoothstep(0.6, 0.9, r - math.floor(r))
end

M.light = vec3(0.75, 0.52, 0.3)
M.dark = vec3(0.4, 0.22, 0.1)

return M

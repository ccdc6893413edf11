-- lava.lua: glowing cracks between dark cooled crust (DecalMode material).
-- The cracks emit light; the crust is a rough dark rock.
params { scale = 3, glow = 8 }

local function crack(s)
  local f1, f2 = voronoi(s.P * param.scale)
  return 1 - smoothstep(0.02, 0.08, f2 - f1)
end

function color(s) return 0.05, 0.045, 0.04 end
function roughness(s) return 0.8 end
function emission(s)
  local c = crack(s) * param.glow
  return c, 0.35 * c, 0.05 * c
end

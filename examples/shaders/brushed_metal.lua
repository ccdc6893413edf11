-- brushed_metal.lua: a gold metal whose roughness varies in bands.
params { tint = rgb(1.0, 0.78, 0.34) }

function color(s) return param.tint end
function metalness(s) return 1 end
function roughness(s) return 0.1 + 0.3 * smoothstep(-0.3, 0.3, perlin3(s.P * 2)) end

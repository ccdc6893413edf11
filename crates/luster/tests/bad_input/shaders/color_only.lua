function color(s)
  return param.tint.x, param.tint.y, param.tint.z
end

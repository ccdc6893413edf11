function height(s)
  return 0.01 * perlin3(s.P.x * 8, s.P.y * 8, s.P.z * 8)
end

function density(s) return 1 end
function emission(s) return 1, 1, 1 end

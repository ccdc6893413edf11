//! Acceleration structures: a binned-SAH BVH and the triangle-mesh accelerator built on it.

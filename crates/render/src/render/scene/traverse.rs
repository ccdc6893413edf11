//! The two-level traversal behind [`Scene::intersect`] and
//! [`Scene::occluded`]: the infinite planes, then the top-level BVH over the
//! objects, whose leaves test each object (a mesh's own BVH, a sphere, an
//! ellipsoid) in the object's space at the ray's time. On x86-64 with AVX2
//! and FMA the whole walk is one function per query, with the leaf tests as
//! `#[inline(always)]` trait methods so that they compile inside it (closures
//! would keep the target features of the function they are written in).
//! Reads no scene parameters itself: the epsilons and objects are the scene's.

use crate::accel::bvh::{AnyLeaf, ClosestLeaf, Traversal};
use crate::accel::triangle::WatertightRay;
use luster_core::math::Ray;
use std::ops::Range;

use super::{Closest, Geom, Scene};

impl Scene {
    /// Whether anything lies on `ray` at `time` between the intersection
    /// epsilon and `t_max`.
    pub fn occluded(&self, ray: &Ray, t_max: f32, time: f32) -> bool {
        #[cfg(target_arch = "x86_64")]
        if self.simd {
            // SAFETY: `simd` says the CPU has AVX2 and FMA.
            return unsafe { self.occluded_avx2(ray, t_max, time) };
        }
        self.occluded_plain(ray, t_max, time)
    }

    /// [`Scene::occluded`] without AVX2, out of line (see
    /// [`Scene::intersect`]'s `intersect_plain`).
    #[inline(never)]
    fn occluded_plain(&self, ray: &Ray, t_max: f32, time: f32) -> bool {
        self.occluded_with::<false>(ray, t_max, time)
    }

    /// The nearest surface along `ray` and its distance ([`Scene::intersect`]
    /// without the shading frame), for a caller compiled for AVX2 and FMA
    /// (`AVX`) or not: the top-level and mesh traversals and the leaf tests
    /// inline into the caller (the leaf tests are `#[inline(always)]` trait
    /// methods, not closures, for that). The results are bit for bit those
    /// of the plain path: Rust never fuses on its own.
    #[inline(always)]
    pub(super) fn closest_with<const AVX: bool>(
        &self,
        ray: &Ray,
        time: f32,
        cull: f32,
    ) -> (f32, Option<Closest>) {
        let t_min = self.intersection_epsilon;
        let mut best_t = f32::INFINITY;
        let mut best = None;
        for (i, (pl, _, _, _)) in self.planes.iter().enumerate() {
            if let Some(t) = pl.intersect(ray, t_min, best_t) {
                best_t = t;
                best = Some(Closest::Plane(i));
            }
        }
        // The node test's constants and the shear of the watertight
        // triangle test (made when first needed), shared by every mesh that
        // needs no transform.
        let tr = Traversal::new::<AVX>(ray);
        let t_max = best_t;
        let mut leaf = TopClosest::<AVX> {
            scene: self,
            ray,
            world: None,
            tr: &tr,
            time,
            t_min,
            cull,
            best_t: &mut best_t,
            best: &mut best,
        };
        if self.tlas.closest_split(&tr, t_max, &mut leaf).is_none() {
            // Nothing tested yet: the walk starts afresh from the root.
            #[cfg(target_arch = "x86_64")]
            if AVX {
                // Called through an opaque pointer: called directly, LLVM
                // may inline it despite `#[inline(never)]`.
                let deep: unsafe fn(&Self, &Ray, &Traversal, f32, f32, &mut f32, &mut Option<Closest>) =
                    std::hint::black_box(Self::closest_deep_avx2);
                // SAFETY: `AVX` callers run only where the CPU has AVX2 and FMA.
                unsafe { deep(self, ray, &tr, time, cull, &mut best_t, &mut best) };
                return (best_t, best);
            }
            self.closest_deep_plain(ray, &tr, time, cull, &mut best_t, &mut best);
        }
        (best_t, best)
    }

    /// The top level's stack walk after [`Scene::closest_with`]'s head
    /// found a deeper tree, out of line (see `bvh::walk`), compiled for AVX2
    /// and FMA. Not generic, which keeps it out of line.
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[inline(never)]
    unsafe fn closest_deep_avx2(
        &self,
        ray: &Ray,
        tr: &Traversal,
        time: f32,
        cull: f32,
        best_t: &mut f32,
        best: &mut Option<Closest>,
    ) {
        self.closest_deep::<true>(ray, tr, time, cull, best_t, best);
    }

    /// [`Scene::closest_deep_avx2`] without AVX2.
    #[inline(never)]
    fn closest_deep_plain(
        &self,
        ray: &Ray,
        tr: &Traversal,
        time: f32,
        cull: f32,
        best_t: &mut f32,
        best: &mut Option<Closest>,
    ) {
        self.closest_deep::<false>(ray, tr, time, cull, best_t, best);
    }

    #[inline(always)]
    fn closest_deep<const AVX: bool>(
        &self,
        ray: &Ray,
        tr: &Traversal,
        time: f32,
        cull: f32,
        best_t: &mut f32,
        best: &mut Option<Closest>,
    ) {
        let (t_min, t_max) = (self.intersection_epsilon, *best_t);
        let mut leaf =
            TopClosest::<AVX> { scene: self, ray, world: None, tr, time, t_min, cull, best_t, best };
        self.tlas.closest_walk(tr, t_max, &mut leaf);
    }

    /// [`Scene::occluded`] compiled for AVX2 and FMA (see
    /// [`Scene::closest_with`]).
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn occluded_avx2(&self, ray: &Ray, t_max: f32, time: f32) -> bool {
        self.occluded_with::<true>(ray, t_max, time)
    }

    #[inline(always)]
    fn occluded_with<const AVX: bool>(&self, ray: &Ray, t_max: f32, time: f32) -> bool {
        let t_min = self.intersection_epsilon;
        if self.planes.iter().any(|(pl, _, _, _)| pl.intersect(ray, t_min, t_max).is_some()) {
            return true;
        }
        let tr = Traversal::new::<AVX>(ray);
        let mut leaf = TopAny::<AVX> { scene: self, ray, world: None, tr: &tr, time, t_min };
        if let Some(blocked) = self.tlas.any_split(&tr, t_max, &mut leaf) {
            return blocked;
        }
        #[cfg(target_arch = "x86_64")]
        if AVX {
            // Through an opaque pointer (see `closest_with`).
            let deep: unsafe fn(&Self, &Ray, &Traversal, f32, f32) -> bool =
                std::hint::black_box(Self::any_deep_avx2);
            // SAFETY: `AVX` callers run only where the CPU has AVX2 and FMA.
            return unsafe { deep(self, ray, &tr, t_max, time) };
        }
        self.any_deep_plain(ray, &tr, t_max, time)
    }

    /// The top level's any-hit stack walk, out of line (see
    /// [`Scene::closest_deep_avx2`]).
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[inline(never)]
    unsafe fn any_deep_avx2(&self, ray: &Ray, tr: &Traversal, t_max: f32, time: f32) -> bool {
        self.any_deep::<true>(ray, tr, t_max, time)
    }

    /// [`Scene::any_deep_avx2`] without AVX2.
    #[inline(never)]
    fn any_deep_plain(&self, ray: &Ray, tr: &Traversal, t_max: f32, time: f32) -> bool {
        self.any_deep::<false>(ray, tr, t_max, time)
    }

    #[inline(always)]
    fn any_deep<const AVX: bool>(&self, ray: &Ray, tr: &Traversal, t_max: f32, time: f32) -> bool {
        let t_min = self.intersection_epsilon;
        let mut leaf = TopAny::<AVX> { scene: self, ray, world: None, tr, time, t_min };
        self.tlas.any_walk(tr, t_max, &mut leaf)
    }
}

/// The closest-hit leaf test of the top level: each primitive of the leaf,
/// in order, against the nearest hit so far.
struct TopClosest<'a, const AVX: bool> {
    scene: &'a Scene,
    ray: &'a Ray,
    /// The world ray's watertight form, once a mesh in world space needs it.
    world: Option<WatertightRay>,
    tr: &'a Traversal,
    time: f32,
    t_min: f32,
    cull: f32,
    best_t: &'a mut f32,
    best: &'a mut Option<Closest>,
}

impl<const AVX: bool> ClosestLeaf for TopClosest<'_, AVX> {
    #[inline(always)]
    fn test(&mut self, range: Range<usize>, t_max: &mut f32) -> bool {
        let scene = self.scene;
        let t_min = self.t_min;
        let mut hit = false;
        for pi in range {
            let p = &scene.prims[pi];
            // An object in world space sees the world ray itself (`to_local`
            // would give the same bits: `o − 0·t` is `o`).
            let moved;
            let local = if p.in_world() {
                self.ray
            } else {
                moved = p.to_local(self.ray, self.time);
                &moved
            };
            match p.geom {
                Geom::Mesh(m) => {
                    let mut own = None;
                    let wr = p.watertight(&mut self.world, self.ray, local, &mut own, scene.axes_by_table);
                    let pre = p.in_world().then_some(self.tr);
                    let accel = scene.meshes[m as usize].accel();
                    if let Some(h) = accel.intersect_split::<AVX>(local, wr, pre, t_min, *t_max, self.cull) {
                        *t_max = h.t;
                        *self.best = Some(Closest::Triangle(pi, h));
                        hit = true;
                    }
                }
                Geom::Sphere(s) => {
                    if let Some(t) = s.intersect(local, t_min, *t_max) {
                        *t_max = t;
                        *self.best = Some(Closest::Sphere(pi));
                        hit = true;
                    }
                }
                Geom::Ellipsoid(e) => {
                    if let Some(t) = scene.ellipsoids[e as usize].intersect(local, t_min, *t_max) {
                        *t_max = t;
                        *self.best = Some(Closest::Ellipsoid(pi));
                        hit = true;
                    }
                }
            }
        }
        if hit {
            *self.best_t = *t_max;
        }
        hit
    }
}

/// The any-hit leaf test of the top level.
struct TopAny<'a, const AVX: bool> {
    scene: &'a Scene,
    ray: &'a Ray,
    /// The world ray's watertight form, once a mesh in world space needs it.
    world: Option<WatertightRay>,
    tr: &'a Traversal,
    time: f32,
    t_min: f32,
}

impl<const AVX: bool> AnyLeaf for TopAny<'_, AVX> {
    #[inline(always)]
    fn test(&mut self, range: Range<usize>, t_max: f32) -> bool {
        let scene = self.scene;
        let t_min = self.t_min;
        // A loop, not `Iterator::any`: a closure would be compiled apart
        // from the AVX2 caller (see `ClosestLeaf`).
        for pi in range {
            let p = &scene.prims[pi];
            let moved;
            let local = if p.in_world() {
                self.ray
            } else {
                moved = p.to_local(self.ray, self.time);
                &moved
            };
            let blocked = match p.geom {
                Geom::Mesh(m) => {
                    let mut own = None;
                    let wr = p.watertight(&mut self.world, self.ray, local, &mut own, scene.axes_by_table);
                    let pre = p.in_world().then_some(self.tr);
                    scene.meshes[m as usize].accel().occluded_split::<AVX>(local, wr, pre, t_min, t_max)
                }
                Geom::Sphere(s) => s.intersect(local, t_min, t_max).is_some(),
                Geom::Ellipsoid(e) => scene.ellipsoids[e as usize].intersect(local, t_min, t_max).is_some(),
            };
            if blocked {
                return true;
            }
        }
        false
    }
}

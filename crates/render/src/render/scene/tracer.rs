//! The render scene as the [`Tracer`] shaders cast their rays into
//! (`trace()`, `occlusion()`, `edgewear()`, `bevel()`; `docs/tracing.md`).
//! A shader's ray leaves its surface as the renderer's own secondary rays
//! do: moved off it along the geometric normal by [`Scene::offset`], on
//! the side the ray heads to, and it sees both sides of every surface.

use luster_core::math::{Ray, Vec3};
use luster_shading::shader::{TraceHit, TraceRay, Tracer};

use super::Scene;

impl Scene {
    /// The world ray `r` is traced as, and how far along its direction it
    /// starts from `r.origin` (the offset's share along it); `None` for a
    /// ray with no direction or a point that is not finite.
    fn shader_ray(&self, r: &TraceRay) -> Option<(Ray, f32)> {
        let (o, d, ng) = (Vec3::from_array(r.origin), Vec3::from_array(r.dir), Vec3::from_array(r.ng));
        if !(o.is_finite() && d.is_finite() && ng.is_finite()) || d == Vec3::ZERO {
            return None;
        }
        if ng == Vec3::ZERO {
            return Some((Ray::new(o, d), 0.0));
        }
        let eps = self.offset(o, o);
        let start = o + ng * if d.dot(ng) < 0.0 { -eps } else { eps };
        Some((Ray::new(start, d), (start - o).dot(d)))
    }
}

impl Tracer for Scene {
    fn trace(&self, r: &TraceRay) -> Option<TraceHit> {
        let (ray, lead) = self.shader_ray(r)?;
        let hit = self.intersect(&ray, r.time, false)?;
        let t = hit.t + lead;
        if t > r.max_dist || t.is_nan() {
            return None;
        }
        let (object_id, instance_id) = self.object_ids(&hit);
        Some(TraceHit {
            t,
            p: hit.p.to_array(),
            n: hit.ns.to_array(),
            ng: hit.ng.to_array(),
            object_id,
            instance_id,
        })
    }

    fn occluded(&self, r: &TraceRay) -> bool {
        let Some((ray, lead)) = self.shader_ray(r) else { return false };
        let reach = r.max_dist - lead;
        reach > 0.0 && Scene::occluded(self, &ray, reach, r.time)
    }
}

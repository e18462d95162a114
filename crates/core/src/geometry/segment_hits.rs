//! Every hit along a ray in one query: what a segment through null boundaries needs
//! (`Scene::crossings`), which otherwise restarts a closest-hit query past each boundary.
//!
//! A core answers with the set of (t, primitive) whose own primitive test hits within
//! (0, t_max) — the same set in every core that answers, since each runs the primitives' own
//! tests (the wide BVH's boxes never cull a primitive whose test hits, `wide.rs`) — sorted by
//! (t, primitive index), so the order does not depend on the traversal either. Cores without the
//! query (obvhs's BVH, Embree) say so, and the caller falls back to restarting. A primitive's
//! test gives its nearest hit only: a curved one (`may_hit_again`) may be crossed again beyond it,
//! which the caller must look for itself.

use super::primitive::{PrimHit, Primitive};
use super::ray::Ray;
use super::triangle::ShearedRay;

/// Every hit by testing every primitive: the flat cores' answer and the reference for the others.
pub fn all_hits_scalar(
    prims: &[Primitive],
    ray: &Ray,
    sheared: &ShearedRay,
    out: &mut Vec<PrimHit>,
) {
    for (i, p) in prims.iter().enumerate() {
        let t = p.intersect(sheared, ray.o, ray.d, ray.t_max);
        if t.is_finite() {
            out.push(PrimHit { t, prim: i as u32 });
        }
    }
}

/// Puts hits in the order a walk along the ray meets them; a tie in t (two triangles sharing the
/// edge the ray crosses) goes to the lower index, as in the closest-hit queries.
pub fn sort_along_ray(hits: &mut [PrimHit]) {
    hits.sort_unstable_by(|a, b| a.t.total_cmp(&b.t).then(a.prim.cmp(&b.prim)));
}

/// Whether a ray may hit the primitive a second time beyond the hit its test gives (a sphere,
/// cylinder or SDF voxel); a triangle, parallelogram or disk is planar: once at most.
pub fn may_hit_again(p: &Primitive) -> bool {
    !matches!(
        p,
        Primitive::Triangle { .. } | Primitive::Quad { .. } | Primitive::Disk { .. }
    )
}

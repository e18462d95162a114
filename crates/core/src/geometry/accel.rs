//! How rays find primitives. Small scenes without triangles (every shipped one but the mesh-light
//! box) test all their primitives at once in vectorised loops (`flat.rs`); the others use one
//! BVH over every primitive (our 8-wide one, `wide.rs`, where AVX2 runs and the scene has at most
//! `WIDE_MAX_PRIMITIVES`; obvhs's compressed-wide one otherwise):
//! triangles, parallelograms and analytic spheres live in the same structure, so a scene pays only
//! for the kinds it has. Either way the closest hit is the primitive's own distance, unrounded.

use super::flat::{self, Flat, Isa};
use super::packet::PACKET;
use super::primitive::{PrimHit, Primitive};
use super::ray::Ray;
use super::segment_hits;
use super::triangle::ShearedRay;
use super::wide::WideBvh;
use crate::math::Vec3;
use glam::UVec2;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::cwbvh::CwBvh;
use obvhs::faststack::StackStack;
use obvhs::{Boundable, BvhBuildParams};
use std::sync::atomic::{AtomicU8, Ordering};

/// Which structure answers ray queries. `Flat` and `FlatScalar` give the same hits bit for bit
/// (at every vector width). The BVH finds the same primitives' own distances except: at an exact
/// tie it names the first primitive it visits (the flat cores the lower index); two hits closer
/// than the rounding of its traversal back-off may resolve either way; and a ray grazing exactly a
/// box corner may be lost by obvhs's node test (tests in this file).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayCore {
    /// `Flat` for scenes of at most `FLAT_MAX_PRIMITIVES` parallelograms and spheres and no
    /// triangles, else `Wide` up to `WIDE_MAX_PRIMITIVES` where the CPU has AVX2, else `Bvh`.
    Auto,
    Bvh,
    /// Every primitive tested against every ray, in vectorised loops (`flat.rs`).
    Flat,
    /// Every primitive tested one at a time: the reference `Flat` is held to.
    FlatScalar,
    /// Intel's Embree 3 (`embree.rs`), where this build found it (`RayCore::available`).
    Embree,
    /// Our 8-wide BVH with triangles tested 8 at a time (`wide.rs`): the flat cores' answer,
    /// bit for bit.
    Wide,
}

/// Above this many primitives a BVH beats testing them all (`benches/ray_cores.rs`; results/bench.md,
/// "The flat core against the BVH").
pub const FLAT_MAX_PRIMITIVES: usize = 64;

/// Up to this many primitives `Auto` picks the wide BVH over obvhs's: the largest size at which
/// it measured faster on both closest hits and occlusion (results/bench.md, "wide BVH": 0.38× and
/// 0.68× at 10⁵ triangles, 1.58× and 1.97× at 10⁶).
pub const WIDE_MAX_PRIMITIVES: usize = 100_000;

impl RayCore {
    pub const ALL: [RayCore; 6] = [
        RayCore::Auto,
        RayCore::Bvh,
        RayCore::Flat,
        RayCore::FlatScalar,
        RayCore::Embree,
        RayCore::Wide,
    ];

    pub fn name(self) -> &'static str {
        match self {
            RayCore::Auto => "auto",
            RayCore::Bvh => "bvh",
            RayCore::Flat => "flat",
            RayCore::FlatScalar => "flat-scalar",
            RayCore::Embree => "embree",
            RayCore::Wide => "wide",
        }
    }

    pub fn from_name(name: &str) -> Option<RayCore> {
        RayCore::ALL.into_iter().find(|c| c.name() == name)
    }

    /// Whether this build can run it: every core but Embree always; Embree when `build.rs`
    /// found its library.
    pub fn available(self) -> bool {
        self != RayCore::Embree || cfg!(lt_embree)
    }

    /// The command line's `--ray-core`: a known name this build can run, else why not.
    pub fn parse(name: &str) -> Result<RayCore, String> {
        let names: Vec<&str> = RayCore::ALL
            .iter()
            .filter(|c| c.available())
            .map(|c| c.name())
            .collect();
        match RayCore::from_name(name) {
            Some(c) if c.available() => Ok(c),
            Some(_) => Err(format!(
                "the ray core '{name}' is not in this build: Embree 3 was not found when it was \
                 compiled (install libembree-dev, or set LT_EMBREE_DIR, and rebuild); available: {}",
                names.join(", ")
            )),
            None => Err(format!(
                "unknown ray core '{name}' (available: {})",
                names.join(", ")
            )),
        }
    }
}

static RAY_CORE: AtomicU8 = AtomicU8::new(0);

/// The ray core every `Accel::build` after this call uses (the command line's `--ray-core`).
pub fn set_ray_core(core: RayCore) {
    let i = RayCore::ALL.iter().position(|&c| c == core).unwrap_or(0);
    RAY_CORE.store(i as u8, Ordering::Relaxed);
}

fn default_ray_core() -> RayCore {
    RayCore::ALL[RAY_CORE.load(Ordering::Relaxed) as usize]
}

/// The structure behind an `Accel`.
enum Structure {
    Bvh {
        bvh: CwBvh,
        /// Whether the tree is shallow enough for the small traversal stack (`SMALL_STACK`).
        shallow: bool,
    },
    Flat(Flat),
    FlatScalar,
    Wide(WideBvh),
    #[cfg(lt_embree)]
    Embree(super::embree::EmbreeScene),
}

pub struct Accel {
    structure: Structure,
    /// Primitives in the structure's order (the BVH's, or as given), so hit ids index this directly.
    prims: Vec<Primitive>,
    bounds: (Vec3, Vec3),
    /// Whether any primitive is a triangle: only triangles need the per-ray shear.
    has_triangles: bool,
}

/// obvhs's own traversal state zeroes a 32-entry stack (256 bytes, a `memset` call) for every ray,
/// which costs about as much as traversing a tree of a few nodes. Scenes whose tree is at most
/// `SMALL_STACK - 2` levels deep (every Cornell-box variant) traverse with an 8-entry stack
/// instead; deeper trees keep obvhs's 32. The traversal itself is obvhs's `traverse!` macro, so
/// the nodes and primitives visited, their order and every result are the same either way.
const SMALL_STACK: usize = 8;
const FULL_STACK: usize = 32;

/// The fields obvhs's `traverse!` macro reads and writes, with a stack of `N` entries (it holds
/// `N − 1`: a push onto a full `StackStack` overwrites its last entry).
struct Traversal<const N: usize> {
    stack: StackStack<UVec2, N>,
    current_group: UVec2,
    primitive_group: UVec2,
    oct_inv4: u32,
    primitive_id: u32,
    hitmask: u32,
}

impl<const N: usize> Traversal<N> {
    /// Starts at the root (a tree with nodes), children visited in the order `d`'s octant gives.
    #[inline(always)]
    fn new(d: Vec3) -> Self {
        // The octant code obvhs's node test expects: per axis, one bit in every byte when that
        // component is non-negative (x 4, y 2, z 1).
        let bit = |c: f32, b: u32| if c < 0.0 { 0 } else { b * 0x0101_0101 };
        Traversal {
            stack: StackStack::default(),
            current_group: UVec2::new(0, 0x8000_0000),
            primitive_group: UVec2::ZERO,
            oct_inv4: bit(d.x, 4) | bit(d.y, 2) | bit(d.z, 1),
            primitive_id: 0,
            hitmask: 0,
        }
    }
}

/// Levels of inner nodes below and including `node` (a leaf-only node counts 1). The inner
/// children of a node are stored contiguously from `child_base_idx`, one per set `imask` bit.
fn tree_depth(bvh: &CwBvh, node: usize) -> usize {
    let n = &bvh.nodes[node];
    let base = n.child_base_idx as usize;
    1 + (0..n.imask.count_ones() as usize)
        .map(|k| tree_depth(bvh, base + k))
        .max()
        .unwrap_or(0)
}

impl Accel {
    /// The structure `set_ray_core` chose (`Auto` unless set).
    pub fn build(prims: Vec<Primitive>) -> Accel {
        Accel::build_with(prims, default_ray_core())
    }

    pub fn build_with(prims: Vec<Primitive>, core: RayCore) -> Accel {
        let total = prims
            .iter()
            .fold(Aabb::empty(), |acc, p| acc.union(&p.aabb()));
        let bounds = if prims.is_empty() {
            (Vec3::ZERO, Vec3::ZERO)
        } else {
            (total.min.into(), total.max.into())
        };
        let has_triangles = prims
            .iter()
            .any(|p| matches!(p, Primitive::Triangle { .. }));
        let core = match core {
            // Triangles are tested one by one in the flat core, which made a Cornell box with an
            // 8-triangle light 30 % slower than the BVH (results/bench.md).
            RayCore::Auto if prims.len() <= FLAT_MAX_PRIMITIVES && !has_triangles => RayCore::Flat,
            // The 8-wide tree beats obvhs's up to 10⁵ triangles where AVX2 runs its box and edge
            // tests (results/bench.md, "wide BVH"; results/bench-peers.md, round 6 of
            // "Participating media"); past that its full-precision nodes fall out of cache.
            RayCore::Auto if prims.len() <= WIDE_MAX_PRIMITIVES && Isa::widest() >= Isa::Avx2 => {
                RayCore::Wide
            }
            RayCore::Auto => RayCore::Bvh,
            c => c,
        };
        let (structure, prims) = match core {
            #[cfg(lt_embree)]
            RayCore::Embree if !prims.is_empty() => match super::embree::EmbreeScene::new(&prims) {
                Some(e) => (Structure::Embree(e), prims),
                None => {
                    eprintln!("warning: Embree could not build the scene; using the BVH");
                    return Accel::build_with(prims, RayCore::Bvh);
                }
            },
            RayCore::Flat => (Structure::Flat(Flat::new(&prims)), prims),
            RayCore::FlatScalar => (Structure::FlatScalar, prims),
            RayCore::Wide if !prims.is_empty() => (Structure::Wide(WideBvh::new(&prims)), prims),
            _ if prims.is_empty() => (
                Structure::Bvh {
                    bvh: CwBvh::default(),
                    shallow: true,
                },
                prims,
            ),
            _ => {
                let mut build_time = Default::default();
                let bvh = build_cwbvh(&prims, BvhBuildParams::medium_build(), &mut build_time);
                let ordered: Vec<Primitive> = bvh
                    .primitive_indices
                    .iter()
                    .map(|&i| prims[i as usize])
                    .collect();
                let shallow = bvh.nodes.is_empty() || tree_depth(&bvh, 0) + 2 <= SMALL_STACK;
                (Structure::Bvh { bvh, shallow }, ordered)
            }
        };
        Accel {
            structure,
            prims,
            bounds,
            has_triangles,
        }
    }

    /// The structure in use and, for `Flat`, the instruction set its loops run on: "bvh",
    /// "flat (avx512)", "flat-scalar", …
    pub fn describe(&self) -> String {
        match &self.structure {
            Structure::Flat(f) => format!("flat ({})", f.isa().name()),
            Structure::Wide(w) => format!("wide ({})", w.isa().name()),
            _ => self.core().name().to_string(),
        }
    }

    /// The structure in use (never `Auto`).
    pub fn core(&self) -> RayCore {
        match self.structure {
            Structure::Bvh { .. } => RayCore::Bvh,
            Structure::Flat(_) => RayCore::Flat,
            Structure::FlatScalar => RayCore::FlatScalar,
            Structure::Wide(_) => RayCore::Wide,
            #[cfg(lt_embree)]
            Structure::Embree(_) => RayCore::Embree,
        }
    }

    /// The triangle test's per-ray setup, skipped (never read) in scenes without triangles.
    #[inline]
    fn sheared(&self, o: Vec3, d: Vec3) -> ShearedRay {
        if self.has_triangles {
            ShearedRay::new(o, d)
        } else {
            ShearedRay::UNUSED
        }
    }

    #[inline]
    pub fn primitive(&self, i: u32) -> &Primitive {
        &self.prims[i as usize]
    }

    pub fn primitive_count(&self) -> usize {
        self.prims.len()
    }

    /// Axis-aligned bounds of all primitives (min, max).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    /// obvhs's wide-node test clamps the entry distance to an absolute 1e-4 (`cwbvh::node::EPSILON`),
    /// which would cull every box closer than 1e-4 scene units — at millimetre scale, whole walls.
    /// Traversal therefore starts `TRAVERSAL_BACKOFF` behind the real origin, so every true hit is
    /// at least that far along the traversal ray; primitive tests subtract it again.
    ///
    /// The direction's signed zeros become +0: obvhs inverts a zero component to ±1/ε by its sign
    /// bit but picks the slab's near side by `d < 0`, so a −0 component (a negated axis vector, as
    /// a shadow ray towards a directional light along an axis) swapped near and far and missed
    /// every box.
    #[inline]
    fn obvhs_ray(ray: &Ray) -> obvhs::ray::Ray {
        let o = ray.o - ray.d * TRAVERSAL_BACKOFF;
        let d = ray.d + Vec3::ZERO; // −0 + +0 = +0; every other value unchanged
        obvhs::ray::Ray::new(o.into(), d.into(), 0.0, ray.t_max + TRAVERSAL_BACKOFF)
    }

    /// Closest hit along the ray within (0, t_max).
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        if self.prims.is_empty() {
            return None;
        }
        match &self.structure {
            Structure::Flat(flat) => flat.closest(&self.prims, ray, &self.sheared(ray.o, ray.d)),
            Structure::FlatScalar => {
                flat::closest_scalar(&self.prims, ray, &self.sheared(ray.o, ray.d))
            }
            Structure::Wide(w) => w.closest(&self.prims, ray, &self.sheared(ray.o, ray.d)),
            Structure::Bvh { bvh, shallow: true } => self.closest::<SMALL_STACK>(bvh, ray),
            Structure::Bvh { bvh, .. } => self.closest::<FULL_STACK>(bvh, ray),
            #[cfg(lt_embree)]
            Structure::Embree(e) => e.closest(&self.prims, ray, &self.sheared(ray.o, ray.d)),
        }
    }

    /// `intersect` of each ray of a packet whose `active` flag is set (`None` on the others): the
    /// flat core tests the rays together (`packet.rs`), the other cores one by one.
    pub fn intersect_packet(
        &self,
        rays: &[Ray; PACKET],
        active: &[bool; PACKET],
    ) -> [Option<PrimHit>; PACKET] {
        match &self.structure {
            Structure::Flat(flat) if !self.prims.is_empty() => {
                let sheared = std::array::from_fn(|i| self.sheared(rays[i].o, rays[i].d));
                flat.closest_packet(&self.prims, rays, &sheared, active)
            }
            _ => std::array::from_fn(|i| active[i].then(|| self.intersect(&rays[i])).flatten()),
        }
    }

    /// `occluded` of each ray of a packet whose `active` flag is set (false on the others): the
    /// flat core tests the rays together (`packet.rs`), the other cores one by one.
    pub fn occluded_packet(&self, rays: &[Ray; PACKET], active: &[bool; PACKET]) -> [bool; PACKET] {
        match &self.structure {
            Structure::Flat(flat) if !self.prims.is_empty() => {
                let sheared = std::array::from_fn(|i| self.sheared(rays[i].o, rays[i].d));
                flat.occluded_packet(&self.prims, rays, &sheared, active)
            }
            _ => std::array::from_fn(|i| active[i] && self.occluded(&rays[i])),
        }
    }

    /// `intersect` with a traversal stack of `N` entries: obvhs's `ray_traverse`, on our state.
    #[inline(always)]
    fn closest<const N: usize>(&self, bvh: &CwBvh, ray: &Ray) -> Option<PrimHit> {
        let prims = &self.prims;
        let (o, d) = (ray.o, ray.d);
        let sheared = self.sheared(o, d);
        let mut traverse_ray = Self::obvhs_ray(ray);
        let t_limit = traverse_ray.tmax;
        let mut best = PrimHit {
            t: f32::INFINITY,
            prim: u32::MAX,
        };
        let mut state = Traversal::<N>::new(d);
        let mut node;
        obvhs::traverse!(
            bvh,
            node,
            state,
            node.intersect_ray(&traverse_ray, state.oct_inv4),
            {
                let id = state.primitive_id;
                // Tested from the real origin, compared in traversal-ray distance, reported as
                // the primitive's own distance (the back-off would round it).
                let t = prims[id as usize].intersect(
                    &sheared,
                    o,
                    d,
                    traverse_ray.tmax - TRAVERSAL_BACKOFF,
                );
                if t + TRAVERSAL_BACKOFF < traverse_ray.tmax {
                    best = PrimHit { t, prim: id };
                    traverse_ray.tmax = t + TRAVERSAL_BACKOFF;
                }
            }
        );
        (best.t + TRAVERSAL_BACKOFF < t_limit && best.t < ray.t_max).then_some(best)
    }

    /// True when anything blocks the ray within (0, t_max). Stops at the first blocker.
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        if self.prims.is_empty() {
            return false;
        }
        match &self.structure {
            Structure::Flat(flat) => flat.occluded(&self.prims, ray, &self.sheared(ray.o, ray.d)),
            Structure::FlatScalar => {
                flat::occluded_scalar(&self.prims, ray, &self.sheared(ray.o, ray.d))
            }
            Structure::Wide(w) => w.occluded(&self.prims, ray, &self.sheared(ray.o, ray.d)),
            Structure::Bvh { bvh, shallow: true } => self.any_hit::<SMALL_STACK>(bvh, ray),
            Structure::Bvh { bvh, .. } => self.any_hit::<FULL_STACK>(bvh, ray),
            #[cfg(lt_embree)]
            Structure::Embree(e) => e.occluded(ray, &self.sheared(ray.o, ray.d)),
        }
    }

    /// Every hit within (0, t_max) in one query, sorted along the ray (`segment_hits.rs`) into
    /// `out` (cleared first); false, with `out` empty, where this core has no such query.
    pub fn all_hits(&self, ray: &Ray, out: &mut Vec<PrimHit>) -> bool {
        out.clear();
        let sheared = self.sheared(ray.o, ray.d);
        match &self.structure {
            Structure::Flat(_) | Structure::FlatScalar => {
                segment_hits::all_hits_scalar(&self.prims, ray, &sheared, out)
            }
            Structure::Wide(w) => w.all_hits(&self.prims, ray, &sheared, out),
            _ if self.prims.is_empty() => {}
            _ => return false,
        }
        segment_hits::sort_along_ray(out);
        true
    }

    /// `occluded` with a traversal stack of `N` entries: obvhs's `ray_traverse_miss`, negated.
    #[inline(always)]
    fn any_hit<const N: usize>(&self, bvh: &CwBvh, ray: &Ray) -> bool {
        let prims = &self.prims;
        let (o, d, t_max) = (ray.o, ray.d, ray.t_max);
        let sheared = self.sheared(o, d);
        let traverse_ray = Self::obvhs_ray(ray);
        let mut state = Traversal::<N>::new(d);
        let mut node;
        let mut hit = false;
        'outer: {
            obvhs::traverse!(
                bvh,
                node,
                state,
                node.intersect_ray(&traverse_ray, state.oct_inv4),
                {
                    let t = prims[state.primitive_id as usize].intersect(&sheared, o, d, t_max)
                        + TRAVERSAL_BACKOFF;
                    if t < traverse_ray.tmax {
                        hit = true;
                        break 'outer;
                    }
                }
            );
        }
        hit
    }
}

/// How far behind its origin a ray's BVH traversal starts (see `Accel::obvhs_ray`): twice obvhs's
/// clamp. Only box tests see it; primitives are always intersected from the true origin.
const TRAVERSAL_BACKOFF: f32 = 2e-4;

#[cfg(test)]
mod tests;

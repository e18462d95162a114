//! Small scenes without a tree: every primitive is tested against every ray, in loops the
//! compiler vectorises.
//!
//! A Cornell box is 18 parallelograms. Traversing a wide BVH over them costs two or three node
//! tests, a stack and a scalar test per candidate (~1 250 instructions per closest hit, measured
//! in results/bench.md). Here the parallelograms (`QuadSoa`) and spheres (`SphereSoa`) are stored
//! component by component and their branch-free tests run over all of them at once; triangles are
//! tested one by one. The loops are compiled three times — for AVX-512, for AVX2 and for the
//! baseline (SSE2 on x86-64, whatever the target has elsewhere) — and `Isa::detect` picks one at
//! run time, so the shipped build needs no `target-cpu`.
//!
//! Bits: every lane performs the scalar test's IEEE operations in the scalar order (Rust never
//! fuses a multiply and an add, nor reassociates), so every width gives the same distances. The
//! answer is defined without reference to an order of work: the closest hit is the smallest
//! (distance, primitive index) pair, so a tie (a ray through a shared box edge) goes to the lower
//! index. `closest_scalar`/`occluded_scalar` are the reference every width is tested against.

use super::primitive::{PrimHit, Primitive};
use super::quad::QuadSoa;
use super::ray::Ray;
use super::soa::CHUNK;
use super::sphere::SphereSoa;
use super::triangle::ShearedRay;

/// The instruction sets the loops are compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Isa {
    Baseline,
    Avx2,
    Avx512,
}

impl Isa {
    /// AVX2 where the CPU has it, else the baseline; or the one `LT_FLAT_ISA` (baseline, avx2,
    /// avx512) names, if the CPU runs it. AVX-512 is not the default: on the project's machine it
    /// measured slower than AVX2 (results/bench.md: 18 parallelograms fill 2 × 16 lanes against
    /// 3 × 8, and 512-bit work lowers the clock).
    pub fn detect() -> Isa {
        let preferred = Isa::widest().min(Isa::Avx2);
        std::env::var("LT_FLAT_ISA")
            .ok()
            .and_then(|name| Isa::available().into_iter().find(|i| i.name() == name))
            .unwrap_or(preferred)
    }

    /// The widest instruction set this CPU runs, whatever `LT_FLAT_ISA` says.
    pub(crate) fn widest() -> Isa {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f") {
                return Isa::Avx512;
            }
            if std::arch::is_x86_feature_detected!("avx2") {
                return Isa::Avx2;
            }
        }
        Isa::Baseline
    }

    pub fn name(self) -> &'static str {
        match self {
            Isa::Baseline => "baseline",
            Isa::Avx2 => "avx2",
            Isa::Avx512 => "avx512",
        }
    }

    /// Every instruction set this CPU runs (for tests: each must give the same bits).
    pub fn available() -> Vec<Isa> {
        let best = Isa::widest();
        [Isa::Baseline, Isa::Avx2, Isa::Avx512]
            .into_iter()
            .filter(|&i| i <= best)
            .collect()
    }
}

pub struct Flat {
    pub(super) quads: QuadSoa,
    /// Index in the scene's primitive list of each parallelogram (`u32::MAX` for padding, to a
    /// multiple of `CHUNK`).
    pub(super) quad_ids: Vec<u32>,
    pub(super) spheres: SphereSoa,
    pub(super) sphere_ids: Vec<u32>,
    /// Indices of the triangles, disks and cylinders, tested one by one.
    pub(super) triangles: Vec<u32>,
    pub(super) isa: Isa,
}

/// The smaller of two candidate hits by (distance, primitive index).
#[inline(always)]
pub(super) fn nearer(a: PrimHit, t: f32, prim: u32) -> PrimHit {
    if t < a.t || (t == a.t && prim < a.prim) {
        PrimHit { t, prim }
    } else {
        a
    }
}

/// `best` becomes the nearest of itself and the lanes that hit: a mask of the hits is built
/// without branches, then only its set bits are visited (measured as fast as a branch per lane,
/// with fewer instructions). A function, not a closure: a closure is not inlined into the
/// target-feature functions.
#[inline(always)]
pub(super) fn take_hits<const W: usize>(best: &mut PrimHit, ts: &[f32; W], ids: &[u32]) {
    let mut hits = ts
        .iter()
        .enumerate()
        .fold(0u32, |m, (i, &t)| m | (((t < f32::INFINITY) as u32) << i));
    while hits != 0 {
        let lane = hits.trailing_zeros() as usize;
        *best = nearer(*best, ts[lane], ids[lane]);
        hits &= hits - 1;
    }
}

pub(super) const NONE: PrimHit = PrimHit {
    t: f32::INFINITY,
    prim: u32::MAX,
};

/// Indices padded with `u32::MAX` to a multiple of `CHUNK`.
fn padded_ids(mut ids: Vec<u32>) -> Vec<u32> {
    ids.resize(ids.len().div_ceil(CHUNK) * CHUNK, u32::MAX);
    ids
}

impl Flat {
    pub fn new(prims: &[Primitive]) -> Flat {
        Flat::with_isa(prims, Isa::detect())
    }

    /// With the loops of `isa`, which must be one `Isa::available` lists.
    pub fn with_isa(prims: &[Primitive], isa: Isa) -> Flat {
        let (mut quads, mut quad_ids) = (Vec::new(), Vec::new());
        let (mut spheres, mut sphere_ids) = (Vec::new(), Vec::new());
        let mut triangles = Vec::new();
        for (i, p) in prims.iter().enumerate() {
            let i = i as u32;
            match *p {
                Primitive::Quad { q, .. } => {
                    quads.push(q);
                    quad_ids.push(i);
                }
                Primitive::Sphere { center, radius, .. } => {
                    spheres.push((center, radius));
                    sphere_ids.push(i);
                }
                // Triangles, disks and cylinders: tested one by one.
                Primitive::Triangle { .. }
                | Primitive::Disk { .. }
                | Primitive::Cylinder { .. }
                | Primitive::SdfVoxel { .. } => triangles.push(i),
            }
        }
        assert!(Isa::available().contains(&isa), "{isa:?} is not available");
        Flat {
            quads: QuadSoa::new(&quads),
            quad_ids: padded_ids(quad_ids),
            spheres: SphereSoa::new(&spheres),
            sphere_ids: padded_ids(sphere_ids),
            triangles,
            isa,
        }
    }

    pub fn isa(&self) -> Isa {
        self.isa
    }

    /// The smallest (t, index) hit within (0, t_max).
    #[inline]
    pub fn closest(&self, prims: &[Primitive], ray: &Ray, sheared: &ShearedRay) -> Option<PrimHit> {
        // SAFETY: `isa` is only ever a set this CPU runs (`Isa::detect`/`Isa::available`).
        let best = match self.isa {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => unsafe { self.closest_avx512(prims, ray, sheared) },
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { self.closest_avx2(prims, ray, sheared) },
            _ => self.closest_in::<4>(prims, ray, sheared),
        };
        best.t.is_finite().then_some(best)
    }

    /// True when any primitive blocks the ray within (0, t_max).
    #[inline]
    pub fn occluded(&self, prims: &[Primitive], ray: &Ray, sheared: &ShearedRay) -> bool {
        // SAFETY: as in `closest`.
        match self.isa {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => unsafe { self.occluded_avx512(prims, ray, sheared) },
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { self.occluded_avx2(prims, ray, sheared) },
            _ => self.occluded_in::<4>(prims, ray, sheared),
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    unsafe fn closest_avx512(&self, prims: &[Primitive], ray: &Ray, s: &ShearedRay) -> PrimHit {
        self.closest_in::<16>(prims, ray, s)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn closest_avx2(&self, prims: &[Primitive], ray: &Ray, s: &ShearedRay) -> PrimHit {
        self.closest_in::<8>(prims, ray, s)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    unsafe fn occluded_avx512(&self, prims: &[Primitive], ray: &Ray, s: &ShearedRay) -> bool {
        self.occluded_in::<16>(prims, ray, s)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn occluded_avx2(&self, prims: &[Primitive], ray: &Ray, s: &ShearedRay) -> bool {
        self.occluded_in::<8>(prims, ray, s)
    }

    /// `W` lanes at a time; groups of `W` that are all padding are skipped.
    #[inline(always)]
    fn closest_in<const W: usize>(
        &self,
        prims: &[Primitive],
        ray: &Ray,
        sheared: &ShearedRay,
    ) -> PrimHit {
        let (o, d, t_max) = (ray.o, ray.d, ray.t_max);
        let o_abs = o.abs();
        let mut best = NONE;
        for (g, ids) in self.quad_ids.chunks_exact(W).enumerate() {
            if ids[0] != u32::MAX {
                let ts = self.quads.distances::<W>(g * W, o, o_abs, d, t_max);
                take_hits(&mut best, &ts, ids);
            }
        }
        for (g, ids) in self.sphere_ids.chunks_exact(W).enumerate() {
            if ids[0] != u32::MAX {
                let ts = self.spheres.distances::<W>(g * W, o, d, t_max);
                take_hits(&mut best, &ts, ids);
            }
        }
        for &i in &self.triangles {
            let t = prims[i as usize].intersect(sheared, o, d, t_max);
            best = nearer(best, t, i);
        }
        best
    }

    /// Stops at the first group of `W` that blocks the ray.
    #[inline(always)]
    fn occluded_in<const W: usize>(
        &self,
        prims: &[Primitive],
        ray: &Ray,
        sheared: &ShearedRay,
    ) -> bool {
        let (o, d, t_max) = (ray.o, ray.d, ray.t_max);
        let o_abs = o.abs();
        for (g, ids) in self.quad_ids.chunks_exact(W).enumerate() {
            if ids[0] != u32::MAX && blocks(&self.quads.distances::<W>(g * W, o, o_abs, d, t_max)) {
                return true;
            }
        }
        for (g, ids) in self.sphere_ids.chunks_exact(W).enumerate() {
            if ids[0] != u32::MAX && blocks(&self.spheres.distances::<W>(g * W, o, d, t_max)) {
                return true;
            }
        }
        for &i in &self.triangles {
            if prims[i as usize]
                .intersect(sheared, o, d, t_max)
                .is_finite()
            {
                return true;
            }
        }
        false
    }
}

/// Whether any lane hit.
#[inline(always)]
pub(super) fn blocks<const W: usize>(ts: &[f32; W]) -> bool {
    ts.iter().fold(false, |any, &t| any | (t < f32::INFINITY))
}

/// The reference: every primitive's scalar test in index order, keeping the smallest (t, index).
pub fn closest_scalar(prims: &[Primitive], ray: &Ray, sheared: &ShearedRay) -> Option<PrimHit> {
    let mut best = NONE;
    for (i, p) in prims.iter().enumerate() {
        best = nearer(
            best,
            p.intersect(sheared, ray.o, ray.d, ray.t_max),
            i as u32,
        );
    }
    best.t.is_finite().then_some(best)
}

/// The reference for `Flat::occluded`.
pub fn occluded_scalar(prims: &[Primitive], ray: &Ray, sheared: &ShearedRay) -> bool {
    prims
        .iter()
        .any(|p| p.intersect(sheared, ray.o, ray.d, ray.t_max).is_finite())
}

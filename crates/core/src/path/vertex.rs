//! One vertex of a light or camera subpath. The constructors here are the only place where a vertex
//! is born from a sampled direction, so they are the only place that turns the walk's density into
//! the stored area-measure `pdf_fwd` (through [`PathVertex::convert_density`], which calls the named
//! conversions of `crate::measure`).

use crate::camera::Camera;
use crate::light::{LightLeSample, LightLiSample};
use crate::math::{Color, Vec3};
use crate::measure;
use crate::scene::{ConnectionEnd, Scene, SurfaceHit};

/// What a vertex lies on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexKind {
    /// The pinhole. `ng` = `ns` = the viewing axis, so G(x_{k−1} ↔ x_k) carries the camera's cos θ
    /// that `Camera::importance` (N / (A cos⁴θ)) expects.
    Camera,
    /// A light endpoint (x0 of a full path). With `infinite` (sun, directional, environment) the
    /// vertex sits at infinity: `p` is the unit direction from the scene towards the light,
    /// densities of this vertex are solid angle (the discrete 1 for a directional light's
    /// delta direction) and G(x0 ↔ x1) = |cos θ1|. A point light has `ng` = `ns` = 0: it has no
    /// surface, so G carries no cosine at it. A directional light's x0 has `delta` set.
    Light { light: u32, infinite: bool },
    /// A scattering surface.
    Surface { material: u32 },
    /// A scattering point inside medium `medium` (`Scene::media`). It has no surface: `ng` =
    /// `ns` = 0, so G carries no cosine at it (as at a point light), its densities are volume
    /// measure (`measure::solid_angle_to_volume`) and it scatters by the medium's phase function,
    /// never a delta.
    Medium { medium: crate::medium::MediumId },
}

/// A path vertex (pbrt-v4's `Vertex` without the union): `Copy`, integrator-independent.
///
/// **Invariant:** `pdf_fwd` and `pdf_rev` are area measure, except at a vertex at infinity (solid
/// angle) and at a delta position (point light, pinhole: discrete, 1 when chosen).
#[derive(Clone, Copy, Debug)]
pub struct PathVertex {
    pub kind: VertexKind,
    /// Position, or the unit direction towards a light at infinity.
    pub p: Vec3,
    /// Rounding-error bound of `p` (zero for endpoints, whose rays the lights already offset).
    pub p_err: Vec3,
    pub ng: Vec3,
    pub ns: Vec3,
    /// Throughput of the subpath that created the vertex, up to and including it (pbrt's β):
    /// a camera subpath starts at 1, a light subpath at Le / pdf_fwd of x0, and each sample
    /// multiplies it by f_cos / pdf_w. A light endpoint reached by a camera walk
    /// (`as_light_endpoint`, `light_escaped`) keeps the camera walk's β.
    pub beta: Color,
    /// Density with which the walk that created this vertex chose it.
    pub pdf_fwd: f32,
    /// Density of choosing it by a walk in the opposite direction (set by the integrator, 0 here).
    pub pdf_rev: f32,
    /// The vertex scattered (or will scatter) through a delta lobe: it cannot be connected to.
    /// Integrators set it from `BsdfSample::delta`; the from-scratch `Path` code asks the material.
    /// At a light vertex it means the same thing for the emission: the light is delta in
    /// direction (directional), set by the light constructors here. (A delta in position, a
    /// point light, shows as `on_surface()` false instead: the two deltas are kept apart.)
    pub delta: bool,
    /// Unit direction towards the vertex the walk came from, exactly as the walk traced it (zero
    /// at endpoints). Connections evaluate the BSDF with it instead of rebuilding it from two f32
    /// positions, which is ill-conditioned for short segments and sharp (small-α GGX) lobes.
    pub wo: Vec3,
    /// The light a surface vertex emits as, when it lies on an emitter (technique s = 0);
    /// `NO_EMITTER` when none (read it with `emitter()`). A bare u32 instead of `Option<u32>`
    /// keeps the vertex at 128 bytes, which the compiler copies inline: at 132 every push of a
    /// vertex was a `memcpy` call (results/bench.md, "Per-sample costs").
    emitter: u32,
    /// Texture point of a surface vertex (zero elsewhere).
    pub uv: crate::texture::TexPoint,
    /// The hit's `SurfaceHit::tangent` (zero unless the material is anisotropic), so frames
    /// rebuilt at this vertex agree with the one the walk sampled with.
    pub tangent: Vec3,
    /// The media on either side of a surface vertex: an index into `Scene::interfaces` (0: no
    /// medium on either side, every vertex of a scene without media). A u16 fits the padding
    /// beside `delta`, so the vertex stays at 128 bytes.
    pub interface: u16,
}

// Walks push a vertex per bounce; beyond 128 bytes each copy is a `memcpy` call.
const _: () = assert!(std::mem::size_of::<PathVertex>() <= 128);

/// `PathVertex::emitter` of a vertex on no emitter (no scene has 2³² − 1 lights).
const NO_EMITTER: u32 = u32::MAX;

impl PathVertex {
    fn endpoint(kind: VertexKind, p: Vec3, n: Vec3, beta: Color, pdf_fwd: f32) -> PathVertex {
        PathVertex {
            kind,
            p,
            p_err: Vec3::ZERO,
            ng: n,
            ns: n,
            beta,
            pdf_fwd,
            pdf_rev: 0.0,
            delta: false,
            wo: Vec3::ZERO,
            emitter: NO_EMITTER,
            uv: Default::default(),
            tangent: Vec3::ZERO,
            interface: 0,
        }
    }

    /// The camera at the centre of its lens (the pinhole's eye). Its density is 1: the pinhole's
    /// delta position, or a thin lens's aperture sample, which every technique draws alike
    /// (`camera` module docs).
    pub fn camera(camera: &Camera, beta: Color) -> PathVertex {
        PathVertex::camera_at(camera, camera.eye, beta)
    }

    /// The camera vertex at lens point `origin` (a primary ray's origin, or a lens connection's).
    /// An orthographic camera's vertex is a delta in direction (`delta` set): nothing joins it.
    pub fn camera_at(camera: &Camera, origin: Vec3, beta: Color) -> PathVertex {
        let mut v = PathVertex::endpoint(VertexKind::Camera, origin, camera.forward(), beta, 1.0);
        v.delta = camera.is_delta_direction();
        v
    }

    /// A surface the walk reached from `prev` along a ray of direction −`wo`, with density `pdf` —
    /// solid angle at `prev`, except when `prev` is a light at infinity, where it is the density
    /// on the disk perpendicular to the ray (`LightLeSample::pdf_pos`).
    pub fn surface(
        hit: &SurfaceHit,
        wo: Vec3,
        beta: Color,
        pdf: f32,
        prev: &PathVertex,
    ) -> PathVertex {
        let mut v = PathVertex {
            kind: VertexKind::Surface {
                material: hit.material,
            },
            p: hit.p,
            p_err: hit.p_err,
            ng: hit.ng,
            ns: hit.ns,
            beta,
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
            delta: false,
            wo,
            emitter: hit.light.unwrap_or(NO_EMITTER),
            uv: hit.uv,
            tangent: hit.tangent,
            interface: hit.interface,
        };
        v.pdf_fwd = prev.convert_density(pdf, &v);
        v
    }

    /// `surface` reached through participating media: the walk passed every medium piece between
    /// `prev` and the hit with probability `p_pass` (the product of `Medium::free_flight_density`
    /// of the passes, `Scene::free_flight_density`), so `pdf_fwd` = p_ω |cos| / d² · P_pass.
    pub fn surface_through_media(
        hit: &SurfaceHit,
        wo: Vec3,
        beta: Color,
        pdf: f32,
        p_pass: f32,
        prev: &PathVertex,
    ) -> PathVertex {
        let mut v = PathVertex::surface(hit, wo, beta, pdf, prev);
        v.pdf_fwd *= p_pass;
        v
    }

    /// A scattering point `p` in medium `medium`, reached from `prev` along −`wo` by a direction
    /// sampled with solid-angle density `pdf_w` and a free flight that stopped at `p` with density
    /// `p_ff` per unit length (`Scene::free_flight_density`, scattered at the end): `pdf_fwd` =
    /// p_ω p_ff / d², volume measure (`measure::solid_angle_to_volume`). No normal, no uv; `p_err`
    /// bounds the rounding of the point along the ray.
    pub fn medium(
        medium: crate::medium::MediumId,
        p: Vec3,
        wo: Vec3,
        beta: Color,
        pdf_w: f32,
        p_ff: f32,
        prev: &PathVertex,
    ) -> PathVertex {
        let mut v = PathVertex::endpoint(VertexKind::Medium { medium }, p, Vec3::ZERO, beta, 0.0);
        v.wo = wo;
        // p = o + t·d rounds by at most γ₂(|o| + |t·d|) ≤ γ₂(2|o| + |p|) per axis, o within
        // `prev`'s own bound (a ray from a surface starts an offset away); from infinity the
        // origin lies on the scene's bounding disk, bounded by |p| + the scene's size ~ |p| here.
        let o = if prev.is_infinite() {
            p.abs()
        } else {
            prev.p.abs()
        };
        v.p_err = (2.0 * o + p.abs()) * crate::math::gamma(3) + prev.p_err;
        v.pdf_fwd = prev.convert_density(pdf_w, &v) * p_ff;
        v
    }

    /// The medium a segment leaving this vertex in direction `w` lies in, at its start (Mitsuba's
    /// per-ray medium, `scene/media.rs`): a medium vertex's own, the side of a surface `w` leaves
    /// into, the camera's, the medium a light emits into from this point along `w`
    /// (`Scene::light_medium_towards`; at infinity none). Later null boundaries on the way are
    /// `Scene`'s business.
    pub fn medium_towards(&self, scene: &Scene, w: Vec3) -> Option<crate::medium::MediumId> {
        match self.kind {
            VertexKind::Medium { medium } => Some(medium),
            VertexKind::Surface { .. } => scene.medium_across(self.interface, self.ng, w),
            VertexKind::Camera => scene.camera_medium,
            VertexKind::Light { light, .. } => scene.light_medium_towards(light, self.into(), w),
        }
    }

    /// The free-flight density of a walk from this vertex reaching `to`
    /// (`Scene::free_flight_density`: per unit length when `to` lies in a medium, the probability
    /// of passing every medium when it is a surface or a light), starting in the medium this
    /// vertex leaves into towards `to`: the factor of a walk's density that `convert_density`
    /// leaves out. The oracle's (`Path::densities`), the joins' and, where per-ray media are not
    /// reversible, the walks' reverse densities all come from here.
    pub fn free_flight_to(&self, scene: &Scene, to: &PathVertex) -> f32 {
        let medium = self.medium_towards(scene, self.dir_to(to));
        scene.free_flight_density(self.into(), to.into(), medium, to.in_medium())
    }

    /// True for a scattering point inside a medium.
    #[inline]
    pub fn in_medium(&self) -> bool {
        matches!(self.kind, VertexKind::Medium { .. })
    }

    /// The BSDF's frame at a surface vertex: the same as `SurfaceHit::shading_frame` of its hit.
    #[inline]
    pub fn shading_frame(&self) -> crate::bsdf::ShadingFrame {
        crate::bsdf::ShadingFrame::oriented(self.ng, self.ns, self.tangent).with_uv(self.uv)
    }

    /// The same surface as a light endpoint x0 (a camera walk hit an emitter: technique s = 0).
    /// `None` when the surface does not emit.
    pub fn as_light_endpoint(&self) -> Option<PathVertex> {
        let light = self.emitter()?;
        Some(PathVertex {
            kind: VertexKind::Light {
                light,
                infinite: false,
            },
            delta: false,
            ..*self
        })
    }

    /// A camera walk left the scene in direction `dir` towards light `light` at infinity, chosen
    /// with solid-angle density `pdf_w`: the density stays solid angle.
    pub fn light_escaped(light: u32, dir: Vec3, beta: Color, pdf_w: f32) -> PathVertex {
        PathVertex::endpoint(
            VertexKind::Light {
                light,
                infinite: true,
            },
            dir,
            -dir,
            beta,
            pdf_w,
        )
    }

    /// x0 of a light subpath from `Light::sample_le` after choosing the light with `pmf`.
    /// `pdf_fwd` = pmf · pdf_pos (area; 1 for a point light), or pmf · pdf_dir (solid angle; the
    /// discrete 1 for a directional light) at infinity, where the position on the disk belongs to
    /// x1; `beta` = Le / pdf_fwd.
    pub fn light_emitted(scene: &Scene, light: u32, s: &LightLeSample, pmf: f32) -> PathVertex {
        let l = &scene.lights[light as usize];
        if l.is_infinite() {
            let pdf = pmf * s.pdf_dir;
            let kind = VertexKind::Light {
                light,
                infinite: true,
            };
            let mut v = PathVertex::endpoint(kind, -s.ray.d, s.ray.d, s.radiance / pdf, pdf);
            v.delta = l.delta_direction();
            return v;
        }
        let pdf = pmf * s.pdf_pos;
        let n = if l.delta_position() { Vec3::ZERO } else { s.n };
        let mut v = PathVertex::endpoint(
            VertexKind::Light {
                light,
                infinite: false,
            },
            s.p,
            n,
            s.radiance / pdf,
            pdf,
        );
        v.p_err = s.p_err;
        v.uv = s.uv;
        v
    }

    /// x0 chosen by next-event estimation from `from` (`Light::sample_li`, light chosen with `pmf`):
    /// `pdf_fwd` = pmf · pdf_li converted to area at x0 (solid angle at infinity), or pmf alone
    /// for a delta light (point, directional: `LightLiSample::delta`, discrete 1). `beta` =
    /// Le / pdf_fwd (Le: a point light's intensity, a directional light's irradiance).
    pub fn light_sampled(
        scene: &Scene,
        light: u32,
        s: &LightLiSample,
        pmf: f32,
        from: &PathVertex,
    ) -> PathVertex {
        let l = &scene.lights[light as usize];
        let infinite = l.is_infinite();
        let kind = VertexKind::Light { light, infinite };
        let (p, n, le) = match l {
            _ if l.delta_position() => (s.p, Vec3::ZERO, l.intensity_towards(-s.wi)),
            _ if infinite => (s.wi, -s.wi, s.radiance),
            _ => (s.p, s.n, s.radiance),
        };
        let mut v = PathVertex::endpoint(kind, p, n, Color::ZERO, 0.0);
        v.p_err = s.p_err;
        v.uv = s.uv;
        v.delta = l.delta_direction();
        v.pdf_fwd = if s.delta {
            pmf
        } else {
            pmf * from.convert_density(s.pdf_w, &v)
        };
        v.beta = if v.pdf_fwd > 0.0 {
            le / v.pdf_fwd
        } else {
            Color::ZERO
        };
        v
    }

    /// The light a surface vertex emits as, when it lies on an emitter (technique s = 0).
    #[inline]
    pub fn emitter(&self) -> Option<u32> {
        (self.emitter != NO_EMITTER).then_some(self.emitter)
    }

    /// True for a light vertex at infinity.
    #[inline]
    pub fn is_infinite(&self) -> bool {
        matches!(self.kind, VertexKind::Light { infinite: true, .. })
    }

    /// True at a light vertex that no walk can arrive at, whose reverse density c_0 is therefore
    /// zero: a light delta in position (a point light, which has no surface) or in direction (a
    /// directional light, `delta`). `Path::densities` says the same from the scene's light
    /// (`Light::is_delta`).
    #[inline]
    pub fn is_delta_light(&self) -> bool {
        matches!(self.kind, VertexKind::Light { .. }) && (self.delta || !self.on_surface())
    }

    /// True when the vertex has a surface (a normal) whose cosine enters G and area conversions.
    #[inline]
    pub fn on_surface(&self) -> bool {
        self.ng != Vec3::ZERO
    }

    /// Unit direction from this vertex towards `to` (either may be at infinity).
    #[inline]
    pub fn dir_to(&self, to: &PathVertex) -> Vec3 {
        if to.is_infinite() {
            to.p
        } else if self.is_infinite() {
            -self.p
        } else {
            (to.p - self.p).normalize()
        }
    }

    /// pbrt's `ConvertDensity`: a density with which this vertex chose the direction towards
    /// `next` (solid angle; for a vertex at infinity, the perpendicular-disk density) turned into
    /// the measure `next` is stored in. A vertex at infinity keeps solid angle.
    ///
    /// Through media this is the density of `next` given that the free flight reached it: the
    /// caller multiplies the free-flight density of the segment (`Scene::free_flight_density`:
    /// per unit length when `next` is a medium vertex, which makes the product a volume density;
    /// the probability of passing every medium when `next` is a surface).
    #[inline]
    pub fn convert_density(&self, pdf: f32, next: &PathVertex) -> f32 {
        if next.is_infinite() {
            return pdf;
        }
        // Surfaces first: the medium test sits on the branch without a normal, so a scene
        // without media pays nothing for it.
        let n = if next.on_surface() {
            next.ng
        } else if next.in_medium() {
            if self.is_infinite() {
                // A parallel ray from the disk of a light at infinity: no 1/d² (`perpendicular`).
                return pdf;
            }
            return measure::solid_angle_to_volume(pdf, 1.0, self.p, next.p);
        } else {
            self.dir_to(next)
        };
        if self.is_infinite() {
            return measure::perpendicular_to_area(pdf, -self.p, n);
        }
        measure::solid_angle_to_area(pdf, self.p, next.p, n)
    }
}

/// Veach's geometry term G(a ↔ b) between two path vertices, visibility excluded: the cosine at
/// each end that has a surface (the camera's is its viewing axis), over the squared distance;
/// with one end at infinity only the other end's cosine remains.
pub fn geometry(a: &PathVertex, b: &PathVertex) -> f32 {
    let cos_at = |v: &PathVertex, w: Vec3| {
        if v.on_surface() {
            v.ng.dot(w).abs()
        } else {
            1.0
        }
    };
    if a.is_infinite() {
        return cos_at(b, a.p);
    }
    if b.is_infinite() {
        return cos_at(a, b.p);
    }
    if a.on_surface() && b.on_surface() {
        return measure::geometry_term(a.p, a.ng, b.p, b.ng);
    }
    let d = b.p - a.p;
    let d2 = d.length_squared();
    if d2 == 0.0 {
        return 0.0;
    }
    let w = d / d2.sqrt();
    cos_at(a, w) * cos_at(b, w) / d2
}

impl From<&PathVertex> for ConnectionEnd {
    /// What visibility needs of a vertex (for one at infinity, `p` is its direction).
    fn from(v: &PathVertex) -> ConnectionEnd {
        ConnectionEnd {
            p: v.p,
            p_err: v.p_err,
            ng: v.ng,
            infinite: v.is_infinite(),
        }
    }
}

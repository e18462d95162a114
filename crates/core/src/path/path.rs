//! A complete path x̄ = x0 … xk (x0 on a light, xk the camera: Veach's order) and, from scratch,
//! its measurement contribution f(x̄) and its density p_s(x̄) under every technique s.

use super::densities::Densities;
use super::scatter::{connectable, delta_tolerance, scatter, Scatter};
use super::vertex::{geometry, PathVertex, VertexKind};
use crate::bsdf::TransportMode;
use crate::light::Light;
use crate::math::Color;
use crate::scene::Scene;
use glam::DVec3;

/// A full path, light end first. Interior vertices are `Surface`s or `Medium` points.
#[derive(Clone, Debug)]
pub struct Path {
    pub vertices: Vec<PathVertex>,
}

impl Path {
    /// Panics unless x0 is a light, xk the camera and the rest surfaces or medium points (a
    /// programming error).
    pub fn new(vertices: Vec<PathVertex>) -> Path {
        let n = vertices.len();
        assert!(n >= 2, "a path needs a light and a camera vertex");
        assert!(
            matches!(vertices[0].kind, VertexKind::Light { .. }),
            "x0 must be a light vertex"
        );
        assert!(
            matches!(vertices[n - 1].kind, VertexKind::Camera),
            "xk must be the camera"
        );
        assert!(
            vertices[1..n - 1].iter().all(|v| matches!(
                v.kind,
                VertexKind::Surface { .. } | VertexKind::Medium { .. }
            )),
            "interior vertices must be surfaces or medium points"
        );
        Path { vertices }
    }

    /// Joins a light subpath (x0 first) and a camera subpath (camera first, as it was walked).
    pub fn from_subpaths(light: &[PathVertex], camera: &[PathVertex]) -> Path {
        Path::new(light.iter().chain(camera.iter().rev()).copied().collect())
    }

    /// Number of segments k (vertices x0 … xk).
    pub fn k(&self) -> usize {
        self.vertices.len() - 1
    }

    /// Scattering at x_i with `wo` towards x_from and `wi` towards x_to.
    fn scatter_at(
        &self,
        scene: &Scene,
        i: usize,
        from: usize,
        to: usize,
        mode: TransportMode,
    ) -> Scatter {
        let v = &self.vertices;
        let tol = delta_tolerance(&v[i], &v[from], &v[to]);
        scatter(
            scene,
            &v[i],
            v[i].dir_to(&v[from]),
            v[i].dir_to(&v[to]),
            mode,
            tol,
        )
    }

    /// T(x_i ↔ x_j) per channel through every medium between them (`Scene::edge_transmittance`),
    /// starting in the medium x_i leaves into. 1 in a scene without media, which asks nothing.
    fn transmittance(&self, scene: &Scene, i: usize, j: usize) -> DVec3 {
        if !scene.has_media {
            return DVec3::ONE;
        }
        let v = &self.vertices;
        let medium = v[i].medium_towards(scene, v[i].dir_to(&v[j]));
        scene
            .edge_transmittance((&v[i]).into(), (&v[j]).into(), medium)
            .as_dvec3()
    }

    /// The free-flight density of the walk from x_from reaching x_to (`Scene::free_flight_density`:
    /// per unit length when x_to is a medium point, a pass probability when it is a surface),
    /// which multiplies the converted direction density into x_to's density. 1 without media.
    fn free_flight(&self, scene: &Scene, from: usize, to: usize) -> f64 {
        if !scene.has_media {
            return 1.0;
        }
        let v = &self.vertices;
        v[from].free_flight_to(scene, &v[to]) as f64
    }

    fn light<'a>(&self, scene: &'a Scene) -> &'a Light {
        match self.vertices[0].kind {
            VertexKind::Light { light, .. } => &scene.lights[light as usize],
            _ => unreachable!("Path::new checks x0"),
        }
    }

    /// Veach's measurement contribution (1997, ch. 8):
    /// f(x̄) = Le(x0→x1) G(x0↔x1) ∏_{i=1}^{k−1} fs(x_{i−1}→x_i→x_{i+1}) G(x_i↔x_{i+1}) · We(x_{k−1}→x_k),
    /// with visibility NOT included (the caller traced or will test the segments).
    ///
    /// fs is `f_cos / |ng·wi|` in radiance mode (bsdf/mod.rs). In importance mode the material
    /// returns the adjoint and the shading-normal correction moves the |ns|/|ng| ratio to the other
    /// side, so for every non-delta BSDF the factor is the same number: both equal
    /// f · |ns·ω_L| / |ng·ω_L| with ω_L towards the light end — which is f itself when ns = ng.
    /// Where ns ≠ ng that ratio is part of the integrand every technique estimates (Veach 1997,
    /// ch. 5); the `path_space` tests hold both modes to it.
    ///
    /// Delta vertices contribute their delta-stripped lobe value (see `scatter`), stripped of the
    /// Dirac in the direction towards the light, as a camera walk samples it. That is the
    /// convention of every technique that samples the vertex from the camera side; see
    /// `contribution_for` for the others. At a point light Le is the intensity and G has no
    /// cosine at x0; at infinity Le is the radiance along x0.p, and for a directional light
    /// (a delta in direction, stripped like a delta lobe) its irradiance.
    /// The result is f64: per-segment factors scale as 1/length², which underflows f32 for long
    /// paths in scenes measured in kilometres.
    ///
    /// Through media (Pauly et al. 2000) every edge carries T(x_i ↔ x_{i+1}) through every
    /// medium and null boundary between them, and a medium vertex scatters by σs · phase with no
    /// cosine in its G (`scatter`, `path/mod.rs`).
    pub fn contribution(&self, scene: &Scene) -> DVec3 {
        self.contribution_for(scene, 0)
    }

    /// f(x̄) with each delta vertex stripped in the measure in which technique s samples it:
    /// vertices x_i with i < s are sampled by the light subpath, which draws the direction towards
    /// the camera (importance mode). For mirrors and every non-delta BSDF this equals
    /// `contribution` exactly; at a refraction the two strippings differ by the solid-angle
    /// Jacobian dω_C/dω_L = η_L² cos θ_L / (η_C² cos θ_C) (Veach 1997, §5.2, the η² asymmetry of
    /// refraction), so f/p_s must pair each p_s with its own stripping, as `estimate` does.
    pub fn contribution_for(&self, scene: &Scene, s: usize) -> DVec3 {
        let v = &self.vertices;
        let k = self.k();
        let x0 = &v[0];
        let le = match self.light(scene) {
            l if l.delta_position() => l.intensity_towards(x0.dir_to(&v[1])),
            Light::Directional(d) => d.irradiance,
            l if x0.is_infinite() => l.escaped(x0.p),
            l => l.emitted(x0.ng, x0.dir_to(&v[1]), x0.uv),
        };
        let mut f = le.as_dvec3() * geometry(x0, &v[1]) as f64 * self.transmittance(scene, 0, 1);
        for i in 1..k {
            let fs = if i < s {
                self.scatter_at(scene, i, i - 1, i + 1, TransportMode::Importance)
                    .f
            } else {
                self.scatter_at(scene, i, i + 1, i - 1, TransportMode::Radiance)
                    .f
            };
            f *= fs.as_dvec3()
                * geometry(&v[i], &v[i + 1]) as f64
                * self.transmittance(scene, i, i + 1);
        }
        f * scene.camera.importance(v[k].p, v[k].dir_to(&v[k - 1])) as f64
    }

    /// The per-vertex densities of both walks (see `Densities`).
    pub fn densities(&self, scene: &Scene) -> Densities {
        let v = &self.vertices;
        let k = self.k();
        let (x0, x1) = (&v[0], &v[1]);
        let VertexKind::Light { light: li, .. } = x0.kind else {
            unreachable!("Path::new checks x0")
        };
        let light = self.light(scene);
        let pmf = scene.light_sampler.pmf(li as usize) as f64;

        // Light subpath: x0 from pdf_le, x1 from its direction, then BSDFs in importance mode.
        let mut pl = vec![0.0f64; k + 1];
        let d01 = x0.dir_to(x1);
        let (pos, dir) = light.pdf_le(x0.ng, d01, scene.bounding_sphere);
        pl[0] = pmf * if x0.is_infinite() { dir } else { pos } as f64;
        // Through media each density is the converted direction density times the free flight's
        // (`PathVertex::convert_density`).
        if k >= 2 {
            pl[1] = x0.convert_density(if x0.is_infinite() { pos } else { dir }, x1) as f64
                * self.free_flight(scene, 0, 1);
        }
        for i in 2..k {
            let pdf_w = self
                .scatter_at(scene, i - 1, i - 2, i, TransportMode::Importance)
                .pdf_w;
            pl[i] =
                v[i - 1].convert_density(pdf_w, &v[i]) as f64 * self.free_flight(scene, i - 1, i);
        }

        // Next-event estimation of x0 from x1: a delta light (point or directional) is chosen
        // with the discrete density 1, so by the pmf alone.
        let nee = if light.is_delta() {
            pmf
        } else {
            let pdf_w = light.pdf_li(x1.p, x1.dir_to(x0), x0.p, x0.ng);
            pmf * x1.convert_density(pdf_w, x0) as f64
        };

        // Camera subpath: the pinhole, x_{k−1} from the film-wide direction pdf, then BSDFs.
        let mut pc = vec![0.0f64; k + 1];
        pc[k] = 1.0;
        let pdf_dir = scene.camera.pdf_dir(v[k].p, v[k].dir_to(&v[k - 1]));
        pc[k - 1] =
            v[k].convert_density(pdf_dir, &v[k - 1]) as f64 * self.free_flight(scene, k, k - 1);
        for i in (0..k.saturating_sub(1)).rev() {
            let pdf_w = self
                .scatter_at(scene, i + 1, i + 2, i, TransportMode::Radiance)
                .pdf_w;
            pc[i] =
                v[i + 1].convert_density(pdf_w, &v[i]) as f64 * self.free_flight(scene, i + 1, i);
        }
        // No walk hits a delta light: a point has no area, a directional light's one direction
        // has no solid angle.
        if light.is_delta() {
            pc[0] = 0.0;
        }

        // An inner vertex where the path follows a delta lobe beside smooth ones (plastic) is
        // joined by no technique (`scatter::connectable_inside`).
        let conn = (0..=k)
            .map(|i| {
                connectable(scene, &v[i])
                    && (i == 0
                        || i == k
                        || !self
                            .scatter_at(scene, i, i + 1, i - 1, TransportMode::Radiance)
                            .delta)
            })
            .collect();
        Densities {
            light: pl,
            camera: pc,
            nee,
            connectable: conn,
            light_tracing_ratio: 1.0,
        }
    }

    /// p_s(x̄): the density of generating this path with s vertices from the light and
    /// t = k+1−s from the camera (Russian roulette excluded). s ranges over 0 … k+1.
    pub fn pdf(&self, scene: &Scene, s: usize) -> f64 {
        self.densities(scene).technique(s)
    }

    /// p_s(x̄) for every s = 0 … k+1.
    pub fn pdfs(&self, scene: &Scene) -> Vec<f64> {
        self.densities(scene).all()
    }

    /// The unweighted per-pixel estimate of technique s with one light subpath per camera
    /// sample: f(x̄) / (N · p_s(x̄)), N the pixel count (see the module docs for why N); zero when
    /// the technique cannot produce the path.
    pub fn estimate(&self, scene: &Scene, s: usize) -> Color {
        self.estimate_with(scene, s, 1.0)
    }

    /// The same with `light_tracing_ratio` = M/N light subpaths per camera sample: light tracing
    /// (s = k) then averages over M = ratio·N paths, f / (ratio · N · p_k).
    pub fn estimate_with(&self, scene: &Scene, s: usize, light_tracing_ratio: f64) -> Color {
        let p = self.pdf(scene, s);
        if p <= 0.0 {
            return Color::ZERO;
        }
        let n = if s == self.k() {
            light_tracing_ratio
        } else {
            1.0
        };
        (self.contribution_for(scene, s) / (scene.camera.pixel_count() as f64 * n * p)).as_vec3()
    }
}

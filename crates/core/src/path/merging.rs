//! Vertex merging's techniques beside the connection techniques of [`Densities`], computed from
//! scratch: the oracle that VCM's and BPM's recursive weights are held to.
//!
//! Merging at x_i (Georgiev et al. 2012, §4.1; Hachisuka et al. 2012's UPS) takes x0 … x_{i−1}
//! and a light vertex near x_i from a light subpath and x_i … xk from a camera subpath, and accepts
//! the pair when the two x_i lie within r. Its density is
//!
//!   p_VM,i = π r² · ∏_{j≤i} l_j · ∏_{j≥i} c_j,   1 ≤ i ≤ k−1, x_i not delta,
//!
//! with l_0 the light walk's density of x0 (never next-event estimation's: merging uses the light
//! subpath as it was traced). A pass merges each camera subpath with all N_VM light subpaths, so
//! relative to a connection (one per camera sample) it counts N_VM times: the heuristics compare
//! η · ∏ l · ∏ c with η = N_VM π r² (Georgiev et al.'s η_VCM) against n_s · p_s.

use super::correlation::Correlation;
use super::densities::Densities;
use super::mis::{oracle_weight, Heuristic};
use super::path::Path;
use super::scatter::{delta_tolerance, scatter};
use super::vertex::PathVertex;
use crate::bsdf::TransportMode;
use crate::scene::Scene;

/// Which techniques an estimator runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TechniqueSet {
    /// Connections s ≥ 1 (next-event estimation, connections, light tracing). The camera walk
    /// hitting a light (s = 0) is always on: it is the only technique for paths no other can make.
    pub connections: bool,
    /// η = N_VM π r² of merging; 0 turns merging off.
    pub merging_eta: f64,
    /// Vertex connections s ≥ 2, t ≥ 2 (a light subpath vertex joined to a camera subpath
    /// vertex by a shadow ray), when `connections` is on. Off keeps next-event estimation and
    /// light tracing: one of the choices efficiency-aware MIS makes. Only the full-path weights
    /// (`path::camis`) and the oracle read it; `SubpathMis` assumes it equals `connections`.
    pub vertex_connections: bool,
}

impl TechniqueSet {
    /// Connections (every s, t) and merging counted η times; vertex connections with the others.
    pub fn new(connections: bool, merging_eta: f64) -> TechniqueSet {
        TechniqueSet {
            connections,
            merging_eta,
            vertex_connections: connections,
        }
    }
}

/// One technique of a path of the full VCM family.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Technique {
    /// Vertex connection (or the walks' own ends) with s light vertices.
    Connect(usize),
    /// Vertex merging at x_i.
    Merge(usize),
}

impl Densities {
    /// The densities of a path completed by merging at x_i, from scratch: `light` = y_0 … y_i
    /// (the light subpath, its merged vertex last), `camera` = z_0 … z_{t−1} (camera first, the
    /// merging camera vertex last), i = light.len() − 1. A merge has two x_i, y_i and z: the
    /// light side (l_0 … l_i, c_0 … c_{i−2}) is that of the path through y_i (a specular x_{i−1}
    /// aims the light walk at y_i, not at z), the camera side (c_i … c_k, l_{i+2} …) that of the
    /// path through z. The two densities that join them are defined as Georgiev et al. (2012)
    /// evaluate them: z's BSDF with the light vertex's incoming direction ω_y (towards y_{i−1}) —
    /// c_{i−1} = its density of ω_y (given the direction towards z_{t−2}), in area at y_{i−1} seen
    /// from y_i; l_{i+1} = its density of the direction towards z_{t−2} given ω_y, in area at
    /// z_{t−2}.
    pub fn merged(scene: &Scene, light: &[PathVertex], camera: &[PathVertex]) -> Densities {
        let i = light.len() - 1;
        let t = camera.len();
        assert!(i >= 1 && t >= 2, "a merge needs y_1 and z_1");
        let at_light = Path::from_subpaths(light, &camera[..t - 1]).densities(scene);
        let at_camera = Path::from_subpaths(&light[..i], camera).densities(scene);
        let k = at_light.k();
        let pick = |light_side: bool| if light_side { &at_light } else { &at_camera };
        let mut d = Densities {
            light: (0..=k).map(|j| pick(j <= i).light[j]).collect(),
            camera: (0..=k).map(|j| pick(j + 1 < i).camera[j]).collect(),
            nee: at_light.nee,
            connectable: (0..=k)
                .map(|j| pick(j < i).connectable[j] && (j != i || at_light.connectable[j]))
                .collect(),
            light_tracing_ratio: at_light.light_tracing_ratio,
        };
        let (y, yp, z, zp) = (&light[i], &light[i - 1], &camera[t - 1], &camera[t - 2]);
        let w_y = y.dir_to(yp);
        let w_z = z.dir_to(zp);
        let tol = delta_tolerance(z, y, zp);
        let towards_light = scatter(scene, z, w_z, w_y, TransportMode::Radiance, tol).pdf_w;
        // No walk lands on a delta light. Ask the light itself, not the path through z: z's BSDF
        // towards y_0 from z may vanish (y_0 behind z's surface) while c_0 here is z's BSDF along
        // ω_y, which is what the walk would have sampled.
        let landable = i > 1 || !light_is_delta(scene, &light[0]);
        d.camera[i - 1] = if landable {
            y.convert_density(towards_light, yp) as f64
        } else {
            0.0
        };
        d.light[i + 1] = if i + 1 < k {
            let towards_camera = scatter(scene, z, w_y, w_z, TransportMode::Importance, tol).pdf_w;
            z.convert_density(towards_camera, zp) as f64
        } else {
            0.0
        };
        d
    }

    /// ∏_{j≤i} l_j · ∏_{j≥i} c_j (without π r²), or 0 where merging at x_i is impossible.
    pub fn merging(&self, i: usize) -> f64 {
        let k = self.k();
        if i == 0 || i >= k || !self.connectable[i] {
            return 0.0;
        }
        let l: f64 = self.light[..=i].iter().product();
        let c: f64 = self.camera[i..].iter().product();
        l * c
    }

    /// The effective densities the heuristics compare under `set`: n_s·p_s of the connection
    /// techniques s = 0 … k+1 (zero for s ≥ 1 without connections), then η·p_VM,i for i = 0 … k.
    pub fn effective_vcm(&self, set: TechniqueSet) -> (Vec<f64>, Vec<f64>) {
        let mut vc = self.effective_all();
        let k = self.k();
        if !set.connections {
            vc.iter_mut().skip(1).for_each(|p| *p = 0.0);
        } else if !set.vertex_connections {
            // s = 2 … k−1: both subpaths have an inner vertex at the joint.
            vc.iter_mut().take(k).skip(2).for_each(|p| *p = 0.0);
        }
        let vm = (0..=self.k())
            .map(|i| set.merging_eta * self.merging(i))
            .collect();
        (vc, vm)
    }

    /// Correlation-aware MIS's ρ_i of merging at x_i (`path::camis`), from scratch: P_c,i and
    /// P_l,i as their own products over the path's densities, ρ = 1 at the primary hit x_{k−1}.
    pub fn correlation_ratio(&self, i: usize, corr: &Correlation) -> f64 {
        let k = self.k();
        if i + 1 >= k {
            return 1.0;
        }
        let a = corr.footprint;
        let p_camera: f64 = (i..k).map(|j| (a * self.camera[j]).min(1.0)).product();
        let p_light: f64 = (0..=i).map(|j| (a * self.light[j]).min(1.0)).product();
        corr.ratio(p_camera, p_light)
    }

    /// `effective_vcm` with merging at x_i counted η ρ_i times when `corr` is given
    /// (correlation-aware MIS, `path::camis`), η times otherwise.
    pub fn effective_vcm_with(
        &self,
        set: TechniqueSet,
        corr: Option<&Correlation>,
    ) -> (Vec<f64>, Vec<f64>) {
        let (vc, mut vm) = self.effective_vcm(set);
        if let Some(corr) = corr {
            for (i, p) in vm.iter_mut().enumerate() {
                *p *= self.correlation_ratio(i, corr);
            }
        }
        (vc, vm)
    }

    /// The weight of `technique` under `h` over every technique of `set`, by brute force over
    /// the effective densities (`oracle_weight`).
    pub fn vcm_weight(&self, set: TechniqueSet, technique: Technique, h: Heuristic) -> f64 {
        self.vcm_weight_with(set, None, technique, h)
    }

    /// `vcm_weight`, correlation-aware when `corr` is given.
    pub fn vcm_weight_with(
        &self,
        set: TechniqueSet,
        corr: Option<&Correlation>,
        technique: Technique,
        h: Heuristic,
    ) -> f64 {
        let (vc, vm) = self.effective_vcm_with(set, corr);
        let index = match technique {
            Technique::Connect(s) => s,
            Technique::Merge(i) => vc.len() + i,
        };
        let all: Vec<f64> = vc.into_iter().chain(vm).collect();
        oracle_weight(&all, index, h)
    }

    /// Every technique of `set` that can produce this path (positive effective density).
    pub fn vcm_techniques(&self, set: TechniqueSet) -> Vec<Technique> {
        let (vc, vm) = self.effective_vcm(set);
        let connect = vc
            .iter()
            .enumerate()
            .filter(|(_, &p)| p > 0.0)
            .map(|(s, _)| Technique::Connect(s));
        let merge = vm
            .iter()
            .enumerate()
            .filter(|(_, &p)| p > 0.0)
            .map(|(i, _)| Technique::Merge(i));
        connect.chain(merge).collect()
    }
}

/// Whether the light that emitted `x0` is a point or directional light, on which no walk lands.
fn light_is_delta(scene: &Scene, x0: &PathVertex) -> bool {
    match x0.kind {
        crate::path::VertexKind::Light { light, .. } => scene.lights[light as usize].is_delta(),
        _ => unreachable!("a light subpath starts on a light"),
    }
}

//! UPBP's volumetric techniques (Křivánek et al. 2014, §4–5) beside the connection techniques of
//! [`Densities`], computed from scratch: the oracle `upbp`'s weights are held to.
//!
//! A path x0 … xk with a medium vertex x_i (1 ≤ i ≤ k−1) can also be made by
//!
//! - **point–point 3-D** (PP3D): the light subpath's x_i (a photon) found within r of the camera
//!   subpath's x_i (the camera walk's medium vertex), a ball of volume (4/3)πr³:
//!   p_P,i = N · (4/3)πr³ · ∏_{j≤i} l_j · ∏_{j≥i} c_j;
//! - **point–beam 2-D** (PB2D): the photon found within r of the camera walk's segment
//!   x_{i+1} → x_i as a beam (a disk of area πr² across it), the query point integrated along
//!   the beam with T evaluated, not sampled. The camera side no longer samples the distance to
//!   x_i: instead of the free flight's scattering density at x_i (per unit length, inside c_i)
//!   the beam covers x_i with the probability that the flight passes it (a short beam ends where
//!   the walk's flight ended). So c_i becomes c_i / σ̂_i, σ̂_i = p_scatter / P_pass of the flight
//!   x_{i+1} → x_i at x_i (`Scene::free_flight_density` with and without scattering; the pieces
//!   before the last cancel): p_B,i = N · πr² · ∏_{j≤i} l_j · (c_i / σ̂_i) · ∏_{j>i} c_j.
//! - **beam–beam 1-D** (BB1D): the light walk's segment x_{i−1} → x_i as a short photon beam
//!   (it covers a point with the probability P_pass that the light's flight passes it) within r
//!   of the camera walk's segment x_{i+1} → x_i as a short camera beam, both integrated along,
//!   T evaluated on each. Neither side samples the distance to x_i: l_i / σ̂ᴸ_i (σ̂ᴸ_i of the
//!   light's flight x_{i−1} → x_i at x_i) and c_i / σ̂_i. Jarosz et al. 2011's beam × beam
//!   estimate counts a pair of beams k(u)/sin θ (k(u) = 1/(2r) across the lines' separation u,
//!   θ the angle between them; `volume_density::beam_beam`): a contribution of the form
//!   f · d_L² d_C² / (p_ω,L p_ω,C · 2r sin θ), the d² the two segments' lengths to x_i, so its
//!   density in the volume measure of x_i is
//!   p_BB,i = N · 2r · sin θ_i · ∏_{j≤i} l_j · (c_i / σ̂_i) · ∏_{j>i} c_j / σ̂ᴸ_i
//!   (l_i / σ̂ᴸ_i = p_ω,L P_pass / d_L², c_i / σ̂_i alike: per unit area across each beam, and
//!   2r sin θ turns their product into a volume density: the box across u times the Jacobian
//!   of (s, t) → the plane of the two lines).
//!
//! - **beam–point 2-D** (BP2D): the light walk's segment x_{i−1} → x_i as a photon beam within
//!   r of the camera walk's medium vertex x_i (sampled by free flight, as PP3D's), a disk of
//!   area πr² across the beam, T evaluated along it (Jarosz et al. 2011's beam × point 2-D
//!   estimate, `volume_density::point_beam`). PB2D mirrored: the light side no longer samples
//!   the distance to x_i, so l_i becomes l_i / σ̂ᴸ_i and the camera's c_i stays a sampled
//!   point's: p_BP,i = N_B · πr² · ∏_{j<i} l_j · (l_i / σ̂ᴸ_i) · ∏_{j≥i} c_j, N_B the light
//!   subpaths whose segments are beams (BB1D's); no sin θ (one side is a point).
//! - **long photon beams** (`VolumeSet::long_beams`, BB1D and BP2D): a light segment's beam runs
//!   to the next surface whatever the free flight sampled, so it covers x_i with probability 1:
//!   σ̂ᴸ_i is replaced by the flight's whole scattering density at x_i (`flight_rate`, the pass
//!   probabilities of every piece before x_i included), so l_i / σ̂ᴸ_i = p_ω,L / d_L², the
//!   direction's density alone (SmallUPBP's `mRaySamplePdfInv` for long beams against
//!   `mRaySamplePdfsRatio` for short ones).
//!
//! - **surface merging** (vcm's vertex merging, `merging`) at a non-delta surface vertex x_i:
//!   p_S,i = N · πr_S² · ∏_{j≤i} l_j · ∏_{j≥i} c_j (`Densities::merging`), so that a scene
//!   without media has vcm's technique set.
//!
//! N is the number of light subpaths whose photons every camera subpath queries (a pass's), so
//! against a connection (one per camera sample) the heuristics compare η_P = N (4/3)πr³ and
//! η_B = N πr² times the products (as `merging`'s η = N π r² for surfaces). Every density is in
//! the path's measure: a medium vertex's l_j, c_j per unit volume (no cosine), a surface's per
//! unit area. The merged path has two x_i (light side y_i, camera side z or the beam's query
//! point): as `Densities::merged`, with the two densities that join them taking their free
//! flights (the light walk's segment y_i → y_{i−1} walked back, the camera's z → z_{t−2}).

use super::densities::Densities;
use super::mis::{oracle_weight, Heuristic};
use super::path::Path;
use super::vertex::PathVertex;
use crate::scene::Scene;

/// Which of UPBP's techniques an estimator runs, with the merges' counts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeSet {
    /// bdpt's connections s ≥ 1 (s = 0, the camera walk hitting a light, always runs).
    pub connections: bool,
    /// η_P = N (4/3)πr³ of PP3D; 0 turns it off.
    pub points_eta: f64,
    /// η_B = N πr² of PB2D; 0 turns it off.
    pub beams_eta: f64,
    /// η_BB = N · 2r of BB1D; 0 turns it off.
    pub beam_beams_eta: f64,
    /// η_S = N π r_S² of surface vertex merging (vcm's, `merging`); 0 turns it off.
    pub surface_eta: f64,
    /// η_BP = N_B πr² of BP2D; 0 turns it off.
    pub beam_points_eta: f64,
    /// The photon beams (BB1D's and BP2D's) are long: σ̂ᴸ_i → the flight's scattering density.
    pub long_beams: bool,
    /// Which paths are estimated and which techniques the heuristics count (`UpbpMode`).
    pub mode: UpbpMode,
}

/// SmallUPBP's `-compatible` and `-previous` (Křivánek et al. 2014's comparisons with "previous
/// work"). Both estimate only the paths of class ES*M(S|D|M)*L: from the camera, delta surface
/// vertices up to a first medium vertex x_m (`first_medium_from_camera`); every other path gets
/// weight 0 from every technique.
///
/// - `Full`: every path, every technique of the set counted: Σw = 1 over the set.
/// - `Compatible`: class-C paths only, with `Full`'s weights: every technique that can make a
///   class-C path runs for it, so Σw = 1 over the whole set on class C (0 outside) — the image is
///   `Full`'s restricted to class C, term for term.
/// - `Previous`: class-C paths, and only the techniques that meet at x_m count and run: the
///   merges at x_m (PP3D, PB2D, BB1D, BP2D), the connections whose camera subpath ends at x_m
///   (s = m) or whose light subpath does (s = m + 1: light tracing when x_m is the camera's
///   first vertex): Σw = 1 over those on class C (0 outside). The camera walks "stop" at x_m:
///   nothing runs past it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum UpbpMode {
    #[default]
    Full,
    Compatible,
    Previous,
}

impl UpbpMode {
    pub fn parse(text: &str) -> Result<UpbpMode, String> {
        match text.trim() {
            "full" => Ok(UpbpMode::Full),
            "compatible" => Ok(UpbpMode::Compatible),
            "previous" => Ok(UpbpMode::Previous),
            other => Err(format!(
                "unknown mode '{other}' (known: full, compatible, previous)"
            )),
        }
    }

    /// Whether the heuristics count `technique` on a path whose class vertex is `m`
    /// (`first_medium_from_camera`).
    pub fn counts(self, m: Option<usize>, technique: VolumeTechnique) -> bool {
        match (self, m) {
            (UpbpMode::Full, _) => true,
            (_, None) => false,
            (UpbpMode::Compatible, Some(_)) => true,
            (UpbpMode::Previous, Some(m)) => match technique {
                VolumeTechnique::Connect(s) => s == m || s == m + 1,
                VolumeTechnique::Point(i)
                | VolumeTechnique::Beam(i)
                | VolumeTechnique::BeamBeam(i)
                | VolumeTechnique::Surface(i)
                | VolumeTechnique::BeamPoint(i) => i == m,
            },
        }
    }
}

/// The class vertex of a path x_0 … x_k: scanning from the camera (x_{k−1} down to x_1) past
/// delta surface vertices (neither in a medium nor `connectable`), the first other vertex when it
/// lies in a medium; None when it is a surface or there is none (the path is not of class
/// ES*M(S|D|M)*L).
pub fn first_medium_from_camera(
    k: usize,
    medium: impl Fn(usize) -> bool,
    connectable: &[bool],
) -> Option<usize> {
    for j in (1..k).rev() {
        if medium(j) {
            return Some(j);
        }
        if connectable[j] {
            return None;
        }
    }
    None
}

/// Technique `j` of `Densities::effective_upbp`'s list for a path of k = n − 1 segments.
fn technique_at(n: usize, j: usize) -> VolumeTechnique {
    if j <= n {
        VolumeTechnique::Connect(j)
    } else if j <= 2 * n {
        VolumeTechnique::Point(j - n - 1)
    } else if j <= 3 * n {
        VolumeTechnique::Beam(j - 2 * n - 1)
    } else if j <= 4 * n {
        VolumeTechnique::BeamBeam(j - 3 * n - 1)
    } else if j <= 5 * n {
        VolumeTechnique::Surface(j - 4 * n - 1)
    } else {
        VolumeTechnique::BeamPoint(j - 5 * n - 1)
    }
}

/// One technique of UPBP's family on a path.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum VolumeTechnique {
    /// Vertex connection (or a walk's own end) with s light vertices.
    Connect(usize),
    /// PP3D at the medium vertex x_i.
    Point(usize),
    /// PB2D at the medium vertex x_i.
    Beam(usize),
    /// BB1D at the medium vertex x_i.
    BeamBeam(usize),
    /// Surface vertex merging (vcm's) at the surface vertex x_i.
    Surface(usize),
    /// BP2D at the medium vertex x_i: a photon beam gathered at the camera walk's x_i.
    BeamPoint(usize),
}

/// Per vertex x_j of a path: whether it lies in a medium, σ̂_j (module doc) of the camera
/// direction's flight x_{j+1} → x_j (0 where no flight scatters: surfaces, endpoints), σ̂ᴸ_j of
/// the light direction's flight x_{j−1} → x_j, sin θ_j between those two flights, and the light
/// direction's whole scattering density at x_j (`flight_rate`: a long beam's σ̂ᴸ).
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeRates {
    pub medium: Vec<bool>,
    pub rate: Vec<f64>,
    pub light_rate: Vec<f64>,
    pub sin: Vec<f64>,
    pub light_flight: Vec<f64>,
}

impl VolumeRates {
    /// σ̂ᴸ_j as `set`'s photon beams read it: the short beam's ratio, or a long beam's whole
    /// scattering density.
    pub fn light_side(&self, set: &VolumeSet, j: usize) -> f64 {
        if set.long_beams {
            self.light_flight[j]
        } else {
            self.light_rate[j]
        }
    }
}

/// A long beam's σ̂ᴸ at `to` of the flight `from` → `to`: its scattering density per unit length
/// over all its pieces (a long beam covers every point of the flight: its cover probability is
/// 1), from scratch; 0 when `to` is no medium vertex.
pub fn flight_rate(scene: &Scene, from: &PathVertex, to: &PathVertex) -> f64 {
    if !to.in_medium() {
        return 0.0;
    }
    free_flight(scene, from, to)
}

/// sin θ between the flights from `a` into `x` and from `b` into `x` (the lines' angle: the
/// order does not matter).
pub fn sin_between(a: &PathVertex, x: &PathVertex, b: &PathVertex) -> f64 {
    let (u, v) = (x.dir_to(a), x.dir_to(b));
    let c = u.cross(v);
    (c.dot(c) as f64).sqrt()
}

/// σ̂ of the flight `from` → `to` at `to`: its scattering density per unit length over its pass
/// probability, from scratch (`Scene::free_flight_density`); 0 when `to` is no medium vertex.
pub fn scatter_rate(scene: &Scene, from: &PathVertex, to: &PathVertex) -> f64 {
    if !to.in_medium() {
        return 0.0;
    }
    let m = from.medium_towards(scene, from.dir_to(to));
    let scatter = scene.free_flight_density(from.into(), to.into(), m, true) as f64;
    let pass = scene.free_flight_density(from.into(), to.into(), m, false) as f64;
    if pass > 0.0 {
        scatter / pass
    } else {
        0.0
    }
}

/// The free-flight density of a walk from `from` reaching `to` (scattering there when it is a
/// medium vertex), from scratch.
fn free_flight(scene: &Scene, from: &PathVertex, to: &PathVertex) -> f64 {
    let m = from.medium_towards(scene, from.dir_to(to));
    scene.free_flight_density(from.into(), to.into(), m, to.in_medium()) as f64
}

impl VolumeRates {
    /// The rates of `path` (x0 … xk) from scratch.
    pub fn of_path(scene: &Scene, path: &Path) -> VolumeRates {
        let v = &path.vertices;
        let k = v.len() - 1;
        let medium: Vec<bool> = v.iter().map(|x| x.in_medium()).collect();
        let rate = (0..=k)
            .map(|j| {
                if j < k && medium[j] {
                    scatter_rate(scene, &v[j + 1], &v[j])
                } else {
                    0.0
                }
            })
            .collect();
        let light_rate = (0..=k)
            .map(|j| {
                if j > 0 && medium[j] {
                    scatter_rate(scene, &v[j - 1], &v[j])
                } else {
                    0.0
                }
            })
            .collect();
        let sin = (0..=k)
            .map(|j| {
                if j > 0 && j < k && medium[j] {
                    sin_between(&v[j - 1], &v[j], &v[j + 1])
                } else {
                    0.0
                }
            })
            .collect();
        let light_flight = (0..=k)
            .map(|j| {
                if j > 0 && medium[j] {
                    flight_rate(scene, &v[j - 1], &v[j])
                } else {
                    0.0
                }
            })
            .collect();
        VolumeRates {
            medium,
            rate,
            light_rate,
            sin,
            light_flight,
        }
    }

    /// The rates of a merged path (`light` = y_0 … y_i, `camera` = z_0 … z_{t−1}, its last the
    /// camera side's x_i), each from the side its density is read from (`Densities::merged`):
    /// σ̂_j below i from the light side (x_{i−1} seen from y_i), from i up from the camera side;
    /// σ̂ᴸ_j up to i from the light side, above from the camera side; sin θ_j below i from the
    /// light side, above from the camera side, and at x_i between the two beams themselves
    /// (y_{i−1} → y_i and z_{t−2} → z_{t−1}).
    pub fn merged(scene: &Scene, light: &[PathVertex], camera: &[PathVertex]) -> VolumeRates {
        let i = light.len() - 1;
        let t = camera.len();
        let at_light = VolumeRates::of_path(scene, &Path::from_subpaths(light, &camera[..t - 1]));
        let at_camera = VolumeRates::of_path(scene, &Path::from_subpaths(&light[..i], camera));
        let pick = |j: usize| if j < i { &at_light } else { &at_camera };
        let k = at_light.rate.len() - 1;
        let mut sin: Vec<f64> = (0..=k).map(|j| pick(j).sin[j]).collect();
        let (u, v) = (
            light[i].dir_to(&light[i - 1]),
            camera[t - 1].dir_to(&camera[t - 2]),
        );
        let c = u.cross(v);
        sin[i] = (c.dot(c) as f64).sqrt();
        VolumeRates {
            medium: (0..=k).map(|j| pick(j).medium[j]).collect(),
            rate: (0..=k).map(|j| pick(j).rate[j]).collect(),
            light_rate: (0..=k)
                .map(|j| {
                    let side = if j <= i { &at_light } else { &at_camera };
                    side.light_rate[j]
                })
                .collect(),
            light_flight: (0..=k)
                .map(|j| {
                    let side = if j <= i { &at_light } else { &at_camera };
                    side.light_flight[j]
                })
                .collect(),
            sin,
        }
    }
}

impl Densities {
    /// The densities of a path completed by a merge at x_i (PP3D, PB2D, BB1D, or a surface
    /// merge in a scene with media), from scratch: `Densities::merged`, whose two joining densities take their free flights here.
    pub fn volume_merged(scene: &Scene, light: &[PathVertex], camera: &[PathVertex]) -> Densities {
        let mut d = Densities::merged(scene, light, camera);
        let i = light.len() - 1;
        let t = camera.len();
        let k = d.k();
        d.camera[i - 1] *= free_flight(scene, &light[i], &light[i - 1]);
        if i + 1 < k {
            d.light[i + 1] *= free_flight(scene, &camera[t - 1], &camera[t - 2]);
        }
        d
    }

    /// The effective densities the heuristics compare under `set`: n_s·p_s of the connection
    /// techniques s = 0 … k+1 (zero for s ≥ 1 without connections), then η_P·p_P,i for
    /// i = 0 … k, then η_B·p_B,i, then η_BB·p_BB,i for i = 0 … k (module doc; zero where x_i is
    /// no medium vertex), then η_S·p_VM,i of surface merging (`Densities::merging`: zero where
    /// x_i lies in a medium or is delta), then η_BP·p_BP,i; under `set.mode` (`UpbpMode`) the
    /// techniques it does not count are zero.
    pub fn effective_upbp(&self, set: VolumeSet, rates: &VolumeRates) -> Vec<f64> {
        let k = self.k();
        let mut all = self.effective_all();
        if !set.connections {
            all.iter_mut().skip(1).for_each(|p| *p = 0.0);
        }
        let mergeable = |i: usize| i >= 1 && i < k && rates.medium[i];
        let light_to = |i: usize| -> f64 { self.light[..=i].iter().product() };
        let camera_from = |i: usize| -> f64 { self.camera[i..].iter().product() };
        for i in 0..=k {
            all.push(if mergeable(i) {
                set.points_eta * light_to(i) * camera_from(i)
            } else {
                0.0
            });
        }
        for i in 0..=k {
            let r = rates.rate[i];
            all.push(if mergeable(i) && r > 0.0 {
                set.beams_eta * light_to(i) * (self.camera[i] / r) * camera_from(i + 1)
            } else {
                0.0
            });
        }
        for i in 0..=k {
            let (r, rl, sin) = (rates.rate[i], rates.light_side(&set, i), rates.sin[i]);
            all.push(if mergeable(i) && r > 0.0 && rl > 0.0 {
                set.beam_beams_eta
                    * sin
                    * (light_to(i) / rl)
                    * (self.camera[i] / r)
                    * camera_from(i + 1)
            } else {
                0.0
            });
        }
        for i in 0..=k {
            all.push(if rates.medium[i] {
                0.0
            } else {
                set.surface_eta * self.merging(i)
            });
        }
        for i in 0..=k {
            let rl = rates.light_side(&set, i);
            all.push(if mergeable(i) && rl > 0.0 {
                set.beam_points_eta * (light_to(i) / rl) * camera_from(i)
            } else {
                0.0
            });
        }
        if set.mode != UpbpMode::Full {
            let m = first_medium_from_camera(k, |j| rates.medium[j], &self.connectable);
            for (j, p) in all.iter_mut().enumerate() {
                if !set.mode.counts(m, technique_at(k + 1, j)) {
                    *p = 0.0;
                }
            }
        }
        all
    }

    /// Where `technique` sits in `effective_upbp`'s list.
    pub fn upbp_index(&self, technique: VolumeTechnique) -> usize {
        let n = self.k() + 1;
        match technique {
            VolumeTechnique::Connect(s) => s,
            VolumeTechnique::Point(i) => n + 1 + i,
            VolumeTechnique::Beam(i) => 2 * n + 1 + i,
            VolumeTechnique::BeamBeam(i) => 3 * n + 1 + i,
            VolumeTechnique::Surface(i) => 4 * n + 1 + i,
            VolumeTechnique::BeamPoint(i) => 5 * n + 1 + i,
        }
    }

    /// The weight of `technique` under `h` over every technique of `set`, by brute force over the
    /// effective densities (`oracle_weight`).
    pub fn upbp_weight(
        &self,
        set: VolumeSet,
        rates: &VolumeRates,
        technique: VolumeTechnique,
        h: Heuristic,
    ) -> f64 {
        let all = self.effective_upbp(set, rates);
        oracle_weight(&all, self.upbp_index(technique), h)
    }

    /// Every technique of `set` that can produce this path (positive effective density).
    pub fn upbp_techniques(&self, set: VolumeSet, rates: &VolumeRates) -> Vec<VolumeTechnique> {
        let all = self.effective_upbp(set, rates);
        let n = self.k() + 1;
        all.iter()
            .enumerate()
            .filter(|(_, &p)| p > 0.0)
            .map(|(j, _)| technique_at(n, j))
            .collect()
    }
}

//! The correlation factor of correlation-aware MIS for merging (Grittmann, Georgiev & Slusallek,
//! EG 2021; `path::camis` states the formulation): ρ of two prefix probabilities and the footprint
//! they are measured in. Its own module so that the oracle (`merging.rs`) and the integrators'
//! full-path routine (`camis.rs`) both read it and neither imports the other's side.

/// What correlation-aware MIS needs besides the per-vertex densities.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Correlation {
    /// N_VM, light subpaths per pass: the lower clamp 1 / N_VM of ρ (one independent sample).
    pub light_paths: f64,
    /// A = π r_c² of the path's footprint.
    pub footprint: f64,
}

impl Correlation {
    /// For a path whose primary hit x_{k−1} lies `primary_distance` from the camera vertex x_k.
    pub fn new(light_paths: f64, primary_distance: f64) -> Correlation {
        let r = primary_distance * 1f64.to_radians().tan();
        Correlation {
            light_paths,
            footprint: std::f64::consts::PI * r * r,
        }
    }

    /// ρ from the two prefix probabilities, clamped; 0/0 (a merge no walk makes: its density is 0
    /// whatever ρ) gives the clamp.
    #[inline]
    pub fn ratio(&self, p_camera: f64, p_light: f64) -> f64 {
        let rho = p_camera / (p_camera + p_light - p_camera * p_light);
        let lo = 1.0 / self.light_paths;
        if rho >= lo {
            rho.min(1.0)
        } else {
            lo
        }
    }
}

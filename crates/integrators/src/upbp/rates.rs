//! The per-vertex inputs of `weights::weight` besides the walks' densities: σ̂ of each flight
//! into a medium vertex (its scattering density over its pass probability there, the pieces
//! before the last cancelling: `lt_core::path::volume_merging::scatter_rate`, which the oracle
//! uses) and sin θ between the two flights at it. Computed only for the techniques that read
//! them: σ̂ of the camera direction for PB2D and BB1D, the light direction's and sin θ for BB1D
//! and BP2D. With long photon beams the light direction's σ̂ᴸ is the flight's whole scattering
//! density (`flight_rate`: a long beam covers every point of its flight).

use super::weights::VertexRate;
use lt_core::path::volume_merging::{flight_rate, scatter_rate, sin_between};
use lt_core::path::{PathVertex, VolumeSet};
use lt_core::Scene;

/// Which rates the pass's techniques read.
#[derive(Clone, Copy, Debug, Default)]
pub struct Needs {
    /// σ̂ of the camera direction (PB2D, BB1D).
    pub camera: bool,
    /// σ̂ᴸ of the light direction and sin θ (BB1D, BP2D).
    pub light: bool,
    /// The photon beams are long: σ̂ᴸ is `flight_rate`, not `scatter_rate`.
    pub long: bool,
}

impl Needs {
    pub fn of(set: &VolumeSet) -> Needs {
        Needs {
            camera: set.beams_eta > 0.0 || set.beam_beams_eta > 0.0,
            light: set.beam_beams_eta > 0.0 || set.beam_points_eta > 0.0,
            long: set.long_beams,
        }
    }
}

/// Vertex `j` of a walk `v` (walk order): the rate `rate_of` gives (σ̂, or a long beam's σ̂ᴸ)
/// of the walk's own flight v_{j−1} → v_j when `forward`, of the flight v_{j+1} → v_j walked
/// back when `backward`, and sin θ_j between them when `sin` (each 0 where the neighbour is
/// missing or v_j lies on no medium).
pub fn along_walk(
    scene: &Scene,
    v: &[PathVertex],
    j: usize,
    (forward, backward, sin): (bool, bool, bool),
    rate_of: (RateFn, RateFn),
) -> (f64, f64, f64) {
    if !v[j].in_medium() {
        return (0.0, 0.0, 0.0);
    }
    let has_next = j + 1 < v.len();
    let f = if forward && j >= 1 {
        (rate_of.0)(scene, &v[j - 1], &v[j])
    } else {
        0.0
    };
    let b = if backward && has_next {
        (rate_of.1)(scene, &v[j + 1], &v[j])
    } else {
        0.0
    };
    let s = if sin && j >= 1 && has_next {
        sin_between(&v[j - 1], &v[j], &v[j + 1])
    } else {
        0.0
    };
    (f, b, s)
}

/// A flight's rate at its end: `scatter_rate` (σ̂) or `flight_rate` (a long beam's σ̂ᴸ).
pub type RateFn = fn(&Scene, &PathVertex, &PathVertex) -> f64;

impl Needs {
    /// The light direction's rate function (σ̂ᴸ as the pass's photon beams read it).
    pub fn light_fn(&self) -> RateFn {
        if self.long {
            flight_rate
        } else {
            scatter_rate
        }
    }
}

/// The rates of light walk vertex `j` (`y`): σ̂ᴸ its own direction, σ̂ the camera's.
pub fn light_vertex(scene: &Scene, y: &[PathVertex], j: usize, needs: Needs) -> VertexRate {
    let fns = (needs.light_fn(), scatter_rate as RateFn);
    let (f, b, s) = along_walk(scene, y, j, (needs.light, needs.camera, needs.light), fns);
    VertexRate {
        medium: y[j].in_medium(),
        rate: b,
        light_rate: f,
        sin: s,
    }
}

/// The rates of camera walk vertex `j` (`z`): σ̂ its own direction, σ̂ᴸ the light's.
pub fn camera_vertex(scene: &Scene, z: &[PathVertex], j: usize, needs: Needs) -> VertexRate {
    let fns = (scatter_rate as RateFn, needs.light_fn());
    let (f, b, s) = along_walk(scene, z, j, (needs.camera, needs.light, needs.light), fns);
    VertexRate {
        medium: z[j].in_medium(),
        rate: f,
        light_rate: b,
        sin: s,
    }
}

/// A connection's two ends (`light` = y_0 … y_{s−1}, `camera` = z_0 … z_{t−1}, the camera's
/// in camera order), each end's rates with the other end as its neighbour: y_{s−1}'s σ̂ from
/// z_{t−1} and sin θ, z_{t−1}'s σ̂ᴸ from y_{s−1} and sin θ. `stored` are the walks' own rates
/// of the two ends (the directions their walks took).
pub fn junction(
    scene: &Scene,
    (light, camera): (&[PathVertex], &[PathVertex]),
    (light_stored, camera_stored): (VertexRate, VertexRate),
    needs: Needs,
) -> (VertexRate, VertexRate) {
    let (s, t) = (light.len(), camera.len());
    let (y, z) = (&light[s - 1], &camera[t - 1]);
    let mut ly = light_stored;
    let mut cz = camera_stored;
    if y.in_medium() {
        ly.rate = if needs.camera {
            scatter_rate(scene, z, y)
        } else {
            0.0
        };
        ly.sin = if needs.light && s >= 2 {
            sin_between(&light[s - 2], y, z)
        } else {
            0.0
        };
    }
    if z.in_medium() {
        cz.light_rate = if needs.light {
            (needs.light_fn())(scene, y, z)
        } else {
            0.0
        };
        cz.sin = if needs.light && t >= 2 {
            sin_between(y, z, &camera[t - 2])
        } else {
            0.0
        };
    }
    (ly, cz)
}

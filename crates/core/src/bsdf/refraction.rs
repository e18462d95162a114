//! What crossing an interface does to a path, apart from Fresnel: the refracted direction and the
//! non-symmetric scaling of radiance.

use super::TransportMode;

/// The factor a refracted path's throughput takes for the transport mode, with `eta` = η_t / η_i
/// of the path's step (η of the `wi` side over η of the `wo` side).
///
/// Radiance is compressed into the narrower cone on entering the denser medium, so refracted
/// radiance scales by 1/η²; importance (the adjoint, carried from lights) does not (Veach 1997,
/// §5.2, and the non-symmetric BSDF of §5.3.2). **This is the one place that factor lives**: the
/// smooth dielectric and the rough dielectric (and anything else that refracts) call it, and
/// nothing else divides by η².
#[inline]
pub fn refracted_throughput_scale(eta: f32, mode: TransportMode) -> f32 {
    match mode {
        TransportMode::Radiance => 1.0 / (eta * eta),
        TransportMode::Importance => 1.0,
    }
}

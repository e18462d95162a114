//! The integrator flags every command that renders shares. Each flag is one documented key of the
//! integrators' parameter tables; `--set key=value` reaches any key. An integrator refuses keys
//! it does not take, naming the ones it does.

use clap::Args;
use lt_integrators::IntegratorParams;

#[derive(Args, Debug, Clone, Default)]
pub struct IntegratorArgs {
    /// Longest path in segments, camera ray included (overrides the scene): key max_depth.
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// Russian roulette from this many segments on (overrides the scene): key rr_depth.
    #[arg(long)]
    pub rr_depth: Option<u32>,
    /// MIS heuristic: power (default), balance, or none (bdpt): key mis.
    #[arg(long)]
    pub mis: Option<String>,
    /// pt's techniques: both, light (NEE only) or bsdf: key techniques.
    #[arg(long)]
    pub techniques: Option<String>,
    /// Light subpaths per pass (default: the pixel count): key light_paths.
    #[arg(long)]
    pub light_paths: Option<u64>,
    /// pm: photon paths in the map: key photons.
    #[arg(long)]
    pub photons: Option<u64>,
    /// ppm/sppm: photon paths per pass (default: the pixel count): key photons_per_pass.
    #[arg(long)]
    pub photons_per_pass: Option<u64>,
    /// Photon family: gather radius in scene units (prefer --radius-px): key radius.
    #[arg(long)]
    pub radius: Option<f32>,
    /// Photon family: (initial) radius in pixel footprints at the visible point (default 2): key radius_px.
    #[arg(long)]
    pub radius_px: Option<f32>,
    /// Photon family: (initial) radius as a fraction of the scene diameter: key radius_scene.
    #[arg(long)]
    pub radius_scene: Option<f32>,
    /// pm: gather the K nearest photons: key knn.
    #[arg(long)]
    pub knn: Option<u32>,
    /// Photon family: density-estimation kernel, disk or epanechnikov: key kernel.
    #[arg(long)]
    pub kernel: Option<String>,
    /// Photon family: direct light by nee (default) or photons: key direct.
    #[arg(long)]
    pub direct: Option<String>,
    /// ppm/sppm/vcm/bpm: radius reduction α in (0, 1] (default 2/3; vcm/bpm 0.75): key alpha.
    #[arg(long)]
    pub alpha: Option<f64>,
    /// ppm/sppm: radius schedule, global (Knaus & Zwicker, default) or local (Hachisuka): key radius_update.
    #[arg(long)]
    pub radius_update: Option<String>,
    /// vcm: connections only, no merging — BDPT through vcm's code: key merging=false.
    #[arg(long)]
    pub no_merge: bool,
    /// Any integrator key, as key=value (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

impl IntegratorArgs {
    pub fn to_params(&self) -> Result<IntegratorParams, String> {
        let mut p = IntegratorParams::new();
        if let Some(v) = self.max_depth {
            p.set("max_depth", v);
        }
        if let Some(v) = self.rr_depth {
            p.set("rr_depth", v);
        }
        if let Some(v) = &self.mis {
            p.set("mis", v);
        }
        if let Some(v) = &self.techniques {
            p.set("techniques", v);
        }
        if let Some(v) = self.light_paths {
            p.set("light_paths", v);
        }
        let optional: [(&str, Option<String>); 10] = [
            ("photons", self.photons.map(|v| v.to_string())),
            (
                "photons_per_pass",
                self.photons_per_pass.map(|v| v.to_string()),
            ),
            ("radius", self.radius.map(|v| v.to_string())),
            ("radius_px", self.radius_px.map(|v| v.to_string())),
            ("radius_scene", self.radius_scene.map(|v| v.to_string())),
            ("knn", self.knn.map(|v| v.to_string())),
            ("kernel", self.kernel.clone()),
            ("direct", self.direct.clone()),
            ("alpha", self.alpha.map(|v| v.to_string())),
            ("radius_update", self.radius_update.clone()),
        ];
        for (key, value) in optional {
            if let Some(v) = value {
                p.set(key, v);
            }
        }
        if self.no_merge {
            p.set("merging", false);
        }
        for pair in &self.set {
            p.set_pair(pair)?;
        }
        Ok(p)
    }
}

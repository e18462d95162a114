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
        for pair in &self.set {
            p.set_pair(pair)?;
        }
        Ok(p)
    }
}

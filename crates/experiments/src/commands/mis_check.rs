//! `lt mis-check`: an integrator's MIS weights against the path-space oracle
//! (`crate::verify::mis_check`).

use crate::verify::mis_check::pt_bdpt::{check_scene, Options, Which};
use crate::verify::mis_check::tolerance::DEFAULT_SLACK;
use crate::verify::mis_check::upbp::{self, UpbpOptions};
use crate::verify::mis_check::vcm_bpm::{self, VcmOptions};
use clap::Args;
use lt_core::path::Heuristic;
use lt_integrators::registry::{self, Weights};
use std::fmt::Write as _;
use std::path::PathBuf;

#[derive(Args, Debug, Clone)]
pub struct MisCheckArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Integrator whose weights are checked: pt, bdpt, lvc-bdpt, vcm, bpm or upbp (for eamis, its counts are
    /// checked through vcm with `--no-vertex-connections --checkerboard-merging`).
    #[arg(long, default_value = "bdpt")]
    pub integrator: String,
    /// MIS heuristic: power (the integrators' default), balance, or none (bdpt only).
    #[arg(long)]
    pub mis: Option<String>,
    /// Paths to check per (path length, technique); each length gets at least this many.
    #[arg(long, default_value_t = 1000)]
    pub paths: usize,
    /// Longest path in segments (default: the scene's max_depth).
    #[arg(long)]
    pub max_depth: Option<u32>,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Film resolution (square) the passes run at.
    #[arg(long, default_value_t = 16)]
    pub resolution: u32,
    /// Give up on lengths still short of `paths` after this many passes.
    #[arg(long, default_value_t = 2000)]
    pub max_passes: u32,
    /// bdpt, lvc-bdpt: light subpaths per pass (default: the pixel count).
    #[arg(long)]
    pub light_paths: Option<u64>,
    /// lvc-bdpt: cache vertices each camera vertex connects to (N).
    #[arg(long, default_value_t = 1)]
    pub connections: u32,
    /// Multiplier on each path's tolerance, which is derived from the rounding of the walks'
    /// densities and vertex positions (see the module docs of verify::mis_check::tolerance).
    #[arg(long, default_value_t = DEFAULT_SLACK)]
    pub slack: f64,
    /// vcm: without vertex connections s ≥ 2, t ≥ 2 (one of eamis's choices).
    #[arg(long)]
    pub no_vertex_connections: bool,
    /// vcm, bpm: merging only in a checkerboard of pixels (eamis's per-pixel choice).
    #[arg(long)]
    pub checkerboard_merging: bool,
    /// upbp: its `techniques` (all, or a comma-separated subset of bpt, surf, pp3d, pb2d, bb1d,
    /// bp2d).
    #[arg(long)]
    pub techniques: Option<String>,
    /// upbp: its `beams` (short or long photon beams for BB1D and BP2D).
    #[arg(long)]
    pub beams: Option<String>,
    /// upbp: its `mode` (full, compatible or previous: SmallUPBP's).
    #[arg(long)]
    pub mode: Option<String>,
}

/// `lt mis-check`: the report, or an error carrying it when any check fails.
pub fn run(args: &MisCheckArgs) -> Result<String, String> {
    let integrator = match registry::find(&args.integrator)?.weights {
        Weights::PathTracing => Which::Pt,
        Weights::Connections => Which::Bdpt,
        Weights::VertexCache => Which::Lvc,
        Weights::ConnectMerge { connections } => return run_vcm_bpm(args, connections),
        Weights::Volumetric => return run_upbp(args),
        Weights::EfficiencyAware => {
            return Err(format!(
                "mis-check: {}'s weights are vcm's full-path weights with the counts its pilot \
                 chose; check those counts through vcm: `lt mis-check --integrator vcm \
                 --no-vertex-connections --checkerboard-merging`",
                args.integrator
            ))
        }
        Weights::None => {
            let checked: Vec<&str> = registry::with_weights(|w| w != Weights::None).collect();
            return Err(format!(
                "mis-check: {} applies no MIS weights (the integrators that do: {})",
                args.integrator,
                checked.join(", ")
            ));
        }
    };
    let mut scene = lt_scene_io::load_scene(&args.scene).map_err(|e| e.to_string())?;
    crate::verify::mis_check::refuse_media(&scene, &args.integrator)?;
    let mut opts = Options::new(&scene, integrator);
    if let Some(m) = &args.mis {
        opts.heuristic = Heuristic::parse(m)?;
        if integrator == Which::Pt && opts.heuristic == Heuristic::Uniform {
            return Err("mis-check: pt takes power or balance".into());
        }
    }
    if let Some(d) = args.max_depth {
        if d == 0 {
            return Err("mis-check: max_depth must be at least 1".into());
        }
        opts.max_depth = d;
    }
    if args.light_paths == Some(0) {
        return Err("mis-check: light_paths must be at least 1".into());
    }
    if args.light_paths.is_some() && integrator == Which::Pt {
        return Err("mis-check: --light-paths is a bdpt option".into());
    }
    opts.paths = args.paths;
    opts.seed = args.seed;
    opts.resolution = args.resolution.max(1);
    opts.max_passes = args.max_passes;
    opts.light_paths = args.light_paths;
    if args.connections == 0 {
        return Err("mis-check: connections must be at least 1".into());
    }
    opts.connections = args.connections;
    opts.slack = args.slack;
    let name = args.scene.display().to_string();
    let report = check_scene(&mut scene, &opts, &name);
    let mut out = String::new();
    let _ = write!(out, "{report}");
    if report.passed() {
        Ok(out)
    } else {
        print!("{out}");
        Err(format!(
            "mis-check: {} of {} paths fail",
            report.failures(),
            report.checked()
        ))
    }
}

/// `lt mis-check --integrator upbp`: connections, PP3D and PB2D through media.
fn run_upbp(args: &MisCheckArgs) -> Result<String, String> {
    let mut scene = lt_scene_io::load_scene(&args.scene).map_err(|e| e.to_string())?;
    let mut opts = UpbpOptions::new(&scene);
    if let Some(m) = &args.mis {
        opts.heuristic = Heuristic::parse(m)?;
    }
    if let Some(d) = args.max_depth {
        if d == 0 {
            return Err("mis-check: max_depth must be at least 1".into());
        }
        opts.max_depth = d;
    }
    if let Some(t) = &args.techniques {
        opts.techniques = t.clone();
    }
    if let Some(b) = &args.beams {
        opts.beams = b.clone();
    }
    if let Some(m) = &args.mode {
        opts.mode = m.clone();
    }
    opts.paths = args.paths;
    opts.seed = args.seed;
    opts.resolution = args.resolution.max(1);
    opts.max_passes = args.max_passes;
    opts.slack = args.slack;
    let name = args.scene.display().to_string();
    let (report, summary) = upbp::check_scene(&mut scene, &opts, &name)?;
    let out = format!("{report}{summary}");
    if report.passed() {
        Ok(out)
    } else {
        Err(out)
    }
}

/// `lt mis-check --integrator vcm|bpm`: vcm has connections, bpm has merges only.
fn run_vcm_bpm(args: &MisCheckArgs, connections: bool) -> Result<String, String> {
    let mut scene = lt_scene_io::load_scene(&args.scene).map_err(|e| e.to_string())?;
    crate::verify::mis_check::refuse_media(&scene, &args.integrator)?;
    let mut opts = VcmOptions::new(&scene, connections);
    if let Some(m) = &args.mis {
        opts.heuristic = Heuristic::parse(m)?;
    }
    if let Some(d) = args.max_depth {
        if d == 0 {
            return Err("mis-check: max_depth must be at least 1".into());
        }
        opts.max_depth = d;
    }
    if args.light_paths == Some(0) {
        return Err("mis-check: light_paths must be at least 1".into());
    }
    opts.light_paths = args.light_paths;
    opts.paths = args.paths;
    opts.seed = args.seed;
    opts.resolution = args.resolution;
    opts.max_passes = args.max_passes;
    opts.slack = args.slack;
    opts.vertex_connections = !args.no_vertex_connections;
    opts.checkerboard_merging = args.checkerboard_merging;
    let name = args.scene.display().to_string();
    let report = vcm_bpm::check_scene(&mut scene, &opts, &name);
    let mut out = String::new();
    write!(out, "{report}").unwrap();
    if report.passed() {
        Ok(out)
    } else {
        Err(out)
    }
}

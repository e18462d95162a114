//! `lt bench`: raw traversal and integrator throughput as a Markdown table (results/bench.md).

use crate::bench::{
    camera_rays, closest_hit_rate, incoherent_rays, integrator_rate, peak_memory_mib, shadow_rate,
    surface_rays,
};
use clap::Args;
use lt_core::geometry::{set_ray_core, RayCore};
use lt_scene_io::load_scene;
use std::fmt::Write;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Scene files to measure.
    #[arg(default_values = ["scenes/cornell-box.toml", "scenes/veach-mis.toml"])]
    pub scenes: Vec<PathBuf>,
    /// Integrators to measure.
    #[arg(long, value_delimiter = ',', default_value = "pt")]
    pub integrators: Vec<String>,
    /// Passes (spp) per integrator measurement.
    #[arg(long, default_value_t = 16)]
    pub passes: u32,
    /// Threads for the integrator measurements (0 = one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    #[arg(long, default_value_t = 8)]
    pub max_depth: u32,
    /// Ray cores to measure side by side (auto, bvh, flat, flat-scalar, wide, embree); each scene is loaded
    /// once per core. Default: the global --ray-core.
    #[arg(long, value_delimiter = ',', value_parser = parse_core)]
    pub ray_cores: Vec<RayCore>,
    /// Write the table here as well as printing it.
    #[arg(long, short)]
    pub output: Option<PathBuf>,
}

fn parse_core(s: &str) -> Result<RayCore, String> {
    RayCore::parse(s)
}

pub fn run(args: &BenchArgs) -> Result<String, String> {
    let threads = if args.threads == 0 {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    } else {
        args.threads
    };
    let mut out = String::new();
    let cmd: Vec<String> = std::env::args().collect();
    writeln!(out, "Command: `{}`  ", cmd.join(" ")).unwrap();
    writeln!(
        out,
        "Machine: {} hardware threads; integrators on {threads} thread(s), max depth {}.\n",
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1),
        args.max_depth
    )
    .unwrap();
    writeln!(out, "Rays on one thread, Mrays/s: incoherent (origins uniform in the scene's bounds, directions uniform), coherent (the camera's primary rays, row by row), leaving surfaces (from the incoherent rays' hits, random directions on the side they arrived from: what a path's bounces trace); shadow = the incoherent rays as segments of length 1.\n").unwrap();
    writeln!(out, "| scene | ray core | primitives | closest, incoherent | hit fraction | closest, coherent | closest, leaving surfaces | shadow |").unwrap();
    writeln!(out, "|---|---|---:|---:|---:|---:|---:|---:|").unwrap();
    let mut scenes = Vec::new();
    // Each scene once per core; `None` keeps the global choice.
    let cores: Vec<Option<RayCore>> = if args.ray_cores.is_empty() {
        vec![None]
    } else {
        args.ray_cores.iter().copied().map(Some).collect()
    };
    for (path, core) in args
        .scenes
        .iter()
        .flat_map(|p| cores.iter().map(move |c| (p, c)))
    {
        if let Some(core) = core {
            set_ray_core(*core);
        }
        let scene = load_scene(path).map_err(|e| e.to_string())?;
        let rays = incoherent_rays(&scene, 200_000, 1);
        let (rate, hit) = closest_hit_rate(&scene, &rays, 5);
        let (coherent, _) = closest_hit_rate(&scene, &camera_rays(&scene, 200_000), 5);
        let (leaving, _) = closest_hit_rate(&scene, &surface_rays(&scene, &rays, 2), 5);
        let shadow = shadow_rate(&scene, &rays, 5);
        let name = path
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        writeln!(
            out,
            "| {name} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} |",
            scene.ray_core(),
            scene.primitive_count(),
            rate / 1e6,
            hit,
            coherent / 1e6,
            leaving / 1e6,
            shadow / 1e6
        )
        .unwrap();
        scenes.push((name, scene, rate));
    }
    writeln!(out, "\n| scene | ray core | integrator | resolution | spp/s | Msamples/s | Mrays/s (all threads) | rays/s per thread vs raw closest hit | closest + shadow rays per sample |").unwrap();
    writeln!(out, "|---|---|---|---|---:|---:|---:|---:|---|").unwrap();
    for (name, scene, raw) in &scenes {
        for integ in &args.integrators {
            let r = integrator_rate(scene, integ, Some(args.max_depth), args.passes, threads)?;
            writeln!(
                out,
                "| {name} | {} | {integ} | {}×{} | {:.1} | {:.2} | {:.2} | {:.0} % | {:.2} + {:.2} |",
                scene.ray_core(),
                scene.camera.width,
                scene.camera.height,
                r.spp_per_second,
                r.samples_per_second / 1e6,
                r.rays_per_second / 1e6,
                100.0 * r.rays_per_second / threads as f64 / raw,
                r.closest_per_sample,
                r.shadow_per_sample
            )
            .unwrap();
        }
    }
    if let Some(m) = peak_memory_mib() {
        writeln!(out, "\nPeak resident memory of the whole run: {m:.0} MiB.").unwrap();
    }
    if let Some(path) = &args.output {
        crate::image_io::write_atomic(path, out.as_bytes())?;
    }
    Ok(out)
}

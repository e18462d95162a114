//! `cargo bench -p lt-experiments --features bench`: raw BVH traversal and integrator throughput on the shipped
//! scenes. `lt bench` prints the same figures as a table for results/bench.md.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use lt_experiments::bench::incoherent_rays;
use lt_integrators::{make_integrator, IntegratorParams};
use lt_scene_io::load_scene;
use std::path::Path;

fn scene(name: &str) -> lt_core::Scene {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(format!("{name}.toml"));
    load_scene(&p).unwrap_or_else(|e| panic!("{e}"))
}

fn traversal(c: &mut Criterion) {
    let mut g = c.benchmark_group("closest_hit");
    for name in ["cornell-box", "veach-mis"] {
        let s = scene(name);
        let rays = incoherent_rays(&s, 100_000, 1);
        g.throughput(Throughput::Elements(rays.len() as u64));
        g.bench_function(name, |b| {
            b.iter(|| rays.iter().filter(|r| s.intersect(r).is_some()).count())
        });
    }
    g.finish();
}

fn path_tracing(c: &mut Criterion) {
    let mut g = c.benchmark_group("pt_pass");
    g.sample_size(10);
    for name in ["cornell-box", "veach-mis"] {
        let s = scene(name);
        let pt = make_integrator("pt", &s, &IntegratorParams::default()).unwrap();
        g.throughput(Throughput::Elements(s.camera.pixel_count() as u64));
        let mut pass = 0;
        g.bench_function(name, |b| {
            b.iter(|| {
                pass += 1;
                pt.unbiased().unwrap().render_pass(&s, 1, pass)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, traversal, path_tracing);
criterion_main!(benches);

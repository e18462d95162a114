#!/bin/sh
# Instruction profiles of one render per integrator (callgrind: counts instructions, so the
# machine's load does not move them), and the share of each category of work, as in
# results/bench.md, "Where a sample's time goes".
#
#   crates/experiments/scripts/bench_profile.sh [LT] [OUT_DIR]
#
# LT defaults to target/profiling/lt (`cargo build --profile profiling --bin lt`: release code
# with debug info, so code inlined into a function is attributed to the source file it came
# from). Each render: cornell-box, seed 1, one thread, no checkpoints (a checkpoint adds output
# work that depends on how long the run took). Prints a markdown table.
set -e
LT=${1:-target/profiling/lt}
OUT=${2:-/tmp/lt-profiles}
mkdir -p "$OUT"
for x in "pt 2" "light 2" "bdpt 1" "sppm 2" "vcm 1"; do
  set -- $x
  valgrind --tool=callgrind --callgrind-out-file="$OUT/$1.out" "$LT" render scenes/cornell-box.toml \
    -i "$1" --spp "$2" --seed 1 --threads 1 --checkpoint 100000 --quiet -o "$OUT/$1.exr" \
    > "$OUT/$1.log" 2>&1 &
done
wait
python3 - "$OUT" <<'PY'
import collections, re, sys
out = sys.argv[1]

def self_costs(path):
    """Self cost (Ir) per (function, source file of the inlined line) from a callgrind file."""
    names, costs = {}, collections.Counter()
    def name(kind, s):
        m = re.match(r'\((\d+)\)(?:\s+(.*))?', s)
        if not m:
            return s
        if m.group(2) is not None:
            names[(kind, m.group(1))] = m.group(2)
        return names.get((kind, m.group(1)), s)
    fl = fi = fn = None
    skip = False
    for line in open(path, errors='replace'):
        line = line.rstrip('\n')
        if not line:
            continue
        if line[0].isdigit() or line[0] in '+-*':
            if skip:  # the cost line after calls= is the callee's inclusive cost
                skip = False
                continue
            parts = line.split()
            if len(parts) >= 2:
                costs[(fn, fi or fl)] += int(parts[1])
        elif line.startswith('fl='):
            fl, fi = name('fl', line[3:]), None
        elif line.startswith(('fi=', 'fe=')):
            fi = name('fl', line[3:])
            fi = None if fi == fl else fi
        elif line.startswith('fn='):
            fn, fi = name('fn', line[3:]), None
        elif line.startswith('calls='):
            skip = True
        elif line.startswith('cfn='):
            name('fn', line[4:])
        elif line.startswith(('cfl=', 'cfi=')):
            name('fl', line[4:])
    return costs

# First match wins: (category, regex on the function symbol, regex on the inlined source file).
RULES = [
    ('output/load', r'miniz|exr::|png::|image::|write_exr|write_png|zmij|simd_adler|crc32|load_scene|toml|render_cmd|Accel::build|obvhs::(ploc|bvh2|cwbvh::builder|cwbvh::bvh2_to)|_dl_|serde', None),
    ('allocation, memcpy', r'malloc|free|realloc|calloc|alloc::|RawVec|_int_|memcpy|memmove', None),
    ('BVH traversal', r'memset', r'obvhs'),
    ('primitive tests + hit record', r'Scene::intersect|Accel::|Primitive::|Parallelogram|intersect_triangle|intersect_sphere|SurfaceHit|refine_sphere|shading_normal', r'geometry/(quad|triangle|sphere|accel)'),
    ('shadow-ray setup', r'visibility|End::towards|offset_ray_origin|connection_visible', r'scene/visibility'),
    ('photon grid', r'PointGrid|spatial::|photons::|progressive::|Engine::merge|gather', r'spatial/|photons\.rs|progressive\.rs'),
    ('MIS bookkeeping', r'mis_weight|Chain::|mis::|SubpathMis|convert_density|camera_records|light_records|power_heuristic|Densities', r'path/(mis|subpath_mis)'),
    ('splatting', r'splat|Splats|connect_to_camera|Camera::importance|Camera::project', r'splat\.rs'),
    ('shading (BSDF eval/sample)', r'bsdf::|Diffuse|Glossy|Dielectric|Mirror|ShadingFrame|continue_path', r'bsdf/'),
    ('light sampling', r'light::|Distribution1D|LightSampler|next_event|direct_light|sincosf|pow', r'light/'),
]
OTHER = 'other (integrator loop, RNG, pass loop)'
ints = ['pt', 'light', 'bdpt', 'sppm', 'vcm']
table = {}
for i in ints:
    acc = collections.Counter()
    for (fn, fl), v in self_costs(f'{out}/{i}.out').items():
        fn, fl = str(fn), str(fl)
        for cat, rfn, rfl in RULES:
            if re.search(rfn, fn) or (rfl and re.search(rfl, fl)):
                acc[cat] += v
                break
        else:
            acc[OTHER] += v
    table[i] = acc
cats = [c for c, _, _ in RULES[1:]] + [OTHER]
print('| category | ' + ' | '.join(ints) + ' |')
print('|---|' + '---:|' * len(ints))
render = {i: sum(table[i].values()) - table[i]['output/load'] for i in ints}
for c in cats:
    print(f'| {c} | ' + ' | '.join(f'{100 * table[i][c] / render[i]:.1f} %' for i in ints) + ' |')
print('| render instructions (output, load left out) | ' + ' | '.join(f'{render[i] / 1e6:.0f} M' for i in ints) + ' |')
PY

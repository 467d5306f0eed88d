// Segment / sphere tracing and terrain shading, one primary ray per invocation: the GPU
// twin of the CPU renderer's trace.rs, shade.rs and cpu.rs. Concatenated
// after field.wgsl (which provides eval_tape).

struct Uniforms {
    eye: vec4<f32>,       // xyz, w = tan(fov_y / 2)
    right: vec4<f32>,     // xyz, w = aspect
    up: vec4<f32>,        // xyz, w = width
    forward: vec4<f32>,   // xyz, w = height
    box_min: vec4<f32>,   // support box, w = epsilon
    box_max: vec4<f32>,   // w = cone
    trace: vec4<f32>,     // x = global Lipschitz, y = grow, z = grad step, w = method (0 segment, 1 sphere)
    sun: vec4<f32>,       // xyz, w = shadows (0 / 1)
    sun_color: vec4<f32>, // w = haze distance
    zenith: vec4<f32>,    // w = cave-scale occlusion reach
    horizon: vec4<f32>,   // w = occlusion radius
    bounce: vec4<f32>,    // w = exposure
    rock: vec4<f32>,      // w = rock slope lower end
    soil: vec4<f32>,      // w = rock slope upper end
    grass: vec4<f32>,     // w = soil slope lower end
    snow: vec4<f32>,      // w = soil slope upper end
    snow_line: vec4<f32>, // altitude, blend (0: no snow), variation, variation wavelength
    feature: vec4<f32>,   // feature depths d0, d1, dry-grass scale
    dry: vec4<f32>,       // dry grass
    disk_u: vec4<f32>,    // the sun's disk (shade.rs Shading::sun_disk)
    disk_v: vec4<f32>,
    water: vec4<f32>,     // level, clarity, 1 when there is water (0: none)
    water_colour: vec4<f32>,
    dims: vec4<u32>,      // width, height, max steps, ground parameters + 1 (0: no ground)
    consts: vec4<u32>,    // variation seed, occlusion samples, ground flags, sun seed
}

// A storage buffer, not a uniform one: llvmpipe compiles a variant of the shader for
// each set of values of the uniforms it inlines (seconds each).
@group(0) @binding(0) var<storage, read> u: Uniforms;
@group(0) @binding(4) var<storage, read_write> out_rgba: array<u32>;
@group(0) @binding(5) var<storage, read_write> out_depth: array<f32>;
@group(0) @binding(6) var<storage, read_write> out_steps: array<u32>;
@group(0) @binding(7) var<storage, read> probe_in: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> probe_out: array<vec2<f32>>;
@group(0) @binding(9) var<storage, read_write> saved: array<Saved>;
// Written by the host before each pass: [0, 0, 2 (the canary's count), first row of the
// tile, pass (0: start), evaluations per pass (0: no limit), 0, 0]; the pass counts the
// pixels it leaves unfinished into [0] and those that made no progress into [1].
@group(0) @binding(10) var<storage, read_write> progress: array<atomic<u32>, 8>;

const MAX_REFINE: u32 = 12u;
const FIRST_DELTA: f32 = 0.0625;
const GAMMA_STEPS: f32 = 4095.0;
const MISS: f32 = -1.0;

// [t0, t1] of the ray inside the support box, t0 >= 0; t0 > t1 on a miss.
fn clip(o: vec3<f32>, d: vec3<f32>) -> vec2<f32> {
    let inv = 1.0 / d;
    let a = (u.box_min.xyz - o) * inv;
    let b = (u.box_max.xyz - o) * inv;
    let lo = min(a, b);
    let hi = max(a, b);
    let t0 = max(max(max(lo.x, lo.y), lo.z), 0.0);
    let t1 = min(min(hi.x, hi.y), hi.z);
    return vec2<f32>(t0, t1);
}

// One ray's march (trace.rs::trace: steps of at least the tolerance) and, once the sign
// of f − T changes, its refinement (trace.rs::refine: false position with the Illinois
// modification), advanced one field evaluation at a time by `render`.
struct Ray {
    o: vec3<f32>,
    d: vec3<f32>,
    t: f32,
    t1: f32,
    delta: f32,
    side: f32, // sign of f − T at the start, 0 before the first step
    prev_t: f32,
    prev_e: f32,
    steps: u32,
    // The refinement's bracket [a, b] with f − T = ea, eb, its iterate m (the result: the
    // hit, or MISS), the last iterate, the width it stops at, the side kept last, and its
    // evaluations.
    a: f32,
    ea: f32,
    b: f32,
    eb: f32,
    m: f32,
    last: f32,
    width: f32,
    kept: i32,
    n: u32,
}

// What the invocation evaluates next: its phases.
const PH_MARCH: u32 = 0u;  // a march step of the current ray
const PH_REFINE: u32 = 1u; // a refinement step of the current ray
const PH_END: u32 = 2u;    // the current ray is over (result in m): no evaluation
const PH_NORMAL: u32 = 3u; // one of the 4 samples of the normal at the hit
const PH_DONE: u32 = 4u;   // nothing left

fn start_ray(o: vec3<f32>, d: vec3<f32>, t0: f32, t1: f32) -> Ray {
    return Ray(o, d, t0, t1, (t1 - t0) * FIRST_DELTA, 0.0, t0, 0.0, 0u, 0.0, 0.0, 0.0, 0.0, MISS, -3.4e38, 0.0, 0, 0u);
}

// The length of the next march step's segment; 0 for sphere tracing, which evaluates the
// value alone (r = 0) and steps by the global bound.
fn march_len(ray: Ray) -> f32 {
    if u.trace.w == 0.0 {
        return min(ray.t + ray.delta, ray.t1) - ray.t;
    }
    return 0.0;
}

// Consumes the evaluation `ev` of a march step: PH_MARCH to go on, PH_REFINE when the
// sign changed (the bracket is set), PH_END on leaving the segment (a miss).
// `eps` is the tolerance at the ray's origin: ε for primary rays, the pixel's footprint
// at the hit for shadow rays (cpu.rs tile).
fn march_step(ray: ptr<function, Ray>, ev_in: vec2<f32>, eps: f32) -> u32 {
    let cone = u.box_max.w;
    let segment = u.trace.w == 0.0;
    let len = march_len(*ray);
    var ev = ev_in;
    if !segment {
        ev.y = u.trace.x;
    }
    let e = ev.x - ISO;
    (*ray).steps += 1u;
    var s_now = -1.0;
    if e > 0.0 {
        s_now = 1.0;
    }
    if (*ray).side == 0.0 {
        (*ray).side = s_now;
    } else if s_now != (*ray).side {
        (*ray).a = (*ray).prev_t;
        (*ray).ea = (*ray).prev_e;
        (*ray).b = (*ray).t;
        (*ray).eb = e;
        (*ray).m = 0.5 * ((*ray).a + (*ray).b);
        (*ray).width = 0.1 * (eps + cone * (*ray).prev_t);
        return PH_REFINE;
    }
    if (*ray).t >= (*ray).t1 {
        (*ray).m = MISS;
        return PH_END;
    }
    let t = (*ray).t;
    let tol = eps + cone * t;
    var s = 3.4e38;
    if ev.y > 0.0 {
        s = abs(e) / ev.y;
    }
    var step = s;
    if segment {
        if s >= len {
            step = len;
            (*ray).delta = (*ray).delta * u.trace.y;
        } else {
            (*ray).delta = max(s, tol);
        }
    }
    (*ray).prev_t = t;
    (*ray).prev_e = e;
    (*ray).t = min(t + max(step, tol), (*ray).t1);
    return PH_MARCH;
}

// The next refinement iterate into m; false when the refinement is over (m is the hit).
fn refine_next(ray: ptr<function, Ray>) -> bool {
    let a = (*ray).a;
    let b = (*ray).b;
    if (*ray).n >= MAX_REFINE || b - a <= (*ray).width {
        return false;
    }
    let ea = (*ray).ea;
    let eb = (*ray).eb;
    var m = 0.5 * (a + b);
    if ea != eb {
        m = a + (b - a) * ea / (ea - eb);
    }
    (*ray).m = clamp(m, a, b);
    return true;
}

// Consumes f − T = e at the iterate m; false when the refinement is over.
fn refine_step(ray: ptr<function, Ray>, e: f32) -> bool {
    (*ray).n += 1u;
    let m = (*ray).m;
    if abs(m - (*ray).last) < (*ray).width {
        return false;
    }
    (*ray).last = m;
    if (e > 0.0) == ((*ray).ea > 0.0) {
        (*ray).a = m;
        (*ray).ea = e;
        if (*ray).kept == 1 {
            (*ray).eb *= 0.5;
        }
        (*ray).kept = 1;
    } else {
        (*ray).b = m;
        (*ray).eb = e;
        if (*ray).kept == -1 {
            (*ray).ea *= 0.5;
        }
        (*ray).kept = -1;
    }
    return true;
}

// The tetrahedral finite-difference offsets of the normal (the CPU's fold order).
fn normal_offset(i: u32) -> vec3<f32> {
    switch i {
        case 0u: { return vec3<f32>(1.0, -1.0, -1.0); }
        case 1u: { return vec3<f32>(-1.0, -1.0, 1.0); }
        case 2u: { return vec3<f32>(-1.0, 1.0, -1.0); }
        default: { return vec3<f32>(1.0, 1.0, 1.0); }
    }
}

fn smooth_step(a: f32, b: f32, x: f32) -> f32 {
    let v = clamp((x - a) / (b - a), 0.0, 1.0);
    return v * v * (3.0 - 2.0 * v);
}

// shade.rs Shading::sky.
fn sky(d: vec3<f32>) -> vec3<f32> {
    let k = sqrt(clamp(d.z, 0.0, 1.0));
    let glow = pow(max(dot(d, u.sun.xyz), 0.0), 8.0);
    return mix(u.horizon.xyz, u.zenith.xyz, k) + u.sun_color.xyz * (0.12 * glow);
}

// material.rs Materials::off_ground: p.z − h(p.xy), 0 without a ground or off its grid.
fn off_ground(p: vec3<f32>) -> f32 {
    if u.dims.w == 0u {
        return 0.0;
    }
    let o = u.dims.w - 1u;
    let lo = vec2<f32>(params[o + HEIGHT_ORIGIN], params[o + HEIGHT_ORIGIN + 1u]);
    let hi = lo + params[o + HEIGHT_CELL] * (vec2<f32>(params[o + HEIGHT_NX], params[o + HEIGHT_NY]) - 1.0);
    if any(p.xy < lo) || any(p.xy > hi) {
        return 0.0;
    }
    return p.z - elevation(u.consts.z, o, p.x, p.y);
}

// material.rs Materials::feature.
fn feature_of(p: vec3<f32>) -> f32 {
    return smooth_step(u.feature.x, u.feature.y, abs(off_ground(p)));
}

// material.rs resolved.
fn resolved(wavelength: f32, footprint: f32) -> f32 {
    return 1.0 - smooth_step(0.25 * wavelength, 0.5 * wavelength, footprint);
}

// material.rs ground_grain.
fn ground_grain(p: vec3<f32>, footprint: f32) -> f32 {
    return GRAIN_LONG_AMP * resolved(GRAIN_LONG, footprint) * simplex(GRAIN_SEED ^ 1u, p / GRAIN_LONG)
        + GRAIN_SHORT_AMP * resolved(GRAIN_SHORT, footprint) * simplex(GRAIN_SEED ^ 2u, p / GRAIN_SHORT);
}

// material.rs Materials::seen's albedo (cover, then albedo_of, then the ground's grain
// at the pixel's `footprint`), with `feature_of(p)`.
fn albedo(p: vec3<f32>, n: vec3<f32>, feature: f32, footprint: f32) -> vec3<f32> {
    let wander = simplex(u.consts.x, p / u.snow_line.w);
    let nz = n.z + u.snow_line.z * wander;
    let steep = 1.0 - smooth_step(u.rock.w, u.soil.w, nz);
    let soil = 1.0 - smooth_step(u.grass.w, u.snow.w, nz);
    var snow = 0.0;
    if u.snow_line.y > 0.0 {
        let b = u.snow_line.y;
        snow = smooth_step(u.snow_line.x - b, u.snow_line.x + b, p.z + b * wander)
            * smooth_step(u.rock.w, u.soil.w, nz);
    }
    let rock = max(steep, feature);
    let dry = smooth_step(-0.2, 0.5, simplex(u.consts.x ^ 1u, p / (u.feature.z * u.snow_line.w)));
    let grass = mix(u.grass.xyz, u.dry.xyz, dry);
    return mix(mix(mix(grass, u.soil.xyz, soil), u.snow.xyz, snow), u.rock.xyz, rock)
        * (1.0 + (1.0 - rock) * ground_grain(p, footprint));
}

// shade.rs Shading::light.
fn light(n: vec3<f32>, lit: f32, ao: f32) -> vec3<f32> {
    let diffuse = max(dot(n, u.sun.xyz), 0.0) * lit;
    let ambient = mix(u.bounce.xyz, mix(u.zenith.xyz, u.horizon.xyz, 0.5), 0.5 + 0.5 * n.z);
    return u.sun_color.xyz * diffuse + ambient * ao;
}

// shade.rs Shading::haze.
fn haze(c: vec3<f32>, t: f32) -> vec3<f32> {
    let k = 1.0 - exp(-t / u.sun_color.w);
    return mix(c, u.horizon.xyz, k);
}

// shade.rs aces, after the exposure (Shading::display).
fn display(c_in: vec3<f32>) -> vec3<f32> {
    let x = max(c_in * u.bounce.w, vec3<f32>(0.0));
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), vec3<f32>(0.0), vec3<f32>(1.0));
}

// shade.rs waves.
fn waves(at: vec3<f32>, tw: f32) -> vec3<f32> {
    let long = WAVE_LENGTH;
    let short = WAVE_SHORT * WAVE_LENGTH;
    let e = 0.05 * short;
    let gx = wave_height(at.x + e, at.y) - wave_height(at.x - e, at.y);
    let gy = wave_height(at.x, at.y + e) - wave_height(at.x, at.y - e);
    let g = vec3<f32>(gx, gy, 0.0) * (long / (2.0 * e));
    let calm = 1.0 - smooth_step(250.0 * short, 500.0 * short, tw);
    return normalize(vec3<f32>(0.0, 0.0, 1.0) - g * (WAVE_SLOPE * calm));
}

// shade.rs waves: the height of the two octaves.
fn wave_height(x: f32, y: f32) -> f32 {
    let long = WAVE_LENGTH;
    let short = WAVE_SHORT * WAVE_LENGTH;
    return simplex(WAVE_SEED, vec3<f32>(x / long, y / long, 0.0))
        + 0.4 * WAVE_SHORT * simplex(WAVE_SEED + 1u, vec3<f32>(x / short, y / short, 0.0));
}

// shade.rs Shading::seen (t < 0: a miss) and Shading::water_surface.
fn seen(o: vec3<f32>, d: vec3<f32>, t: f32, surface: vec3<f32>) -> vec3<f32> {
    let far = select(t, 3.0e38, t < 0.0);
    if u.water.z > 0.0 && o.z > u.water.x && d.z < 0.0 {
        let tw = (u.water.x - o.z) / d.z;
        if tw < far {
            let at = o + d * tw;
            let path = far - tw;
            let through = exp(-path / u.water.y);
            let up = light(vec3<f32>(0.0, 0.0, 1.0), 1.0, 1.0);
            let body = mix(u.water_colour.xyz * up, surface * WET, through);
            let n = waves(at, tw);
            let cos_n = clamp(-dot(d, n), 0.0, 1.0);
            let fresnel = 0.02 + 0.98 * pow(1.0 - cos_n, 5.0);
            let r = d - 2.0 * dot(d, n) * n;
            let mirrored = sky(vec3<f32>(r.x, r.y, abs(r.z)));
            let water = mix(body, mirrored, fresnel);
            let depth = path * -d.z;
            let broken = smooth_step(-0.2, 0.5, simplex(WAVE_SEED + 2u, at / (WAVE_SHORT * WAVE_LENGTH)));
            let surf = smooth_step(SURF_DEPTH, 0.15 * SURF_DEPTH, depth) * broken;
            return haze(mix(water, vec3<f32>(0.8) * up, 0.85 * surf), tw);
        }
    }
    if t < 0.0 {
        return sky(d);
    }
    return haze(surface, t);
}

// shade.rs Shading::sun_towards: the shadow ray of pixel (i, j).
fn sun_towards(i: u32, j: u32) -> vec3<f32> {
    let h = mix32(i ^ mix32(j ^ u.consts.w));
    let r = sqrt(f32(h & 0xffffu) / 65536.0);
    let phi = 6.2831855 * f32(h >> 16u) / 65536.0;
    return normalize(u.sun.xyz + u.disk_u.xyz * (r * cos(phi)) + u.disk_v.xyz * (r * sin(phi)));
}

// shade.rs Shading::ao_step.
fn ao_step(k: u32) -> f32 {
    return u.horizon.w * f32(k + 1u) / f32(u.consts.y);
}

// shade.rs Shading::cave_offset: the k-th cave-scale sample off a point of normal n.
fn cave_offset(n: vec3<f32>, k: u32) -> vec3<f32> {
    let dir = k / CAVE_STEPS;
    let step = k % CAVE_STEPS;
    let bent = n + vec3<f32>(0.0, 0.0, 1.0);
    var b = n;
    if dot(bent, bent) > 0.01 {
        b = normalize(bent);
    }
    var d = b;
    if dir > 0u {
        // glam's Vec3::any_orthonormal_pair.
        let sign = select(-1.0, 1.0, b.z >= 0.0);
        let a = -1.0 / (sign + b.z);
        let c = b.x * b.y * a;
        let e1 = vec3<f32>(1.0 + sign * b.x * b.x * a, sign * c, -sign * b.x);
        let e2 = vec3<f32>(c, sign + b.y * b.y * a, -b.y);
        let phi = 6.2831855 * f32(dir - 1u) / f32(CAVE_DIRS - 1u);
        d = b * cos(CAVE_TILT) + (e1 * cos(phi) + e2 * sin(phi)) * sin(CAVE_TILT);
    }
    return d * (u.zenith.w * f32(step + 1u) / f32(CAVE_STEPS));
}

// shade.rs cave_closed.
fn cave_closed(f: f32) -> f32 {
    return clamp((f - ISO) / CAVE_RAMP, 0.0, 1.0);
}

// shade.rs cave_sky.
fn cave_sky(first: f32, all: f32) -> f32 {
    let open = first + (1.0 - first) * all;
    return CAVE_FLOOR + (1.0 - CAVE_FLOOR) * open;
}

// Quantised to 1/4095 before encoding, like the CPU's gamma table (shade.rs::to_srgb8).
fn srgb8(c: vec3<f32>) -> u32 {
    let q = floor(clamp(c, vec3<f32>(0.0), vec3<f32>(1.0)) * GAMMA_STEPS + 0.5) / GAMMA_STEPS;
    let e = vec3<u32>(pow(q, vec3<f32>(1.0 / 2.2)) * 255.0 + 0.5);
    return e.x | (e.y << 8u) | (e.z << 16u) | (255u << 24u);
}

// What a pixel interrupted by lavapipe's loop budget keeps for the next pass (see
// `budget_left`): its ray, phase and normal sum.
struct Saved {
    o: vec4<f32>,       // ray.o, ray.t
    d: vec4<f32>,       // ray.d, ray.t1
    march: vec4<f32>,   // delta, side, prev_t, prev_e
    bracket: vec4<f32>, // a, ea, b, eb
    refine: vec4<f32>,  // m, last, width, hit_t
    g: vec4<f32>,       // the normal's sum, the occlusion's weighted sum
    ao: vec4<f32>,      // the occlusion's weights, the cave-scale samples' max, sum, first
    counts: vec4<u32>,  // phase | shadow << 8 | corner << 16 | (kept + 1) << 24, ray.steps, ray.n, hit steps
}

// False once the loops of this SIMD group have used up llvmpipe's budget of 65,535
// iterations per invocation (LP_MAX_TGSI_LOOP_ITERATIONS, shared by every loop; from then
// on each loop ends after one iteration): a loop asked for 2 iterations (read from a
// buffer, so the compiler cannot unroll it) then gets 1. The evaluation before it may have been cut
// short, so its result is dropped. Always true on other drivers.
fn budget_left() -> bool {
    var k = 0u;
    loop {
        k += 1u;
        if k >= atomicLoad(&progress[2]) {
            break;
        }
    }
    return k >= 2u;
}

// One primary ray: march, refine, normal, occlusion samples, shadow ray (march, refine),
// shade. The phases are states of one loop whose body evaluates the tape once, so
// `eval_tape` has a single call site: drivers inline every call site (the shader's size
// drives lavapipe's compile time), and diverging invocations of a SIMD group stay on the
// same code. A pixel whose loop budget runs out (lavapipe) saves its state and is resumed
// by the next dispatch (pass) of its tile; `progress` tells the host how many are left.
// `corner` counts the normal's 4 samples, then the occlusion's, then the cave-scale ones
// (cpu.rs occlusion).
@compute @workgroup_size(8, 8, 1)
fn render(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u.dims.x;
    let h = u.dims.y;
    let row = id.y + atomicLoad(&progress[3]);
    if id.x >= w || row >= h {
        return;
    }
    let at = id.x + row * w;
    let slot = id.x + id.y * w;
    let x = f32(id.x) + 0.5;
    let y = f32(row) + 0.5;
    let su = (2.0 * x / u.up.w - 1.0) * u.eye.w * u.right.w;
    let sv = (1.0 - 2.0 * y / u.forward.w) * u.eye.w;
    let o = u.eye.xyz;
    let d = normalize(u.forward.xyz + u.right.xyz * su + u.up.xyz * sv);
    let ao_end = 4u + select(u.consts.y, 0u, u.horizon.w <= 0.0);
    let cave_end = ao_end + CAVE_DIRS * CAVE_STEPS;
    var phase = PH_DONE;
    var ray: Ray;
    var shadow = false;
    var hit_t = MISS;
    var hit_steps = 0u;
    var g = vec3<f32>(0.0);
    var ao_sum = 0.0;
    var ao_norm = 0.0;
    var cave_max = 0.0;
    var cave_sum = 0.0;
    var cave_first = 1.0;
    var corner = 0u;
    let per_pass = atomicLoad(&progress[5]);
    if atomicLoad(&progress[4]) == 0u {
        let span = clip(o, d);
        ray = start_ray(o, d, span.x, span.y);
        if span.x <= span.y {
            phase = PH_MARCH;
        }
    } else {
        let sv = saved[slot];
        phase = sv.counts.x & 255u;
        if phase == PH_DONE {
            return;
        }
        shadow = ((sv.counts.x >> 8u) & 1u) != 0u;
        corner = (sv.counts.x >> 16u) & 255u;
        ray = Ray(sv.o.xyz, sv.d.xyz, sv.o.w, sv.d.w, sv.march.x, sv.march.y, sv.march.z, sv.march.w, sv.counts.y,
            sv.bracket.x, sv.bracket.y, sv.bracket.z, sv.bracket.w, sv.refine.x, sv.refine.y, sv.refine.z,
            i32(sv.counts.x >> 24u) - 1, sv.counts.z);
        hit_t = sv.refine.w;
        hit_steps = sv.counts.w;
        g = sv.g.xyz;
        ao_sum = sv.g.w;
        ao_norm = sv.ao.x;
        cave_max = sv.ao.y;
        cave_sum = sv.ao.z;
        cave_first = sv.ao.w;
    }
    var p = o + d * hit_t;
    var n = vec3<f32>(0.0, 0.0, 1.0);
    var slope = length(g / (4.0 * u.trace.z));
    if corner >= 4u && slope > 0.0 {
        n = -g / (4.0 * u.trace.z) / slope;
    }
    var lit = 1.0;
    var evals = 0u;
    loop {
        // Transitions that need no evaluation.
        if phase == PH_MARCH && ray.steps >= u.dims.z {
            ray.m = MISS;
            phase = PH_END;
        }
        if phase == PH_REFINE && !refine_next(&ray) {
            phase = PH_END;
        }
        if phase == PH_NORMAL && corner == ao_end && (u.zenith.w <= 0.0 || feature_of(p) <= 0.0) {
            // No cave-scale samples off the DEM's ground (cpu.rs occlusion).
            corner = cave_end;
        }
        if phase == PH_NORMAL && corner == cave_end {
            // The normal and the occlusion are done: the shadow ray.
            phase = PH_DONE;
            if u.sun.w > 0.0 && dot(n, u.sun.xyz) > 0.0 {
                let tol = u.box_min.w + u.box_max.w * hit_t;
                let so = p + n * (2.0 * tol);
                let sd = sun_towards(id.x, row);
                let sspan = clip(so, sd);
                if sspan.x <= sspan.y {
                    ray = start_ray(so, sd, sspan.x, sspan.y);
                    shadow = true;
                    phase = PH_MARCH;
                }
            }
        }
        if phase == PH_END {
            phase = PH_DONE;
            if shadow {
                if ray.m != MISS {
                    lit = 0.0;
                }
            } else {
                hit_t = ray.m;
                hit_steps = ray.steps + ray.n;
                if hit_t != MISS {
                    p = o + d * hit_t;
                    phase = PH_NORMAL;
                }
            }
        }
        if phase == PH_DONE || (per_pass != 0u && evals == per_pass) {
            break;
        }
        // The one evaluation of this step.
        var qp = ray.o + ray.d * ray.t;
        var qc = qp;
        var qr = 0.0;
        if phase == PH_NORMAL {
            if corner < 4u {
                qp = p + normal_offset(corner) * u.trace.z;
                qc = qp;
            } else if corner < ao_end {
                qp = p + n * ao_step(corner - 4u);
                qc = qp;
            } else {
                qp = p + cave_offset(n, corner - ao_end);
                qc = qp;
            }
        } else if phase == PH_REFINE {
            qp = ray.o + ray.d * ray.m;
            qc = qp;
        } else {
            let len = march_len(ray);
            qc = qp + ray.d * (0.5 * len);
            qr = 0.5 * len;
        }
        let ev = eval_tape(qp, qc, qr);
        if !budget_left() {
            break;
        }
        evals += 1u;
        if phase == PH_MARCH {
            phase = march_step(&ray, ev, select(u.box_min.w, u.box_min.w + u.box_max.w * hit_t, shadow));
        } else if phase == PH_REFINE {
            if !refine_step(&ray, ev.x - ISO) {
                phase = PH_END;
            }
        } else if corner < 4u {
            g += normal_offset(corner) * ev.x;
            corner += 1u;
            if corner == 4u {
                let grad = g / (4.0 * u.trace.z);
                slope = length(grad);
                if slope > 0.0 {
                    n = -grad / slope;
                }
            }
        } else if corner >= ao_end {
            // cpu.rs cave_occlusion: a direction is as open as its most closed sample
            // allows; while the first (the bent normal) is open, the others are not asked.
            let k = corner - ao_end;
            cave_max = max(cave_max, cave_closed(ev.x));
            if k % CAVE_STEPS == CAVE_STEPS - 1u {
                let open = 1.0 - cave_max;
                cave_max = 0.0;
                cave_sum += open;
                if k < CAVE_STEPS {
                    cave_first = open;
                    if open >= 1.0 {
                        corner = cave_end - 1u;
                    }
                }
            }
            corner += 1u;
        } else {
            // cpu.rs occlusion. The lowest value so far rides in cave_first (1 = 2T
            // at the start), which the cave phase starts from 1 again.
            let k = corner - 4u;
            cave_first = min(cave_first, ev.x);
            var open = 1.0;
            if slope > 0.0 {
                open = (ISO - ev.x) / min(slope * ao_step(k), clamp(ISO - cave_first, 1e-3, ISO));
            }
            ao_sum += clamp(open, 0.0, 1.0) / f32(k + 1u);
            ao_norm += 1.0 / f32(k + 1u);
            corner += 1u;
            if corner == ao_end {
                cave_first = 1.0;
            }
        }
    }
    if phase != PH_DONE {
        let flags = phase | (u32(shadow) << 8u) | (corner << 16u) | (u32(ray.kept + 1) << 24u);
        saved[slot] = Saved(vec4<f32>(ray.o, ray.t), vec4<f32>(ray.d, ray.t1),
            vec4<f32>(ray.delta, ray.side, ray.prev_t, ray.prev_e), vec4<f32>(ray.a, ray.ea, ray.b, ray.eb),
            vec4<f32>(ray.m, ray.last, ray.width, hit_t), vec4<f32>(g, ao_sum), vec4<f32>(ao_norm, cave_max, cave_sum, cave_first),
            vec4<u32>(flags, ray.steps, ray.n, hit_steps));
        atomicAdd(&progress[0], 1u);
        if evals == 0u {
            atomicAdd(&progress[1], 1u);
        }
        return;
    }
    saved[slot].counts.x = PH_DONE;
    out_steps[at] = hit_steps;
    out_depth[at] = hit_t;
    if hit_t == MISS {
        out_rgba[at] = srgb8(display(seen(o, d, hit_t, vec3<f32>(0.0))));
        return;
    }
    // shade.rs ambient_occlusion.
    var ao = 1.0;
    if ao_norm > 0.0 {
        ao = ao_sum / ao_norm;
    }
    let feature = feature_of(p);
    if cave_first < 1.0 {
        ao *= mix(1.0, cave_sky(cave_first, cave_sum / f32(CAVE_DIRS)), feature);
    }
    let footprint = u.box_max.w * hit_t;
    let c = seen(o, d, hit_t, albedo(p, n, feature, footprint) * light(n, lit, ao));
    out_rgba[at] = srgb8(display(c));
}

// Tape probes for the tests: (p.xyz, r) -> (f(p), Lipschitz bound over B(p, r)).
@compute @workgroup_size(64, 1, 1)
fn probe(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&probe_in) {
        return;
    }
    let q = probe_in[id.x];
    probe_out[id.x] = eval_tape(q.xyz, q.xyz, q.w);
}

// fBm probes for the tests: the fBm encoded at params[0..7] at each p.xyz -> (t(p), 0).
@compute @workgroup_size(64, 1, 1)
fn fbm_probe(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&probe_in) {
        return;
    }
    probe_out[id.x] = vec2<f32>(fbm(0u, probe_in[id.x].xyz), 0.0);
}

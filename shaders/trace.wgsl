// Segment / sphere tracing and terrain shading, one primary ray per invocation: the GPU
// twin of src/render/trace.rs, src/render/shade.rs and src/render/cpu.rs. Concatenated
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
    sun_color: vec4<f32>, // w = fog distance
    sky: vec4<f32>,       // w = snow line
    ground: vec4<f32>,    // w = snow blend
    fog: vec4<f32>,       // w = rock slope lower end
    rock: vec4<f32>,      // w = rock slope upper end
    grass: vec4<f32>,
    snow: vec4<f32>,
    dims: vec4<u32>,      // width, height, max steps, unused
}

@group(0) @binding(0) var<uniform> u: Uniforms;
@group(0) @binding(4) var<storage, read_write> out_rgba: array<u32>;
@group(0) @binding(5) var<storage, read_write> out_depth: array<f32>;
@group(0) @binding(6) var<storage, read_write> out_steps: array<u32>;
@group(0) @binding(7) var<storage, read> probe_in: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> probe_out: array<vec2<f32>>;

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

fn value(p: vec3<f32>) -> f32 {
    return eval_tape(p, p, 0.0).x;
}

struct Hit {
    t: f32, // MISS when no hit
    steps: u32,
}

// False position with the Illinois modification, as trace.rs::refine.
fn refine(o: vec3<f32>, d: vec3<f32>, a_in: f32, ea_in: f32, b_in: f32, eb_in: f32, width: f32) -> Hit {
    var a = a_in;
    var ea = ea_in;
    var b = b_in;
    var eb = eb_in;
    var n = 0u;
    var last = -3.4e38;
    var m = 0.5 * (a + b);
    var kept = 0;
    loop {
        if n >= MAX_REFINE || b - a <= width {
            break;
        }
        if ea != eb {
            m = a + (b - a) * ea / (ea - eb);
        } else {
            m = 0.5 * (a + b);
        }
        m = clamp(m, a, b);
        let e = value(o + d * m) - T;
        n += 1u;
        if abs(m - last) < width {
            break;
        }
        last = m;
        if (e > 0.0) == (ea > 0.0) {
            a = m;
            ea = e;
            if kept == 1 {
                eb *= 0.5;
            }
            kept = 1;
        } else {
            b = m;
            eb = e;
            if kept == -1 {
                ea *= 0.5;
            }
            kept = -1;
        }
    }
    return Hit(m, n);
}

// The march of trace.rs::trace: steps of at least the tolerance, refinement on a crossing.
fn trace_ray(o: vec3<f32>, d: vec3<f32>, t0: f32, t1: f32) -> Hit {
    if !(t0 <= t1) {
        return Hit(MISS, 0u);
    }
    let eps = u.box_min.w;
    let cone = u.box_max.w;
    let segment = u.trace.w == 0.0;
    var t = t0;
    var delta = (t1 - t0) * FIRST_DELTA;
    var steps = 0u;
    var side = 0.0;
    var prev_t = t0;
    var prev_e = 0.0;
    loop {
        if steps >= u.dims.z {
            break;
        }
        let p = o + d * t;
        // One call site of eval_tape (drivers inline it at each): sphere tracing asks for
        // the value alone (r = 0) and uses the global bound.
        var len = 0.0;
        if segment {
            len = min(t + delta, t1) - t;
        }
        var ev = eval_tape(p, p + d * (0.5 * len), 0.5 * len);
        if !segment {
            ev.y = u.trace.x;
        }
        let e = ev.x - T;
        steps += 1u;
        var s_now = -1.0;
        if e > 0.0 {
            s_now = 1.0;
        }
        if side == 0.0 {
            side = s_now;
        } else if s_now != side {
            let h = refine(o, d, prev_t, prev_e, t, e, 0.1 * (eps + cone * prev_t));
            return Hit(h.t, steps + h.steps);
        }
        if t >= t1 {
            break;
        }
        let tol = eps + cone * t;
        var s = 3.4e38;
        if ev.y > 0.0 {
            s = abs(e) / ev.y;
        }
        var step = s;
        if segment {
            if s >= len {
                step = len;
                delta = delta * u.trace.y;
            } else {
                delta = max(s, tol);
            }
        }
        prev_t = t;
        prev_e = e;
        t = min(t + max(step, tol), t1);
    }
    return Hit(MISS, steps);
}

fn normal_at(p: vec3<f32>) -> vec3<f32> {
    let h = u.trace.z;
    // A loop, so the tape is inlined once (same sum order as the CPU's fold).
    var g = vec3<f32>(0.0);
    for (var i = 0u; i < 4u; i += 1u) {
        var k = vec3<f32>(1.0, -1.0, -1.0);
        if i == 1u {
            k = vec3<f32>(-1.0, -1.0, 1.0);
        } else if i == 2u {
            k = vec3<f32>(-1.0, 1.0, -1.0);
        } else if i == 3u {
            k = vec3<f32>(1.0, 1.0, 1.0);
        }
        g += k * value(p + k * h);
    }
    g = g / (4.0 * h);
    let n = -g;
    let l = length(n);
    if l > 0.0 {
        return n / l;
    }
    return vec3<f32>(0.0, 0.0, 1.0);
}

fn smooth_step(a: f32, b: f32, x: f32) -> f32 {
    let v = clamp((x - a) / (b - a), 0.0, 1.0);
    return v * v * (3.0 - 2.0 * v);
}

fn sky(d: vec3<f32>) -> vec3<f32> {
    let k = sqrt(clamp(d.z, 0.0, 1.0));
    return mix(u.fog.xyz, u.sky.xyz * 0.9, k);
}

fn albedo(z: f32, n: vec3<f32>) -> vec3<f32> {
    let flat_ = smooth_step(u.fog.w, u.rock.w, n.z);
    let snowy = smooth_step(u.sky.w - u.ground.w, u.sky.w + u.ground.w, z);
    let top = mix(u.grass.xyz, u.snow.xyz, snowy);
    return mix(u.rock.xyz, top, flat_);
}

fn surface(p: vec3<f32>, n: vec3<f32>, t: f32, lit: f32) -> vec3<f32> {
    let diffuse = max(dot(n, u.sun.xyz), 0.0) * lit;
    let ambient = mix(u.ground.xyz, u.sky.xyz, 0.5 + 0.5 * n.z);
    let c = albedo(p.z, n) * (u.sun_color.xyz * diffuse + ambient);
    let k = 1.0 - exp(-t / u.sun_color.w);
    return mix(c, u.fog.xyz, k);
}

// Quantised to 1/4095 before encoding, like the CPU's gamma table (shade.rs::to_srgb8).
fn srgb8(c: vec3<f32>) -> u32 {
    let q = floor(clamp(c, vec3<f32>(0.0), vec3<f32>(1.0)) * GAMMA_STEPS + 0.5) / GAMMA_STEPS;
    let e = vec3<u32>(pow(q, vec3<f32>(1.0 / 2.2)) * 255.0 + 0.5);
    return e.x | (e.y << 8u) | (e.z << 16u) | (255u << 24u);
}

@compute @workgroup_size(8, 8, 1)
fn render(@builtin(global_invocation_id) id: vec3<u32>) {
    let w = u.dims.x;
    let h = u.dims.y;
    if id.x >= w || id.y >= h {
        return;
    }
    let at = id.x + id.y * w;
    let x = f32(id.x) + 0.5;
    let y = f32(id.y) + 0.5;
    let su = (2.0 * x / u.up.w - 1.0) * u.eye.w * u.right.w;
    let sv = (1.0 - 2.0 * y / u.forward.w) * u.eye.w;
    let o = u.eye.xyz;
    let d = normalize(u.forward.xyz + u.right.xyz * su + u.up.xyz * sv);
    let span = clip(o, d);
    var hit = Hit(MISS, 0u);
    if span.x <= span.y {
        hit = trace_ray(o, d, span.x, span.y);
    }
    out_steps[at] = hit.steps;
    out_depth[at] = hit.t;
    if hit.t == MISS {
        out_rgba[at] = srgb8(sky(d));
        return;
    }
    let p = o + d * hit.t;
    let n = normal_at(p);
    var lit = 1.0;
    if u.sun.w > 0.0 && dot(n, u.sun.xyz) > 0.0 {
        let tol = u.box_min.w + u.box_max.w * hit.t;
        let so = p + n * (2.0 * tol);
        let sspan = clip(so, u.sun.xyz);
        if sspan.x <= sspan.y && trace_ray(so, u.sun.xyz, sspan.x, sspan.y).t != MISS {
            lit = 0.0;
        }
    }
    out_rgba[at] = srgb8(surface(p, n, hit.t, lit));
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

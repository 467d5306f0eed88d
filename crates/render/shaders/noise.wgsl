// Seeded 3D simplex noise and fBm: the GPU twin of crates/core/src/field/noise.rs (same hash, same
// gradients, same corner order, f32, its constants from tape_consts.wgsl), and the noisy
// primitive and turbulence warp of the tape (crates/render/src/tape/noise.rs). An encoded fBm at `o` in
// `params` is FBM_*: [index, seed & 0xffff, seed >> 16, 1/λ, octaves, norm, Lipschitz].

// Gradient `n` of noise.rs GRADIENTS (the 12 cube-edge midpoints, `|g| = √2`; 12..15
// repeat 0, 9, 1 and 11), computed rather than indexed: pair of axes `n >> 2` (xy, xz,
// yz), signs from bits 0 and 1.
fn gradient_of(index: u32) -> vec3<f32> {
    var n = index;
    switch n {
        case 12u: { n = 0u; }
        case 13u: { n = 9u; }
        case 14u: { n = 1u; }
        case 15u: { n = 11u; }
        default: {}
    }
    let a = select(1.0, -1.0, (n & 1u) != 0u);
    let b = select(1.0, -1.0, (n & 2u) != 0u);
    switch n >> 2u {
        case 0u: { return vec3<f32>(a, b, 0.0); }
        case 1u: { return vec3<f32>(a, 0.0, b); }
        default: { return vec3<f32>(0.0, a, b); }
    }
}

// The "lowbias32" finaliser (noise.rs mix32); u32 arithmetic wraps in WGSL.
fn mix32(x: u32) -> u32 {
    var h = x;
    h ^= h >> 16u;
    h *= 0x7feb352du;
    h ^= h >> 15u;
    h *= 0x846ca68bu;
    return h ^ (h >> 16u);
}

fn lattice_gradient(seed: u32, i: i32, j: i32, k: i32) -> vec3<f32> {
    let h = mix32(seed ^ (bitcast<u32>(i) * 0x8da6b343u) ^ (bitcast<u32>(j) * 0xd8163841u) ^ (bitcast<u32>(k) * 0xcb1ab31fu));
    return gradient_of(h >> 28u);
}

// One corner's term (r² − |d|²)⁴ (g · d), 0 beyond the kernel.
fn corner(seed: u32, base: vec3<i32>, off: vec3<i32>, d0: vec3<f32>, c: f32) -> f32 {
    let d = d0 - vec3<f32>(off) + vec3<f32>(c * G3);
    let a = R2 - dot(d, d);
    if a <= 0.0 {
        return 0.0;
    }
    let v = base + off;
    let a2 = a * a;
    return a2 * a2 * dot(lattice_gradient(seed, v.x, v.y, v.z), d);
}

// Simplex noise n(p) in [-1, 1] (noise.rs simplex).
fn simplex(seed: u32, p: vec3<f32>) -> f32 {
    let s = (p.x + p.y + p.z) * F3;
    let i = floor(p.x + s);
    let j = floor(p.y + s);
    let k = floor(p.z + s);
    let t = (i + j + k) * G3;
    let d0 = p - vec3<f32>(i - t, j - t, k - t);
    var o1: vec3<i32>;
    var o2: vec3<i32>;
    if d0.x >= d0.y {
        if d0.y >= d0.z {
            o1 = vec3<i32>(1, 0, 0);
            o2 = vec3<i32>(1, 1, 0);
        } else if d0.x >= d0.z {
            o1 = vec3<i32>(1, 0, 0);
            o2 = vec3<i32>(1, 0, 1);
        } else {
            o1 = vec3<i32>(0, 0, 1);
            o2 = vec3<i32>(1, 0, 1);
        }
    } else if d0.y < d0.z {
        o1 = vec3<i32>(0, 0, 1);
        o2 = vec3<i32>(0, 1, 1);
    } else if d0.x < d0.z {
        o1 = vec3<i32>(0, 1, 0);
        o2 = vec3<i32>(0, 1, 1);
    } else {
        o1 = vec3<i32>(0, 1, 0);
        o2 = vec3<i32>(1, 1, 0);
    }
    let base = vec3<i32>(i32(i), i32(j), i32(k));
    var value = 0.0;
    value += corner(seed, base, vec3<i32>(0), d0, 0.0);
    value += corner(seed, base, o1, d0, 1.0);
    value += corner(seed, base, o2, d0, 2.0);
    value += corner(seed, base, vec3<i32>(1), d0, 3.0);
    return SIMPLEX_SCALE * value;
}

// fBm t(p) in [-1, 1] of the fBm encoded at `o` (noise.rs Fbm::value).
fn fbm(o: u32, p: vec3<f32>) -> f32 {
    let seed = u32(params[o + FBM_SEED_LO]) | (u32(params[o + FBM_SEED_HI]) << 16u);
    let octaves = u32(params[o + FBM_OCTAVES]);
    var q = p * params[o + FBM_INV_WAVELENGTH];
    var amp = 1.0;
    var value = 0.0;
    for (var k = 0u; k < octaves; k += 1u) {
        value += amp * simplex(seed + k * 0x9e3779b9u, q + f32(k) * OCTAVE_SHIFT);
        amp *= GAIN;
        q *= LACUNARITY;
    }
    return value * params[o + FBM_NORM];
}

// d̃ of a noisy primitive at `o` at a point whose projection `pr` on the shape is known,
// given t, the turbulence read at s + R·u (noise.rs noisy_distance): 0 inside, 1 beyond
// R + A.
fn noisy_d(o: u32, pr: Projection, t: f32) -> f32 {
    let r = params[o + NPRIM_RADIUS];
    let a = params[o + NPRIM_AMPLITUDE];
    let rho = max(pr.d, 0.0);
    if rho >= r + a {
        return 1.0;
    }
    if rho <= 0.0 {
        return 0.0;
    }
    return min(rho / (r + a * t), 1.0);
}

// The point s + R·(q − s)/ρ the turbulence of a noisy primitive is read at for q.
fn noise_point(o: u32, q: vec3<f32>, pr: Projection) -> vec3<f32> {
    return pr.at + (q - pr.at) * (params[o + NPRIM_RADIUS] / pr.d);
}

// (value at p, Lipschitz bound over B(c, rb)) of the noisy primitive at `o` from the
// projections of p and c (noise.rs noisy_primitive). Two fBm call sites (see project).
fn noisy_primitive(o: u32, p: vec3<f32>, pp: Projection, c: vec3<f32>, pc: Projection, rb: f32) -> vec2<f32> {
    let r = params[o + NPRIM_RADIUS];
    let e = params[o + NPRIM_ENERGY];
    let a = params[o + NPRIM_AMPLITUDE];
    let slope = params[o + NPRIM_SLOPE];
    let lt = params[o + NPRIM_FBM + FBM_LIPSCHITZ];
    let reach = r + a;
    var tp = 0.0;
    if pp.d > 0.0 && pp.d < reach {
        tp = fbm(o + NPRIM_FBM, noise_point(o, p, pp));
    }
    let dp = noisy_d(o, pp, tp);
    let v = e * wyvill(dp);
    let dc = max(pc.d, 0.0);
    let rho_lo = max(dc - rb, 0.0);
    let rho_hi = dc + rb;
    var den_lo = r - a;
    var den_hi = r + a;
    var x0 = rho_lo / den_hi;
    var x1 = rho_hi / den_lo;
    if rho_lo < reach {
        var tc = 0.0;
        if dc > 0.0 {
            tc = fbm(o + NPRIM_FBM, noise_point(o, c, pc));
        }
        let xc = noisy_d(o, pc, tc);
        if rho_lo > 0.0 {
            let spread = lt * (1.0 + r / rho_lo) * rb;
            den_lo = max(den_lo, r + a * (tc - spread));
            den_hi = min(den_hi, r + a * (tc + spread));
            x0 = min(rho_lo / den_hi, rho_hi / den_lo);
            x1 = max(rho_lo / den_hi, rho_hi / den_lo);
        }
        let lo = max(x0, xc - rb * slope);
        let hi = min(x1, xc + rb * slope);
        if lo <= hi {
            x0 = lo;
            x1 = hi;
        }
    }
    x0 = clamp(x0, 0.0, 1.0);
    x1 = clamp(x1, 0.0, 1.0);
    let dt = (1.0 + a * lt * (min(x1, 1.0) + r / den_lo)) / den_lo;
    return vec2<f32>(v, abs(e) * wyvill_slope(x0, x1) * dt);
}

// ω⁻¹(p) of the turbulence warp at `o` (warp.rs Warp::apply).
fn twarp_apply(o: u32, p: vec3<f32>) -> vec3<f32> {
    var fd = 1.0;
    if params[o + TWARP_HAS_REGION] != 0.0 {
        let q = clamp(p, param3(o + TWARP_REGION_MIN), param3(o + TWARP_REGION_MAX));
        let d = length(p - q);
        if d != 0.0 {
            fd = wyvill(d / params[o + TWARP_FALLOFF]);
        }
    }
    if fd == 0.0 {
        return p;
    }
    // One fBm call site in a loop over the axes (see project).
    var t = vec3<f32>(0.0);
    for (var k = 0u; k < 3u; k += 1u) {
        t[k] = fbm(o + TWARP_TURBULENCE + k * FBM_LEN, p);
    }
    return p + t * (params[o + TWARP_AMPLITUDE] * fd);
}

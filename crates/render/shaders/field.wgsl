// The field tape evaluator: the GPU twin of `Tape::eval` in crates/render/src/tape/interpreter.rs.
// One pass at (p, c, r) returns vec2(f(p), Lipschitz bound of f over the ball B(c, r)).
// The op codes, flags, limits and parameter offsets come from tape_consts.wgsl, generated
// from crates/render/src/tape/format.rs; the `USE_*` overrides there say which parts of this evaluator
// a pipeline keeps (crates/render/src/tape/features.rs).

// x = op, y = flags, z = jump, w = param offset.
@group(0) @binding(1) var<storage, read> instrs: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> params: array<f32>;
@group(0) @binding(3) var<storage, read> heights: array<f32>;

fn wyvill(x: f32) -> f32 {
    if x >= 1.0 {
        return 0.0;
    }
    let s = 1.0 - x * x;
    return s * s * s;
}

fn wyvill_d(x: f32) -> f32 {
    if x >= 1.0 {
        return 0.0;
    }
    let s = 1.0 - x * x;
    return -6.0 * x * s * s;
}

// max |g'| over [lo, hi] (both clamped at 0).
fn wyvill_slope(lo_in: f32, hi_in: f32) -> f32 {
    let a = max(lo_in, 0.0);
    let b = max(hi_in, 0.0);
    if a >= 1.0 {
        return 0.0;
    }
    if a <= WYVILL_PEAK_X && WYVILL_PEAK_X <= b {
        return WYVILL_MAX_SLOPE;
    }
    return max(abs(wyvill_d(a)), abs(wyvill_d(min(b, 1.0))));
}

fn sigma(x: f32, r: f32) -> f32 {
    let u = clamp(x / r, -1.0, 1.0);
    return clamp(ISO * (1.0 + 1.5 * u - 0.5 * u * u * u), 0.0, 2.0 * ISO);
}

// max σ' over [lo, hi]: the slope is largest where |x| is smallest.
fn sigma_slope(lo: f32, hi: f32, r: f32) -> f32 {
    var nearest = 0.0;
    if !(lo <= 0.0 && 0.0 <= hi) {
        nearest = min(abs(lo), abs(hi));
    }
    let u = clamp(nearest / r, -1.0, 1.0);
    return 1.5 * ISO / r * (1.0 - u * u);
}

fn param3(o: u32) -> vec3<f32> {
    return vec3<f32>(params[o], params[o + 1u], params[o + 2u]);
}

// The closest point of a solid cone or ellipsoid and the distance to it (0 inside).
struct Projection {
    at: vec3<f32>,
    d: f32,
}

// Cone (CONE_*; shape.rs cone_projection): the closest point of the triangle (0, 0),
// (r, 0), (0, h) in the half-plane (ρ, z) through the axis.
fn cone_projection(o: u32, p: vec3<f32>) -> Projection {
    let base = param3(o + CONE_BASE);
    let axis = param3(o + CONE_AXIS);
    let h = params[o + CONE_HEIGHT];
    let r = params[o + CONE_RADIUS];
    let w = p - base;
    let z = dot(w, axis);
    let radial = w - axis * z;
    let rho = length(radial);
    if z >= 0.0 && rho * h + z * r <= r * h {
        return Projection(p, 0.0);
    }
    let x = vec2<f32>(rho, z);
    let base_at = vec2<f32>(clamp(rho, 0.0, r), 0.0);
    let d = vec2<f32>(-r, h);
    let tau = dot(x - vec2<f32>(r, 0.0), d) / dot(d, d);
    let slant_at = vec2<f32>(r, 0.0) + d * clamp(tau, 0.0, 1.0);
    let db = dot(x - base_at, x - base_at);
    let ds = dot(x - slant_at, x - slant_at);
    var at = slant_at;
    var d2 = ds;
    if db <= ds {
        at = base_at;
        d2 = db;
    }
    var er = vec3<f32>(0.0);
    if rho > 0.0 {
        er = radial / rho;
    }
    return Projection(base + axis * at.y + er * at.x, sqrt(d2));
}

// Axis-aligned ellipsoid (ELLIPSOID_*; shape.rs ellipsoid_projection): Newton on
// F(t) = Σ (eᵢyᵢ/(t + eᵢ²))² − 1 from the lower bound ‖e∘y‖ − e²_max of its root.
fn ellipsoid_projection(o: u32, p: vec3<f32>) -> Projection {
    let c = param3(o + ELLIPSOID_CENTER);
    let e = param3(o + ELLIPSOID_RADII);
    let y = p - c;
    let ye = y / e;
    if dot(ye, ye) <= 1.0 {
        return Projection(p, 0.0);
    }
    let e2 = e * e;
    let ey = e * y;
    let emax = max(e2.x, max(e2.y, e2.z));
    var t = max(length(ey) - emax, 0.0);
    for (var k = 0u; k < ELLIPSOID_NEWTON; k += 1u) {
        let inv = 1.0 / (vec3<f32>(t) + e2);
        let q = ey * inv;
        let f = dot(q, q) - 1.0;
        if f <= 0.0 {
            break;
        }
        let qqi = q * q * inv;
        let df = -2.0 * (qqi.x + qqi.y + qqi.z);
        let step = -f / df;
        t += step;
        if step <= 1e-6 * (t + emax) {
            break;
        }
    }
    let den = vec3<f32>(t) + e2;
    return Projection(c + e2 * y / den, length(y * t / den));
}

// The closest point of the shape `kind` at `o` to `p` and the signed distance to it
// (shape.rs project). Called at two sites only (p and c in eval_tape): every call site
// inlines the ellipsoid's Newton loop, and on lavapipe every loop on the way costs
// iterations of the invocation's shared loop budget, taken or not.
fn project(kind: u32, o: u32, p: vec3<f32>) -> Projection {
    switch kind {
        case SHAPE_SPHERE: {
            let c = param3(o + SPHERE_CENTER);
            let w = p - c;
            let d = length(w);
            let rho = params[o + SPHERE_RADIUS];
            var at = p;
            if d > rho {
                at = c + w * (rho / d);
            }
            return Projection(at, d - rho);
        }
        case SHAPE_CAPSULE: {
            let a = param3(o + CAPSULE_A);
            let ab = param3(o + CAPSULE_B) - a;
            let ap = p - a;
            let l2 = dot(ab, ab);
            var h = 0.0;
            if l2 > 0.0 {
                h = clamp(dot(ap, ab) / l2, 0.0, 1.0);
            }
            let s = a + ab * h;
            let w = ap - ab * h;
            let d = length(w);
            let rho = params[o + CAPSULE_RADIUS];
            var at = p;
            if d > rho {
                at = s + (p - s) * (rho / d);
            }
            return Projection(at, d - rho);
        }
        case SHAPE_BOX: {
            let c = param3(o + CUBOID_CENTER);
            let half = param3(o + CUBOID_HALF);
            let d = abs(p - c) - half;
            let sd = length(max(d, vec3<f32>(0.0))) + min(max(d.x, max(d.y, d.z)), 0.0);
            return Projection(c + clamp(p - c, -half, half), sd);
        }
        case SHAPE_CONE: {
            if USE_CONE {
                return cone_projection(o, p);
            }
            return Projection(p, 0.0);
        }
        case SHAPE_ELLIPSOID: {
            if USE_ELLIPSOID {
                return ellipsoid_projection(o, p);
            }
            return Projection(p, 0.0);
        }
        default: {
            // SHAPE_PRISM: a heightfield's prism, the largest horizontal excess over
            // [lo, hi] combined with the vertical one; inside, minus the depth below the
            // nearest face (shape.rs project; no closest point: never noisy).
            let lo = param3(o + PRISM_MIN);
            let hi = param3(o + PRISM_MAX);
            let e = max(lo - p, p - hi);
            let dxy = max(max(e.x, e.y), 0.0);
            let dz = max(e.z, 0.0);
            let inside = min(max(max(e.x, e.y), e.z), 0.0);
            return Projection(p, sqrt(dxy * dxy + dz * dz) + inside);
        }
    }
}

// A primitive at `o` from the signed distances of p and of the ball's centre c.
fn primitive(flags: u32, o: u32, sd_p: f32, sd_c: f32, r: f32) -> vec2<f32> {
    let rad = params[o + PRIM_RADIUS];
    let energy = params[o + PRIM_ENERGY];
    if (flags & FLAG_SIGMA) != 0u {
        return vec2<f32>(sigma(-sd_p, rad), sigma_slope(-sd_c - r, -sd_c + r, rad));
    }
    let v = energy * wyvill(max(sd_p, 0.0) / rad);
    let l = abs(energy) / rad * wyvill_slope(max(sd_c - r, 0.0) / rad, max(sd_c + r, 0.0) / rad);
    return vec2<f32>(v, l);
}

// The grid cell holding (x, y) of the heightfield at `o` (grid.rs Heightfield::sample):
// its lower corner (i, j), the fractions within it, the grid's size and the samples'
// offset in `heights`.
struct Cell {
    i: i32,
    j: i32,
    fx: f32,
    fy: f32,
    w: i32,
    h: i32,
    off: u32,
}

fn grid_cell(o: u32, x: f32, y: f32) -> Cell {
    let ox = params[o + HEIGHT_ORIGIN];
    let oy = params[o + HEIGHT_ORIGIN + 1u];
    let cell = params[o + HEIGHT_CELL];
    let nx = params[o + HEIGHT_NX];
    let ny = params[o + HEIGHT_NY];
    let gx = clamp((x - ox) / cell, 0.0, nx - 1.0);
    let gy = clamp((y - oy) / cell, 0.0, ny - 1.0);
    let fi = min(floor(gx), nx - 2.0);
    let fj = min(floor(gy), ny - 2.0);
    return Cell(i32(fi), i32(fj), gx - fi, gy - fj, i32(nx), i32(ny), u32(params[o + HEIGHT_OFFSET]));
}

fn bilinear(o: u32, x: f32, y: f32) -> f32 {
    return bilinear_at(o, u32(params[o + HEIGHT_OFFSET]), x, y);
}

// Bilinear value at (x, y) of the samples at `off` in `heights` on the grid of the
// heightfield at `o` (its elevations, or its detail's roughness).
fn bilinear_at(o: u32, off: u32, x: f32, y: f32) -> f32 {
    let c = grid_cell(o, x, y);
    let w = u32(c.w);
    let k = off + u32(c.i) + w * u32(c.j);
    let z00 = heights[k];
    let z10 = heights[k + 1u];
    let z01 = heights[k + w];
    let z11 = heights[k + w + 1u];
    let bottom = z00 + (z10 - z00) * c.fx;
    let top = z01 + (z11 - z01) * c.fx;
    return bottom + (top - bottom) * c.fy;
}

// Catmull-Rom weights of samples -1..=2 at t (crates/dem/src/dem/interp.rs cr_weights).
fn cr_weights(t: f32) -> vec4<f32> {
    let t2 = t * t;
    let t3 = t2 * t;
    return vec4<f32>(
        0.5 * (-t3 + 2.0 * t2 - t),
        0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
        0.5 * (-3.0 * t3 + 4.0 * t2 + t),
        0.5 * (t3 - t2),
    );
}

// One row of the bicubic stencil: Σ wx[a]·z[i + a − 1, jj], indices clamped, summed in
// order (no loop: see project).
fn cr_row(base: u32, i: i32, w: i32, wx: vec4<f32>) -> f32 {
    var row = 0.0;
    row += wx.x * heights[base + u32(clamp(i - 1, 0, w - 1))];
    row += wx.y * heights[base + u32(clamp(i, 0, w - 1))];
    row += wx.z * heights[base + u32(clamp(i + 1, 0, w - 1))];
    row += wx.w * heights[base + u32(clamp(i + 2, 0, w - 1))];
    return row;
}

// Bicubic elevation (height.rs bicubic, grid.rs Heightfield::sample): the cell of bilinear,
// its 4 × 4 stencil with indices clamped to the grid, rows summed first.
fn bicubic(o: u32, x: f32, y: f32) -> f32 {
    let c = grid_cell(o, x, y);
    let wx = cr_weights(c.fx);
    let wy = cr_weights(c.fy);
    var v = 0.0;
    v += wy.x * cr_row(c.off + u32(c.w * clamp(c.j - 1, 0, c.h - 1)), c.i, c.w, wx);
    v += wy.y * cr_row(c.off + u32(c.w * clamp(c.j, 0, c.h - 1)), c.i, c.w, wx);
    v += wy.z * cr_row(c.off + u32(c.w * clamp(c.j + 1, 0, c.h - 1)), c.i, c.w, wx);
    v += wy.w * cr_row(c.off + u32(c.w * clamp(c.j + 2, 0, c.h - 1)), c.i, c.w, wx);
    return v;
}

fn elevation(flags: u32, o: u32, x: f32, y: f32) -> f32 {
    if USE_BICUBIC && (flags & FLAG_BICUBIC) != 0u {
        return bicubic(o, x, y);
    }
    return bilinear(o, x, y);
}

// The highest bit where a and b differ (0 when they are equal).
fn high_bit(a: u32, b: u32) -> u32 {
    let x = a ^ b;
    return select(firstLeadingBit(x), 0u, x == 0u);
}

// A bound of |∇h| over the disc B(c, r) from the heightfield's slope pyramid (height.rs
// slope_under): the cells under the disc's square lie in at most 2 × 2 blocks of level k.
fn slope_under(o: u32, c: vec3<f32>, r: f32) -> f32 {
    let lo = grid_cell(o, c.x - r, c.y - r);
    let hi = grid_cell(o, c.x + r, c.y + r);
    let i0 = u32(lo.i);
    let i1 = u32(hi.i);
    let j0 = u32(lo.j);
    let j1 = u32(hi.j);
    let levels = u32(params[o + HEIGHT_LEVELS]);
    let k = min(max(high_bit(i0, i1), high_bit(j0, j1)), levels - 1u);
    let w = (u32(lo.w) - 1u + (1u << k) - 1u) >> k;
    let at = u32(params[o + HEIGHT_PYRAMID + k]);
    let a = heights[at + (i0 >> k) + w * (j0 >> k)];
    let b = heights[at + (i1 >> k) + w * (j0 >> k)];
    let d = heights[at + (i0 >> k) + w * (j1 >> k)];
    let e = heights[at + (i1 >> k) + w * (j1 >> k)];
    return max(max(a, b), max(d, e));
}

// The detail A·m(x, y)·t(p) of the heightfield at `o` (height.rs eval).
fn height_detail(o: u32, p: vec3<f32>) -> f32 {
    let m = bilinear_at(o, u32(params[o + HEIGHT_DETAIL_ROUGH]), p.x, p.y);
    return params[o + HEIGHT_DETAIL_AMPLITUDE] * m * fbm(o + HEIGHT_DETAIL_FBM, p);
}

fn heightfield(flags: u32, o: u32, p: vec3<f32>, c: vec3<f32>, r: f32) -> vec2<f32> {
    let fall = params[o + HEIGHT_FALLOFF];
    let slope = slope_under(o, c, r);
    var hp = elevation(flags, o, p.x, p.y);
    let hc = elevation(flags, o, c.x, c.y);
    var lo = hc - slope * r - c.z - r;
    var hi = hc + slope * r - c.z + r;
    var l = sqrt(1.0 + slope * slope);
    if USE_HEIGHT_DETAIL && (flags & FLAG_DETAIL) != 0u {
        let a = params[o + HEIGHT_DETAIL_AMPLITUDE];
        let ld = params[o + HEIGHT_DETAIL_SLOPE];
        let dp = height_detail(o, p);
        var dc = dp;
        if any(p != c) {
            dc = height_detail(o, c);
        }
        hp += dp;
        lo += max(dc - ld * r, -a);
        hi += min(dc + ld * r, a);
        l += ld;
    }
    let value = sigma(hp - p.z, fall);
    return vec2<f32>(value, sigma_slope(lo, hi, fall) * l);
}

// M⁻¹p of the warp at `o`: WARP_MATRIX holds 3 rows of 4.
fn affine(o: u32, p: vec3<f32>) -> vec3<f32> {
    let m = o + WARP_MATRIX;
    return vec3<f32>(
        params[m] * p.x + params[m + 1u] * p.y + params[m + 2u] * p.z + params[m + 3u],
        params[m + 4u] * p.x + params[m + 5u] * p.y + params[m + 6u] * p.z + params[m + 7u],
        params[m + 8u] * p.x + params[m + 9u] * p.y + params[m + 10u] * p.z + params[m + 11u],
    );
}

fn box_distance(lo: vec3<f32>, hi: vec3<f32>, q: vec3<f32>) -> f32 {
    return length(q - clamp(q, lo, hi));
}

// (f(p), Lipschitz bound of f over the ball B(c, r)).
// The depth of `q` in the box `[lo, hi]`: the distance to its nearest face, negative
// outside (`Transition::depth`).
fn face_depth(lo: vec3<f32>, hi: vec3<f32>, q: vec3<f32>) -> f32 {
    let d = min(q - lo, hi - q);
    return min(d.x, min(d.y, d.z));
}

// The replace weight at depth `d` (`Transition::ramp`).
fn replace_ramp(d: f32, width: f32) -> f32 {
    if d <= 0.0 {
        return 0.0;
    }
    return 1.0 - wyvill(d / width);
}

// `REPLACE` of the entries `a` (the base) and `b` (`interpreter::replace`).
fn replace(o: u32, a: vec2<f32>, b: vec2<f32>, p: vec3<f32>, c: vec3<f32>, r: f32) -> vec2<f32> {
    let lo = param3(o + REPLACE_MIN);
    let hi = param3(o + REPLACE_MAX);
    let width = params[o + REPLACE_WIDTH];
    let value = a.x + replace_ramp(face_depth(lo, hi, p), width) * (b.x - a.x);
    let dc = face_depth(lo, hi, c);
    var bound = a.y;
    if replace_ramp(dc - r, width) >= 1.0 {
        bound = b.y;
    } else if replace_ramp(dc + r, width) > 0.0 {
        let gap = min(abs(b.x - a.x) + (a.y + b.y) * (distance(p, c) + r), params[o + REPLACE_GAP]);
        bound = max(a.y, b.y) + gap * (WYVILL_MAX_SLOPE / width);
    }
    return vec2<f32>(value, bound);
}

fn eval_tape(p_in: vec3<f32>, c_in: vec3<f32>, r_in: f32) -> vec2<f32> {
    var stack: array<vec2<f32>, MAX_STACK>;
    var sp = 0u;
    var frames: array<vec4<f32>, WARP_FRAMES>; // two per warp: (p, r) and (c, 0)
    var fp = 0u;
    var p = p_in;
    var c = c_in;
    var r = r_in;
    var pc = 0u;
    let n = arrayLength(&instrs);
    loop {
        if pc >= n {
            break;
        }
        let ins = instrs[pc];
        let o = ins.w;
        switch ins.x {
            case OP_CONST: {
                stack[sp] = vec2<f32>(params[o + CONST_VALUE], 0.0);
                sp += 1u;
            }
            case OP_PRIM, OP_NPRIM: {
                var shape_at = o + PRIM_SHAPE;
                if ins.x == OP_NPRIM {
                    shape_at = o + NPRIM_SHAPE;
                }
                let kind = ins.y & FLAG_SHAPE_MASK;
                let pp = project(kind, shape_at, p);
                let pc = project(kind, shape_at, c);
                if ins.x == OP_PRIM {
                    stack[sp] = primitive(ins.y, o, pp.d, pc.d, r);
                } else if USE_NPRIM {
                    stack[sp] = noisy_primitive(o, p, pp, c, pc, r);
                }
                sp += 1u;
            }
            case OP_SFIELD: {
                if USE_SFIELD {
                    stack[sp] = sfield(o, p, c, r);
                }
                sp += 1u;
            }
            case OP_HEIGHT: {
                if USE_HEIGHT {
                    stack[sp] = heightfield(ins.y, o, p, c, r);
                }
                sp += 1u;
            }
            case OP_BLEND, OP_UNION, OP_INTER, OP_DIFF: {
                let b = stack[sp - 1u];
                let a = stack[sp - 2u];
                sp -= 1u;
                var v: vec2<f32>;
                if ins.x == OP_BLEND {
                    v = a + b;
                } else if ins.x == OP_UNION {
                    v = vec2<f32>(max(a.x, b.x), max(a.y, b.y));
                } else if ins.x == OP_INTER {
                    v = vec2<f32>(min(a.x, b.x), max(a.y, b.y));
                } else {
                    v = vec2<f32>(min(a.x, 2.0 * ISO - b.x), max(a.y, b.y));
                }
                stack[sp - 1u] = v;
            }
            case OP_REPLACE: {
                let b = stack[sp - 1u];
                let a = stack[sp - 2u];
                sp -= 1u;
                stack[sp - 1u] = replace(o, a, b, p, c, r);
            }
            case OP_GUARD: {
                let lo = param3(o + GUARD_MIN);
                let hi = param3(o + GUARD_MAX);
                let inside = all(lo <= p) && all(p <= hi);
                if !inside && box_distance(lo, hi, c) > r {
                    stack[sp] = vec2<f32>(0.0, 0.0);
                    sp += 1u;
                    pc = ins.z - 1u; // the jump target, after the `pc += 1u` below

                }
            }
            case OP_WARP: {
                frames[2u * fp] = vec4<f32>(p, r);
                frames[2u * fp + 1u] = vec4<f32>(c, 0.0);
                fp += 1u;
                p = affine(o, p);
                c = affine(o, c);
                r *= params[o + WARP_NORM];
            }
            case OP_TWARP: {
                frames[2u * fp] = vec4<f32>(p, r);
                frames[2u * fp + 1u] = vec4<f32>(c, 0.0);
                fp += 1u;
                if USE_TWARP {
                    p = twarp_apply(o, p);
                }
                r += params[o + TWARP_REACH];
            }
            case OP_UNWARP: {
                fp -= 1u;
                p = frames[2u * fp].xyz;
                r = frames[2u * fp].w;
                c = frames[2u * fp + 1u].xyz;
                stack[sp - 1u].y *= params[o + UNWARP_SCALE];
            }
            default: {}
        }
        pc += 1u;
    }
    return stack[0];
}

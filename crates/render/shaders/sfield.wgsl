// S-field leaves: the GPU twin of SField::value (crates/volume/src/voxel/sfield.rs, sparse.rs locate and
// trilinear, tricubic.rs blend) and of the ball bound of crates/render/src/tape/sfield.rs, on the
// buffers laid out there. Parameters at `o` (SF_*): domain min, max, R, R_f, ±1, noisy,
// levels, L_S', tricubic, weights offset, fbm, then from SF_HEAD one block of SF_LEVEL_LEN
// per level (SF_LEVEL_*): origin, h, dims, offsets of its table, S, α, β.

@group(0) @binding(11) var<storage, read> sf_table: array<u32>;
@group(0) @binding(12) var<storage, read> sf_data: array<f32>;

// What S' reads where no level is complete.
const SF_BIG: f32 = 3.4028235e38;

// Data index of node `g` of the level at `lv` (sparse.rs Bricks::node), SF_NONE when its
// brick is missing.
fn sf_node(lv: u32, g: vec3<i32>) -> u32 {
    let dims = vec3<i32>(param3(lv + SF_LEVEL_DIMS));
    let bd = (dims + vec3<i32>(SF_BRICK - 1)) / SF_BRICK;
    let b = g >> vec3<u32>(SF_BRICK_BITS);
    if any(b < vec3<i32>(0)) || any(b >= bd) {
        return SF_NONE;
    }
    let k = sf_table[u32(params[lv + SF_LEVEL_TABLE]) + u32(b.x + bd.x * (b.y + bd.y * b.z))];
    if k == SF_NONE {
        return SF_NONE;
    }
    let l = g & vec3<i32>(SF_BRICK - 1);
    return k * SF_BRICK_NODES + u32(l.x + SF_BRICK * (l.y + SF_BRICK * l.z));
}

// Trilinear interpolation of the channel at `at` (sparse.rs trilinear_grad's value).
fn sf_trilinear(at: u32, idx: array<u32, 8>, f: vec3<f32>) -> f32 {
    let c00 = sf_data[at + idx[0]] + (sf_data[at + idx[1]] - sf_data[at + idx[0]]) * f.x;
    let c10 = sf_data[at + idx[2]] + (sf_data[at + idx[3]] - sf_data[at + idx[2]]) * f.x;
    let c01 = sf_data[at + idx[4]] + (sf_data[at + idx[5]] - sf_data[at + idx[4]]) * f.x;
    let c11 = sf_data[at + idx[6]] + (sf_data[at + idx[7]] - sf_data[at + idx[6]]) * f.x;
    let c0 = c00 + (c10 - c00) * f.y;
    let c1 = c01 + (c11 - c01) * f.y;
    return c0 + (c1 - c0) * f.z;
}

// One row of the tricubic stencil at (y, z) = (gy, gz) from x = cx − 1, clamped to the
// level (tricubic.rs stencil), weighted by wx; SF_BIG when a node is missing.
fn sf_cubic_row(lv: u32, at: u32, cx: i32, gy: i32, gz: i32, wx: vec4<f32>) -> f32 {
    let dmax = i32(params[lv + SF_LEVEL_DIMS]) - 1;
    let n0 = sf_node(lv, vec3<i32>(clamp(cx - 1, 0, dmax), gy, gz));
    let n1 = sf_node(lv, vec3<i32>(clamp(cx, 0, dmax), gy, gz));
    let n2 = sf_node(lv, vec3<i32>(clamp(cx + 1, 0, dmax), gy, gz));
    let n3 = sf_node(lv, vec3<i32>(clamp(cx + 2, 0, dmax), gy, gz));
    if n0 == SF_NONE || n1 == SF_NONE || n2 == SF_NONE || n3 == SF_NONE {
        return SF_BIG;
    }
    var row = 0.0;
    row += wx.x * sf_data[at + n0];
    row += wx.y * sf_data[at + n1];
    row += wx.z * sf_data[at + n2];
    row += wx.w * sf_data[at + n3];
    return row;
}

// S'(q) of the leaf at `o`, q clamped to the domain (SField::s_value): the finest level
// whose cell around q is complete, trilinear, blended with the tricubic stencil on the
// finest level, minus the displacement; SF_BIG when no level is complete there.
fn sf_s(o: u32, q_in: vec3<f32>) -> f32 {
    let q = clamp(q_in, param3(o + SF_MIN), param3(o + SF_MAX));
    let levels = u32(params[o + SF_LEVELS]);
    var level = levels;
    var lv = 0u;
    var idx: array<u32, 8>;
    var f = vec3<f32>(0.0);
    var cell = vec3<i32>(0);
    for (var l = levels; l > 0u; l -= 1u) {
        lv = o + SF_HEAD + (l - 1u) * SF_LEVEL_LEN;
        let dims = vec3<i32>(param3(lv + SF_LEVEL_DIMS));
        let g = clamp((q - param3(lv + SF_LEVEL_ORIGIN)) / params[lv + SF_LEVEL_H], vec3<f32>(0.0), vec3<f32>(dims - vec3<i32>(1)));
        cell = min(vec3<i32>(floor(g)), dims - vec3<i32>(2));
        f = g - vec3<f32>(cell);
        idx[0] = sf_node(lv, cell);
        idx[1] = sf_node(lv, cell + vec3<i32>(1, 0, 0));
        idx[2] = sf_node(lv, cell + vec3<i32>(0, 1, 0));
        idx[3] = sf_node(lv, cell + vec3<i32>(1, 1, 0));
        idx[4] = sf_node(lv, cell + vec3<i32>(0, 0, 1));
        idx[5] = sf_node(lv, cell + vec3<i32>(1, 0, 1));
        idx[6] = sf_node(lv, cell + vec3<i32>(0, 1, 1));
        idx[7] = sf_node(lv, cell + vec3<i32>(1, 1, 1));
        if idx[0] != SF_NONE && idx[1] != SF_NONE && idx[2] != SF_NONE && idx[3] != SF_NONE
            && idx[4] != SF_NONE && idx[5] != SF_NONE && idx[6] != SF_NONE && idx[7] != SF_NONE {
            level = l - 1u;
            break;
        }
    }
    if level == levels {
        return SF_BIG;
    }
    let s_at = u32(params[lv + SF_LEVEL_S]);
    var s = sf_trilinear(s_at, idx, f);
    if USE_SF_CUBIC && params[o + SF_TRICUBIC] != 0.0 && level + 1u == levels {
        // The blend L + w·(C − L) (tricubic.rs Cubic::eval), where a corner's weight (0 or
        // 1) is set.
        let w_at = u32(params[o + SF_WEIGHTS]);
        let w0 = sf_data[w_at + idx[0]] + sf_data[w_at + idx[1]] + sf_data[w_at + idx[2]] + sf_data[w_at + idx[3]];
        let w1 = sf_data[w_at + idx[4]] + sf_data[w_at + idx[5]] + sf_data[w_at + idx[6]] + sf_data[w_at + idx[7]];
        if w0 + w1 != 0.0 {
            let wx = cr_weights(f.x);
            let wy = cr_weights(f.y);
            let wz = cr_weights(f.z);
            let dims = vec3<i32>(param3(lv + SF_LEVEL_DIMS));
            var val = 0.0;
            var plane = 0.0;
            var complete = true;
            for (var r = 0; r < 16; r += 1) {
                let j = r & 3;
                let k = r >> 2u;
                let gy = clamp(cell.y + j - 1, 0, dims.y - 1);
                let gz = clamp(cell.z + k - 1, 0, dims.z - 1);
                let row = sf_cubic_row(lv, s_at, cell.x, gy, gz, wx);
                complete = complete && row != SF_BIG;
                plane += wy[j] * row;
                if j == 3 {
                    val += wz[k] * plane;
                    plane = 0.0;
                }
            }
            if complete {
                s += sf_trilinear(w_at, idx, f) * (val - s);
            }
        }
    }
    if USE_SF_NOISE && params[o + SF_NOISY] != 0.0 {
        let a = sf_trilinear(u32(params[lv + SF_LEVEL_ALPHA]), idx, f);
        let b = sf_trilinear(u32(params[lv + SF_LEVEL_BETA]), idx, f);
        s -= a * fbm(o + SF_FBM, (q - param3(o + SF_MIN)) * b);
    }
    return s;
}

// (f(p), Lipschitz bound over B(c, r)) of the S-field leaf at `o` (sfield.rs eval and
// bound): S' read at p and at c through one call site.
fn sfield(o: u32, p: vec3<f32>, c: vec3<f32>, r: f32) -> vec2<f32> {
    let lo = param3(o + SF_MIN);
    let hi = param3(o + SF_MAX);
    let inside = all(lo <= p) && all(p <= hi);
    let bmin = c - vec3<f32>(r);
    let bmax = c + vec3<f32>(r);
    let overlaps = all(bmin <= hi) && all(lo <= bmax);
    var s_at = vec2<f32>(SF_BIG);
    for (var k = 0u; k < 2u; k += 1u) {
        var q = p;
        var needed = inside;
        if k == 1u {
            q = c;
            needed = overlaps;
        }
        if needed {
            s_at[k] = sf_s(o, q);
        }
    }
    let trans = params[o + SF_TRANSITION];
    let fall = params[o + SF_FALLOFF];
    let sign = params[o + SF_SIGN];
    var v = 0.0;
    if inside {
        let e = min(p - lo, hi - p);
        let d = max(min(e.x, min(e.y, e.z)), 0.0);
        v = min(sigma(sign * s_at.x, trans), 2.0 * ISO * (1.0 - wyvill(d / fall)));
    }
    if !overlaps {
        return vec2<f32>(v, 0.0);
    }
    let ls = params[o + SF_S_LIPSCHITZ];
    let x = sign * s_at.y;
    let sig = sigma_slope(x - ls * r, x + ls * r, trans) * ls;
    let cmin = max(bmin, lo);
    let cmax = min(bmax, hi);
    let dl = min(cmin - lo, hi - cmax);
    let dh = min(cmax - lo, hi - cmin);
    let d_lo = max(min(dl.x, min(dl.y, dl.z)), 0.0);
    let d_hi = max(min(dh.x, min(dh.y, dh.z)), 0.0);
    let face = 2.0 * ISO * wyvill_slope(d_lo / fall, d_hi / fall) / fall;
    return vec2<f32>(v, max(sig, face));
}

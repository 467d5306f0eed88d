//! A picture of a mesh's triangles: an OBJ written by `karstic build` drawn in parallel
//! projection from the south-east and above, each triangle flat-shaded with its edges
//! darkened, hidden faces removed with a depth buffer.

use std::path::Path;

use glam::Vec3;
use image::{Rgb, RgbImage};

/// Background.
const SKY: Rgb<u8> = Rgb([206, 221, 236]);

/// Edge half-width, in pixels.
const EDGE: f32 = 0.7;

/// The triangles of the OBJ file at `path` drawn into a `w × h` picture.
pub fn mesh_picture(path: &Path, w: u32, h: u32) -> RgbImage {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let (positions, faces) = read_obj(&text);
    let forward = Vec3::new(-1.0, 1.0, -0.8).normalize();
    let right = forward.cross(Vec3::Z).normalize();
    let up = right.cross(forward);
    let light = Vec3::new(0.4, -0.5, 0.8).normalize();
    let view: Vec<Vec3> = positions
        .iter()
        .map(|p| Vec3::new(p.dot(right), p.dot(up), p.dot(forward)))
        .collect();
    let (lo, hi) = view.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), v| (lo.min(*v), hi.max(*v)),
    );
    let (wf, hf) = (w as f32, h as f32);
    let scale = 0.9 * (wf / (hi.x - lo.x)).min(hf / (hi.y - lo.y));
    let centre = (lo + hi) / 2.0;
    let screen: Vec<Vec3> = view
        .iter()
        .map(|v| {
            Vec3::new(
                wf / 2.0 + (v.x - centre.x) * scale,
                hf / 2.0 - (v.y - centre.y) * scale,
                v.z,
            )
        })
        .collect();
    let mut img = RgbImage::from_pixel(w, h, SKY);
    let mut depth = vec![f32::MAX; (w * h) as usize];
    for f in &faces {
        let [a, b, c] = f.map(|i| screen[i]);
        let n = (positions[f[1]] - positions[f[0]]).cross(positions[f[2]] - positions[f[0]]);
        let n = if n.dot(forward) > 0.0 { -n } else { n }.normalize_or_zero();
        let shade = 0.35 + 0.65 * n.dot(light).max(0.0);
        let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        if area.abs() < 1e-9 {
            continue;
        }
        let x0 = a.x.min(b.x).min(c.x).floor().max(0.0) as u32;
        let x1 = (a.x.max(b.x).max(c.x).ceil() as u32).min(w - 1);
        let y0 = a.y.min(b.y).min(c.y).floor().max(0.0) as u32;
        let y1 = (a.y.max(b.y).max(c.y).ceil() as u32).min(h - 1);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let p = (x as f32 + 0.5, y as f32 + 0.5);
                // Signed distances to the three edges, in pixels, inside positive.
                let dist = |s: Vec3, t: Vec3| {
                    ((t.x - s.x) * (p.1 - s.y) - (t.y - s.y) * (p.0 - s.x)) * area.signum()
                        / (t - s).truncate().length().max(1e-9)
                };
                let d = [dist(a, b), dist(b, c), dist(c, a)];
                if d.iter().any(|&d| d < 0.0) {
                    continue;
                }
                // Depth interpolated with the barycentric weights.
                let wa = d[1] * (c - b).truncate().length();
                let wb = d[2] * (a - c).truncate().length();
                let wc = d[0] * (b - a).truncate().length();
                let z = (wa * a.z + wb * b.z + wc * c.z) / (wa + wb + wc).max(1e-9);
                let i = (y * w + x) as usize;
                if z >= depth[i] {
                    continue;
                }
                depth[i] = z;
                let edge = d.iter().any(|&d| d < EDGE);
                let k = if edge { shade * 0.45 } else { shade };
                let base = [150.0, 140.0, 128.0];
                img.put_pixel(x, y, Rgb(base.map(|c| (c * k + 40.0).min(255.0) as u8)));
            }
        }
    }
    img
}

/// The vertices (Z-up again: OBJ files are written Y-up, `(x, z, −y)`) and triangles of
/// an OBJ file's `v` and `f` lines.
fn read_obj(text: &str) -> (Vec<Vec3>, Vec<[usize; 3]>) {
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let c: Vec<f32> = words.map(|w| w.parse().expect("a coordinate")).collect();
                positions.push(Vec3::new(c[0], -c[2], c[1]));
            }
            Some("f") => {
                let i: Vec<usize> = words
                    .map(|w| {
                        w.split('/')
                            .next()
                            .and_then(|i| i.parse().ok())
                            .expect("an index")
                    })
                    .collect();
                faces.push([i[0] - 1, i[1] - 1, i[2] - 1]);
            }
            _ => {}
        }
    }
    (positions, faces)
}

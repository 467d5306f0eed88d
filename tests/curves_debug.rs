use std::path::Path;
use karstic::curves::spec::load_ron;
use karstic::curves::FeatureVolumeSpec;
use karstic::field::{Field, T};
use glam::Vec3;

#[test]
#[ignore]
fn debug_section() {
    let name = std::env::var("SCENE").unwrap_or("ridge".into());
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/curves");
    let spec: FeatureVolumeSpec = load_ron(&dir.join(format!("{name}.ron"))).unwrap();
    let t0 = std::time::Instant::now();
    let f = spec.build(&dir, 1).unwrap();
    eprintln!("build {:?}", t0.elapsed());
    eprintln!("{:#?}", f.stats());
    let axis: usize = std::env::var("AXIS").ok().and_then(|s| s.parse().ok()).unwrap_or(0);
    let at: f32 = std::env::var("AT").ok().and_then(|s| s.parse().ok()).unwrap_or(64.0);
    let d = f.params().domain;
    let step = 2.0;
    let (u_ax, v_ax) = match axis { 0 => (1, 2), 1 => (0, 2), _ => (0, 1) };
    let mut v = d.max[v_ax];
    while v >= d.min[v_ax] {
        let mut line = String::new();
        let mut u = d.min[u_ax];
        while u <= d.max[u_ax] {
            let mut p = Vec3::ZERO;
            p[axis] = at; p[u_ax] = u; p[v_ax] = v;
            let val = f.value(p);
            line.push(if val > T { '#' } else if val > 0.0 { '.' } else { '-' });
            u += step;
        }
        eprintln!("{line}");
        v -= step;
    }
}

#[test]
#[ignore]
fn debug_levels() {
    let name = std::env::var("SCENE").unwrap_or("cliff".into());
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/curves");
    let spec: FeatureVolumeSpec = load_ron(&dir.join(format!("{name}.ron"))).unwrap();
    let mut spec = spec;
    if let Ok(b) = std::env::var("BASE") { spec.solver.base = b.parse().unwrap(); }
    let features = spec.feature_set(&dir).unwrap().resolve(&|_| None).unwrap();
    let (p, _) = spec.params(1, 1 << 33);
    let vol = karstic::voxel::run(&features, &p).unwrap();
    let pts: Vec<Vec3> = std::env::var("PTS").unwrap_or("64,50,55;64,50,40;64,10,40;64,10,55".into()).split(';').map(|s| { let v: Vec<f32> = s.split(',').map(|x| x.parse().unwrap()).collect(); Vec3::new(v[0], v[1], v[2]) }).collect();
    for (l, b) in vol.levels.iter().enumerate() {
        let vals: Vec<String> = pts.iter().map(|&q| match b.cell(q) { Some((idx, f)) => format!("{:7.2}", karstic::voxel::sparse::trilinear(&vol.s[l], &idx, f)), None => "   --  ".into() }).collect();
        eprintln!("level h={} bricks={} : {}", b.geom.h, b.len(), vals.join(" "));
    }
}

#[test]
#[ignore]
fn debug_points() {
    let name = std::env::var("SCENE").unwrap_or("cliff".into());
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/curves");
    let spec: FeatureVolumeSpec = load_ron(&dir.join(format!("{name}.ron"))).unwrap();
    let f = spec.build(&dir, 1).unwrap();
    let pts: Vec<Vec3> = std::env::var("PTS").unwrap_or("64,50,55;64,50,40;64,10,40;64,10,55".into()).split(';').map(|s| { let v: Vec<f32> = s.split(',').map(|x| x.parse().unwrap()).collect(); Vec3::new(v[0], v[1], v[2]) }).collect();
    for q in pts { eprintln!("{q}: S'={} f={}", f.s_value(q), f.value(q)); }
}

#[test]
#[ignore]
fn debug_lip() {
    let name = std::env::var("SCENE").unwrap_or("ridge".into());
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/curves");
    let spec: FeatureVolumeSpec = load_ron(&dir.join(format!("{name}.ron"))).unwrap();
    let features = spec.feature_set(&dir).unwrap().resolve(&|_| None).unwrap();
    let (p, _) = spec.params(1, 1 << 33);
    let vol = karstic::voxel::run(&features, &p).unwrap();
    for (l, b) in vol.bounds.iter().enumerate() {
        let mut worst = (0.0f32, 0usize);
        for (i, bb) in b.iter().enumerate() { if bb.grad_s.length() > worst.0 { worst = (bb.grad_s.length(), i); } }
        let c = vol.levels[l].coords()[worst.1];
        eprintln!("level {l} h={} max|grad S| = {} at brick {c}", vol.levels[l].geom.h, worst.0);
    }
}

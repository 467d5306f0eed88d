//! Terrain analysis (slope, stream power, sinks, coastal accessibility) and the landform
//! generators of Paris et al. 2019 §6: karst networks are connected and stay out of hard
//! rock, sea erosion stays in its band, expansion is deterministic across thread counts
//! and `tree expand` writes a plain tree that compiles to the same field.

use std::collections::VecDeque;
use std::path::Path;

use glam::{Vec2, Vec3};

use karstic::analysis::flow::{drainage_area, fill_depressions};
use karstic::analysis::relief::{coastal_accessibility, sinks, slope, stream_power};
use karstic::dem::Heightfield;
use karstic::field::Resistance;
use karstic::field::{Aabb, Field, ISO, Tree};
use karstic::landform::{Ground, Terminal, carving_sphere};
use karstic::scene::landform::{HoodooSpec, KarstSpec, SeaSpec};
use karstic::scene::spec::Nary;
use karstic::scene::spec::{GeneratorSpec, LandformSpec};
use karstic::scene::{NodeSpec, SceneFile, parse_scene};

fn grid(nx: usize, ny: usize, cell: f32, f: impl Fn(f32, f32) -> f32) -> Heightfield {
    let z = (0..nx * ny)
        .map(|k| f((k % nx) as f32 * cell, (k / nx) as f32 * cell))
        .collect();
    Heightfield::new(nx, ny, Vec2::ZERO, Vec2::splat(cell), z).unwrap()
}

#[test]
fn slope_and_stream_power_on_a_tilted_plane() {
    // z = 100 − 0.5·x: slope 0.5 everywhere; drainage grows by one cell per column
    // downslope, so stream power grows as the square root of the distance.
    let (nx, ny) = (40, 41);
    let hf = grid(nx, ny, 10.0, |x, _| 100.0 - 0.5 * x);
    for s in slope(&hf) {
        assert!((s - 0.5).abs() < 1e-4, "slope {s}");
    }
    let area = drainage_area(&fill_depressions(&hf));
    let sp = stream_power(&hf);
    let j = ny / 2;
    for i in 0..nx {
        let k = i + nx * j;
        let want = ((i + 1) as f32 * 100.0).sqrt() * 0.5;
        assert!((area[k] - (i + 1) as f32 * 100.0).abs() < 0.1, "area {i}");
        assert!(
            (sp[k] - want).abs() < 1e-3 * want,
            "σ at {i}: {} ≠ {want}",
            sp[k]
        );
    }
}

#[test]
fn sinks_are_the_deep_pits_only() {
    // A plane with two closed basins, 5 m and 0.5 m deep, and noise-free elsewhere.
    let hf = grid(50, 50, 2.0, |x, y| {
        let bowl = |cx: f32, cy: f32, r: f32, d: f32| {
            let q = ((x - cx).powi(2) + (y - cy).powi(2)) / (r * r);
            if q < 1.0 { -d * (1.0 - q).powi(2) } else { 0.0 }
        };
        0.02 * x + bowl(30.0, 30.0, 12.0, 5.0) + bowl(70.0, 70.0, 8.0, 0.5)
    });
    let deep = sinks(&hf, 1.0);
    assert_eq!(deep, vec![15 + 50 * 15], "the deep bowl's bottom only");
    assert_eq!(sinks(&hf, 0.1).len(), 2);
}

#[test]
fn coastal_accessibility_is_higher_on_a_headland_than_in_a_bay() {
    // Sea below y = 40 except a headland (x in 40..60) reaching to y = 20, and a bay
    // (x in 120..140) reaching inland to y = 60.
    let land = |x: f32, y: f32| {
        let coast = if (40.0..60.0).contains(&x) {
            20.0
        } else if (120.0..140.0).contains(&x) {
            60.0
        } else {
            40.0
        };
        if y >= coast { 20.0 } else { -5.0 }
    };
    let hf = grid(100, 50, 2.0, land);
    let alpha = coastal_accessibility(&hf, 0.0, 1.0, 30.0);
    let at = |x: f32, y: f32| alpha[(x / 2.0) as usize + 100 * (y / 2.0) as usize];
    let (headland, straight, bay) = (at(50.0, 20.0), at(90.0, 40.0), at(130.0, 60.0));
    assert!(
        headland > straight && straight > bay,
        "{headland} {straight} {bay}"
    );
    assert_eq!(at(90.0, 90.0), 0.0, "inland, out of reach");
    assert_eq!(at(90.0, 10.0), 1.0, "the sea itself");
}

/// A compiled scene from RON text (assets relative to `trees/`).
fn scene_file(text: &str) -> SceneFile {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees");
    let path = dir.join("test.ron");
    SceneFile {
        scene: parse_scene(text, &path).unwrap(),
        path,
        base_dir: dir,
    }
}

/// A plateau: a box of rock 120 m wide, its top at about z = 0, 60 m deep.
const PLATEAU: &str =
    "Primitive(shape: Box(center: (0, 0, -32), half_size: (60, 60, 30)), falloff: 4.0)";

fn plateau() -> Tree {
    let text = format!("(version: 1, root: {PLATEAU})");
    scene_file(&text).compile().unwrap().tree
}

/// Strata: soft (0.3) above z = −26, hard (0.95) below.
fn strata(p: Vec3) -> f32 {
    if p.z > -26.0 { 0.3 } else { 0.95 }
}

fn karst() -> KarstSpec {
    ron::from_str("(sinks: [(0, 0)], radius: 3, spacing: 4, threshold: 0.6, max_spheres: 3000)")
        .unwrap()
}

/// The base with `spheres` carved as the generators carve them.
fn carve(base: &str, spheres: &[(Vec3, f32)], radius: f32) -> Tree {
    let mut sf = scene_file(&format!("(version: 1, root: {base})"));
    let carves = spheres
        .iter()
        .map(|(p, e)| carving_sphere(*p, radius, *e))
        .collect();
    let root = std::mem::replace(&mut sf.scene.root, NodeSpec::Blend(Nary::default()));
    sf.scene.root = NodeSpec::Blend(Nary {
        name: None,
        children: vec![
            root,
            NodeSpec::Blend(Nary {
                name: None,
                children: carves,
            }),
        ],
    });
    sf.compile().unwrap().tree
}

/// Floods the lattice `lo + step·(i, j, k)`, `n` points a side, through its `open` points
/// (6-connected) from `start`, and returns the lowest z reached, stopping once at `until`.
fn flood_deepest(
    lo: Vec3,
    step: f32,
    n: [usize; 3],
    start: [usize; 3],
    open: impl Fn(Vec3) -> bool,
    until: f32,
) -> f32 {
    let idx = |i: usize, j: usize, k: usize| i + n[0] * (j + n[1] * k);
    let at = |i: usize, j: usize, k: usize| lo + Vec3::new(i as f32, j as f32, k as f32) * step;
    let mut seen = vec![false; n[0] * n[1] * n[2]];
    seen[idx(start[0], start[1], start[2])] = true;
    let mut queue = VecDeque::from([(start[0], start[1], start[2])]);
    let mut deepest = f32::INFINITY;
    while let Some((i, j, k)) = queue.pop_front() {
        deepest = deepest.min(at(i, j, k).z);
        if deepest <= until {
            break;
        }
        for (a, b, c) in [
            (i.wrapping_sub(1), j, k),
            (i + 1, j, k),
            (i, j.wrapping_sub(1), k),
            (i, j + 1, k),
            (i, j, k.wrapping_sub(1)),
            (i, j, k + 1),
        ] {
            if a >= n[0] || b >= n[1] || c >= n[2] || seen[idx(a, b, c)] {
                continue;
            }
            seen[idx(a, b, c)] = true;
            if open(at(a, b, c)) {
                queue.push_back((a, b, c));
            }
        }
    }
    deepest
}

#[test]
fn karst_is_connected_from_its_sink_to_deep_passages_and_spares_hard_rock() {
    let base = plateau();
    let region = Aabb::new(Vec3::new(-56.0, -56.0, -60.0), Vec3::new(56.0, 56.0, 4.0));
    let rho = strata;
    let ground = Ground::new(&base, region, 2.0, &rho, 7).unwrap();
    let spec = karst();
    let net = spec.network(&ground).unwrap();
    assert!(net.len() > 50, "{} spheres", net.len());
    for (p, _) in &net {
        assert!(strata(*p) < 0.6, "a sphere at {p} in hard rock");
    }
    let carved = carve(PLATEAU, &net, 3.0);
    // Hard rock well below the boundary (more than a sphere's reach) is untouched.
    let reach = 3.0 / 0.61;
    for k in 0..2000 {
        let p = Vec3::new(
            -50.0 + (k % 20) as f32 * 5.0,
            -50.0 + (k / 20 % 20) as f32 * 5.0,
            -26.0 - reach - 1.0 - (k / 400) as f32 * 5.0,
        );
        assert!(carved.value(p) > ISO, "hard rock at {p} was carved");
    }
    // Flood the air from above the sink on a 1 m lattice: it reaches 15 m below the top.
    let (lo, n) = (Vec3::new(-56.0, -56.0, -40.0), [113usize, 113, 46]);
    let at = |i: usize, j: usize, k: usize| lo + Vec3::new(i as f32, j as f32, k as f32);
    let start = [56, 56, n[2] - 1];
    assert!(carved.value(at(start[0], start[1], start[2])) < ISO);
    // Inside the plateau's footprint only, so the flood cannot go round its sides.
    let open = |p: Vec3| p.x.abs() <= 50.0 && p.y.abs() <= 50.0 && carved.value(p) < ISO;
    let deepest = flood_deepest(lo, 1.0, n, start, open, -15.0);
    assert!(deepest <= -15.0, "the flood stops at z = {deepest}");
}

#[test]
fn sea_erosion_carves_only_within_its_band() {
    // A cliff: land (z up to 20) north of y = 0, sea floor at z = −15 to the south.
    let cliff = "Primitive(shape: Box(center: (0, 30, -5), half_size: (40, 30, 25)), falloff: 2.0)";
    let base = scene_file(&format!("(version: 1, root: {cliff})"))
        .compile()
        .unwrap()
        .tree;
    let region = Aabb::new(Vec3::new(-45.0, -20.0, -32.0), Vec3::new(45.0, 64.0, 24.0));
    let rho = |_: Vec3| 0.4;
    let ground = Ground::new(&base, region, 1.0, &rho, 3).unwrap();
    let spec: SeaSpec =
        ron::from_str("(sea_level: 0, band: 5, radius: 2, spacing: 2, reach: 20)").unwrap();
    let samples = spec.samples(&ground).unwrap();
    assert!(samples.len() > 50, "{} samples", samples.len());
    for (p, _) in &samples {
        assert!(p.z.abs() <= 5.0, "a sample at {p}");
    }
    let carved = carve(cliff, &samples, 2.0);
    let reach = 2.0 / 0.61;
    let mut changed = 0;
    for k in 0..60_000 {
        let p = Vec3::new(
            -40.0 + (k % 40) as f32 * 2.0,
            -1.0 + (k / 40 % 30) as f32 * 0.5,
            -30.0 + (k / 1200) as f32,
        );
        if base.value(p) > ISO && carved.value(p) <= ISO {
            changed += 1;
            assert!(p.z.abs() <= 5.0 + reach, "carved at {p}, out of the band");
        }
    }
    assert!(changed > 100, "only {changed} points carved");
}

const KARST_SCENE: &str = "(version: 1, seed: 4, root: Landform(name: \"k\", seed: 9, cell: 2, \
     base: Primitive(shape: Box(center: (0, 0, -32), half_size: (60, 60, 30)), falloff: 4.0), \
     region: (min: (-56, -56, -60), max: (56, 56, 4)), \
     generator: Karst(sinks: [(0, 0), (20, -10)], radius: 3, spacing: 4, threshold: 0.6, max_spheres: 400)))";

#[test]
fn expansion_is_byte_identical_across_thread_counts() {
    let sf = scene_file(KARST_SCENE);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| sf.expand().unwrap().to_ron())
    };
    let one = run(1);
    assert!(one.matches("Primitive").count() > 300, "{one}");
    assert_eq!(one, run(3));
    assert_eq!(one, run(8));
}

#[test]
fn tree_expand_writes_a_plain_tree_that_compiles_to_the_same_field() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("karst.ron");
    std::fs::write(&input, KARST_SCENE).unwrap();
    let output = dir.path().join("plain.ron");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_karstic"))
        .args(["tree", "expand"])
        .arg(&input)
        .arg("-o")
        .arg(&output)
        .status()
        .unwrap();
    assert!(status.success());
    let plain = std::fs::read_to_string(&output).unwrap();
    assert!(!plain.contains("Landform"));
    let a = karstic::scene::load(&input)
        .unwrap()
        .compile()
        .unwrap()
        .tree;
    let b = karstic::scene::load(&output)
        .unwrap()
        .compile()
        .unwrap()
        .tree;
    for k in 0..4000 {
        let p = Vec3::new(
            -50.0 + (k % 20) as f32 * 5.1,
            -50.0 + (k / 20 % 20) as f32 * 5.1,
            -40.0 + (k / 400) as f32 * 4.3,
        );
        assert_eq!(a.value(p).to_bits(), b.value(p).to_bits(), "at {p}");
    }
}

#[test]
fn hoodoos_stand_on_their_axioms_within_the_grammar_depth() {
    let base = plateau();
    let region = Aabb::new(Vec3::new(-50.0, -50.0, -60.0), Vec3::new(50.0, 50.0, 30.0));
    let rho = |p: Vec3| (0.5 + 0.4 * (p.z * 0.7).sin()).clamp(0.0, 1.0);
    let ground = Ground::new(&base, region, 2.0, &rho, 11).unwrap();
    let spec: HoodooSpec =
        ron::from_str("(spacing: 9, size: 5, max_depth: 4, slope: (-0.5, 0.5), max_area: 1e9)")
            .unwrap();
    let hoodoos = spec.hoodoos(&ground).unwrap();
    assert!(hoodoos.len() > 40, "{} hoodoos", hoodoos.len());
    assert!(hoodoos.iter().all(|h| (1..=4).contains(&h.symbols.len())));
    assert!(
        hoodoos.iter().any(|h| h.symbols.len() >= 3),
        "no tall hoodoo"
    );
    let kinds = |t: Terminal| {
        hoodoos
            .iter()
            .flat_map(|h| &h.symbols)
            .filter(|s| s.0 == t)
            .count()
    };
    assert!(kinds(Terminal::Body) > 0 && kinds(Terminal::Cone) > 0 && kinds(Terminal::Cap) > 0);
    // Most keep the caprock that stopped their wearing down (with the paper's `1 − ρ/2`
    // about a third did here).
    let capped = hoodoos
        .iter()
        .filter(|h| h.symbols.last().is_some_and(|s| s.0 == Terminal::Cap))
        .count();
    assert!(
        capped * 2 > hoodoos.len(),
        "{capped} of {} hoodoos capped",
        hoodoos.len()
    );
    // The expanded tree: the terrain and the hoodoos' union.
    let mut sf = scene_file(&format!("(version: 1, root: {PLATEAU})"));
    let rocks = spec.generate(&ground).unwrap();
    let root = std::mem::replace(&mut sf.scene.root, NodeSpec::Blend(Nary::default()));
    sf.scene.root = NodeSpec::Union(Nary {
        name: None,
        children: vec![
            root,
            NodeSpec::Blend(Nary {
                name: None,
                children: rocks,
            }),
        ],
    });
    let tree = sf.compile().unwrap().tree;
    for h in &hoodoos {
        let height = h.height();
        assert!(height > 3.0, "a hoodoo of {height} m");
        for k in 0..=40 {
            let p = h.axiom + Vec3::Z * (height * k as f32 / 40.0 * 0.999);
            assert!(tree.value(p) > ISO, "a hoodoo at {} breaks at {p}", h.axiom);
        }
        // And it stands out of the ground by 2 m at least (its axiom is a quarter of the
        // first symbol's 5 m below the surface).
        assert!(
            height - 0.25 * 5.0 > 2.0,
            "a hoodoo of {height} m at {} ({} symbols)",
            h.axiom,
            h.symbols.len()
        );
    }
    // The beds shape the columns: in each body, above the ground, the column is wider at
    // the height of its hardest rock than at its softest (ρ swings by ±0.4 every 9 m
    // here).
    let radius = |h: &karstic::landform::Hoodoo, z: f32| {
        let mut r = 0.0;
        while r < 10.0 && tree.value(h.axiom.truncate().extend(z) + Vec3::X * r) > ISO {
            r += 0.02;
        }
        r
    };
    let (mut bodies, mut bulging) = (0, 0);
    for h in &hoodoos {
        for &(t, p, size, _, _) in &h.symbols {
            if t != Terminal::Body || size < 3.0 {
                continue;
            }
            // Above the ground around the column (under it, the terrain is solid too).
            let floor = ground.height(h.axiom.truncate()) + 1.0;
            let zs: Vec<f32> = (1..20)
                .map(|k| p.z + size * k as f32 / 20.0)
                .filter(|&z| z > floor)
                .collect();
            let rho_at = |z: f32| rho(h.axiom.truncate().extend(z));
            let hard = zs
                .iter()
                .copied()
                .max_by(|a, b| rho_at(*a).total_cmp(&rho_at(*b)));
            let soft = zs
                .iter()
                .copied()
                .min_by(|a, b| rho_at(*a).total_cmp(&rho_at(*b)));
            let (Some(hard), Some(soft)) = (hard, soft) else {
                continue;
            };
            if rho_at(hard) - rho_at(soft) < 0.3 {
                continue;
            }
            bodies += 1;
            bulging += usize::from(radius(h, hard) > radius(h, soft));
        }
    }
    assert!(bodies >= 10, "{bodies} bodies spanning hard and soft rock");
    assert!(
        bulging * 20 >= bodies * 19,
        "{bulging} of {bodies} bodies wider in their hard rock than in their soft"
    );
    // No two hoodoos share a profile: their radii at a fifth, two fifths … of their
    // heights, to 5 cm.
    let profiles: std::collections::BTreeSet<Vec<i32>> = hoodoos
        .iter()
        .map(|h| {
            (1..5)
                .map(|k| (radius(h, h.axiom.z + h.height() * k as f32 / 5.0) / 0.05) as i32)
                .collect()
        })
        .collect();
    assert_eq!(profiles.len(), hoodoos.len(), "hoodoos sharing a profile");
    // Each rises from a skirt of its debris: half a metre over the ground at its foot the
    // rock reaches a third again as far from its axis as at two fifths of its height.
    let skirted = hoodoos
        .iter()
        .filter(|h| {
            let foot = ground.height(h.axiom.truncate()) + 0.5;
            radius(h, foot) > 1.3 * radius(h, h.axiom.z + 0.4 * h.height())
        })
        .count();
    assert!(
        skirted * 10 >= hoodoos.len() * 9,
        "{skirted} of {} hoodoos rise from a skirt",
        hoodoos.len()
    );
}

/// A scene of `trees/`, loaded.
fn tree_scene(file: &str) -> SceneFile {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("trees")
        .join(file);
    karstic::scene::load(&path).unwrap_or_else(|e| panic!("{file}: {e}"))
}

/// The scene's root `Landform` node.
fn root_landform(sf: &mut SceneFile) -> &mut LandformSpec {
    match &mut sf.scene.root {
        NodeSpec::Landform(l) => l,
        other => panic!("the root is a {}, not a Landform", other.kind()),
    }
}

/// The height of the highest solid at `xy` between `lo` and `hi` (a scan down in 4 m
/// steps, then bisection: no ledge thinner than that is looked for), `None` when the
/// column is air.
fn top_at(tree: &Tree, xy: Vec2, lo: f32, hi: f32) -> Option<f32> {
    let mut z = hi;
    while z > lo {
        if tree.value(xy.extend(z - 4.0)) > ISO {
            let (mut a, mut b) = (z - 4.0, z);
            for _ in 0..20 {
                let m = 0.5 * (a + b);
                if tree.value(xy.extend(m)) > ISO {
                    a = m
                } else {
                    b = m
                }
            }
            return Some(a);
        }
        z -= 4.0;
    }
    None
}

/// `trees/jacksboro_canyon.ron` compiled, and its base: the valley without the canyon.
fn canyon_and_valley() -> (Tree, Tree) {
    let mut sf = tree_scene("jacksboro_canyon.ron");
    let carved = sf.compile().unwrap().tree;
    let base_spec = (*root_landform(&mut sf).base).clone();
    sf.scene.root = base_spec;
    (carved, sf.compile().unwrap().tree)
}

#[test]
fn the_jacksboro_canyon_deepens_the_thalweg_and_leaves_the_hills() {
    // trees/jacksboro_canyon.ron: the canyon generator on a valley of the Jacksboro DEM.
    // Across the valley at five rows, the thalweg (the lowest point of the DEM's surface
    // between x = 5450 and 5850) is lowered by at least 50 m into the gorge (61–70 m when
    // written), and high on the slopes
    // (150 m above the thalweg) the field is the DEM's, bit for bit.
    let (carved, base) = canyon_and_valley();
    let (lo, hi) = (250.0, 1000.0);
    let mut away = 0;
    for y in [6350.0, 6400.0, 6450.0, 6500.0, 6550.0] {
        let tops: Vec<(f32, f32)> = (0..=40)
            .map(|i| {
                let x = 5450.0 + 10.0 * i as f32;
                (x, top_at(&base, Vec2::new(x, y), lo, hi).unwrap())
            })
            .collect();
        let &(x, bed) = tops.iter().min_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
        let now = top_at(&carved, Vec2::new(x, y), lo, hi).unwrap();
        eprintln!("thalweg at ({x}, {y}): {bed:.1} m → {now:.1} m");
        assert!(
            now <= bed - 50.0,
            "the thalweg at ({x}, {y}) went from {bed} m to only {now} m"
        );
        for x in (0..=60).map(|i| 5000.0 + 20.0 * i as f32) {
            let xy = Vec2::new(x, y);
            let h = top_at(&base, xy, lo, hi).unwrap();
            if h < bed + 150.0 {
                continue;
            }
            away += 1;
            for dz in [-4.0, 0.0, 4.0] {
                let p = xy.extend(h + dz);
                assert_eq!(
                    carved.value(p).to_bits(),
                    base.value(p).to_bits(),
                    "the canyon changed the hillside at {p}"
                );
            }
        }
    }
    assert!(away > 40, "only {away} hillside samples");
}

#[test]
fn the_jacksboro_canyon_runs_unbroken_down_its_river() {
    // trees/jacksboro_canyon.ron: every 50 m down the river, from 5,700 m to 7,300 m (short
    // of the region's north side, where the carving fades), the thalweg (the lowest ground
    // of the row within 500 m of the river's line) is carved at least 15 m down (17 to 70 m
    // when written): the gorge runs on through the flatter reaches
    // (where the local stream power falls under the threshold, it stopped in closed
    // bowls before the river's power was carried downstream).
    let (carved, base) = canyon_and_valley();
    let (lo, hi) = (250.0, 1000.0);
    for k in 0..=32 {
        let y = 5700.0 + 50.0 * k as f32;
        // The river's line from (5450, 5400) to (6200, 7350).
        let mid = 5450.0 + (y - 5400.0) / 1950.0 * 750.0;
        let tops: Vec<(f32, f32)> = (0..=50)
            .map(|i| {
                let x = mid - 500.0 + 20.0 * i as f32;
                (x, top_at(&base, Vec2::new(x, y), lo, hi).unwrap())
            })
            .collect();
        let &(x, bed) = tops.iter().min_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
        let now = top_at(&carved, Vec2::new(x, y), lo, hi).unwrap();
        assert!(
            now <= bed - 15.0,
            "the gorge breaks at ({x}, {y}): the thalweg went from {bed} m to {now} m"
        );
    }
}

#[test]
fn the_strata_islands_percolation_caves_open_at_their_sink_and_stay_in_soft_rock() {
    // trees/strata_islands.ron, its karst narrowed to one sink and the box around it (the
    // scene's percolation, cheaper): every carving sphere lies where ρ < ρ₀, and a flood
    // from the sink's mouth through the carved air inside the island reaches passages at
    // least 20 m below the island's top.
    let mut sf = tree_scene("strata_islands.ron");
    let sink = Vec2::new(410.0, 443.0);
    let landform = root_landform(&mut sf);
    let GeneratorSpec::Karst(karst) = &mut landform.generator else {
        panic!("the islands' landform is a Karst")
    };
    assert!(karst.sinks.iter().any(|s| s.0 == sink), "the sink moved");
    karst.sinks.retain(|s| s.0 == sink);
    let rho0 = karst.threshold.0;
    landform.region = Some(ron::from_str("(min: (330, 363, 20), max: (490, 523, 160))").unwrap());
    let base_spec = (*landform.base).clone();
    let compiled = sf.compile().unwrap();
    let carved = compiled.tree;
    let mut centres = Vec::new();
    compiled.expanded.as_ref().unwrap().root.walk(&mut |n, _| {
        if let NodeSpec::Primitive(p) = n
            && let karstic::field::SkeletonSpec::Point { center } = &p.shape
        {
            centres.push(center.0);
        }
    });
    assert!(centres.len() > 150, "{} spheres", centres.len());
    for c in &centres {
        let rho = compiled.geology.resistance(*c);
        assert!(rho < rho0, "a sphere at {c} in rock of ρ = {rho}");
    }
    sf.scene.root = base_spec;
    let base = sf.compile().unwrap().tree;
    let top = top_at(&base, sink, 20.0, 160.0).unwrap();
    // Flood on a 2 m lattice through carved air within the island's base solid, from the
    // first cave cell under the sink (the mouth: the air above it is open sky).
    let (lo, step, n) = (Vec3::new(330.0, 363.0, 20.0), 2.0, [81usize, 81, 71]);
    let at = |i: usize, j: usize, k: usize| lo + Vec3::new(i as f32, j as f32, k as f32) * step;
    let cave = |p: Vec3| base.value(p) > ISO && carved.value(p) < ISO;
    let (si, sj) = (40, 40);
    let sk = (0..n[2])
        .rev()
        .find(|&k| cave(at(si, sj, k)))
        .expect("no cave under the sink");
    let mouth = at(si, sj, sk);
    assert!(
        mouth.z >= top - 8.0 && (sk + 1..n[2]).all(|k| carved.value(at(si, sj, k)) < ISO),
        "the cave under the sink at {mouth} (top {top}) does not open to the sky"
    );
    let deepest = flood_deepest(lo, step, n, [si, sj, sk], cave, top - 20.0);
    eprintln!(
        "{} spheres; top {top:.1} m, the flood reaches {deepest:.1} m",
        centres.len()
    );
    assert!(
        deepest <= top - 20.0,
        "the flood from the mouth stops at z = {deepest}, the top is at {top}"
    );
}

/// A flat ground (top at z = 0) over beds: soft (0.2) below z = 14, hard (0.9) above.
const ARCH_SCENE: &str = "(version: 1, seed: 3, \
    geology: (root: Strata(point: (0, 0, -20), normal: (0, 0, 1), profile: Layers(layers: \
        [(thickness: 34, resistance: 0.2), (thickness: 30, resistance: 0.9)], transition: 1))), \
    root: Landform(name: \"arch\", seed: 1, cell: 2, region: (min: (-80, -60, -30), max: (80, 60, 30)), \
        base: Primitive(name: \"ground\", shape: Box(center: (0, 0, -10), half_size: (120, 120, 10)), falloff: 2.0), \
        generator: Arch(from: (-20, 0), to: (20, 0))))";

fn arch() -> (
    karstic::landform::ArchShape,
    Tree,
    karstic::geology::Geology,
) {
    arch_in(ARCH_SCENE)
}

/// The arch of a scene of one `Arch` landform over the ground of [`ARCH_SCENE`]: its
/// shape, the compiled tree and the geology.
fn arch_in(
    scene: &str,
) -> (
    karstic::landform::ArchShape,
    Tree,
    karstic::geology::Geology,
) {
    let file = scene_file(scene);
    let geology = file.scene.geology().unwrap();
    let NodeSpec::Landform(l) = &file.scene.root else {
        panic!("a landform")
    };
    let GeneratorSpec::Arch(spec) = &l.generator else {
        panic!("an arch")
    };
    let base = scene_file(
        "(version: 1, root: Primitive(shape: Box(center: (0, 0, -10), \
         half_size: (120, 120, 10)), falloff: 2.0))",
    )
    .compile()
    .unwrap()
    .tree;
    let rho = |p: Vec3| geology.resistance(p);
    let r = l.region.expect("the arch gives its region");
    let region = Aabb::new(r.min.0, r.max.0);
    let ground = Ground::new(&base, region, 2.0, &rho, l.full_seed(3)).unwrap();
    let shape = spec.shape(&ground).unwrap();
    let tree = file.compile().unwrap().tree;
    (shape, tree, geology)
}

#[test]
fn an_arch_opens_in_the_soft_bed_under_a_hard_lintel() {
    let (s, t, geology) = arch();
    // The soft bed ends at z = 14: the ceiling is found there.
    assert!(s.ground.abs() < 1.5, "ground at {}", s.ground);
    assert!((s.ceiling - 14.0).abs() < 1.5, "ceiling at {}", s.ceiling);
    assert!((s.span - 40.0).abs() < 1e-3);
    // Under the middle of the span the opening is open, the lintel above it rock.
    let (mut open, mut lintel) = (Vec::new(), Vec::new());
    for i in -6..=6 {
        let x = i as f32;
        for k in 0..8 {
            let z = 2.0 + k as f32 * (s.ceiling - 4.0) / 7.0;
            open.push(Vec3::new(x, 0.0, z));
        }
        for z in [s.ceiling + 1.5, 0.5 * (s.ceiling + s.crest)] {
            lintel.push(Vec3::new(x, 0.0, z));
        }
    }
    for p in &open {
        assert!(t.value(*p) < ISO, "rock in the opening at {p}");
    }
    for p in &lintel {
        assert!(t.value(*p) > ISO, "no lintel at {p}");
    }
    let mean = |v: &[Vec3]| v.iter().map(|&p| geology.resistance(p)).sum::<f32>() / v.len() as f32;
    let (soft, hard) = (mean(&open), mean(&lintel));
    assert!(soft + 0.3 < hard, "opening ρ {soft}, lintel ρ {hard}");
}

#[test]
fn an_arch_varies_along_its_span_and_stands_on_rooted_abutments() {
    let (s, t, _) = arch();
    // The lintel's section (rock above the ceiling, across the fin) along the span.
    let areas: Vec<usize> = (-16..=16)
        .map(|i| {
            let x = i as f32;
            let mut n = 0;
            for j in -40..=40 {
                for k in 0..=60 {
                    let p = Vec3::new(x, 0.5 * j as f32, s.ceiling + 0.5 + 0.5 * k as f32);
                    n += usize::from(t.value(p) > ISO);
                }
            }
            n
        })
        .collect();
    let (lo, hi) = (
        *areas.iter().min().unwrap() as f32,
        *areas.iter().max().unwrap() as f32,
    );
    assert!(lo > 0.0, "the lintel is whole: {areas:?}");
    assert!((hi - lo) / hi >= 0.25, "sections {areas:?}");
    // Each abutment is one rock from below the ground up into the lintel.
    for x in [-26.0f32, 26.0] {
        for k in 0..=40 {
            let z = -3.0 + k as f32 * (s.ceiling + 2.0) / 40.0;
            let p = Vec3::new(x, 0.0, z);
            assert!(t.value(p) > ISO, "the abutment is broken at {p}");
        }
    }
    // Fallen blocks lie beside the fin, a part of each below the ground and a part above
    // it, each one solid rock in the tree.
    assert!(s.talus.len() >= 10, "{} fallen blocks", s.talus.len());
    for b in &s.talus {
        let c = b.center;
        assert!(
            c.z - b.half.z < s.ground && c.z + b.half.z > s.ground,
            "a block at {c} does not lie on the ground at {}",
            s.ground
        );
        let face = s
            .blocks
            .iter()
            .find(|k| k.x.x <= c.x && c.x <= k.x.y)
            .unwrap();
        assert!(
            c.y < face.y.x || c.y > face.y.y,
            "a block inside the fin at {c}"
        );
        assert!(t.value(c) > ISO, "no rock at the block's centre {c}");
    }
    // The same file gives the same arch.
    assert_eq!(arch().0, s);
}

/// `fins: 3` stands three fins of the same joint set on the arch's left, each clear of the
/// last by a slot, rooted in the ground and rock up to most of its height, none across the
/// sight line through the opening (the sky shows through it).
#[test]
fn fins_beside_an_arch_stand_clear_of_its_opening() {
    let scene = ARCH_SCENE
        .replace(
            "(min: (-80, -60, -30), max: (80, 60, 30))",
            "(min: (-130, -60, -30), max: (130, 100, 30))",
        )
        .replace("to: (20, 0))", "to: (20, 0), fins: 3)");
    let (s, t, _) = arch_in(&scene);
    assert_eq!(s.fins.len(), 3, "{} fins", s.fins.len());
    let side = |b: &[karstic::landform::FinBlock]| {
        b.iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), k| {
                (lo.min(k.y.x), hi.max(k.y.y))
            })
    };
    let mut edge = side(&s.blocks).1;
    for f in &s.fins {
        let (lo, hi) = side(&f.blocks);
        let width = f.blocks.iter().map(|b| b.y.y - b.y.x).fold(0.0, f32::max);
        assert!(
            lo > edge + 0.3 * width,
            "a fin at y ≥ {lo} crowds the last, which ends at {edge}"
        );
        edge = hi;
        let height = f.crest - f.ground;
        assert!(height > 10.0, "a fin {height} m high");
        for k in 0..=20 {
            let p = f
                .center
                .extend(f.ground - 2.0 + k as f32 * (0.7 * height + 2.0) / 20.0);
            assert!(t.value(p) > ISO, "a fin is broken at {p}");
        }
    }
    // Straight through the opening, from well before the arch's fin to well behind the
    // last fin, at the middle of the opening's height: all air.
    let z = 0.5 * (s.ground + s.ceiling);
    for y in (-100..=180).map(|k| 0.5 * k as f32) {
        for x in [-4.0f32, 0.0, 4.0] {
            let p = Vec3::new(x, y, z);
            assert!(
                t.value(p) < ISO,
                "rock across the opening's sight line at {p}"
            );
        }
    }
}

/// On a 25° slope an arch's fin runs down past its lower foot: its root must reach below
/// the ground there too, not only below its feet (the fin would hang in the air).
#[test]
fn an_arch_on_a_slope_is_rooted_along_its_whole_fin() {
    let slope = "Transform(rotate: (axis: (0, 1, 0), degrees: 25), \
        child: Primitive(shape: Box(center: (0, 0, -60), half_size: (150, 150, 60)), falloff: 2.0))";
    let ground = scene_file(&format!("(version: 1, root: {slope})"))
        .compile()
        .unwrap()
        .tree;
    let tree = scene_file(&format!(
        "(version: 1, seed: 3, root: Landform(name: \"arch\", seed: 1, cell: 2, \
         region: (min: (-90, -60, -60), max: (90, 60, 60)), base: {slope}, \
         generator: Arch(from: (-20, 0), to: (20, 0), weathering: 0)))"
    ))
    .compile()
    .unwrap()
    .tree;
    let top = |t: &Tree, x: f32| {
        (0..=1200)
            .map(|k| 60.0 - 0.1 * k as f32)
            .find(|&z| t.value(Vec3::new(x, 0.0, z)) > ISO)
            .unwrap()
    };
    // Beside the feet (the abutments) and near both ends of the fin (it runs 28 m past
    // each foot): ground and fin are one rock, no air between them.
    for x in [-46.0f32, -26.0, 26.0, 46.0] {
        let (from, to) = (Vec3::new(x, 0.0, -60.0), Vec3::new(x, 0.0, 60.0));
        let at = |k: i32| tree.value(from.lerp(to, k as f32 / 1200.0)) > ISO;
        let crossings = (1..=1200).filter(|&k| at(k) != at(k - 1)).count();
        assert_eq!(
            crossings, 1,
            "air between the ground and the fin at x = {x}"
        );
    }
    // The fin stands over both feet.
    for x in [-20.0f32, 20.0] {
        assert!(
            top(&tree, x) > top(&ground, x) + 5.0,
            "no fin over the foot at x = {x}"
        );
    }
    // The downhill end stands above its ground (the fin is there, not buried).
    let low_end = if top(&ground, 46.0) < top(&ground, -46.0) {
        46.0
    } else {
        -46.0
    };
    assert!(top(&tree, low_end) > top(&ground, low_end) + 1.0);
}

/// The fin arch scene meshes into one surface: fin, lintel and fallen blocks all one with
/// the ground (no boulder floats, no sliver of rock is left in the opening).
#[test]
fn the_fin_arch_scene_meshes_into_one_piece() {
    let dir = tempfile::tempdir().unwrap();
    let opts = karstic::job::JobOptions {
        out_dir: dir.path().to_path_buf(),
        full: false,
        no_render: true,
        no_views: true,
        quiet: true,
        budget: karstic::io::DEFAULT_MEMORY_BUDGET,
        origin: karstic::mesh::export::Origin::Dem,
        masks: false,
    };
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/fin_arch.ron");
    let r = karstic::job::run(&path, &opts).unwrap();
    assert_eq!(
        r.mesh.component_sizes().len(),
        1,
        "{:?}",
        r.mesh.component_sizes()
    );
}

/// A carving landform fades inside its region and stops at its faces: every carving
/// sphere's support lies inside the region, the spheres within a quarter of the fade band
/// of a face keep at most 16% of the strongest energy in the core, and just outside the
/// faces the field is the base's, bit for bit (the canyon and the sea notch stopped dead
/// at the region's sides before).
#[test]
fn carving_landforms_fade_inside_their_region_and_stop_at_its_faces() {
    use karstic::field::SkeletonSpec;
    let mut sf = tree_scene("jacksboro_canyon.ron");
    let l = root_landform(&mut sf).clone();
    let r = l.region.expect("the canyon gives its region");
    let region = Aabb::new(r.min.0, r.max.0);
    let width = karstic::landform::fade_width(&region, l.cell.0);
    let expanded = sf.expand().unwrap();
    let mut carves: Vec<NodeSpec> = Vec::new();
    expanded.root.walk(&mut |n, _| {
        if n.name() == Some("canyon-carves") {
            carves = n.children().into_iter().cloned().collect();
        }
    });
    assert!(carves.len() > 100, "{} carves", carves.len());
    let (mut core, mut band, mut in_band) = (0f32, 0f32, 0);
    for n in &carves {
        let NodeSpec::Primitive(p) = n else {
            panic!("a carve is a {}", n.kind())
        };
        let SkeletonSpec::Point { center } = p.shape else {
            panic!("a carve is not a sphere")
        };
        let c = center.0;
        let inside = (c - region.min).min(region.max - c).min_element();
        assert!(
            p.falloff.0 <= inside + 1e-3,
            "a sphere at {c} reaches past the faces"
        );
        let e = p.energy.0.abs();
        if inside < 0.25 * width {
            band = band.max(e);
            in_band += 1;
        } else if inside > width {
            core = core.max(e);
        }
    }
    assert!(
        in_band > 0,
        "no carve near the faces: the test shows nothing"
    );
    assert!(
        band <= 0.16 * core,
        "near the faces {band}, in the core {core}"
    );
    // Outside the faces, the field is the base's.
    let tree = sf.compile().unwrap().tree;
    let mut scene = sf.scene.clone();
    scene.root = (*l.base).clone();
    let base = SceneFile { scene, ..sf }.compile().unwrap().tree;
    let mut checked = 0;
    for k in 0..400 {
        let t = (k as f32 + 0.5) / 400.0;
        let (x, y) = match k % 4 {
            0 => (
                region.min.x - 0.5,
                region.min.y + t * (region.max.y - region.min.y),
            ),
            1 => (
                region.max.x + 0.5,
                region.min.y + t * (region.max.y - region.min.y),
            ),
            2 => (
                region.min.x + t * (region.max.x - region.min.x),
                region.min.y - 0.5,
            ),
            _ => (
                region.min.x + t * (region.max.x - region.min.x),
                region.max.y + 0.5,
            ),
        };
        let z = region.min.z + ((k * 37) % 100) as f32 / 100.0 * (region.max.z - region.min.z);
        let p = Vec3::new(x, y, z);
        assert_eq!(tree.value(p), base.value(p), "at {p}");
        checked += 1;
    }
    assert_eq!(checked, 400);
}

/// A slope of 1 in 2 falling east, under a sandstone bed from z = −6 to 10 that crops
/// out across it (its base meets the ground at x = 12), with a rock shelter and a spur with
/// a window.
const CAPROCK_SCENE: &str = "(version: 1, seed: 2, \
    root: Landform(name: \"cliff\", seed: 4, cell: 2, region: (min: (-100, -80, -60), max: (100, 80, 60)), \
        base: Transform(name: \"ground\", rotate: (axis: (0, 1, 0), degrees: 26.56505), \
            child: Primitive(shape: Box(center: (0, 0, -100), half_size: (400, 400, 100)), falloff: 1.0)), \
        generator: Caprock(top: 10, thickness: 16, joints: 8, strike: 15, \
            spurs: [(from: (12, 25), to: (42, 25), width: 9, window: 14)], \
            recesses: [(at: (14, 0), length: 20, depth: 8, height: 7)])))";

fn caprock() -> (karstic::landform::CliffLine, Tree, Tree) {
    caprock_of(CAPROCK_SCENE)
}

/// The cliff line of a caprock scene over a region 200 × 160 × 120 m about the origin,
/// its tree and its base's.
fn caprock_of(scene: &str) -> (karstic::landform::CliffLine, Tree, Tree) {
    let file = scene_file(scene);
    let NodeSpec::Landform(l) = &file.scene.root else {
        panic!("a landform")
    };
    let GeneratorSpec::Caprock(spec) = &l.generator else {
        panic!("a caprock")
    };
    let mut bare = file.clone();
    bare.scene.root = (*l.base).clone();
    let base = bare.compile().unwrap().tree;
    let rho = |_: Vec3| 0.5;
    let region = Aabb::new(
        Vec3::new(-100.0, -80.0, -60.0),
        Vec3::new(100.0, 80.0, 60.0),
    );
    let ground = Ground::new(&base, region, 2.0, &rho, l.full_seed(2)).unwrap();
    let line = spec.shape(&ground).unwrap();
    assert_eq!(
        line,
        spec.shape(&ground).unwrap(),
        "the same seed, the same cliff"
    );
    (line, file.compile().unwrap().tree, base)
}

/// The slope's height at `x` (the box's rounding lifts it by half a metre).
fn slope_at(x: f32) -> f32 {
    -0.5 * x + 0.5
}

#[test]
fn a_caprock_stands_as_a_cliff_where_its_bed_crops_out() {
    let (line, tree, base) = caprock();
    assert_eq!(line.bed, Vec2::new(10.0, -6.0));
    // Across the middle, clear of the sides' fade: walking east at each y, the top drops
    // by at least half the bed within 3 m, near where the bed's base meets the slope.
    // (North of y = 14 the spur stands out from the face.)
    for k in 0..9 {
        let y = -27.5 + 5.0 * k as f32;
        let tops: Vec<f32> = (0..=140)
            .map(|i| top_at(&tree, Vec2::new(-40.0 + 0.5 * i as f32, y), -60.0, 60.0).unwrap())
            .collect();
        let (drop, i) = (3..tops.len())
            .map(|i| (tops[i - 6.min(i)] - tops[i], i))
            .fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a });
        let x = -40.0 + 0.5 * i as f32;
        assert!(drop > 8.0, "y {y}: the top drops by {drop} m at most");
        // Blocks stand where the ground reaches the base within a quarter of the bed (8 m
        // along this slope), a block reaches a joint spacing beyond its middle, and the
        // warp moves faces by a quarter spacing more.
        assert!(
            (x - 12.0).abs() < 18.0,
            "y {y}: the cliff stands at x = {x}"
        );
        // Its top is the bed's top, not the slope's.
        assert!(
            (tops[i - 6] - 10.0).abs() < 2.0,
            "y {y}: the cliff's top at {}",
            tops[i - 6]
        );
    }
    // Upslope, beyond the bed's top, and far downslope the terrain is the slope's.
    for &(x, y) in &[(-60.0, 0.0), (-90.0, 40.0), (80.0, -20.0), (95.0, 70.0)] {
        let p = Vec3::new(x, y, slope_at(x));
        for dz in [-1.0, 0.0, 1.0] {
            let q = p + Vec3::Z * dz;
            assert!(
                (tree.value(q) - base.value(q)).abs() < 1e-6,
                "changed at {q}"
            );
        }
    }
    // Past the region's sides nothing changes; toward them the cliff dies out.
    for i in 0..=40 {
        let x = -20.0 + i as f32;
        for y in [-80.5, 80.5] {
            for z in [-10.0, 0.0, 10.0] {
                let p = Vec3::new(x, y, z);
                assert_eq!(tree.value(p), base.value(p), "changed at {p}");
            }
        }
    }
    let step = |y: f32| {
        (0..=80)
            .map(|i| {
                let x = -20.0 + 0.5 * i as f32;
                top_at(&tree, Vec2::new(x, y), -60.0, 60.0).unwrap() - slope_at(x)
            })
            .fold(0.0f32, f32::max)
    };
    let (middle, side) = (step(0.0), step(77.0));
    assert!(
        middle > 8.0 && side < 0.25 * middle,
        "rises {middle} m mid-line, {side} m at the side"
    );
}

/// A gentle slope (1 in 5 falling east) under a sandstone bed 12 m thick that crops out
/// across it, with a talus apron banked against its foot.
const APRON_SCENE: &str = "(version: 1, seed: 2, \
    root: Landform(name: \"cliff\", seed: 5, cell: 2, region: (min: (-100, -80, -60), max: (100, 80, 60)), \
        base: Transform(name: \"ground\", rotate: (axis: (0, 1, 0), degrees: 11.30993), \
            child: Primitive(shape: Box(center: (0, 0, -100), half_size: (400, 400, 100)), falloff: 1.0)), \
        generator: Caprock(top: 10, thickness: 12, joints: 8, strike: 0, talus: 0, apron: 0.4)))";

#[test]
fn a_caprock_talus_apron_lies_at_its_angle_of_repose_against_the_foot() {
    let (line, tree, base) = caprock_of(APRON_SCENE);
    assert!(
        line.aprons.len() >= 5,
        "{} cones of scree along the cliff",
        line.aprons.len()
    );
    let slope = |x: f32| -0.2 * x + 0.5 * 1.04f32.sqrt();
    let limit = (karstic::landform::REPOSE + 4.0).to_radians().tan();
    let (mut banked, mut steep, mut raised) = (0, 0, 0);
    for a in &line.aprons {
        // Before each cone's apex, out from the face: the ground stands raised by scree.
        let lift = [Vec2::X, -Vec2::X, Vec2::Y, -Vec2::Y]
            .map(|d| a.apex.truncate() + 2.0 * d)
            .into_iter()
            .filter(|&xy| !line.in_block(xy))
            .map(|xy| {
                top_at(&tree, xy, -60.0, 60.0).unwrap() - top_at(&base, xy, -60.0, 60.0).unwrap()
            })
            .fold(0.0f32, f32::max);
        if lift > 0.25 * (a.apex.z - slope(a.apex.x)) {
            raised += 1;
        }
        // Across the cone, clear of the blocks: where scree covers the ground, its surface
        // falls no steeper than the angle of repose (and a few degrees of roughness).
        for i in 0..12 {
            for j in -4..=4 {
                let xy = a.apex.truncate() + Vec2::new(3.0 + 2.0 * i as f32, 2.0 * j as f32);
                if line.in_block(xy) || line.in_block(xy - Vec2::X * 2.0) {
                    continue;
                }
                let top = |xy: Vec2| top_at(&tree, xy, -60.0, 60.0).unwrap();
                let lifted = top(xy) - top_at(&base, xy, -60.0, 60.0).unwrap();
                if lifted < 0.5 {
                    continue;
                }
                let g = Vec2::new(
                    top(xy + Vec2::X * 0.5) - top(xy - Vec2::X * 0.5),
                    top(xy + Vec2::Y * 0.5) - top(xy - Vec2::Y * 0.5),
                )
                .length();
                banked += 1;
                steep += usize::from(g > limit);
            }
        }
    }
    assert!(
        2 * raised >= line.aprons.len(),
        "scree stands before {raised} of {} cones' apices",
        line.aprons.len()
    );
    assert!(banked > 50, "{banked} columns of scree checked");
    assert!(
        steep * 10 <= banked,
        "{steep} of {banked} columns of scree steeper than the angle of repose"
    );
    // Far downslope the ground is the slope's.
    for y in [-40.0, 0.0, 40.0] {
        let p = Vec3::new(90.0, y, slope(90.0));
        assert!(
            (tree.value(p) - base.value(p)).abs() < 1e-6,
            "changed at {p}"
        );
    }
}

#[test]
fn a_caprock_shelter_is_a_hollow_under_a_lip_of_its_bed() {
    let (line, tree, _) = caprock();
    let r = &line.recesses[0];
    let t = line.bed.x - line.bed.y;
    assert!(r.out.x > 0.9, "the shelter looks downslope: {}", r.out);
    // Its floor is the ground before the face, which stands where the bed's base meets the
    // slope.
    assert!(
        (r.mouth.z - slope_at(r.mouth.x)).abs() < 2.0,
        "floor at {}",
        r.mouth.z
    );
    assert!(
        (r.mouth.z - line.bed.y).abs() < 0.25 * t + 4.0,
        "floor at {}",
        r.mouth.z
    );
    let mut open = 0;
    assert_eq!(r.faces.len(), 4, "a piece of face every 6 m");
    for &face in &r.faces {
        let inside = face - r.out * (0.3 * r.size.y);
        // Air in the shelter, rock over it (its lip, the bed) and under it (its floor).
        open += usize::from(tree.value(inside.extend(r.mouth.z + 0.5 * r.size.z)) < ISO);
        let lip = r.mouth.z + r.size.z + 0.5 * (line.bed.x - r.mouth.z - r.size.z);
        assert!(tree.value(inside.extend(lip)) > ISO, "no lip over {inside}");
        // Rock under the floor (or under the slope, where the face steps out and the floor
        // runs above it).
        let floor = r.mouth.z.min(slope_at(inside.x));
        assert!(
            tree.value(inside.extend(floor - 1.5)) > ISO,
            "no floor at {inside}"
        );
    }
    assert!(open >= 3, "the shelter is open at {open} of 4 points");
    // Blocks fallen from the face lie on the slope below the cliff, half sunk.
    assert!(!line.fallen.is_empty());
    for f in &line.fallen {
        let ground = slope_at(f.center.x);
        assert!(
            (f.center.z - ground).abs() < f.half.z + 1.0 || (f.center.z - r.mouth.z).abs() < 1e-3,
            "a block at {} floats over the ground at {ground}",
            f.center
        );
        // Below the cliff: under the bed's base where the bed is whole, under its top
        // where it thins out toward the sides.
        let foot = match f.center.y.abs() < 30.0 {
            true => line.bed.y + 0.25 * t + 1.0,
            false => line.bed.x,
        };
        assert!(
            ground < foot,
            "a block at {} lies above the cliff",
            f.center
        );
    }
}

#[test]
fn a_caprock_spur_window_is_an_arch_under_the_beds_top_layer() {
    let (line, tree, _) = caprock();
    let w = line.windows[0];
    assert_eq!(w.along, Vec2::X);
    // Its floor is the highest ground under the span, its roof the base of the top layer.
    assert!(
        (w.floor.z - slope_at(27.0 - 7.0)).abs() < 1.0,
        "floor at {}",
        w.floor.z
    );
    assert_eq!(w.roof, line.bedding.y);
    // Across the spur's middle: open from above the floor to below the roof, rock over it
    // (the lintel, up to the spur's worn top), and the same all along the middle third of
    // the span.
    let mut open = 0;
    let mut total = 0;
    for i in -2..=2 {
        let xy = w.floor.truncate() + w.along * (i as f32 * w.span / 12.0);
        for k in 1..8 {
            let z = w.floor.z + 1.0 + (w.roof - w.floor.z - 2.0) * k as f32 / 8.0;
            open += usize::from(tree.value(xy.extend(z)) < ISO);
            total += 1;
        }
        let lintel = w.roof + 1.0;
        assert!(tree.value(xy.extend(lintel)) > ISO, "no lintel over {xy}");
    }
    assert!(
        open * 10 >= total * 9,
        "the window is open at {open} of {total} points"
    );
}

#[test]
fn the_bluffs_tunnel_opens_through_its_cliff_and_runs_clear() {
    // trees/jacksboro_bluff.ron: the tunnel's mouth is a recess of the cliff, and the
    // blocks over the tunnel behind it stop above its roof.
    let tree = tree_scene("jacksboro_bluff.ron").compile().unwrap().tree;
    for i in 0..=400 {
        let p = Vec3::new(3800.0, 4950.0, 863.0)
            .lerp(Vec3::new(3480.0, 4972.0, 867.0), i as f32 / 400.0);
        assert!(tree.value(p) < ISO, "rock in the tunnel at {p}");
    }
    // It runs inside the hill: rock above its inner part.
    assert!(tree.value(Vec3::new(3480.0, 4972.0, 886.0)) > ISO);
}

/// A generator's parameters out of scale with its region are errors naming them, given at
/// once (issue 40: `talus: 4294967296` in a caprock, `banks` in a canyon, `band` in sea
/// erosion made even `tree validate` run for hours).
#[test]
fn parameters_out_of_scale_with_the_region_are_refused_at_once() {
    let cases = [
        ("radius: 3", "radius: 4294967296", "`Karst.radius`"),
        ("spacing: 4", "spacing: 0.001", "`Karst.spacing`"),
        (
            "max_spheres: 400",
            "max_spheres: 4000000000",
            "`Karst.max_spheres`",
        ),
    ];
    for (from, to, named) in cases {
        let text = KARST_SCENE.replace(from, to);
        assert_ne!(text, KARST_SCENE);
        let t = std::time::Instant::now();
        let e = scene_file(&text).compile().err().expect("refused");
        let mut chain = e.to_string();
        let mut source = std::error::Error::source(&e);
        while let Some(s) = source {
            chain += &format!(": {s}");
            source = s.source();
        }
        assert!(chain.contains(named), "{to}: {chain}");
        assert!(t.elapsed().as_secs_f32() < 5.0, "{to}: {:?}", t.elapsed());
    }
    // The same checks reach the caprock, canyon, sea and hoodoo generators: the scenes of
    // trees/ with one parameter blown up.
    let scenes = [
        (
            "jacksboro_bluff.ron",
            "talus: 0.25",
            "talus: 4294967296",
            "`Caprock.talus`",
        ),
        (
            "jacksboro_canyon.ron",
            "banks: 80",
            "banks: 4294967296",
            "`Canyon.banks`",
        ),
        (
            "sea_cliffs.ron",
            "band: 8",
            "band: 4294967296",
            "`SeaErosion.band`",
        ),
        (
            "hoodoo_field.ron",
            "size: 7",
            "size: 4294967296",
            "`Hoodoos.size`",
        ),
    ];
    let dir = tempfile::tempdir().unwrap();
    for (scene, from, to, named) in scenes {
        let trees = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees");
        let text = std::fs::read_to_string(trees.join(scene)).unwrap();
        let blown = text.replacen(from, to, 1);
        assert_ne!(blown, text, "{scene}: no `{from}`");
        // Its DEM where the scene's own is.
        let data = format!("\"{}/data/", trees.display());
        let path = dir.path().join(scene);
        std::fs::write(&path, blown.replace("\"data/", &data)).unwrap();
        let t = std::time::Instant::now();
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_karstic"))
            .args(["tree", "validate"])
            .arg(&path)
            .output()
            .unwrap();
        assert!(
            t.elapsed().as_secs_f32() < 30.0,
            "{scene}: {:?}",
            t.elapsed()
        );
        let err = String::from_utf8_lossy(&out.stdout) + String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(named),
            "{scene}: {err}"
        );
    }
}

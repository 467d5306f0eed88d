//! The sea cliff generator on `trees/sea_stacks.ron` (a 35 m plateau of bedded sandstone on
//! a wavy coast): the base's stretched cliff is cleared and rebuilt as joint blocks, the
//! notch cuts into the face at sea level, the platform lies at sea level before it, stacks
//! stand free, caves and arches open under hard beds, boulders lie on the ground, nothing
//! changes past the region, and the expansion is the same on any number of threads.

use std::path::Path;

use glam::{Vec2, Vec3};

use karstic::field::{Aabb, Field, ISO, Resistance, Tree};
use karstic::landform::{Ground, SeaCliff};
use karstic::scene::spec::GeneratorSpec;
use karstic::scene::{NodeSpec, SceneFile};

/// The scene, with `edit` applied to its text.
fn scene(edit: impl Fn(String) -> String) -> SceneFile {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/sea_stacks.ron");
    let text = edit(std::fs::read_to_string(&path).unwrap());
    SceneFile {
        scene: karstic::scene::parse_scene(&text, &path).unwrap(),
        base_dir: path.parent().unwrap().to_path_buf(),
        path,
    }
}

/// The scene's cliff, its tree and its base's tree.
fn cliff(file: &SceneFile) -> (SeaCliff, Tree, Tree) {
    let NodeSpec::Landform(l) = &file.scene.root else {
        panic!("a landform")
    };
    let GeneratorSpec::SeaCliff(spec) = &l.generator else {
        panic!("a sea cliff")
    };
    let mut bare = file.clone();
    bare.scene.root = (*l.base).clone();
    let base = bare.compile().unwrap().tree;
    let geology = file.scene.geology().expect("a geology");
    let rho = |p: Vec3| geology.resistance(p);
    let r = l.region.unwrap();
    let region = Aabb::new(r.min.0, r.max.0);
    let ground = Ground::new(&base, region, l.cell.0, &rho, l.full_seed(file.scene.seed)).unwrap();
    let shape = spec.shape(&ground).unwrap();
    assert_eq!(
        shape,
        spec.shape(&ground).unwrap(),
        "the same seed, the same cliff"
    );
    (shape, file.compile().unwrap().tree, base)
}

fn solid(tree: &Tree, p: Vec3) -> bool {
    tree.value(p) > ISO
}

/// The first solid met walking from `from` along `dir` (0.1 m steps) within `reach`,
/// as a distance.
fn first_rock(tree: &Tree, from: Vec3, dir: Vec3, reach: f32) -> Option<f32> {
    (0..=(reach / 0.1) as usize)
        .map(|i| 0.1 * i as f32)
        .find(|&t| solid(tree, from + dir * t))
}

#[test]
fn a_sea_cliff_rebuilds_the_coast_as_joint_blocks_with_a_platform_and_stacks() {
    let file = scene(|t| t);
    let (c, tree, base) = cliff(&file);
    let sea = c.sea;
    let cliffs: Vec<_> = c.blocks.iter().filter(|b| !b.stack).collect();
    let stacks: Vec<_> = c.blocks.iter().filter(|b| b.stack).collect();
    assert!(cliffs.len() > 30, "{} cliff blocks", cliffs.len());
    assert!(
        (2..=12).contains(&stacks.len()),
        "{} stacks off the headlands",
        stacks.len()
    );
    assert!(c.slabs.len() > 30, "{} platform slabs", c.slabs.len());

    // The base's cliff is gone where the sea now is: over the platform, columns whose
    // base stood as rock 5 m above the sea are air there now, unless a stack stands on them.
    let (mut cleared, mut left) = (0, 0);
    let mut medians = Vec::new();
    for sl in &c.slabs {
        let stacked = stacks.iter().any(|b| {
            c.grid
                .to_frame(sl.center - b.center)
                .abs()
                .cmplt(sl.half + b.half)
                .all()
        });
        if stacked {
            continue;
        }
        let points: Vec<Vec2> = (0..25)
            .map(|k| {
                let f = Vec2::new((k % 5) as f32, (k / 5) as f32) / 4.0 * 1.6 - Vec2::splat(0.8);
                sl.center + c.grid.to_world(f * sl.half)
            })
            .collect();
        // The platform itself, clear of the blocks (a piece, off its lattice, reaches a
        // little under the cliff's foot) and of the boulders on it (as large as a piece):
        // its median top (its roughness is 0.35 m, its fall 2°).
        let under_block = |xy: Vec2| {
            c.blocks.iter().any(|b| {
                c.grid
                    .to_frame(xy - b.center)
                    .abs()
                    .cmplt(b.half + Vec2::splat(2.0))
                    .all()
            })
        };
        let mut tops: Vec<f32> = points
            .iter()
            .filter(|&&xy| {
                !under_block(xy)
                    && c.fallen
                        .iter()
                        .all(|f| f.center.truncate().distance(xy) > f.half.max_element() + 0.5)
            })
            .map(|&xy| top_at(&tree, xy, sea - 14.0, sea + 40.0).unwrap_or(sea - 14.0))
            .collect();
        tops.sort_by(f32::total_cmp);
        if tops.len() >= 5 {
            medians.push(tops[tops.len() / 2]);
        }
        for xy in points {
            let p = xy.extend(sea + 5.0);
            let stack = stacks.iter().any(|b| {
                c.grid
                    .to_frame(xy - b.center)
                    .abs()
                    .cmplt(b.half + Vec2::splat(3.0))
                    .all()
            });
            // Pieces reach a little under the cliff's blocks (each is off its lattice).
            let cliff = cliffs.iter().any(|b| {
                c.grid
                    .to_frame(xy - b.center)
                    .abs()
                    .cmplt(b.half + Vec2::splat(2.0))
                    .all()
            });
            if stack || cliff || !solid(&base, p) {
                continue;
            }
            match solid(&tree, p) {
                false => cleared += 1,
                true => left += 1,
            }
        }
    }
    // Four pieces in five within a metre of the sea (the outer edge goes under it), none
    // a metre over it, none more than six under (an arch cuts its channel to 5 m under its
    // floor).
    let near = medians.iter().filter(|z| (*z - sea).abs() < 1.0).count();
    let (lo, hi) = medians
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &z| {
            (a.min(z), b.max(z))
        });
    assert!(
        near as f32 >= 0.8 * medians.len() as f32 && hi < sea + 1.0 && lo > sea - 6.0,
        "{near} of {} platform pieces within a metre of the sea, from {lo} to {hi} m",
        medians.len()
    );
    assert!(
        cleared >= 5 && left == 0,
        "{cleared} columns cleared, {left} left"
    );

    // The cliff stands to the plateau's height and the stacks free of it: between a stack
    // and its nearest cliff block, the ground is no higher than the platform.
    for s in &stacks {
        let top = top_at(&tree, s.center, sea - 12.0, sea + 50.0).unwrap();
        assert!(
            top > sea + 10.0 && (top - s.top()).abs() < 2.5,
            "a stack at {} stands {top} m (its beds to {})",
            s.center,
            s.top()
        );
        let near = cliffs
            .iter()
            .min_by(|a, b| {
                a.center
                    .distance(s.center)
                    .total_cmp(&b.center.distance(s.center))
            })
            .unwrap();
        let d = near.center - s.center;
        let gap = (1..20)
            .map(|k| s.center + d * (k as f32 / 20.0))
            .map(|xy| top_at(&tree, xy, sea - 12.0, sea + 50.0).unwrap_or(sea - 12.0))
            .fold(f32::INFINITY, f32::min);
        assert!(
            gap < sea + 1.5,
            "the stack at {} joins the cliff ({gap} m)",
            s.center
        );
    }
    for a in &stacks {
        for b in &stacks {
            let d = c.grid.to_frame(a.center - b.center).abs();
            let beside = d.cmplt(a.half + b.half + Vec2::splat(2.0)).all();
            assert!(a == b || !beside, "stacks side by side at {}", a.center);
        }
    }

    // Boulders lie at the foot, on the ground: each sunk into it and standing out of it.
    assert!(c.fallen.len() > 20, "{} boulders", c.fallen.len());
    for f in &c.fallen {
        let xy = f.center.truncate();
        // Rock in its middle (its roughening may thin a flat one there), air over it
        // unless another boulder lies there (fallen blocks pile up).
        let rock = (-4..=4).any(|k| solid(&tree, f.center + Vec3::Z * (0.2 * k as f32 * f.half.z)));
        let over = f.center + Vec3::Z * (f.half.z + 1.5);
        let piled = c
            .fallen
            .iter()
            .any(|g| g != f && g.center.distance(over) < 1.3 * g.half.length());
        assert!(
            rock && (piled || !solid(&tree, over)),
            "a boulder at {} is not on the ground",
            f.center
        );
        assert!(
            cliffs
                .iter()
                .all(|b| c.grid.to_frame(xy - b.center).abs().cmpgt(b.half).any()),
            "a boulder at {xy} lies in the cliff"
        );
    }

    // Past the region's sides nothing changes.
    let r = match &file.scene.root {
        NodeSpec::Landform(l) => l.region.unwrap(),
        _ => unreachable!(),
    };
    for k in 0..200 {
        let t = k as f32 / 199.0;
        let (x, y) = match k % 2 {
            0 => (r.min.0.x - 0.5, r.min.0.y + t * (r.max.0.y - r.min.0.y)),
            _ => (r.max.0.x + 0.5, r.min.0.y + t * (r.max.0.y - r.min.0.y)),
        };
        for z in [-10.0, 0.0, 20.0, 34.0] {
            let p = Vec3::new(x, y, z);
            assert_eq!(tree.value(p), base.value(p), "changed at {p}");
        }
    }
}

#[test]
fn the_sea_cuts_a_notch_caves_and_arches_where_its_effect_is_strongest() {
    let (c, tree, _) = cliff(&scene(|t| t));
    let (flat, flat_tree, _) = cliff(&scene(|t| t.replace("notch: 3", "notch: 0")));
    assert!(flat.notches.is_empty(), "no notch asked, none cut");
    // At the notch's height, the face stands farther back than without a notch, by at
    // least a third of the notch's depth on most sides (the beds' rounding and roughness
    // take up some of it); 6 m above it, the face is the same.
    let (mut deeper, mut sides) = (0, 0);
    for n in c.notches.iter().filter(|n| n.depth > 1.0) {
        let out = n.out.extend(0.0);
        // Clear of caves and arches, which open the face at the same height.
        let by_hollow = c
            .caves
            .iter()
            .any(|r| r.mouth.truncate().distance(n.center.truncate()) < 0.5 * r.size.x + 4.0)
            || c.arches
                .iter()
                .any(|a| a.floor.truncate().distance(n.center.truncate()) < a.span + a.width);
        if by_hollow {
            continue;
        }
        // 0.6 m over the notch's deepest cut, clear of the platform's roughness.
        let from = n.center + out * 8.0 + Vec3::Z * 0.6;
        let (Some(with), Some(without)) = (
            first_rock(&tree, from, -out, 20.0),
            first_rock(&flat_tree, from, -out, 20.0),
        ) else {
            continue;
        };
        sides += 1;
        if with - without >= n.depth / 3.0 {
            deeper += 1;
        }
        let above = from + Vec3::Z * 6.0;
        assert_eq!(
            first_rock(&tree, above, -out, 20.0),
            first_rock(&flat_tree, above, -out, 20.0),
            "the notch at {} reaches 6 m up",
            n.center
        );
    }
    let pieces = c.notches.iter().filter(|n| n.depth > 1.0).count();
    assert!(sides >= 10, "{sides} notched sides probed of {pieces}");
    assert!(
        deeper as f32 >= 0.8 * sides as f32,
        "the face recedes at the notch on {deeper} of {sides} sides"
    );

    // Caves and arches: open at mid-height, rock over their roofs, roofs under hard beds.
    assert!(
        !c.caves.is_empty() && !c.arches.is_empty(),
        "{} caves, {} arches",
        c.caves.len(),
        c.arches.len()
    );
    let geology = scene(|t| t).scene.geology().unwrap();
    let rho = |p: Vec3| geology.resistance(p);
    for r in &c.caves {
        let mid = r.mouth + Vec3::Z * (0.5 * r.size.z) - r.out.extend(0.0) * 2.0;
        assert!(!solid(&tree, mid), "the cave at {} is closed", r.mouth);
        let roof = r.mouth.z + r.size.z;
        assert!(
            solid(&tree, mid + Vec3::Z * (roof + 1.5 - mid.z)),
            "no rock over the cave at {}",
            r.mouth
        );
    }
    for a in &c.arches {
        let through = a.along.perp().extend(0.0);
        let mid = a.floor + Vec3::Z * (0.5 * (a.roof - a.floor.z));
        for t in [-0.6, -0.3, 0.0, 0.3, 0.6] {
            let p = mid + through * (t * a.width);
            assert!(!solid(&tree, p), "the arch at {} is closed at {p}", a.floor);
        }
        let lintel = a.floor.truncate().extend(a.roof + 1.5);
        assert!(
            solid(&tree, lintel),
            "no lintel over the arch at {}",
            a.floor
        );
    }
    // Roofs at the base of a hard bed: harder rock just over them than just under.
    let roofs = c
        .caves
        .iter()
        .map(|r| (r.mouth.truncate() - r.out * 3.0).extend(r.mouth.z + r.size.z))
        .chain(c.arches.iter().map(|a| a.floor.truncate().extend(a.roof)));
    let (mut under_hard, mut all) = (0, 0);
    for p in roofs {
        all += 1;
        if rho(p + Vec3::Z * 0.75) > rho(p - Vec3::Z * 0.75) {
            under_hard += 1;
        }
    }
    assert!(
        under_hard as f32 >= 0.75 * all as f32,
        "{under_hard} of {all} roofs under a harder bed"
    );
}

#[test]
fn a_sea_cliff_expands_alike_on_any_number_of_threads() {
    let file = scene(|t| t);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| file.expand().unwrap().to_ron())
    };
    let one = run(1);
    assert!(one.contains("coast-clears"), "the base's coast is cleared");
    assert_eq!(one, run(3));
}

/// The height of the highest solid at `xy` between `lo` and `hi` (a scan down in 0.5 m
/// steps, then bisection), `None` when the column is air.
fn top_at(tree: &Tree, xy: Vec2, lo: f32, hi: f32) -> Option<f32> {
    let mut z = hi;
    while z > lo {
        if solid(tree, xy.extend(z - 0.5)) {
            let (mut a, mut b) = (z - 0.5, z);
            for _ in 0..16 {
                let m = 0.5 * (a + b);
                match solid(tree, xy.extend(m)) {
                    true => a = m,
                    false => b = m,
                }
            }
            return Some(a);
        }
        z -= 0.5;
    }
    None
}

/// A stack's beds are rounded at their vertical edges (the sea and the weather attack a
/// corner from two sides), not square: at the root bed's mid height, the corners of its
/// footprint are air while its faces are rock.
#[test]
fn sea_stacks_wear_round_at_the_corners() {
    let file = scene(|t| t);
    let (c, _, _) = cliff(&file);
    // The blocks' rocks alone, unwarped: each stack stands free of every other rock.
    let mut bare = file.clone();
    bare.scene.root = NodeSpec::Blend(karstic::scene::spec::Nary {
        name: None,
        children: c.block_rocks(10.0), // the scene's `joints: 10`
    });
    let rocks = bare.compile().unwrap().tree;
    let (mut corners, mut faces) = (Vec::new(), Vec::new());
    for b in c.blocks.iter().filter(|b| b.stack) {
        let z = 0.5 * (b.beds[0].z.x + b.beds[0].z.y);
        let at = |q: Vec2| {
            solid(
                &rocks,
                c.grid.to_world(c.grid.to_frame(b.center) + q).extend(z),
            )
        };
        let h = b.half;
        let corner =
            [(1., 1.), (1., -1.), (-1., 1.), (-1., -1.)].map(|(u, v)| at(h * Vec2::new(u, v)));
        corners.extend(corner);
        let inside = h - Vec2::splat(0.2);
        faces.extend([
            at(Vec2::new(inside.x, 0.0)),
            at(Vec2::new(-inside.x, 0.0)),
            at(Vec2::new(0.0, inside.y)),
            at(Vec2::new(0.0, -inside.y)),
        ]);
    }
    let share =
        |v: &[bool], want: bool| v.iter().filter(|&&s| s == want).count() as f32 / v.len() as f32;
    assert!(!corners.is_empty());
    assert!(
        share(&faces, true) > 0.9,
        "faces rock: {}",
        share(&faces, true)
    );
    assert!(
        share(&corners, false) > 0.7,
        "corners air: {}",
        share(&corners, false)
    );
}

//! Issue 16, heightfield sources: erosion (stream power at steady state against the
//! analytic slope–area relation, thermal erosion against its talus angle), generators'
//! determinism across thread counts, and the `generate` / `erode` commands.

use std::process::Command;

use glam::Vec2;
use karstic::analysis::flow::FlowGraph;
use karstic::dem::Heightfield;
use karstic::erosion::{Eroder, ErosionStage, StreamPowerSpec, ThermalSpec};
use karstic::procedural::GenerateSpec;
use karstic::value::{NonNegative, Positive};

use crate::common::Rng;

const BUDGET: u64 = 1 << 30;

/// Uniform noise in `[0, amplitude)` on an `n × n` grid of `cell`-metre cells.
fn noise(n: usize, cell: f32, amplitude: f32, seed: u64) -> Heightfield {
    let mut rng = Rng(seed);
    let z = (0..n * n).map(|_| amplitude * rng.f32()).collect();
    Heightfield::new(n, n, Vec2::ZERO, Vec2::splat(cell), z).unwrap()
}

/// Runs uplift and stream power (no diffusion) to steady state, then checks every
/// non-base sample's slope to its receiver against `S = (U/K)^{1/n} A^{−m/n}` (Braun and
/// Willett 2013, eq. 4 at `∂h/∂t = 0`).
fn steady_state_matches_slope_area(n_exp: f32) {
    let (n, cell) = (48, 100.0f32);
    let spec = StreamPowerSpec {
        steps: 0,
        dt: Positive(5e4),
        uplift: NonNegative(1e-3),
        k: Positive(2e-4),
        m: NonNegative(0.4),
        n: Positive(n_exp),
        diffusion: NonNegative(0.0),
        deposition: NonNegative(0.0),
    };
    let mut e = Eroder::new(&noise(n, cell, 1.0, 5), BUDGET).unwrap();
    let mut change = f32::INFINITY;
    let mut steps = 0;
    while change > 1e-4 && steps < 20_000 {
        let before = e.samples().to_vec();
        e.stream_power_step(&spec);
        change = before
            .iter()
            .zip(e.samples())
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f32::max);
        steps += 1;
    }
    assert!(
        change <= 1e-4,
        "n = {n_exp}: no steady state after {steps} steps ({change} m)"
    );
    let z = e.samples();
    // The step routes water over the uplifted surface (base level does not rise): route
    // the same way here, so that each sample has the receiver the solver used.
    let rise = spec.uplift.get() * spec.dt.get();
    let uplifted: Vec<f32> = (0..z.len())
        .map(|k| {
            z[k] + if FlowGraph::is_base_level(z, n, n, k) {
                0.0
            } else {
                rise
            }
        })
        .collect();
    let mut g = FlowGraph::new();
    assert_eq!(
        g.update(&uplifted, n, n, cell, cell),
        0,
        "pits at steady state"
    );
    let mut area = Vec::new();
    g.accumulate(cell * cell, &mut area);
    let (u, k, m) = (1e-3f64, 2e-4f64, 0.4f64);
    let mut checked = 0;
    let mut worst = 0.0f64;
    for &s in g.stack() {
        let s = s as usize;
        let r = g.receivers()[s] as usize;
        if r == s {
            continue;
        }
        let slope = f64::from(z[s] - z[r]) / f64::from(g.lengths()[s]);
        let want =
            (u / k).powf(1.0 / f64::from(n_exp)) * f64::from(area[s]).powf(-m / f64::from(n_exp));
        worst = worst.max((slope - want).abs() / want);
        checked += 1;
    }
    assert!(checked > 40 * 40, "{checked} samples checked");
    assert!(
        worst < 0.01,
        "n = {n_exp}: worst relative slope error {worst}"
    );
    // The relief is the analytic one's order: not a flat grid that trivially passes.
    let top = z.iter().copied().fold(0.0, f32::max);
    assert!(top > 50.0, "relief {top} m");
}

#[test]
fn stream_power_steady_state_follows_the_slope_area_relation() {
    steady_state_matches_slope_area(1.0);
}

#[test]
fn stream_power_steady_state_follows_the_slope_area_relation_for_n_above_one() {
    steady_state_matches_slope_area(1.5);
}

#[test]
fn thermal_erosion_leaves_no_slope_above_the_talus_angle_and_keeps_the_mass() {
    let (n, cell) = (40, 1.0f32);
    let hf = noise(n, cell, 20.0, 9);
    let mut e = Eroder::new(&hf, BUDGET).unwrap();
    let spec = ThermalSpec {
        talus: Positive(30.0),
        tolerance: Positive(0.01),
        max_iterations: 200_000,
    };
    let report = e.thermal(&spec);
    assert!(report.iterations > 10, "{report:?}");
    assert!(report.max_excess <= 0.01, "{report:?}");
    let z = e.samples();
    let tan = 30f32.to_radians().tan();
    let mut worst = f32::NEG_INFINITY;
    for j in 0..n {
        for i in 0..n {
            for (di, dj) in [(1i32, 0i32), (0, 1), (1, 1), (1, -1)] {
                let (a, b) = (i as i32 + di, j as i32 + dj);
                if a < 0 || b < 0 || a as usize >= n || b as usize >= n {
                    continue;
                }
                let dist = cell * ((di * di + dj * dj) as f32).sqrt();
                let drop = (z[i + n * j] - z[a as usize + n * b as usize]).abs();
                worst = worst.max(drop - tan * dist);
            }
        }
    }
    assert!(
        worst <= 0.01 + 1e-4,
        "a slope exceeds the talus by {worst} m"
    );
    let sum = |v: &[f32]| v.iter().map(|&x| f64::from(x)).sum::<f64>();
    let (before, after) = (sum(hf.samples()), sum(z));
    assert!((before - after).abs() < 1e-3 * before, "{before} → {after}");
}

/// Every generator, small, with an erosion stage on one of them.
const RECIPES: &[&str] = &[
    "(kind: Fbm((wavelength: 300)), size: (67, 45), cell: 10, relief: 100, seed: 3)",
    "(kind: Ridged((wavelength: 300, octaves: 6)), size: (67, 45), cell: 10, relief: 100, seed: 3)",
    "(kind: Hybrid((wavelength: 300)), size: (67, 45), cell: 10, relief: 100, seed: 3)",
    "(kind: DiamondSquare((roughness: 0.7)), size: (67, 45), cell: 10, relief: 100, seed: 3)",
    "(kind: Faults((count: 50, width: 30)), size: (67, 45), cell: 10, relief: 100, seed: 3)",
    "(kind: Deposition((series: 3, particles: 2000, radius: 5)), size: (67, 45), cell: 10, relief: 100, seed: 3)",
    "(kind: Ridged((wavelength: 300)), size: (67, 45), cell: 10, relief: 100, seed: 3,
      erosion: [StreamPower((steps: 20, dt: 20000, uplift: 0.001, k: 2e-4, diffusion: 0.01)),
                Thermal((talus: 40))])",
];

fn build_with_threads(spec: &GenerateSpec, threads: usize) -> Vec<u32> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let hf = pool.install(|| spec.build(BUDGET).unwrap());
    hf.samples().iter().map(|v| v.to_bits()).collect()
}

#[test]
fn generators_are_deterministic_whatever_the_thread_count_and_follow_the_seed() {
    for text in RECIPES {
        let spec: GenerateSpec = ron::from_str(text).unwrap();
        let one = build_with_threads(&spec, 1);
        assert_eq!(one, build_with_threads(&spec, 4), "{text}");
        let mut other = spec.clone();
        other.seed = 4;
        assert_ne!(
            one,
            build_with_threads(&other, 1),
            "{text}: the seed changes nothing"
        );
        let z: Vec<f32> = one.iter().map(|&b| f32::from_bits(b)).collect();
        let (lo, hi) = z
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        assert!(
            lo >= -1e-3 && hi <= 100.0 + 1e-3 && hi - lo > 10.0,
            "{text}: {lo} … {hi}"
        );
    }
}

/// The ridged generator draws no straight crease across its grid: on the reproducer of
/// issue 40 item 18 (257², 20 m cells, wavelength 1500 m), over several seeds, no row and
/// no column has a mean curvature (|second difference|) past 1.8 times the median row's
/// (column's). Unwarped, the crests gathered on the noise lattice's planes: seed 7 had a
/// row at 2.22×, seed 3 a column at 2.04×.
#[test]
fn the_ridged_generator_draws_no_straight_crease_across_the_grid() {
    let worst = |z: &[f32], n: usize, along_rows: bool| -> f64 {
        let at = |i: usize, j: usize| {
            f64::from(if along_rows {
                z[i * n + j]
            } else {
                z[j * n + i]
            })
        };
        let means: Vec<f64> = (1..n - 1)
            .map(|i| {
                (0..n)
                    .map(|j| (at(i + 1, j) - 2.0 * at(i, j) + at(i - 1, j)).abs())
                    .sum::<f64>()
                    / n as f64
            })
            .collect();
        let mut sorted = means.clone();
        sorted.sort_by(f64::total_cmp);
        means.iter().copied().fold(0.0, f64::max) / sorted[sorted.len() / 2]
    };
    for seed in [0, 3, 7, 11] {
        let text = format!(
            "(kind: Ridged((wavelength: 1500)), size: (257, 257), cell: 20, relief: 600, \
             seed: {seed})"
        );
        let spec: GenerateSpec = ron::from_str(&text).unwrap();
        let hf = spec.build(BUDGET).unwrap();
        for along_rows in [true, false] {
            let w = worst(hf.samples(), 257, along_rows);
            assert!(
                w <= 1.8,
                "seed {seed}: a {} with {w:.2}× the median curvature",
                if along_rows { "row" } else { "column" }
            );
        }
    }
}

#[test]
fn recipes_refuse_bad_values_naming_the_field() {
    let big = "(kind: Fbm((wavelength: 300)), size: (200000, 200000), cell: 10, relief: 100)";
    let e = ron::from_str::<GenerateSpec>(big)
        .unwrap()
        .build(BUDGET)
        .unwrap_err();
    assert!(e.to_string().contains("generate.size"), "{e}");
    let thin = "(kind: Fbm((wavelength: 300)), size: (1, 20), cell: 10, relief: 100)";
    let e = ron::from_str::<GenerateSpec>(thin)
        .unwrap()
        .build(BUDGET)
        .unwrap_err();
    assert!(e.to_string().contains("generate.size"), "{e}");
    let steep = "(kind: Fbm((wavelength: 300)), size: (9, 9), cell: 10, relief: 100,
                  erosion: [Thermal((talus: 95))])";
    let e = ron::from_str::<GenerateSpec>(steep)
        .unwrap()
        .build(BUDGET)
        .unwrap_err();
    assert!(e.to_string().contains("Thermal.talus"), "{e}");
    let e = ron::from_str::<GenerateSpec>(
        "(kind: Fbm((wavelength: -3)), size: (9, 9), cell: 10, relief: 1)",
    )
    .unwrap_err();
    assert!(e.to_string().contains("> 0"), "{e}");
    assert!(
        ErosionStage::Thermal(ThermalSpec {
            talus: Positive(45.0),
            tolerance: Positive(0.1),
            max_iterations: 1
        })
        .validate()
        .is_ok()
    );
}

/// Hydraulic erosion with transport and deposition (issue 38): a step of the same stream
/// power on a ridged range with the deposition coefficient `G = 1` keeps part of what it
/// cuts, as fill on the valley floors (the samples of most drainage area); the ridges,
/// which nothing flows into, are cut alike.
#[test]
fn deposition_fills_the_valley_floors() {
    let g: GenerateSpec = ron::from_str(
        "(kind: Ridged((wavelength: 600)), size: (65, 65), cell: 20, relief: 120, seed: 3)",
    )
    .unwrap();
    let hf = g.build(BUDGET).unwrap();
    let run = |deposition: f32| {
        let spec: StreamPowerSpec = ron::from_str(&format!(
            "(steps: 0, dt: 20000, k: 5e-4, deposition: {deposition})"
        ))
        .unwrap();
        let mut e = Eroder::new(&hf, BUDGET).unwrap();
        e.stream_power_step(&spec);
        e.samples().to_vec()
    };
    let (bare, filled) = (run(0.0), run(1.0));
    let mut graph = FlowGraph::new();
    let mut z = bare.clone();
    karstic::analysis::flow::fill_in_place(&mut z, 65, 65);
    graph.update(&z, 65, 65, 20.0, 20.0);
    let mut area = Vec::new();
    graph.accumulate(400.0, &mut area);
    let mut order: Vec<usize> = (0..area.len()).collect();
    order.sort_by(|&a, &b| area[a].total_cmp(&area[b]));
    let mean_rise =
        |ks: &[usize]| ks.iter().map(|&k| filled[k] - bare[k]).sum::<f32>() / ks.len() as f32;
    let n = order.len();
    // the ridges: samples nothing flows into (their own cell only)
    let ridges: Vec<usize> = order
        .iter()
        .copied()
        .filter(|&k| area[k] <= 400.0)
        .collect();
    let floors = &order[n - n / 20..];
    let (r, f) = (mean_rise(&ridges), mean_rise(floors));
    assert!(f > 0.5, "the valley floors rose {f} m with deposition");
    assert!(
        r.abs() < 0.2 * f,
        "the ridges moved {r} m, the floors {f} m"
    );
    let volume = |z: &[f32]| z.iter().map(|&v| f64::from(v)).sum::<f64>();
    assert!(volume(&filled) > volume(&bare), "deposition kept nothing");
}

#[test]
fn generate_then_erode_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let raw = dir.path().join("raw.tif");
    let eroded = dir.path().join("eroded.tif");
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_karstic"))
            .args(args)
            .output()
            .unwrap()
    };
    let o = run(&[
        "generate",
        "hybrid",
        "-o",
        raw.to_str().unwrap(),
        "--size",
        "65",
        "49",
        "--cell",
        "20",
        "--seed",
        "5",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run(&[
        "erode",
        raw.to_str().unwrap(),
        "-o",
        eroded.to_str().unwrap(),
        "--steps",
        "10",
        "--diffusion",
        "0.01",
        "--talus",
        "35",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let opts = karstic::dem::ReadOptions::default();
    let a = karstic::dem::read(&raw, &opts).unwrap().heightfield;
    let b = karstic::dem::read(&eroded, &opts).unwrap().heightfield;
    assert_eq!((b.nx(), b.ny(), b.cell()), (65, 49, Vec2::splat(20.0)));
    assert_ne!(a.samples(), b.samples());
    // Errors name the flag and refuse to overwrite the input.
    let o = run(&["erode", raw.to_str().unwrap(), "-o", raw.to_str().unwrap()]);
    assert!(!o.status.success());
    let o = run(&[
        "erode",
        raw.to_str().unwrap(),
        "-o",
        eroded.to_str().unwrap(),
        "--talus",
        "90",
    ]);
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("--talus"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = run(&[
        "generate",
        "fbm",
        "-o",
        raw.to_str().unwrap(),
        "--size",
        "100000",
        "100000",
        "--max-memory",
        "1G",
    ]);
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("memory budget"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

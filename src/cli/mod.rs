//! The command line: flags (clap) over the library. Each subcommand lives in its own file.

mod build;
mod curves;
mod dem;
mod edit;
mod erode;
mod eval;
mod generate;
mod geology;
mod heightmap;
mod masks;
mod render;
mod run;
mod sample;
mod tile;
mod tin;
mod tree;

use std::path::Path;

use clap::{Args, Parser, Subcommand};
use glam::Vec3;
use karstic::field::Aabb;
use karstic::io::parse_byte_size;

/// karstic: implicit terrain modelling — DEMs amplified with caves, arches and overhangs.
#[derive(Parser, Debug)]
#[command(name = "karstic", version, about)]
pub struct Cli {
    /// Subcommand.
    #[command(subcommand)]
    command: Command,
}

/// All subcommands.
#[derive(Subcommand, Debug)]
enum Command {
    /// The main job: mesh a tree's region and render a preview, timing every stage.
    Run(run::RunArgs),
    /// Build a mesh (.glb, .gltf, .obj, .ply) from a tree with bound-pruned Marching Cubes.
    Build(build::BuildArgs),
    /// Inspect and convert DEMs.
    Dem(dem::DemArgs),
    /// Validate, inspect and edit tree files.
    Tree(tree::TreeArgs),
    /// The interactive editor: outline, inspector, live preview, placement on the terrain.
    Edit(edit::EditArgs),
    /// Print field values and gradients at points (CSV `x,y,z` from a file or stdin).
    Eval(eval::EvalArgs),
    /// Sample a tree's field on a grid as a float32 .npy with a JSON sidecar.
    Sample(sample::SampleArgs),
    /// Render a PNG preview of a tree by tracing its implicit surface.
    Render(render::RenderArgs),
    /// Write texture masks (slope, rock, cave/overhang, flow) as PNGs over the DEM frame.
    Masks(masks::MasksArgs),
    /// Feature Curves: run the voxel pipeline on a `FeatureVolume` file.
    Curves(curves::CurvesArgs),
    /// Write the top surface of a tree's 3D terrain as a georeferenced DEM (.tif, .png, .asc).
    Heightmap(heightmap::HeightmapArgs),
    /// Triangulate a DEM or a tree's heightmap within a vertical error (greedy insertion).
    Tin(tin::TinArgs),
    /// Large terrains: plan a quadtree of tiles, mesh each (an array job), merge into 3D Tiles.
    Tile(tile::TileArgs),
    /// Write a procedural heightfield (fBm, multifractals, diamond-square, faults, deposition).
    Generate(generate::GenerateArgs),
    /// Erode a DEM: uplift and stream power (with hillslope diffusion), then thermal erosion.
    Erode(erode::ErodeArgs),
    /// Inspect a scene's geology: vertical sections of the rock resistance.
    Geology(geology::GeologyArgs),
}

/// The `--max-memory` flag of every command that reads or builds grids and images.
#[derive(Args, Debug, Clone, Copy)]
struct Budget {
    /// Refuse grids, images and files needing more memory than this: bytes, or a number
    /// with a unit — K, M, G, T (or KiB … TiB) are powers of 1024, KB, MB, GB, TB powers
    /// of 1000 (`8G`, `512MiB`, `1.5GB`).
    #[arg(long = "max-memory", value_name = "SIZE", value_parser = parse_byte_size,
          default_value = "8GiB")]
    max_memory: u64,
}

/// The parser of every number flag: a finite number (NaN and the infinities name no
/// place, size or rate, and would only fail later, under another name).
fn finite(s: &str) -> Result<f32, String> {
    let v: f32 = s
        .trim()
        .parse()
        .map_err(|_| format!("{s:?} is not a number"))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("{s} is not a finite number"))
    }
}

/// The box of a `--box XMIN YMIN ZMIN XMAX YMAX ZMAX` flag (clap checks there are six):
/// a minimum past its maximum is refused, not swapped (a typo would move the box).
fn corners(v: &[f32]) -> anyhow::Result<Aabb> {
    if let Some(a) = (0..3).find(|&a| v[a] > v[a + 3]) {
        anyhow::bail!(
            "--box: the minimum {} {} is past the maximum {}",
            ["x", "y", "z"][a],
            v[a],
            v[a + 3]
        );
    }
    Ok(Aabb::new(
        Vec3::new(v[0], v[1], v[2]),
        Vec3::new(v[3], v[4], v[5]),
    ))
}

/// Prints `notices` (a DEM's units, a fallback taken) to standard error, unless `quiet`.
fn notify(notices: &[String], quiet: bool) {
    if !quiet {
        for n in notices {
            eprintln!("notice: {n}");
        }
    }
}

/// Loads a tree file, refuses `outputs` that are among the files it reads (the tree, its
/// DEMs and curve files), and compiles it within `budget` bytes, printing the loader's
/// notices unless `quiet`.
fn load_tree(
    path: &Path,
    budget: u64,
    outputs: &[impl AsRef<Path>],
    quiet: bool,
) -> anyhow::Result<karstic::field::Tree> {
    Ok(load_compiled(path, budget, outputs, quiet)?.1.tree)
}

/// [`load_tree`], keeping the file and what the compiler knows besides the tree (its
/// terrain).
fn load_compiled(
    path: &Path,
    budget: u64,
    outputs: &[impl AsRef<Path>],
    quiet: bool,
) -> anyhow::Result<(karstic::scene::SceneFile, karstic::compile::Compiled)> {
    let file = karstic::scene::load(path)?;
    karstic::io::check_outputs(&file.inputs(), outputs)?;
    let working = karstic::io::spinner("compiling", quiet);
    let compiled = file.compile_with(budget)?;
    working.finish_and_clear();
    notify(&compiled.notices, quiet);
    Ok((file, compiled))
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Run(a) => run::run(a),
        Command::Build(a) => build::run(a),
        Command::Dem(a) => dem::run(a),
        Command::Tree(a) => tree::run(a),
        Command::Edit(a) => edit::run(a),
        Command::Eval(a) => eval::run(a),
        Command::Sample(a) => sample::run(a),
        Command::Render(a) => render::run(a),
        Command::Masks(a) => masks::run(a),
        Command::Curves(a) => curves::run(a),
        Command::Heightmap(a) => heightmap::run(a),
        Command::Tin(a) => tin::run(a),
        Command::Tile(a) => tile::run(a),
        Command::Generate(a) => generate::run(a),
        Command::Erode(a) => erode::run(a),
        Command::Geology(a) => geology::run(a),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_budget_is_the_library_default() {
        let cli = Cli::try_parse_from(["karstic", "render", "t.ron", "-o", "t.png"]).unwrap();
        let Command::Render(a) = cli.command else {
            panic!("parsed as {:?}", cli.command)
        };
        assert_eq!(a.budget.max_memory, karstic::io::DEFAULT_MEMORY_BUDGET);
    }

    #[test]
    fn every_max_memory_takes_units() {
        for argv in [
            &[
                "karstic",
                "build",
                "t.ron",
                "-o",
                "t.glb",
                "--max-memory",
                "8G",
            ][..],
            &[
                "karstic",
                "render",
                "t.ron",
                "-o",
                "t.png",
                "--max-memory",
                "8G",
            ],
            &[
                "karstic",
                "sample",
                "t.ron",
                "--res",
                "2",
                "2",
                "2",
                "-o",
                "t.npy",
                "--max-memory",
                "8G",
            ],
            &["karstic", "dem", "info", "d.tif", "--max-memory", "8G"],
            &["karstic", "curves", "build", "c.ron", "--max-memory", "8G"],
            &["karstic", "run", "t.ron", "--max-memory", "8G"],
            &["karstic", "eval", "t.ron", "--max-memory", "8G"],
        ] {
            Cli::try_parse_from(argv).unwrap_or_else(|e| panic!("{argv:?}: {e}"));
            let mut bad = argv.to_vec();
            *bad.last_mut().unwrap() = "8X";
            assert!(Cli::try_parse_from(&bad).is_err(), "{bad:?}");
        }
    }
}

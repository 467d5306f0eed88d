//! Mesh every tree file of a folder in parallel: each `.ron` is loaded, compiled and
//! polygonized on rayon's pool (the mesher itself is parallel too, and its output does
//! not depend on the thread count), then written as `<name>.glb`. A file that fails is
//! reported and the others go on; the exit status says whether any failed. An empty tree
//! (a Feature Volume of guidance curves alone, `trees/curves/guidance.ron`) has nothing
//! to mesh and is said so.
//!
//! ```sh
//! cargo run --release --example batch_polygonize -- [FOLDER] [OUT_DIR] [RESOLUTION]
//! ```
//!
//! Defaults: `trees/curves`, a folder in the system's temporary folder, and 64 cells
//! along the longest side of each tree's support box.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use karstic::field::Field;
use karstic::mesh::export::{self, ExportOptions};
use karstic::mesh::{GridSpec, MeshOptions, polygonize};
use rayon::prelude::*;

/// Loads, compiles and meshes one tree file; returns a line for the report.
fn mesh_one(tree_path: &Path, out_dir: &Path, resolution: usize) -> anyhow::Result<String> {
    let start = Instant::now();
    let tree = karstic::scene::load(tree_path)?.compile()?.tree;
    if tree.support().is_empty() {
        return Ok("the field is zero everywhere: nothing to mesh".into());
    }
    let grid = GridSpec::with_resolution(&tree.support(), resolution)?;
    let (mesh, _) = polygonize(&tree, &grid, &MeshOptions::default())?;
    let name = tree_path.file_stem().context("a file name")?;
    let out = out_dir.join(name).with_extension("glb");
    export::write(&mesh, &out, &ExportOptions::default())?;
    Ok(format!(
        "{} triangles in {:.2} s → {}",
        mesh.triangles.len(),
        start.elapsed().as_secs_f64(),
        out.display()
    ))
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let folder = PathBuf::from(args.next().unwrap_or_else(|| "trees/curves".into()));
    let out_dir = args.next().map_or_else(
        || std::env::temp_dir().join("karstic-examples/batch"),
        PathBuf::from,
    );
    let resolution: usize = match args.next() {
        Some(s) => s
            .parse()
            .with_context(|| format!("RESOLUTION: expected cells, found {s:?}"))?,
        None => 64,
    };

    // The tree files, sorted so the report comes out in the same order every run.
    let mut trees: Vec<PathBuf> = std::fs::read_dir(&folder)
        .with_context(|| format!("reading {}", folder.display()))?
        .map(|entry| entry.map(|e| e.path()))
        .collect::<Result<_, _>>()
        .with_context(|| format!("reading {}", folder.display()))?;
    trees.retain(|p| p.extension().is_some_and(|e| e == "ron"));
    trees.sort();
    std::fs::create_dir_all(&out_dir).with_context(|| format!("creating {}", out_dir.display()))?;

    let start = Instant::now();
    let results: Vec<anyhow::Result<String>> = trees
        .par_iter()
        .map(|tree| mesh_one(tree, &out_dir, resolution))
        .collect();
    let mut failed = 0;
    for (tree, result) in trees.iter().zip(&results) {
        match result {
            Ok(line) => println!("{}: {line}", tree.display()),
            Err(e) => {
                failed += 1;
                eprintln!("{}: {e:#}", tree.display());
            }
        }
    }
    println!(
        "{} of {} trees meshed in {:.2} s on {} threads",
        trees.len() - failed,
        trees.len(),
        start.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
    anyhow::ensure!(failed == 0, "{failed} tree files failed");
    Ok(())
}

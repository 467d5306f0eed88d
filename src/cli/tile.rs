//! `karstic tile plan | run | merge`: a large terrain as a quadtree of tiles, meshed as an
//! array job and merged into a 3D Tiles tileset.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::{Args, Subcommand};
use karstic::field::Field;
use karstic::tiles::{self, Loaded, Plan};

use super::Budget;

/// Arguments of `karstic tile`.
#[derive(Args, Debug)]
pub(super) struct TileArgs {
    #[command(subcommand)]
    command: TileCommand,
}

#[derive(Subcommand, Debug)]
enum TileCommand {
    /// Plan a quadtree of tiles over a tree's region: writes DIR/plan.json.
    Plan(PlanArgs),
    /// Mesh one tile (or all): its index from --index, or from the array job's variable.
    Run(RunArgs),
    /// Write DIR/tileset.json (3D Tiles 1.1) over the tiles that ran.
    Merge(MergeArgs),
}

#[derive(Args, Debug)]
struct PlanArgs {
    /// Tree file (.ron).
    tree: PathBuf,
    /// Cells per tile side at every level (a multiple of 32).
    #[arg(long, value_name = "CELLS", default_value_t = 256)]
    tile: usize,
    /// Levels of detail; each coarser level doubles the cell size.
    #[arg(long, default_value_t = 1)]
    levels: usize,
    /// Finest cell size in metres (default: the job's `cell`, else 1/256 of the region).
    #[arg(value_parser = super::finite, long)]
    cell: Option<f32>,
    /// Region to tile (default: the tree's support box).
    #[arg(value_parser = super::finite, long = "box", num_args = 6, value_names = ["XMIN", "YMIN", "ZMIN", "XMAX", "YMAX", "ZMAX"], allow_negative_numbers = true, conflicts_with = "job_region")]
    bbox: Option<Vec<f32>>,
    /// Tile the job's region instead of the tree's support box.
    #[arg(long)]
    job_region: bool,
    /// Tiles folder.
    #[arg(short, long)]
    output: PathBuf,
    /// Memory budget.
    #[command(flatten)]
    budget: Budget,
}

#[derive(Args, Debug)]
struct RunArgs {
    /// Tiles folder (with its plan.json).
    dir: PathBuf,
    /// Tile index (default: SLURM_ARRAY_TASK_ID, JOB_COMPLETION_INDEX or
    /// AWS_BATCH_JOB_ARRAY_INDEX).
    #[arg(long, conflicts_with = "all")]
    index: Option<usize>,
    /// Run every tile of the plan: as many at once as there are threads, each on one
    /// thread with its share of the memory budget.
    #[arg(long)]
    all: bool,
    /// Memory budget.
    #[command(flatten)]
    budget: Budget,
}

#[derive(Args, Debug)]
struct MergeArgs {
    /// Tiles folder.
    dir: PathBuf,
}

/// Runs `karstic tile`.
pub(super) fn run(args: TileArgs) -> anyhow::Result<()> {
    match args.command {
        TileCommand::Plan(a) => plan(a),
        TileCommand::Run(a) => run_tiles(a),
        TileCommand::Merge(a) => {
            let plan = Plan::read(&a.dir)?;
            let r = tiles::merge(&a.dir, &plan)?;
            println!(
                "wrote {}: {} tiles, {} with a mesh, {} triangles; {}",
                r.path.display(),
                r.tiles,
                r.contents,
                r.triangles,
                plan.georeference
            );
            Ok(())
        }
    }
}

fn plan(a: PlanArgs) -> anyhow::Result<()> {
    let out = a.output.join(tiles::plan::PLAN_FILE);
    let (file, compiled) = super::load_compiled(&a.tree, a.budget.max_memory, &[&out], false)?;
    let tree = &compiled.tree;
    let job = file.scene.job.as_ref();
    let region = match (&a.bbox, a.job_region) {
        (Some(b), _) => super::corners(b)?,
        (None, true) => {
            let r = job.and_then(|j| j.region).with_context(|| {
                format!(
                    "{}: --job-region, but the tree has no job region",
                    a.tree.display()
                )
            })?;
            karstic::field::Aabb::new(r.min.0, r.max.0)
        }
        (None, false) => tree.support(),
    };
    let cell = a
        .cell
        .or(job.map(|j| j.cell.0))
        .unwrap_or(region.size().max_element() / 256.0);
    let mut plan = Plan::new(&a.tree, &region, cell, a.tile, a.levels)
        .with_context(|| format!("{}: planning the tiles", a.tree.display()))?;
    if let Some(why) = plan.georeference(compiled.ground.as_deref()) {
        eprintln!("notice: tiles left in the tree's frame: {why}");
    }
    plan.write(&a.output)?;
    let counts: Vec<String> = (0..plan.levels)
        .map(|l| {
            let [x, y] = plan.tile_counts(l);
            format!("{x}×{y}")
        })
        .collect();
    println!(
        "wrote {}: {} tiles over {} levels ({}), finest cell {} m, {}×{} cells per tile",
        out.display(),
        plan.tiles.len(),
        plan.levels,
        counts.join(", "),
        plan.spacing[0],
        plan.tile_cells,
        plan.tile_cells
    );
    println!(
        "array indices 0-{}; {}",
        plan.tiles.len() - 1,
        plan.georeference
    );
    Ok(())
}

fn run_tiles(a: RunArgs) -> anyhow::Result<()> {
    let plan = Plan::read(&a.dir)?;
    let indices: Vec<usize> = if a.all {
        (0..plan.tiles.len()).collect()
    } else {
        vec![tiles::array_index(a.index, |k| std::env::var(k).ok())?]
    };
    if let Some(&bad) = indices.iter().find(|&&i| i >= plan.tiles.len()) {
        anyhow::bail!(
            "tile index {bad}: {} has {} tiles (0-{})",
            a.dir.display(),
            plan.tiles.len(),
            plan.tiles.len() - 1
        );
    }
    let started = Instant::now();
    let loaded = Loaded::new(&plan, a.budget.max_memory, &indices)?;
    println!(
        "loaded {} in {:.2} s",
        plan.tree.display(),
        started.elapsed().as_secs_f64()
    );
    // Tiles are independent: with several, each core meshes its own share of them one
    // after the other on a single thread (a tile's own parallel stages keep two cores
    // only ~80% busy), each with its share of the memory budget. Every tile's bytes are
    // the same whatever the threads.
    let workers = rayon::current_num_threads().min(indices.len()).max(1);
    let budget = a.budget.max_memory / workers as u64;
    let one = |i: usize| -> anyhow::Result<()> {
        let t = Instant::now();
        let s = tiles::run_tile(&a.dir, &plan, &loaded, i, budget)?;
        println!(
            "tile {i} ({}): {} vertices, {} triangles in {:.2} s",
            s.tile.stem(),
            s.vertices,
            s.triangles,
            t.elapsed().as_secs_f64()
        );
        Ok(())
    };
    if workers == 1 {
        return indices.into_iter().try_for_each(one);
    }
    std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers)
            .map(|w| {
                let mine: Vec<usize> = indices.iter().copied().skip(w).step_by(workers).collect();
                scope.spawn(move || {
                    let single = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
                    single.install(|| mine.into_iter().try_for_each(one))
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join()
                    .unwrap_or_else(|_| Err(anyhow::anyhow!("a tile worker panicked")))
            })
            .collect::<anyhow::Result<Vec<()>>>()
    })?;
    Ok(())
}

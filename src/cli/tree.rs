//! `karstic tree …`: validate, inspect and edit tree files.

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, Subcommand};

use karstic::compile::edit;
use karstic::field::{Aabb, Field};
use karstic::scene::{self};

/// Tree-file commands.
#[derive(Args, Debug)]
pub(super) struct TreeArgs {
    /// What to do.
    #[command(subcommand)]
    command: TreeCommand,
}

/// The `tree` subcommands.
#[derive(Subcommand, Debug)]
pub(super) enum TreeCommand {
    /// Parse, check and compile tree files; reports the first error of each.
    Validate {
        /// Tree files.
        #[arg(required = true)]
        files: Vec<PathBuf>,
    },
    /// Print the outline of a tree: names, kinds, support boxes, Lipschitz bounds, counts.
    Show {
        /// Tree file.
        file: PathBuf,
    },
    /// Set a node parameter: `tree set FILE NAME.PARAM VALUE` (VALUE in RON).
    Set {
        /// Tree file.
        file: PathBuf,
        /// `NAME.PARAM`, e.g. `boulder.falloff` or `boulder.shape.radius`.
        target: String,
        /// The new value, in RON: `3.5`, `(0, 0, 10)`, `"dem.tif"`.
        value: String,
    },
    /// Append a node (RON) to the children of the node named PARENT.
    Add {
        /// Tree file.
        file: PathBuf,
        /// Name of the parent node.
        parent: String,
        /// The node, in RON.
        node: String,
    },
    /// Expand the tree's `Landform` generators into the plain primitives they make, and
    /// write the result as a tree file (for hand editing; it compiles to the same tree).
    Expand {
        /// Tree file.
        file: PathBuf,
        /// The expanded tree file to write.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Remove the node named NAME.
    Rm {
        /// Tree file.
        file: PathBuf,
        /// Name of the node.
        name: String,
    },
}

fn fmt_box(b: &Aabb) -> String {
    if b.is_empty() {
        return "empty".into();
    }
    format!(
        "[{:.1}, {:.1}, {:.1}]..[{:.1}, {:.1}, {:.1}]",
        b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
    )
}

/// Runs a `tree` subcommand.
pub(super) fn run(args: TreeArgs) -> anyhow::Result<()> {
    match args.command {
        TreeCommand::Validate { files } => {
            let mut failed = 0;
            for f in &files {
                match scene::load(f).and_then(|s| s.compile().map(|_| ())) {
                    Ok(()) => println!("{}: ok", f.display()),
                    Err(e) => {
                        eprintln!("{}", karstic::io::chain(&e));
                        failed += 1;
                    }
                }
            }
            anyhow::ensure!(
                failed == 0,
                "{failed} of {} tree files are invalid",
                files.len()
            );
            Ok(())
        }
        TreeCommand::Show { file } => show(&file),
        TreeCommand::Set {
            file,
            target,
            value,
        } => {
            edit::set_param(&file, &target, &value)?;
            println!("{}: set {target} = {value}", file.display());
            Ok(())
        }
        TreeCommand::Add { file, parent, node } => {
            edit::add_node(&file, &parent, &node)?;
            println!("{}: added a node under {parent}", file.display());
            Ok(())
        }
        TreeCommand::Expand { file, output } => {
            let sf = scene::load(&file)?;
            karstic::io::check_outputs(&sf.inputs(), &[&output])?;
            let expanded = sf
                .expand()
                .with_context(|| format!("expanding {}", file.display()))?;
            karstic::io::write_bytes_atomic(&output, expanded.to_ron().as_bytes())?;
            let mut primitives = 0;
            expanded
                .root
                .walk(&mut |n, _| primitives += usize::from(n.kind() == "Primitive"));
            println!(
                "{}: expanded into {} ({primitives} primitives)",
                file.display(),
                output.display()
            );
            Ok(())
        }
        TreeCommand::Rm { file, name } => {
            edit::remove_node(&file, &name)?;
            println!("{}: removed {name}", file.display());
            Ok(())
        }
    }
}

fn show(file: &PathBuf) -> anyhow::Result<()> {
    let sf = scene::load(file)?;
    let compiled = sf
        .compile()
        .with_context(|| format!("compiling {}", file.display()))?;
    let tree = &compiled.tree;
    let mut specs = Vec::new();
    let scene = compiled.expanded.as_ref().unwrap_or(&sf.scene);
    scene.root.walk(&mut |n, _| specs.push(n));
    let mut kinds: BTreeMap<&str, usize> = BTreeMap::new();
    println!("{}", sf.scene.name.as_deref().unwrap_or("(unnamed scene)"));
    for (spec, &(depth, id)) in specs.iter().zip(&compiled.outline) {
        *kinds.entry(spec.kind()).or_default() += 1;
        let info = tree.info(id);
        println!(
            "{:indent$}{} {}  support {}  λ ≤ {:.3}  f ∈ [{:.3}, {:.3}]",
            "",
            spec.kind(),
            spec.name().map(|n| format!("{n:?}")).unwrap_or_default(),
            fmt_box(&info.support),
            info.bound.lipschitz,
            info.bound.range.lo,
            info.bound.range.hi,
            indent = 2 * depth
        );
    }
    let counts: Vec<String> = kinds.iter().map(|(k, n)| format!("{n} {k}")).collect();
    println!(
        "{} scene nodes ({}); {} compiled nodes; support {}; global Lipschitz {:.3}",
        specs.len(),
        counts.join(", "),
        tree.nodes().len(),
        fmt_box(&tree.support()),
        tree.lipschitz()
    );
    Ok(())
}

//! Reading the repository's documents for the doc suites — the pages (README.md and
//! docs/*.md), their fenced blocks and their picture links — the sandbox folder the doc
//! commands run in, and the making of the pictures (sections, mesh drawings, small PNGs).

mod markdown;
mod mesh_picture;
mod sandbox;
mod section;
mod small_png;
mod transcript;

pub use markdown::{Fence, fences, picture_links};
pub use mesh_picture::mesh_picture;
pub use sandbox::Sandbox;
pub use section::section_picture;
pub use small_png::write_indexed;
pub use transcript::matches;

use std::path::{Path, PathBuf};

/// The repository's root (where Cargo.toml is).
pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The pages a reader follows: README.md, then docs/*.md in name order, with their text.
pub fn pages() -> Vec<(PathBuf, String)> {
    let mut paths = vec![root().join("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .expect("docs/")
        .map(|e| e.expect("docs/ entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    paths.extend(docs);
    let pages: Vec<_> = paths
        .into_iter()
        .map(|p| {
            let text =
                std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            (p, text)
        })
        .collect();
    // The scan must see the pages it guards.
    for must in ["README.md", "docs/rendering.md", "docs/feature-curves.md"] {
        assert!(
            pages.iter().any(|(p, _)| p.ends_with(must)),
            "{must} not found"
        );
    }
    pages
}

/// `path` relative to the repository root, for messages.
pub fn shown(path: &Path) -> String {
    path.strip_prefix(root())
        .unwrap_or(path)
        .display()
        .to_string()
}

/// Copies the folder `from` into `to` (created), files and subfolders.
pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap_or_else(|e| panic!("{}: {e}", to.display()));
    for entry in std::fs::read_dir(from).unwrap_or_else(|e| panic!("{}: {e}", from.display())) {
        let entry = entry.expect("directory entry");
        let target = to.join(entry.file_name());
        if entry.path().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), &target)
                .unwrap_or_else(|e| panic!("{}: {e}", entry.path().display()));
        }
    }
}

//! The repository's documents cite what it holds: no citation points at a file outside the
//! repository (the papers' local copies or the design notes they came with), and every
//! author–year citation (`Paris et al. 2019 §5.1`, `Hart 1996`, `Felzenszwalb &
//! Huttenlocher 2012`) is listed in `docs/references.md`.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The folders and top-level files whose text is checked.
const CHECKED: &[&str] = &[
    "src",
    "crates",
    "tests",
    "benches",
    "docs",
    "trees",
    "examples",
    "README.md",
    "BENCHMARKS.md",
    "ARCHITECTURE.md",
];

/// The extensions of the text files under [`CHECKED`] folders.
const TEXT: &[&str] = &["rs", "md", "wgsl", "ron", "py", "mjs", "toml"];

/// Pointers to files that are not in the repository, spelled so that this file does not
/// hold them itself.
const OUTSIDE: &[&str] = &[concat!("seed", " 00"), concat!("DESIGN", ".md")];

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Every text file under `rel` (a folder or a file), in a stable order.
fn text_files(rel: &str) -> Vec<PathBuf> {
    let path = root().join(rel);
    if path.is_file() {
        return vec![path];
    }
    let mut out = Vec::new();
    let mut stack = vec![path];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries {
            let p = entry.expect("directory entry").path();
            if p.is_dir() {
                stack.push(p);
            } else if p
                .extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| TEXT.contains(&e))
            {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

fn checked_texts() -> Vec<(PathBuf, String)> {
    let texts: Vec<_> = CHECKED
        .iter()
        .flat_map(|rel| text_files(rel))
        .map(|p| {
            let text =
                std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            (p, text)
        })
        .collect();
    // The scan must see the tree it guards: the sources, the docs and this very file.
    assert!(texts.len() > 150, "only {} text files found", texts.len());
    for must in [
        "src/lib.rs",
        "docs/references.md",
        "tests/docs.rs",
        "README.md",
    ] {
        assert!(
            texts.iter().any(|(p, _)| p.ends_with(must)),
            "{must} not scanned"
        );
    }
    texts
}

/// A year of the form `1900`–`2099`, with the punctuation around it removed.
fn year(word: &str) -> Option<&str> {
    let w = word.trim_matches(|c: char| !c.is_ascii_alphanumeric());
    let is_year = w.len() == 4
        && w.bytes().all(|b| b.is_ascii_digit())
        && (w.starts_with("19") || w.starts_with("20"));
    is_year.then_some(w)
}

/// An author's name as written before `et al.` or a year: a capitalized word of letters
/// (and hyphens), without the punctuation around it.
fn author(word: &str) -> Option<&str> {
    let w = word.trim_matches(|c: char| "([{*`'\",;:.".contains(c));
    let name = w.chars().next().is_some_and(char::is_uppercase)
        && w.chars().all(|c| c.is_alphabetic() || c == '-');
    name.then_some(w)
}

/// The citations in `text`: `<name> et al.`, `<name> et al. <year>`, `<a> and <b> <year>`,
/// `<a> & <b> <year>` (written with `and`) and `<name> <year>`.
fn citations(text: &str) -> BTreeSet<String> {
    let words: Vec<&str> = text
        .split_whitespace()
        .filter(|w| !matches!(*w, "//" | "///" | "//!" | "*" | "#" | "--"))
        .collect();
    let mut out = BTreeSet::new();
    for i in 1..words.len() {
        let et_al = words[i].starts_with("al.") && words[i - 1] == "et";
        if et_al
            && i >= 2
            && let Some(name) = author(words[i - 2])
        {
            out.insert(format!("{name} et al."));
        }
        let Some(y) = year(words[i]) else { continue };
        if i >= 3 && words[i - 1] == "al." && words[i - 2] == "et" {
            if let Some(name) = author(words[i - 3]) {
                out.insert(format!("{name} et al. {y}"));
            }
        } else if i >= 3 && matches!(words[i - 2], "and" | "&") {
            if let (Some(a), Some(b)) = (author(words[i - 3]), author(words[i - 1])) {
                out.insert(format!("{a} and {b} {y}"));
            }
        } else if let Some(name) = author(words[i - 1]) {
            out.insert(format!("{name} {y}"));
        }
    }
    out
}

#[test]
fn no_citation_points_outside_the_repository() {
    let mut found = Vec::new();
    for (path, text) in checked_texts() {
        for (n, line) in text.lines().enumerate() {
            let lower = line.to_lowercase();
            for pattern in OUTSIDE {
                if lower.contains(&pattern.to_lowercase()) {
                    found.push(format!("{}:{}: {}", path.display(), n + 1, line.trim()));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "cite papers by authors, year and section (docs/references.md) instead:\n{}",
        found.join("\n")
    );
}

#[test]
fn every_citation_is_listed_in_the_references() {
    let references =
        std::fs::read_to_string(root().join("docs/references.md")).expect("docs/references.md");
    let mut cited = BTreeSet::new();
    let mut missing = Vec::new();
    // The list itself is not scanned: its entries hold publishers and places.
    let sources = checked_texts().into_iter();
    for (path, text) in sources.filter(|(p, _)| !p.ends_with("docs/references.md")) {
        for key in citations(&text) {
            if !references.contains(&key) {
                missing.push(format!("{}: {key}", path.display()));
            }
            cited.insert(key);
        }
    }
    // The four works the project is built on are cited somewhere: the scan finds them.
    for key in [
        "Becher 2016",
        "Génevaux et al. 2015",
        "Paris et al. 2019",
        "Frasson et al.",
    ] {
        assert!(
            cited.contains(key),
            "{key} not found by the scan: {cited:?}"
        );
    }
    assert!(
        missing.is_empty(),
        "citations not listed in docs/references.md:\n{}",
        missing.join("\n")
    );
}

#[test]
fn the_citation_scanner_reads_every_form() {
    let text = "//! (Paris et al. 2019 §5.1), Hart 1996; Felzenszwalb & Huttenlocher 2012,\n\
                //! Steele, Lea and Flood 2014 and Frasson et al. §5; in 2012, Galin et al.\n\
                //! 2020.";
    let keys: Vec<String> = citations(text).into_iter().collect();
    assert_eq!(
        keys,
        [
            "Felzenszwalb and Huttenlocher 2012",
            "Frasson et al.",
            "Galin et al.",
            "Galin et al. 2020",
            "Hart 1996",
            "Lea and Flood 2014",
            "Paris et al.",
            "Paris et al. 2019",
        ]
    );
}

/// The RON of the pages is what the program reads: every ```` ```ron ```` block of
/// `README.md` and `docs/` parses, as a tree file, a node, a curve or a section of a tree
/// file (`geology:`, `job:`), the fields and values the page shows included. A block that
/// elides parts with `(..)`, `[..]` or a `/* … */` placeholder is a sketch and is not read.
#[test]
fn the_pages_ron_parses() {
    use karstic::scene::parse_scene;
    let opts = karstic::value::ron_options();
    let point = "Primitive(shape: Point(center: (0, 0, 0)), falloff: 1, energy: 1)";
    let mut read = 0;
    let mut pages = vec![root().join("README.md")];
    pages.extend(
        text_files("docs")
            .into_iter()
            .filter(|p| p.extension().is_some_and(|e| e == "md")),
    );
    for page in pages {
        let text = std::fs::read_to_string(&page).unwrap();
        for (k, block) in text.split("```ron\n").skip(1).enumerate() {
            let block = block.split("```").next().unwrap();
            if ["(..)", "[..]", "/*"]
                .iter()
                .any(|sketch| block.contains(sketch))
            {
                continue;
            }
            let body: String = block
                .lines()
                .filter(|l| !l.trim_start().starts_with("//"))
                .collect::<Vec<_>>()
                .join("\n");
            let body = body.trim();
            let at = || format!("{} block {}", page.display(), k + 1);
            let result = if body.starts_with('(') && body.contains("version:") {
                parse_scene(body, &page)
                    .map(|_| ())
                    .map_err(|e| e.to_string())
            } else if body.starts_with("(") {
                opts.from_str::<karstic::voxel::spec::CurveSpec>(body)
                    .map(|_| ())
                    .map_err(|e| e.to_string())
            } else if body.starts_with(|c: char| c.is_ascii_lowercase()) {
                let scene = format!("(version: 1, root: {point}, {body})");
                parse_scene(&scene, &page)
                    .map(|_| ())
                    .map_err(|e| e.to_string())
            } else {
                let scene = format!("(version: 1, root: {body})");
                parse_scene(&scene, &page)
                    .map(|_| ())
                    .map_err(|e| e.to_string())
            };
            if let Err(e) = result {
                panic!("{}: {e}\n{body}", at());
            }
            read += 1;
        }
    }
    assert!(read >= 10, "only {read} blocks read");
}

//! Every malformed, truncated or lying file in `tests/data/dem_corpus/` must give a clear
//! error (never a panic, never a grid). `expected.txt` pairs each file with a substring of
//! its expected message (which must also name the file or its sidecar); `make_corpus.py` regenerates the files, and inputs found by the
//! fuzz tests (`dem_fuzz.rs`) are added here once fixed.

use std::path::Path;

use karstic::dem::{self, ReadOptions};

#[test]
fn every_corpus_file_gives_its_expected_error() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dem_corpus");
    let expected = std::fs::read_to_string(dir.join("expected.txt")).unwrap();
    let mut listed = Vec::new();
    let mut failures = Vec::new();
    for line in expected
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
    {
        let (file, want) = line
            .split_once('\t')
            .unwrap_or_else(|| panic!("expected.txt: no tab in {line:?}"));
        listed.push(file.to_string());
        match dem::read(&dir.join(file), &ReadOptions::default()) {
            Ok(_) => failures.push(format!("{file}: read without error")),
            Err(e) => {
                // The error and its sources, as the command line prints them.
                let msg = format!("{:#}", anyhow::Error::from(e));
                // the message names the file at fault: the input or its sidecar
                let stem = file.rsplit_once('.').map_or(file, |s| s.0);
                if !msg.contains(want) || !msg.contains(stem) {
                    failures.push(format!("{file}: {msg:?} lacks {want:?} or the file name"));
                }
            }
        }
    }
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        let data = !(name.ends_with(".json") || name.ends_with(".py") || name == "expected.txt");
        if data && !listed.contains(&name) {
            let e = dem::read(&dir.join(&name), &ReadOptions::default())
                .err()
                .map(|e| e.to_string());
            failures.push(format!("{name}: not in expected.txt (gives {e:?})"));
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

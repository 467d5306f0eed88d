//! The WGSL constant header generated from the tape's Rust definitions: the checked-in
//! `crates/render/shaders/tape_consts.wgsl` is what `wgsl_header` generates (regenerate it with
//! `KARSTIC_BLESS=1 cargo test --locked --test tests tape_header`), and every constant a
//! shader uses is declared by the header or by that shader itself.

use std::collections::BTreeSet;
use std::path::Path;

use karstic::render::gpu::SHADER_MODULES;
use karstic::render::gpu::header::{HEADER_PATH, SHADER_DIR};
use karstic::render::gpu::wgsl_header;

fn read(rel: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The WGSL without its comments.
fn strip_comments(src: &str) -> String {
    let mut out = String::with_capacity(src.len());
    let mut rest = src;
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix("//") {
            rest = r.find('\n').map_or("", |k| &r[k..]);
        } else if let Some(r) = rest.strip_prefix("/*") {
            rest = r.find("*/").map_or("", |k| &r[k + 2..]);
            out.push(' ');
        } else {
            let c = rest.chars().next().expect("not empty");
            out.push(c);
            rest = &rest[c.len_utf8()..];
        }
    }
    out
}

/// The identifiers of `src` (comments stripped) in order; numbers (`0x7feb352du`, `1e-6`)
/// are skipped whole.
fn identifiers(src: &str) -> Vec<String> {
    let src = strip_comments(src);
    let mut out = Vec::new();
    let mut chars = src.char_indices().peekable();
    while let Some((start, c)) = chars.next() {
        let word = |c: char| c.is_ascii_alphanumeric() || c == '_';
        if c.is_ascii_digit() {
            while chars.next_if(|&(_, c)| word(c) || c == '.').is_some() {}
        } else if c.is_ascii_alphabetic() || c == '_' {
            let mut end = start + c.len_utf8();
            while let Some((k, c)) = chars.next_if(|&(_, c)| word(c)) {
                end = k + c.len_utf8();
            }
            out.push(src[start..end].to_string());
        }
    }
    out
}

/// A constant's name: upper case, digits and underscores, with a letter.
fn is_constant(name: &str) -> bool {
    name.chars().any(|c| c.is_ascii_uppercase())
        && name
            .chars()
            .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
}

/// The names `src` declares with `const` or `override`.
fn declared(src: &str) -> BTreeSet<String> {
    let ids = identifiers(src);
    ids.windows(2)
        .filter(|w| w[0] == "const" || w[0] == "override")
        .map(|w| w[1].clone())
        .collect()
}

#[test]
fn tape_header_is_the_generated_text() {
    let generated = wgsl_header();
    if std::env::var_os("KARSTIC_BLESS").is_some() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(HEADER_PATH);
        std::fs::write(&path, &generated).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    }
    assert!(
        read(HEADER_PATH) == generated,
        "{HEADER_PATH} is stale: regenerate it with \
         `KARSTIC_BLESS=1 cargo test --locked --test tests tape_header`"
    );
    // It declares the limits the evaluator sizes its arrays with, from Rust's values.
    let limit = karstic::tape::format::limit::MAX_WARPS;
    assert!(generated.contains(&format!("const WARP_FRAMES: u32 = {}u;", 2 * limit)));
}

#[test]
fn tape_header_constants_are_the_shaders_only_copies() {
    let header = declared(&wgsl_header());
    assert!(header.len() > 100, "{} constants", header.len());
    let file = HEADER_PATH
        .trim_start_matches(SHADER_DIR)
        .trim_start_matches('/');
    let mut checked = 0;
    for (module, parts) in SHADER_MODULES {
        assert_eq!(
            parts.first(),
            Some(&file),
            "{module} starts with the header"
        );
        for part in &parts[1..] {
            let src = read(&format!("{SHADER_DIR}/{part}"));
            let own = declared(&src);
            let again: Vec<_> = own.intersection(&header).collect();
            assert!(again.is_empty(), "{part} declares {again:?} again");
            let unknown: BTreeSet<_> = identifiers(&src)
                .into_iter()
                .filter(|n| is_constant(n) && !header.contains(n) && !own.contains(n))
                .collect();
            assert!(
                unknown.is_empty(),
                "{part} uses {unknown:?}, which neither {HEADER_PATH} (the Rust definitions) \
                 nor {part} declares"
            );
            checked += 1;
        }
    }
    assert!(checked >= 4, "{checked} shaders checked");
}

/// The scanner the checks above rely on finds what it must: a constant the header lacks
/// is reported, numbers and comments are not identifiers.
#[test]
fn the_shader_scanner_sees_constants_and_skips_numbers_and_comments() {
    let src = "const OWN: u32 = 0x7FEBu; // NOT_USED\n/* ALSO_NOT */ let a = OWN + 1e-6 + MISSING_ONE + T;";
    let ids = identifiers(src);
    let constants: Vec<_> = ids.iter().filter(|n| is_constant(n)).collect();
    assert_eq!(constants, ["OWN", "OWN", "MISSING_ONE", "T"]);
    assert_eq!(declared(src), BTreeSet::from(["OWN".to_string()]));
}

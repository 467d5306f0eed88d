//! The shell commands of README.md and docs/*.md run, against the binary under test, on
//! the repository's scenes and data, and print what the pages say they print.
//!
//! Every fenced block says what it holds in its info string:
//!
//! * ```` ```sh ```` — commands that run: each line (comments and blank lines aside, `\`
//!   continuing a line) runs in bash and must exit with status 0;
//! * ```` ```console ```` — a transcript that runs: `$ command` lines, each followed by the
//!   output it must print (stdout and stderr as a terminal shows them), where `[..]`
//!   stands for any text within a line and a `...` line for any number of lines, so
//!   figures that vary (times, counts) are elided where they are shown;
//! * ```` ```sh,no-run ```` — commands shown but not run here (building, testing,
//!   installing: `cargo test`, `npm install`, the library examples, which `.ci/run` runs);
//! * anything else (`text`, `ron`, `rust`, `json`) is not a command. A bare fence is
//!   refused, so that nothing is left unchecked by omission.
//!
//! `cargo run --release --` in a page is the binary under test (`karstic`). Each page runs
//! in its own sandbox (`doc_util::Sandbox`: a copy of `trees/`, `../shared` linked, outputs
//! in a temporary folder), its blocks in order (a later block may read what an earlier one
//! wrote); pages run in parallel. A small extractor rather than `trycmd`: the pages' commands
//! use pipes, globs and `cargo run`, which trycmd does not run, and its transcripts'
//! elision syntax is all we need of it (`doc_util::matches`).

use std::path::Path;
use std::time::Instant;

use crate::doc_util::{Fence, Sandbox, fences, matches, pages, shown};

/// Info strings of blocks that run (unless marked `no-run`).
const RUNS: &[&str] = &["sh", "console"];

/// Shell info strings spelled otherwise: one spelling keeps the rule visible.
const OTHER_SHELLS: &[&str] = &["bash", "shell", "zsh", "shell-session", "terminal"];

/// How a page invokes the binary; the test runs it as `karstic`.
const CARGO_RUN: &str = "cargo run --release -- ";

/// One command of a block: its 1-based line, its text as run, and the output the page
/// shows for it (transcripts only).
struct Command {
    line: usize,
    text: String,
    expected: Option<String>,
}

/// The commands of a block that runs.
fn commands(fence: &Fence) -> Vec<Command> {
    let mut out: Vec<Command> = Vec::new();
    let mut pending = String::new();
    for (i, raw) in fence.body.iter().enumerate() {
        let line = fence.line + 1 + i;
        if fence.lang == "console" {
            if let Some(cmd) = raw.strip_prefix("$ ") {
                out.push(Command {
                    line,
                    text: cmd.to_string(),
                    expected: Some(String::new()),
                });
            } else if let Some(Command {
                expected: Some(e), ..
            }) = out.last_mut()
            {
                e.push_str(raw);
                e.push('\n');
            }
            continue;
        }
        let trimmed = raw.trim();
        if pending.is_empty() && (trimmed.is_empty() || trimmed.starts_with('#')) {
            continue;
        }
        match trimmed.strip_suffix('\\') {
            Some(head) => {
                pending.push_str(head);
                pending.push(' ');
            }
            None => {
                pending.push_str(trimmed);
                out.push(Command {
                    line,
                    text: std::mem::take(&mut pending),
                    expected: None,
                });
            }
        }
    }
    for c in &mut out {
        c.text = c.text.replace(CARGO_RUN, "karstic ");
    }
    out
}

/// Whether `fence` runs.
fn runs(fence: &Fence) -> bool {
    RUNS.contains(&fence.lang.as_str()) && !fence.has("no-run")
}

/// What is wrong with how `fence` says what it holds, if anything.
fn fence_problem(fence: &Fence) -> Option<String> {
    let lang = fence.lang.as_str();
    if lang.is_empty() {
        return Some(
            "a bare fence: say what it holds (sh, sh,no-run, console, text, ron, …)".into(),
        );
    }
    if OTHER_SHELLS.contains(&lang) {
        return Some(format!(
            "write `sh` (commands) or `console` (a transcript), not `{lang}`"
        ));
    }
    if fence.has("no-run") && !RUNS.contains(&lang) {
        return Some(format!("`no-run` on a `{lang}` block, which never runs"));
    }
    if !RUNS.contains(&lang) && fence.body.iter().any(|l| l.starts_with("$ ")) {
        return Some("a transcript (`$ ` lines): write `console`".into());
    }
    if lang == "console" && !fence.body.first().is_some_and(|l| l.starts_with("$ ")) {
        return Some("a transcript starts with a `$ command` line".into());
    }
    let commands = if runs(fence) {
        commands(fence)
    } else {
        Vec::new()
    };
    commands
        .iter()
        .find(|c| c.text.contains("cargo "))
        .map(|c| {
            format!(
                "line {}: `{}` runs cargo inside the tests: mark the block `sh,no-run`",
                c.line, c.text
            )
        })
}

#[test]
fn every_block_says_whether_it_runs() {
    let mut problems = Vec::new();
    let mut running = 0;
    for (path, text) in pages() {
        for fence in fences(&text) {
            if let Some(p) = fence_problem(&fence) {
                problems.push(format!("{}:{}: {p}", shown(&path), fence.line));
            }
            running += usize::from(runs(&fence));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    // The scan finds the blocks that run: the README's two, those of the CLI pages.
    assert!(running >= 6, "only {running} blocks run");
}

/// Runs the blocks of one page in a sandbox of its own; its failures, one per command.
fn run_page(path: &Path, text: &str) -> Vec<String> {
    let sandbox = Sandbox::new();
    let mut failures = Vec::new();
    let start = Instant::now();
    let mut count = 0;
    for fence in fences(text).iter().filter(|f| runs(f)) {
        for cmd in commands(fence) {
            count += 1;
            let ran = sandbox.run(&cmd.text);
            let at = format!("{}:{}: `{}`", shown(path), cmd.line, cmd.text);
            if !ran.ok {
                failures.push(format!("{at} failed:\n{}", ran.output));
            } else if let Some(expected) = &cmd.expected
                && !matches(expected, &ran.output)
            {
                failures.push(format!(
                    "{at} printed\n{}\nwhere the page shows\n{expected}",
                    ran.output
                ));
            }
        }
    }
    eprintln!(
        "{}: {count} commands in {:.1} s",
        shown(path),
        start.elapsed().as_secs_f64()
    );
    failures
}

#[test]
fn the_pages_commands_run_and_print_what_the_pages_show() {
    let pages = pages();
    let failures: Vec<String> = std::thread::scope(|s| {
        let runs: Vec<_> = pages
            .iter()
            .map(|(path, text)| s.spawn(move || run_page(path, text)))
            .collect();
        runs.into_iter()
            .flat_map(|h| h.join().expect("a page's thread"))
            .collect()
    });
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn commands_are_read_as_a_reader_types_them() {
    let sh = Fence {
        line: 10,
        lang: "sh".into(),
        attrs: vec![],
        body: [
            "# a comment",
            "cargo run --release -- run trees/a.ron -o out",
            "",
            "karstic render trees/b.ron \\",
            "    -o b.png   # trailing comment",
        ]
        .map(String::from)
        .to_vec(),
    };
    let got: Vec<_> = commands(&sh)
        .into_iter()
        .map(|c| (c.line, c.text))
        .collect();
    assert_eq!(
        got,
        [
            (12, "karstic run trees/a.ron -o out".to_string()),
            (
                15,
                "karstic render trees/b.ron  -o b.png   # trailing comment".to_string()
            ),
        ]
    );
    let console = Fence {
        line: 1,
        lang: "console".into(),
        attrs: vec![],
        body: ["$ karstic a", "out 1", "out 2", "$ karstic b"]
            .map(String::from)
            .to_vec(),
    };
    let got: Vec<_> = commands(&console)
        .into_iter()
        .map(|c| (c.text, c.expected))
        .collect();
    assert_eq!(
        got,
        [
            ("karstic a".to_string(), Some("out 1\nout 2\n".to_string())),
            ("karstic b".to_string(), Some(String::new())),
        ]
    );
    // Blocks that must say more: a bare fence, a `text` transcript, cargo in a block that runs.
    let bare = Fence {
        lang: String::new(),
        ..console
    };
    assert!(fence_problem(&bare).is_some());
    let text_transcript = Fence {
        lang: "text".into(),
        ..bare
    };
    assert!(fence_problem(&text_transcript).is_some());
    let cargo_test = Fence {
        body: vec!["cargo test --locked".into()],
        ..sh
    };
    assert!(fence_problem(&cargo_test).is_some());
    let marked = Fence {
        attrs: vec!["no-run".into()],
        ..cargo_test
    };
    assert!(fence_problem(&marked).is_none());
}

//! `karstic eval TREE`: field values and gradients at points read from CSV or stdin.

use std::io::{BufRead, Write};
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use glam::Vec3;

use crate::field::Field;
use crate::scene;

/// Arguments of `karstic eval`.
#[derive(Args, Debug)]
pub struct EvalArgs {
    /// Tree file.
    pub tree: PathBuf,
    /// CSV file of points `x,y,z` (one per line; `#` comments and a header line allowed).
    /// Reads standard input when absent.
    #[arg(long)]
    pub points: Option<PathBuf>,
}

/// Parses one `x,y,z` line (commas or white space); `None` for blank or comment lines.
pub fn parse_point(line: &str) -> Option<Result<Vec3, String>> {
    let line = line.trim();
    if line.is_empty() || line.starts_with('#') {
        return None;
    }
    let parts: Vec<&str> = line
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .collect();
    if parts.len() != 3 {
        return Some(Err(format!(
            "expected 3 numbers x,y,z, found {} fields",
            parts.len()
        )));
    }
    let mut v = [0f32; 3];
    for (slot, s) in v.iter_mut().zip(&parts) {
        match s.parse::<f32>() {
            Ok(x) if x.is_finite() => *slot = x,
            _ => return Some(Err(format!("expected a finite number, found {s:?}"))),
        }
    }
    Some(Ok(Vec3::from_array(v)))
}

/// Runs `karstic eval`.
pub fn run(args: EvalArgs) -> anyhow::Result<()> {
    let compiled = scene::load(&args.tree)?.compile()?;
    let tree = &compiled.tree;
    let (source, reader): (String, Box<dyn BufRead>) = match &args.points {
        Some(p) => (
            p.display().to_string(),
            Box::new(std::io::BufReader::new(
                std::fs::File::open(p).with_context(|| format!("cannot open {}", p.display()))?,
            )),
        ),
        None => ("<stdin>".into(), Box::new(std::io::stdin().lock())),
    };
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    writeln!(out, "x,y,z,value,gx,gy,gz")?;
    for (n, line) in reader.lines().enumerate() {
        let line = line.with_context(|| format!("{source}: reading line {}", n + 1))?;
        let p = match parse_point(&line) {
            None => continue,
            // A header line such as "x,y,z" is skipped.
            Some(Err(_)) if n == 0 && line.chars().any(|c| c.is_ascii_alphabetic()) => continue,
            Some(Err(e)) => anyhow::bail!("{source}:{}: {e}", n + 1),
            Some(Ok(p)) => p,
        };
        let (v, g) = tree.value_grad(p);
        writeln!(out, "{},{},{},{v},{},{},{}", p.x, p.y, p.z, g.x, g.y, g.z)?;
    }
    out.flush()?;
    Ok(())
}

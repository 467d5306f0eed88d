//! `karstic eval TREE`: field values and gradients at points read from CSV or stdin.

use std::io::{BufRead, Read, Write};
use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use glam::Vec3;

use super::Budget;
use karstic::field::Field;

/// Arguments of `karstic eval`.
#[derive(Args, Debug)]
pub(super) struct EvalArgs {
    /// Tree file.
    tree: PathBuf,
    /// CSV file of points `x,y,z` (one per line; `#` comments and a header line allowed).
    /// Reads standard input when absent.
    #[arg(long)]
    points: Option<PathBuf>,
    /// Memory budget.
    #[command(flatten)]
    budget: Budget,
}

/// The longest line of points read, in bytes: far above any `x,y,z`.
const MAX_LINE: usize = 4096;

/// The fields of a line: separated by commas or white space.
fn fields(line: &str) -> Vec<&str> {
    line.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .collect()
}

/// A header line such as `x,y,z`: some field is not a number at all (`nan` and `inf`
/// are numbers, so `nan,0,0` is a bad point, not a header).
fn is_header(line: &str) -> bool {
    fields(line).iter().any(|f| f.parse::<f32>().is_err())
}

/// Parses one `x,y,z` line (commas or white space); `None` for blank or comment lines.
fn parse_point(line: &str) -> Option<Result<Vec3, String>> {
    let line = line.trim();
    if line.is_empty() || line.starts_with('#') {
        return None;
    }
    let parts = fields(line);
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
            _ => {
                let shown: String = s.chars().take(24).collect();
                let more = if shown.len() < s.len() { "…" } else { "" };
                return Some(Err(format!(
                    "expected a finite number, found {shown:?}{more}"
                )));
            }
        }
    }
    Some(Ok(Vec3::from_array(v)))
}

/// Runs `karstic eval`.
pub(super) fn run(args: EvalArgs) -> anyhow::Result<()> {
    let tree = &super::load_tree(&args.tree, args.budget.max_memory, &[] as &[&Path], false)?;
    let (source, mut reader): (String, Box<dyn BufRead>) = match &args.points {
        // A regular file only (a FIFO would block, `/dev/zero` never ends), streamed.
        Some(p) => (
            p.display().to_string(),
            Box::new(std::io::BufReader::new(
                karstic::io::open_regular(p, u64::MAX)?.0,
            )),
        ),
        None => ("<stdin>".into(), Box::new(std::io::stdin().lock())),
    };
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    writeln!(out, "x,y,z,value,gx,gy,gz")?;
    let mut bytes = Vec::new();
    for n in 0.. {
        bytes.clear();
        // One line, at most MAX_LINE bytes: a stream without line breaks (`/dev/zero` on
        // stdin) is an error at once, not a line that grows through the memory.
        let read = (&mut reader)
            .take(MAX_LINE as u64 + 1)
            .read_until(b'\n', &mut bytes)
            .with_context(|| format!("{source}: reading line {}", n + 1))?;
        if read == 0 {
            break;
        }
        if bytes.len() > MAX_LINE {
            anyhow::bail!("{source}:{}: a line longer than {MAX_LINE} bytes", n + 1);
        }
        let line = std::str::from_utf8(&bytes)
            .map_err(|_| anyhow::anyhow!("{source}:{}: not UTF-8 text", n + 1))?;
        // A UTF-8 byte-order mark may open the file.
        let line = if n == 0 {
            line.trim_start_matches('\u{feff}')
        } else {
            line
        };
        let p = match parse_point(line) {
            None => continue,
            Some(Err(_)) if n == 0 && is_header(line) => continue,
            Some(Err(e)) => anyhow::bail!("{source}:{}: {e}", n + 1),
            Some(Ok(p)) => p,
        };
        let (v, g) = tree.value_grad(p);
        writeln!(out, "{},{},{},{v},{},{},{}", p.x, p.y, p.z, g.x, g.y, g.z)?;
    }
    out.flush()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headers_are_words_not_bad_numbers() {
        assert!(is_header("x,y,z"));
        assert!(is_header("\"x\" \"y\" \"z\""));
        assert!(!is_header("nan,0,0"));
        assert!(!is_header("1,2,inf"));
        assert!(parse_point("nan,0,0").unwrap().is_err());
        assert_eq!(
            parse_point(" 1, 2 3 ").unwrap(),
            Ok(Vec3::new(1.0, 2.0, 3.0))
        );
        assert!(parse_point("# note").is_none());
        assert!(parse_point("1,2").unwrap().is_err());
    }
}

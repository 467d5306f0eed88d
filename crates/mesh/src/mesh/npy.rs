//! NumPy `.npy` (format 1.0) for little-endian float32 volumes: what `karstic sample`
//! writes and what `karstic build` and the benches read back.

use std::io::{self, Write};
use std::path::Path;

const MAGIC: &[u8] = b"\x93NUMPY";

/// Errors reading an `.npy` file.
#[derive(Debug, thiserror::Error)]
pub enum NpyError {
    /// The file could not be read, is not a regular file or exceeds the budget.
    #[error(transparent)]
    Read(#[from] crate::io::IoError),
    /// The file is not a float32 C-order `.npy`.
    #[error("{path}: {what}")]
    Format {
        /// The file.
        path: String,
        /// What was expected.
        what: String,
    },
}

/// Writes `values` as a float32 C-order array of the given `shape` (e.g. `[nz, ny, nx]`).
pub fn write_f32(w: &mut dyn Write, shape: &[usize], values: &[f32]) -> io::Result<()> {
    debug_assert_eq!(shape.iter().product::<usize>(), values.len());
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let tuple = if dims.len() == 1 {
        format!("({},)", dims[0])
    } else {
        format!("({})", dims.join(", "))
    };
    let mut header = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': {tuple}, }}");
    // Magic (6) + version (2) + length (2) + header + '\n' is a multiple of 64.
    let total = (10 + header.len() + 1).div_ceil(64) * 64;
    header.extend(std::iter::repeat_n(' ', total - 10 - header.len() - 1));
    header.push('\n');
    w.write_all(MAGIC)?;
    w.write_all(&[1, 0])?;
    w.write_all(&(header.len() as u16).to_le_bytes())?;
    w.write_all(header.as_bytes())?;
    if cfg!(target_endian = "little") {
        w.write_all(bytemuck::cast_slice(values))
    } else {
        values
            .iter()
            .try_for_each(|v| w.write_all(&v.to_le_bytes()))
    }
}

/// Reads a float32 C-order `.npy` file: its shape and values. A file over `budget`
/// bytes is refused before it is read.
pub fn read_f32(path: &Path, budget: u64) -> Result<(Vec<usize>, Vec<f32>), NpyError> {
    let bytes = crate::io::read_regular(path, budget)?;
    parse_f32(&bytes).map_err(|what| NpyError::Format {
        path: path.display().to_string(),
        what,
    })
}

fn parse_f32(bytes: &[u8]) -> Result<(Vec<usize>, Vec<f32>), String> {
    if bytes.len() < 10 || &bytes[..6] != MAGIC {
        return Err("not a .npy file (bad magic string)".into());
    }
    let (len, start) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        v => return Err(format!("unsupported .npy version {v}")),
    };
    let header = bytes
        .get(start..start + len)
        .and_then(|h| std::str::from_utf8(h).ok())
        .ok_or("truncated or non-UTF-8 header")?;
    let field = |key: &str| -> Result<&str, String> {
        let at = header
            .find(&format!("'{key}'"))
            .ok_or(format!("header has no '{key}'"))?;
        Ok(header[at + key.len() + 2..]
            .trim_start()
            .trim_start_matches(':')
            .trim_start())
    };
    if !field("descr")?.starts_with("'<f4'") {
        return Err(format!(
            "expected dtype '<f4' (float32 little-endian), header is {}",
            header.trim()
        ));
    }
    if !field("fortran_order")?.starts_with("False") {
        return Err("expected C order (fortran_order: False)".into());
    }
    let shape_src = field("shape")?;
    let close = shape_src.find(')').ok_or("unterminated shape tuple")?;
    let shape = shape_src[1..close]
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| {
            s.parse::<usize>()
                .map_err(|_| format!("bad shape entry '{s}'"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let n = shape
        .iter()
        .try_fold(1usize, |a, &d| a.checked_mul(d))
        .ok_or("shape overflows")?;
    let data = &bytes[start + len..];
    if data.len() != n * 4 {
        return Err(format!(
            "shape {shape:?} needs {} data bytes, file has {}",
            n * 4,
            data.len()
        ));
    }
    let values = data
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    Ok((shape, values))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_alignment() {
        let values: Vec<f32> = (0..24).map(|i| i as f32 * 0.5).collect();
        let mut buf = Vec::new();
        write_f32(&mut buf, &[2, 3, 4], &values).unwrap();
        let header_len = u16::from_le_bytes([buf[8], buf[9]]) as usize;
        assert_eq!((10 + header_len) % 64, 0);
        assert_eq!(buf.len(), 10 + header_len + 96);
        let (shape, back) = parse_f32(&buf).unwrap();
        assert_eq!(shape, vec![2, 3, 4]);
        assert_eq!(back, values);
    }

    #[test]
    fn rejects_other_dtypes() {
        let mut buf = Vec::new();
        write_f32(&mut buf, &[1], &[1.0]).unwrap();
        let at = buf.windows(3).position(|w| w == b"<f4").unwrap();
        buf[at + 2] = b'8';
        let e = parse_f32(&buf).unwrap_err();
        assert!(e.contains("'<f4'"), "{e}");
        assert!(parse_f32(b"hello").is_err());
    }
}

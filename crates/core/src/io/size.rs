//! Byte sizes as people write them on a command line: `123`, `512M`, `8GiB`, `1.5GB`.

/// Parses a byte size: a non-negative decimal number followed by an optional unit, case
/// insensitive, with optional white space between them.
///
/// * no unit or `B`: bytes;
/// * `K`, `M`, `G`, `T` and `KiB`, `MiB`, `GiB`, `TiB`: powers of 1024 (`8G` = `8GiB` =
///   8 · 2³⁰ bytes);
/// * `KB`, `MB`, `GB`, `TB`: powers of 1000, as SI says (`1.5GB` = 1.5 · 10⁹ bytes).
///
/// Fractions are allowed (`1.5G`) and the result is rounded down to whole bytes. Errors
/// name what was found and what was expected.
pub fn parse_byte_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = (&t[..split], t[split..].trim_start());
    let expected =
        || format!("expected a size such as 1000000, 512M, 8GiB or 1.5GB, found {text:?}");
    if number.is_empty() {
        return Err(expected());
    }
    let value: f64 = number.parse().map_err(|_| expected())?;
    let scale = match unit.to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kib" => 1024f64,
        "m" | "mib" => 1024f64.powi(2),
        "g" | "gib" => 1024f64.powi(3),
        "t" | "tib" => 1024f64.powi(4),
        "kb" => 1e3,
        "mb" => 1e6,
        "gb" => 1e9,
        "tb" => 1e12,
        _ => {
            return Err(format!(
                "{}: unknown unit {unit:?} (use B, K, M, G, T, KiB…TiB or KB…TB)",
                expected()
            ));
        }
    };
    let bytes = value * scale;
    if !(bytes < u64::MAX as f64) {
        return Err(format!("{text:?} is too large a size"));
    }
    Ok(bytes as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_binary_decimal_and_bytes() {
        assert_eq!(parse_byte_size("123"), Ok(123));
        assert_eq!(parse_byte_size("123B"), Ok(123));
        assert_eq!(parse_byte_size("8G"), Ok(8 << 30));
        assert_eq!(parse_byte_size("8GiB"), Ok(8 << 30));
        assert_eq!(parse_byte_size("8 gib"), Ok(8 << 30));
        assert_eq!(parse_byte_size("512MiB"), Ok(512 << 20));
        assert_eq!(parse_byte_size("512m"), Ok(512 << 20));
        assert_eq!(parse_byte_size("64k"), Ok(64 << 10));
        assert_eq!(parse_byte_size("2T"), Ok(2 << 40));
        assert_eq!(parse_byte_size("1.5GB"), Ok(1_500_000_000));
        assert_eq!(parse_byte_size("1.5G"), Ok(3 << 29));
        assert_eq!(parse_byte_size("10MB"), Ok(10_000_000));
        assert_eq!(parse_byte_size(" 7 "), Ok(7));
        assert_eq!(parse_byte_size("0"), Ok(0));
    }

    #[test]
    fn refuses_what_is_not_a_size() {
        for bad in [
            "",
            "G",
            ".",
            "lots",
            "-1K",
            "1e9",
            "8X",
            "8 GiBs",
            "NaN",
            "inf",
            "1.2.3M",
            "99999999999T",
        ] {
            let e = parse_byte_size(bad).unwrap_err();
            assert!(e.contains(&format!("{bad:?}")), "{bad}: {e}");
        }
    }
}

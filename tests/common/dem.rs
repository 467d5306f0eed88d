//! The Jacksboro DEM (UTM 16N, 90 m cells) from `../shared/data/dem`, read with a
//! minimal ESRI ASCII parser and cropped to the largest centred window without
//! no-data cells; elevations in metres, x east and y north from the window's
//! south-west sample.

use std::path::Path;

/// An elevation grid without no-data cells.
pub struct Dem {
    /// Samples along x (east).
    pub nx: usize,
    /// Samples along y (north).
    pub ny: usize,
    /// Sample spacing in metres.
    pub cell: f32,
    /// `z[i + nx·j]`, `j = 0` the southern row.
    pub z: Vec<f32>,
}

/// The Jacksboro DEM's largest clean centred window.
pub fn jacksboro() -> Dem {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/dem/jacksboro_utm16n_90m.asc");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut head = std::collections::HashMap::new();
    let mut values = Vec::new();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some(k) if k.chars().next().is_some_and(|c| c.is_ascii_alphabetic()) => {
                head.insert(
                    k.to_ascii_lowercase(),
                    it.next().unwrap().parse::<f64>().unwrap(),
                );
            }
            Some(first) => {
                values.push(first.parse::<f32>().unwrap());
                values.extend(it.map(|v| v.parse::<f32>().unwrap()));
            }
            None => {}
        }
    }
    let (cols, rows) = (head["ncols"] as usize, head["nrows"] as usize);
    let nodata = head["nodata_value"] as f32;
    assert_eq!(values.len(), cols * rows);
    let at = |c: usize, r: usize| values[c + cols * r];
    let clean = |m: usize| (m..rows - m).all(|r| (m..cols - m).all(|c| at(c, r) != nodata));
    let m = (0..rows.min(cols) / 2)
        .find(|&m| clean(m))
        .expect("some clean window");
    let (nx, ny) = (cols - 2 * m, rows - 2 * m);
    let z = (0..nx * ny)
        .map(|k| at(m + k % nx, rows - 1 - m - k / nx))
        .collect();
    Dem {
        nx,
        ny,
        cell: head["cellsize"] as f32,
        z,
    }
}

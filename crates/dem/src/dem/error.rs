//! Errors of the DEM readers, writers and the heightfield leaf.

use std::path::PathBuf;

/// What went wrong reading, writing or implicitizing a DEM. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum DemError {
    /// The file could not be opened or read.
    #[error("cannot read {path}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// Reading or writing failed, or a size budget was exceeded (the error names the
    /// file).
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
    /// The extension names no known DEM format.
    #[error("{path}: unknown DEM format (expected .tif, .tiff, .png, .asc or .hgt)")]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// The file is not what its format says (truncated, inconsistent, lying sizes).
    #[error("{path}: malformed: expected {what}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// What was expected and what was found.
        what: String,
    },
    /// A text file has a bad token.
    #[error("{path}:{line}:{column}: expected {what}")]
    Syntax {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What was expected and what was found.
        what: String,
    },
    /// A valid file using a feature this reader does not handle.
    #[error("{path}: unsupported: {what}")]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// The feature.
        what: String,
    },
    /// The TIFF decoder refused the file.
    #[error("{path}: TIFF")]
    Tiff {
        /// The file.
        path: PathBuf,
        /// The decoder's error.
        source: tiff::TiffError,
    },
    /// The PNG decoder or encoder refused the file.
    #[error("{path}: PNG")]
    Png {
        /// The file.
        path: PathBuf,
        /// The codec's error.
        source: image::ImageError,
    },
    /// The elevation values cannot be used.
    #[error("{path}: {what}")]
    BadData {
        /// The file.
        path: PathBuf,
        /// What is wrong (no valid sample, infinite values...).
        what: String,
    },
    /// A parameter of the heightfield leaf or a resampling request is invalid.
    #[error("{what}")]
    Invalid {
        /// What is wrong.
        what: String,
    },
}

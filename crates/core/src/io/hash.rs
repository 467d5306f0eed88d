//! Content hashes: what caches key their entries by and sidecars check their files by.

/// FNV-1a over bytes: a stable content hash (the Feature Volume caches, the tiles, a
/// sampled grid's sidecar).
pub fn content_hash(parts: &[&[u8]]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for p in parts {
        for &b in *p {
            h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
        h = (h ^ 0xff).wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// The content hash of the files `files`, in order: each file's contents, or a marker for
/// one that cannot be read (a sidecar a reader would have taken when present). What the
/// Feature Volume memo and the tiles key their inputs by.
pub fn files_hash(files: &[std::path::PathBuf]) -> u64 {
    let parts: Vec<[u8; 8]> = files
        .iter()
        .map(
            |f| match super::read_regular(f, super::DEFAULT_MEMORY_BUDGET) {
                Ok(bytes) => content_hash(&[&bytes]).to_le_bytes(),
                Err(_) => *b"absent\0\0",
            },
        )
        .collect();
    content_hash(&parts.iter().map(|p| p.as_slice()).collect::<Vec<_>>())
}

//! The voxel pipeline's results kept between runs: in memory for the process, and on
//! disk for the next one ([`run_cached`]).
//!
//! A Feature Volume's pipeline (diffusion, propagation, bounds) is most of the time of
//! compiling a tree that holds one: about 2 CPU-seconds for the main job's two volumes,
//! against a few milliseconds to read their 10 MB back. Every command that compiles the
//! tree again — `karstic render` after `karstic build`, the editor opening a file, each
//! `tile run` task under a volume — reads the volume back instead of recomputing it.
//!
//! * **Where:** `$KARSTIC_CACHE` when set (`off` turns the cache off), else
//!   `$XDG_CACHE_HOME/karstic/volumes`, else `$HOME/.cache/karstic/volumes`.
//! * **Key:** the pipeline's content hash (the resolved primitives and every parameter)
//!   with the running executable's identity (its length and modification time) and the
//!   file format's version: a rebuilt or upgraded karstic never reads what an older one
//!   wrote, so a change of the pipeline's code cannot serve stale results.
//! * **Files:** one per volume, written to a temporary name and renamed (readers never
//!   see half a file), checked on reading (magic, key, lengths, a checksum): anything
//!   unexpected is a miss, never an error, and the volume is computed again.
//! * **Size:** after each write the oldest files (by modification time) are removed
//!   until the directory holds at most [`MAX_BYTES`].
//!
//! The results are bit-identical to a fresh run: the file holds the run's own arrays.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

use glam::{IVec3, Vec3};

use super::pipeline::{BrickBounds, Params, Stats, Volume, run};
use super::sparse::{BRICK_NODES, Bricks, LevelGeom};
use crate::curves::{CurveError, Features};
use crate::io::content_hash;

/// The most bytes the cache directory keeps.
pub const MAX_BYTES: u64 = 1 << 30;

/// First bytes of a cache file; the digit is the format's version.
const MAGIC: &[u8; 16] = b"karstic-volume1\n";

/// The cache directory, or `None` when the cache is off or no home is known.
pub fn dir() -> Option<&'static Path> {
    static DIR: OnceLock<Option<PathBuf>> = OnceLock::new();
    DIR.get_or_init(|| {
        let env = |k: &str| std::env::var_os(k).filter(|v| !v.is_empty());
        match env("KARSTIC_CACHE") {
            Some(v) if v == "off" => None,
            Some(v) => Some(PathBuf::from(v)),
            None => env("XDG_CACHE_HOME")
                .map(PathBuf::from)
                .or_else(|| env("HOME").map(|h| Path::new(&h).join(".cache")))
                .map(|c| c.join("karstic").join("volumes")),
        }
    })
    .as_deref()
}

/// The key of a run's content hash `content` for this executable.
pub fn key(content: u64) -> u64 {
    static EXE: OnceLock<u64> = OnceLock::new();
    let exe = *EXE.get_or_init(|| {
        let meta = std::env::current_exe().and_then(std::fs::metadata);
        let stamp = meta.map(|m| {
            let t = m
                .modified()
                .ok()
                .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok());
            format!("{} {:?}", m.len(), t)
        });
        content_hash(&[
            MAGIC,
            env!("CARGO_PKG_VERSION").as_bytes(),
            stamp.unwrap_or_default().as_bytes(),
        ])
    });
    content_hash(&[&exe.to_le_bytes(), &content.to_le_bytes()])
}

fn path(dir: &Path, key: u64) -> PathBuf {
    dir.join(format!("{key:016x}.kvol"))
}

/// The volume stored under `key`, if a sound file holds it and it fits `max_bytes`.
pub fn load(key: u64, max_bytes: u64) -> Option<Volume> {
    let p = path(dir()?, key);
    if std::fs::metadata(&p).ok()?.len() > max_bytes.saturating_add(1 << 20) {
        return None;
    }
    decode(&std::fs::read(p).ok()?, key)
}

/// Stores `v` under `key` (best effort: a cache that cannot be written is skipped), then
/// trims the directory to [`MAX_BYTES`].
pub fn store(key: u64, v: &Volume) {
    let Some(dir) = dir() else { return };
    let Ok(()) = std::fs::create_dir_all(dir) else {
        return;
    };
    let target = path(dir, key);
    let tmp = dir.join(format!(
        "{key:016x}.{}.{:?}.tmp",
        std::process::id(),
        std::thread::current().id()
    ));
    let written =
        std::fs::write(&tmp, encode(key, v)).and_then(|()| std::fs::rename(&tmp, &target));
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
        return;
    }
    trim(dir, MAX_BYTES);
}

/// Removes the oldest cache files of `dir` until at most `max` bytes remain.
fn trim(dir: &Path, max: u64) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut files: Vec<(std::time::SystemTime, u64, PathBuf)> = entries
        .filter_map(|e| {
            let e = e.ok()?;
            let p = e.path();
            let m = e.metadata().ok()?;
            (p.extension()? == "kvol").then_some((m.modified().ok()?, m.len(), p))
        })
        .collect();
    let mut total: u64 = files.iter().map(|f| f.1).sum();
    files.sort();
    for (_, len, p) in files {
        if total <= max {
            break;
        }
        if std::fs::remove_file(p).is_ok() {
            total -= len;
        }
    }
}

/// A checksum of `bytes` (8 bytes at a time; catches truncation and corruption).
fn checksum(bytes: &[u8]) -> u64 {
    let mut h = 0x9e37_79b9_7f4a_7c15u64;
    let mut words = bytes.chunks_exact(8);
    for w in &mut words {
        let w = u64::from_le_bytes(w.try_into().expect("8 bytes"));
        h = (h ^ w).wrapping_mul(0x0100_0000_01b3).rotate_left(23);
    }
    for &b in words.remainder() {
        h = (h ^ b as u64).wrapping_mul(0x0100_0000_01b3);
    }
    h
}

fn encode(key: u64, v: &Volume) -> Vec<u8> {
    fn put<T: bytemuck::Pod>(out: &mut Vec<u8>, xs: &[T]) {
        out.extend_from_slice(&(xs.len() as u64).to_le_bytes());
        out.extend_from_slice(bytemuck::cast_slice(xs));
    }
    let mut out = Vec::new();
    let stats = serde_json::to_vec(&v.stats).expect("statistics serialize");
    put(&mut out, &stats);
    put(&mut out, &[v.levels.len() as u64]);
    for (l, b) in v.levels.iter().enumerate() {
        let g = b.geom;
        put(&mut out, &[g.origin.x, g.origin.y, g.origin.z, g.h]);
        put(&mut out, &[g.dims]);
        put(&mut out, b.coords());
        put(&mut out, &v.s[l]);
        put(&mut out, &v.alpha[l]);
        put(&mut out, &v.beta[l]);
        put(&mut out, &v.bounds[l]);
        put(&mut out, v.normals.get(l).map_or(&[][..], |n| &n[..]));
    }
    let mut file = Vec::with_capacity(out.len() + 32);
    file.extend_from_slice(MAGIC);
    file.extend_from_slice(&key.to_le_bytes());
    file.extend_from_slice(&checksum(&out).to_le_bytes());
    file.extend_from_slice(&out);
    file
}

/// Reads what [`encode`] wrote; `None` on any inconsistency.
fn decode(file: &[u8], key: u64) -> Option<Volume> {
    struct Reader<'a>(&'a [u8]);
    impl Reader<'_> {
        fn take<T: bytemuck::Pod>(&mut self) -> Option<Vec<T>> {
            let n = u64::from_le_bytes(self.0.get(..8)?.try_into().ok()?);
            let bytes = usize::try_from(n).ok()?.checked_mul(size_of::<T>())?;
            let data = self.0.get(8..8usize.checked_add(bytes)?)?;
            let mut v = vec![T::zeroed(); bytes / size_of::<T>().max(1)];
            bytemuck::cast_slice_mut::<T, u8>(&mut v).copy_from_slice(data);
            self.0 = &self.0[8 + bytes..];
            Some(v)
        }
        fn one<T: bytemuck::Pod>(&mut self) -> Option<T> {
            let v = self.take::<T>()?;
            (v.len() == 1).then(|| v[0])
        }
    }
    let rest = file.strip_prefix(MAGIC)?;
    let stored_key = u64::from_le_bytes(rest.get(..8)?.try_into().ok()?);
    let sum = u64::from_le_bytes(rest.get(8..16)?.try_into().ok()?);
    let body = rest.get(16..)?;
    if stored_key != key || checksum(body) != sum {
        return None;
    }
    let mut r = Reader(body);
    let stats: Stats = serde_json::from_slice(&r.take::<u8>()?).ok()?;
    let n = usize::try_from(r.one::<u64>()?).ok()?;
    let mut v = Volume {
        stats,
        ..Volume::default()
    };
    for _ in 0..n.min(64) {
        let [x, y, z, h] = <[f32; 4]>::try_from(r.take::<f32>()?).ok()?;
        let dims = r.one::<IVec3>()?;
        let coords = r.take::<IVec3>()?;
        let geom = LevelGeom {
            origin: Vec3::new(x, y, z),
            h,
            dims,
        };
        if !(h > 0.0) || dims.cmplt(IVec3::splat(2)).any() {
            return None;
        }
        let bricks = Bricks::new(geom, coords.clone());
        let nodes = bricks.len() * BRICK_NODES;
        let s = r.take::<f32>()?;
        let alpha = r.take::<f32>()?;
        let beta = r.take::<f32>()?;
        let bounds = r.take::<BrickBounds>()?;
        let normals = r.take::<Vec3>()?;
        let sound = bricks.coords() == &coords[..]
            && [s.len(), alpha.len(), beta.len()]
                .iter()
                .all(|&k| k == nodes)
            && bounds.len() == bricks.len()
            && (normals.is_empty() || normals.len() == nodes);
        if !sound {
            return None;
        }
        if !normals.is_empty() {
            v.normals.push(normals);
        }
        v.levels.push(bricks);
        v.s.push(s);
        v.alpha.push(alpha);
        v.beta.push(beta);
        v.bounds.push(bounds);
    }
    let complete = v.levels.len() == n
        && r.0.is_empty()
        && (v.normals.is_empty() || v.normals.len() == v.levels.len());
    complete.then_some(v)
}

/// The content hash of a run: the canonical text of the primitives and the parameters
/// (RON, every number written so that it reads back to the same bits, infinities and NaN
/// by name).
fn run_key(features: &Features, p: &Params) -> u64 {
    let text = ron::to_string(&(features, p)).expect("resolved primitives serialize");
    content_hash(&[text.as_bytes()])
}

type Cache = Mutex<Vec<(u64, Arc<Volume>)>>;
static CACHE: Cache = Mutex::new(Vec::new());
const CACHE_ENTRIES: usize = 8;

/// [`run`], memoised by the content hash of the primitives and the parameters: in-process,
/// then on disk (this module's files). Returns the volume and whether it came from a
/// cache.
pub fn run_cached(features: &Features, p: &Params) -> Result<(Arc<Volume>, bool), CurveError> {
    let content = run_key(features, p);
    if let Some((_, v)) = CACHE
        .lock()
        .expect("cache lock")
        .iter()
        .find(|(k, _)| *k == content)
    {
        return Ok((v.clone(), true));
    }
    let disk = key(content);
    let (v, cached) = match load(disk, p.max_memory) {
        Some(v) => (Arc::new(v), true),
        None => {
            let v = run(features, p)?;
            store(disk, &v);
            (Arc::new(v), false)
        }
    };
    let mut c = CACHE.lock().expect("cache lock");
    if c.len() >= CACHE_ENTRIES {
        c.remove(0);
    }
    c.push((content, v.clone()));
    Ok((v, cached))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::voxel::spec::{BuildOptions, FeatureVolumeSpec, parse_ron};

    fn volume() -> Volume {
        let spec: FeatureVolumeSpec = parse_ron(
            r#"FeatureVolume(
                name: "t",
                curves: Inline(tunnels: [(path: [Abs(0, 0, 0), Abs(40, 0, 0)], width: Const(8), height: Const(6))]),
                domain: ((-20, -20, -20), (60, 20, 20)),
                voxel: 2.0,
            )"#,
            Path::new("<test>"),
        )
        .unwrap();
        let features = spec
            .resolve(Path::new("."), &BuildOptions::default())
            .unwrap();
        let (p, _) = spec.params(1, 1 << 30);
        super::super::pipeline::run(&features, &p).unwrap()
    }

    #[test]
    fn a_volume_reads_back_bit_for_bit() {
        let v = volume();
        assert!(!v.levels.is_empty());
        let back = decode(&encode(7, &v), 7).expect("decodes");
        assert_eq!(back.stats, v.stats);
        assert_eq!(back.levels.len(), v.levels.len());
        for l in 0..v.levels.len() {
            assert_eq!(back.levels[l].coords(), v.levels[l].coords());
            assert_eq!(back.levels[l].geom, v.levels[l].geom);
            let bits = |x: &[f32]| x.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&back.s[l]), bits(&v.s[l]));
            assert_eq!(bits(&back.alpha[l]), bits(&v.alpha[l]));
            assert_eq!(bits(&back.beta[l]), bits(&v.beta[l]));
            assert_eq!(back.bounds[l], v.bounds[l]);
        }
    }

    #[test]
    fn damaged_or_foreign_files_are_misses() {
        let v = volume();
        let file = encode(7, &v);
        assert!(decode(&file, 8).is_none(), "another key");
        for cut in [0, 10, 40, file.len() / 2, file.len() - 1] {
            assert!(decode(&file[..cut], 7).is_none(), "cut at {cut}");
        }
        let mut flipped = file.clone();
        let k = flipped.len() - 100;
        flipped[k] ^= 0x10;
        assert!(decode(&flipped, 7).is_none(), "a flipped bit");
    }

    #[test]
    fn trimming_removes_the_oldest_files_first() {
        let dir = tempfile::tempdir().unwrap();
        for (k, age) in [(1u64, 30u64), (2, 20), (3, 10)] {
            let p = path(dir.path(), k);
            std::fs::write(&p, vec![0u8; 1000]).unwrap();
            let t = std::time::SystemTime::now() - std::time::Duration::from_secs(age);
            std::fs::File::options()
                .write(true)
                .open(&p)
                .unwrap()
                .set_modified(t)
                .unwrap();
        }
        trim(dir.path(), 2000);
        assert!(!path(dir.path(), 1).exists());
        assert!(path(dir.path(), 2).exists() && path(dir.path(), 3).exists());
    }
}

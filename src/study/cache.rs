//! The study's cache: every finished cell's error and cost, one small JSON file each under
//! `DIR/cache/`, named by a hash of everything that decides it — the binary, the adapter, the
//! scene's geometry and light, the method, its knobs, the map and image sizes, the reference's
//! K and V(t) (the error), the timing protocol (the cost). A run that stops resumes from what it
//! finds there; a rebuilt binary, another adapter or a changed scene finds nothing and measures
//! again. The references are cached the same way (their V, colour and counted pixels, binary).

use std::fs;
use std::hash::Hasher;
use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::scene::Scene;

/// A 64-bit FNV-1a hasher: stable across runs and machines, unlike `std`'s.
pub struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Hasher for Fnv {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
}

/// The hash of `text`.
pub fn hash_str(text: &str) -> u64 {
    let mut h = Fnv::default();
    h.write(text.as_bytes());
    h.finish()
}

/// What identifies the running binary: its size and modification time (a rebuild changes
/// them), and the crate's version.
pub fn binary_id() -> String {
    let exe = std::env::current_exe()
        .ok()
        .and_then(|p| fs::metadata(p).ok())
        .map(|m| {
            let modified = m
                .modified()
                .ok()
                .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
                .map_or(0, |d| d.as_nanos());
            format!("{}:{modified}", m.len())
        })
        .unwrap_or_default();
    format!("{} {exe}", env!("CARGO_PKG_VERSION"))
}

/// A hash of what a scene renders: every object's triangles and whether it casts, the light and
/// the camera.
pub fn scene_hash(scene: &Scene) -> u64 {
    let mut h = Fnv::default();
    for o in &scene.objects {
        h.write(&[u8::from(o.casts_shadow)]);
        for p in &o.mesh.positions {
            for c in p.to_array() {
                h.write(&c.to_bits().to_le_bytes());
            }
        }
        for t in &o.mesh.triangles {
            for i in t {
                h.write(&i.to_le_bytes());
            }
        }
    }
    h.write(format!("{:?}|{:?}", scene.light, scene.camera).as_bytes());
    h.finish()
}

/// The cache folder of a study's output folder.
pub struct Cache {
    dir: PathBuf,
}

impl Cache {
    pub fn new(out: &Path) -> std::io::Result<Cache> {
        let dir = out.join("cache");
        fs::create_dir_all(&dir)?;
        Ok(Cache { dir })
    }

    fn path(&self, kind: &str, key: &str, ext: &str) -> PathBuf {
        self.dir
            .join(format!("{kind}-{:016x}.{ext}", hash_str(key)))
    }

    /// The value stored under `key`, if any and it reads (a torn or stale file is ignored).
    pub fn get<T: DeserializeOwned>(&self, kind: &str, key: &str) -> Option<T> {
        let text = fs::read_to_string(self.path(kind, key, "json")).ok()?;
        let (stored, value): (String, T) = serde_json::from_str(&text).ok()?;
        (stored == key).then_some(value)
    }

    /// Store `value` under `key` (written to a temporary file and renamed: never torn).
    pub fn put<T: Serialize>(&self, kind: &str, key: &str, value: &T) -> std::io::Result<()> {
        let text = serde_json::to_string(&(key, value)).map_err(std::io::Error::other)?;
        crate::fsutil::write_atomic(&self.path(kind, key, "json"), text.as_bytes())
    }

    /// Raw bytes stored under `key`, if any (the key is the file's first line).
    pub fn get_bytes(&self, kind: &str, key: &str) -> Option<Vec<u8>> {
        let bytes = fs::read(self.path(kind, key, "bin")).ok()?;
        let newline = bytes.iter().position(|&b| b == b'\n')?;
        (&bytes[..newline] == key.as_bytes()).then(|| bytes[newline + 1..].to_vec())
    }

    pub fn put_bytes(&self, kind: &str, key: &str, data: &[u8]) -> std::io::Result<()> {
        let mut all = Vec::with_capacity(key.len() + 1 + data.len());
        all.extend_from_slice(key.as_bytes());
        all.push(b'\n');
        all.extend_from_slice(data);
        crate::fsutil::write_atomic(&self.path(kind, key, "bin"), &all)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv_is_stable() {
        assert_eq!(hash_str(""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(hash_str("a"), 0xaf63_dc4c_8601_ec8c);
    }

    #[test]
    fn a_value_comes_back_under_its_key_only() {
        let dir = std::env::temp_dir().join(format!("dbuffer-cache-{}", std::process::id()));
        let cache = Cache::new(&dir).unwrap();
        cache.put("err", "k1", &vec![1.5f64, 2.0]).unwrap();
        assert_eq!(cache.get::<Vec<f64>>("err", "k1"), Some(vec![1.5, 2.0]));
        assert_eq!(cache.get::<Vec<f64>>("err", "k2"), None);
        cache.put_bytes("ref", "r", &[1, 2, 3]).unwrap();
        assert_eq!(cache.get_bytes("ref", "r"), Some(vec![1, 2, 3]));
        let _ = fs::remove_dir_all(&dir);
    }
}

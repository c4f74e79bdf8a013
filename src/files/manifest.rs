//! `manifest.json`: the files of one run with their sizes and SHA-256 digests, written last, so
//! that a result directory says which run it holds and whether its files are whole.

use super::read_bounded;
use sha2::{Digest, Sha256};
use std::path::Path;

/// Format tag of `manifest.json`.
pub const MANIFEST_FORMAT: &str = "modaltol-results-1";

/// SHA-256 of `bytes`, as lowercase hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// One file of a result directory, as its manifest lists it.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ManifestEntry {
    pub file: String,
    pub bytes: u64,
    pub sha256: String,
}

/// `manifest.json`: what belongs to one run, written last.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Manifest {
    pub format: String,
    /// The run stopped early (interrupted): the files are complete but hold a partial result.
    pub partial: bool,
    pub files: Vec<ManifestEntry>,
}

impl Manifest {
    /// Reads `dir/manifest.json`, if it is one.
    pub fn read(dir: &Path) -> Option<Manifest> {
        let bytes = read_bounded(&dir.join("manifest.json"), 1 << 20).ok()?;
        let m: Manifest = serde_json::from_slice(&bytes).ok()?;
        (m.format == MANIFEST_FORMAT).then_some(m)
    }

    /// Does every listed file exist with its size and digest?
    pub fn verify(&self, dir: &Path) -> Result<(), String> {
        for e in &self.files {
            let bytes = std::fs::read(dir.join(&e.file)).map_err(|x| format!("{}: {x}", e.file))?;
            if bytes.len() as u64 != e.bytes || sha256_hex(&bytes) != e.sha256 {
                return Err(format!("{}: does not match the manifest", e.file));
            }
        }
        Ok(())
    }
}

/// The files a manifest lists and the manifest itself.
pub(super) fn listed(manifest: Option<&Manifest>) -> Vec<String> {
    let mut names: Vec<String> = manifest
        .map(|m| m.files.iter().map(|f| f.file.clone()).collect())
        .unwrap_or_default();
    names.push("manifest.json".into());
    names
}

pub(super) fn is_plain_name(name: &str) -> bool {
    !name.is_empty() && !name.contains(['/', '\\']) && name != "." && name != ".."
}

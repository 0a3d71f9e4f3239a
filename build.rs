//! Build script: the SHA-256 of the sources the library is built from (every file under
//! `src/`, paths sorted, plus `Cargo.lock`), as `TRNEWS_SOURCE_SHA256`. Stored sweep points
//! are keyed by it, so results computed by other code are never reused (see `src/sweep.rs`).

use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("read src")
        .map(|e| e.expect("entry").path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            files(&p, out);
        } else {
            out.push(p);
        }
    }
}

fn main() {
    println!("cargo:rerun-if-changed=src");
    println!("cargo:rerun-if-changed=Cargo.lock");
    let mut paths = Vec::new();
    files(Path::new("src"), &mut paths);
    paths.push(PathBuf::from("Cargo.lock"));
    let mut hash = Sha256::new();
    for p in &paths {
        hash.update(p.to_string_lossy().as_bytes());
        hash.update(std::fs::read(p).expect("read source"));
    }
    let hex: String = hash.finalize().iter().map(|b| format!("{b:02x}")).collect();
    println!("cargo:rustc-env=TRNEWS_SOURCE_SHA256={hex}");
}

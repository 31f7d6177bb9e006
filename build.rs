//! Build script: a fingerprint of the sources, so that a checkpoint written by one build
//! of kdmpm is refused by another (`checkpoint::BUILD_ID`): a resumed run continues bit for
//! bit only with the code that wrote it.

use std::path::{Path, PathBuf};

/// FNV-1a, 64 bits: a fingerprint, not a defence against anyone.
fn fnv(hash: &mut u64, bytes: &[u8]) {
    for &b in bytes {
        *hash ^= u64::from(b);
        *hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
    }
}

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
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
    println!("cargo:rerun-if-changed=Cargo.toml");
    let mut list = Vec::new();
    files(Path::new("src"), &mut list);
    list.push("Cargo.lock".into());
    list.push("Cargo.toml".into());
    list.sort();
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for p in &list {
        fnv(&mut hash, p.to_string_lossy().as_bytes());
        fnv(&mut hash, &std::fs::read(p).unwrap_or_default());
    }
    let target = std::env::var("TARGET").unwrap_or_default();
    fnv(&mut hash, target.as_bytes());
    println!("cargo:rustc-env=KDMPM_SOURCE_HASH={hash:016x}");
}

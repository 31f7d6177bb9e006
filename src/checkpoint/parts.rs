//! Checkpoints of a run over MPI ranks: each rank writes its own part, rank 0 a manifest
//! written last.
//!
//! A part is a whole checkpoint file of one rank ([`super::encode`]: the solver state, the
//! split of the cell layers, and that rank's points), named after its step and rank,
//! `checkpoint.<step>.<rank>.kdc`. Once every rank has written its part, rank 0 writes
//! `checkpoint.kdc`, the manifest: the header (scene, history mark, wall time), the step,
//! and each part's length and CRC-32. Only then does each rank remove its parts of earlier
//! steps, so that a run killed at any moment leaves a manifest whose parts are all there
//! and unchanged. `kdmpm resume DIR` under `mpirun` with the same rank count reads the
//! manifest on every rank and its own part, checked against it, and continues bit for bit;
//! another rank count is refused with the one to use.

use super::{encode, CheckpointError, Header, Reader, Writer, FILE_NAME};
use crate::dim::Dim;
use crate::output::dir::{remove_if_there, write_atomic};
use crate::simulation::Simulation;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The first bytes of a manifest.
pub const MANIFEST_MAGIC: &[u8; 8] = b"KDMPMMF\0";

/// The file of rank `rank`'s part of the checkpoint taken after step `step`.
pub fn part_name(step: u64, rank: usize) -> String {
    format!("checkpoint.{step:012}.{rank}.kdc")
}

/// The step and rank of a part's file name.
fn parse_part_name(name: &str) -> Option<(u64, usize)> {
    let middle = name.strip_prefix("checkpoint.")?.strip_suffix(".kdc")?;
    let (step, rank) = middle.split_once('.')?;
    Some((step.parse().ok()?, rank.parse().ok()?))
}

/// What the manifest ties together.
#[derive(Clone, Debug, PartialEq)]
pub struct Manifest {
    /// The run's header (rank 0's history mark and wall time).
    pub header: Header,
    /// The step after which the parts were taken.
    pub step: u64,
    /// Each rank's part: its length in bytes and CRC-32.
    pub parts: Vec<(u64, u32)>,
}

impl Manifest {
    fn encode(&self, dimension: u64) -> Vec<u8> {
        let mut w = Writer(Vec::new());
        w.header(MANIFEST_MAGIC, dimension, &self.header);
        w.u64(self.step);
        w.u64(self.parts.len() as u64);
        for &(len, crc) in &self.parts {
            w.u64(len);
            w.u32(crc);
        }
        w.finish()
    }

    /// Reads a manifest, refused unless whole and of this build.
    pub fn read(bytes: &[u8], path: &Path) -> Result<Manifest, CheckpointError> {
        let mut r = Reader::new(bytes, path);
        let header = r.header(MANIFEST_MAGIC)?;
        let step = r.u64()?;
        let ranks = r.u64()?;
        if ranks < 2 || ranks > (r.bytes.len() / 12) as u64 {
            return Err(r.fault(format!("a manifest of {ranks} parts")));
        }
        let parts = (0..ranks)
            .map(|_| Ok((r.u64()?, r.u32()?)))
            .collect::<Result<Vec<_>, CheckpointError>>()?;
        if r.at != r.bytes.len() {
            return Err(r.fault("bytes left after the last part".into()));
        }
        Ok(Manifest { header, step, parts })
    }
}

/// Why a manifest is not resumed on one rank: the rank count to resume it with.
pub(super) fn written_over_ranks(bytes: &[u8], path: &Path) -> String {
    match Manifest::read(bytes, path) {
        Ok(m) => format!(
            "written by a run over {} ranks: resume it with `mpirun -n {} kdmpm resume` and \
             the run's directory",
            m.parts.len(),
            m.parts.len()
        ),
        Err(e) => format!("the manifest of a run over MPI ranks, unreadable: {e}"),
    }
}

/// Writes this rank's part of a checkpoint of `sim` into `dir` and, once every rank's is
/// written, rank 0 the manifest; then each rank removes its parts of earlier steps. A
/// collective: every rank gets the same outcome (an error on one is an error on all).
pub fn write<D: Dim>(sim: &Simulation<D>, header: &Header, dir: &Path) -> std::io::Result<()> {
    let comm = &sim.ctx.comm;
    let (rank, step) = (comm.rank(), sim.ctx.state.clock.step);
    let bytes = encode(sim, header);
    let written = write_atomic(&dir.join(part_name(step, rank)), |out| out.write_all(&bytes));
    // Lengths and CRC-32s are exact in f64.
    let mine = [bytes.len() as f64, crc32fast::hash(&bytes) as f64];
    drop(bytes);
    let all = comm.gather_all(&mine);
    if let Some((r, e)) = comm.first_error(&written) {
        return Err(std::io::Error::other(format!(
            "rank {r}: its part of the checkpoint: {e}"
        )));
    }
    let manifest = if comm.is_root() {
        let m = Manifest {
            header: header.clone(),
            step,
            parts: all.chunks_exact(2).map(|p| (p[0] as u64, p[1] as u32)).collect(),
        };
        let bytes = m.encode(D::N as u64);
        write_atomic(&dir.join(FILE_NAME), |out| out.write_all(&bytes))
    } else {
        Ok(())
    };
    if let Some((_, e)) = comm.first_error(&manifest) {
        return Err(std::io::Error::other(format!("the checkpoint's manifest: {e}")));
    }
    // The manifest names this step's parts: the earlier ones are no longer needed.
    let removed = remove_parts(dir, |s, r| r == rank && s != step);
    if let Some((r, e)) = comm.first_error(&removed) {
        return Err(std::io::Error::other(format!(
            "rank {r}: its earlier checkpoint parts: {e}"
        )));
    }
    Ok(())
}

/// Removes the parts in `dir` whose (step, rank) `which` picks.
fn remove_parts(dir: &Path, which: impl Fn(u64, usize) -> bool) -> std::io::Result<()> {
    for e in std::fs::read_dir(dir)?.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if parse_part_name(&name).is_some_and(|(s, r)| which(s, r)) {
            remove_if_there(&e.path())?;
        }
    }
    Ok(())
}

/// Removes an earlier run's checkpoint from `dir`: the file (or manifest) and every part.
pub fn remove_earlier(dir: &Path) -> std::io::Result<()> {
    remove_if_there(&dir.join(FILE_NAME))?;
    remove_parts(dir, |_, _| true)
}

/// What rank `rank` of `ranks` resumes from `dir`: the manifest and its own part (the
/// part's bytes and file), the part checked against the manifest.
pub fn read(dir: &Path, rank: usize, ranks: usize) -> Result<(Manifest, Vec<u8>, PathBuf), CheckpointError> {
    let path = dir.join(FILE_NAME);
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| CheckpointError::Io { path, source }
    };
    let bytes = std::fs::read(&path).map_err(io(&path))?;
    let manifest = Manifest::read(&bytes, &path)?;
    if manifest.parts.len() != ranks {
        return Err(CheckpointError::Format {
            path,
            reason: format!(
                "written by a run over {} ranks, resumed on {ranks}: a run resumes bit for bit \
                 only on the rank count it was split over (`mpirun -n {} kdmpm resume`)",
                manifest.parts.len(),
                manifest.parts.len()
            ),
        });
    }
    let part = dir.join(part_name(manifest.step, rank));
    let bytes = std::fs::read(&part).map_err(io(&part))?;
    let (len, crc) = manifest.parts[rank];
    if bytes.len() as u64 != len || crc32fast::hash(&bytes) != crc {
        return Err(CheckpointError::Format {
            path: part,
            reason: "it is not the part the manifest names (another length or checksum): \
                     changed or replaced after it was written, so the run is not resumed"
                .into(),
        });
    }
    Ok((manifest, bytes, part))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_part_name_gives_back_its_step_and_rank() {
        assert_eq!(parse_part_name(&part_name(1234, 3)), Some((1234, 3)));
        assert_eq!(parse_part_name(FILE_NAME), None);
        assert_eq!(parse_part_name("checkpoint.12.kdc"), None);
    }

    #[test]
    fn a_manifest_reads_back_and_a_changed_byte_is_refused() {
        let m = Manifest {
            header: Header {
                scene_path: "s.ron".into(),
                scene_text: "Scene()".into(),
                history_bytes: 7,
                history_crc: 9,
                wall_seconds: 1.5,
                meshes_crc: 3,
            },
            step: 42,
            parts: vec![(100, 1), (200, 2)],
        };
        let mut bytes = m.encode(2);
        assert_eq!(Manifest::read(&bytes, Path::new("m")).unwrap(), m);
        let at = bytes.len() / 2;
        bytes[at] ^= 1;
        let e = Manifest::read(&bytes, Path::new("m")).unwrap_err().to_string();
        assert!(e.contains("checksum"), "{e}");
    }
}

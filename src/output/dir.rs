//! An output directory owned by one run: a lock held for the run's lifetime, and files that
//! appear whole or not at all.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Name of the lock file in an output directory. It stays after the run; the lock on it
/// is the operating system's and ends with the process, however the process ends.
pub const LOCK_FILE: &str = ".kdmpm.lock";

/// Why an output directory cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum DirError {
    /// It could not be created or its lock file opened.
    #[error("cannot create output directory {path}: {source}")]
    Create {
        /// The directory.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Another process holds it.
    #[error(
        "output directory {path} is in use by another run ({holder}): wait for it, or choose another --out"
    )]
    InUse {
        /// The directory.
        path: PathBuf,
        /// "process N" as written in the lock file, or "a process" when it cannot be read.
        holder: String,
    },
}

/// An output directory locked for this process.
#[derive(Debug)]
pub struct OutputDir {
    path: PathBuf,
    /// Holds the lock until dropped.
    _lock: File,
}

impl OutputDir {
    /// Creates `path` if needed and takes its lock; refuses a directory another process holds.
    pub fn claim(path: &Path) -> Result<Self, DirError> {
        let create = |source| DirError::Create {
            path: path.to_path_buf(),
            source,
        };
        std::fs::create_dir_all(path).map_err(create)?;
        let mut lock = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(path.join(LOCK_FILE))
            .map_err(create)?;
        match lock.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                let mut holder = String::new();
                let _ = lock.read_to_string(&mut holder);
                let holder = holder.trim();
                return Err(DirError::InUse {
                    path: path.to_path_buf(),
                    holder: if holder.is_empty() {
                        "a process".into()
                    } else {
                        holder.to_string()
                    },
                });
            }
            Err(TryLockError::Error(e)) => return Err(create(e)),
        }
        // Who holds it, for the message another run prints.
        let _ = lock.set_len(0);
        let _ = lock.seek(SeekFrom::Start(0));
        let _ = writeln!(lock, "process {}", std::process::id());
        // Files a killed process was writing (`write_atomic`'s temporaries): no one else
        // writes here while the lock is held, so every one of them is dead.
        remove_partials(path).map_err(create)?;
        Ok(OutputDir {
            path: path.to_path_buf(),
            _lock: lock,
        })
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The path of file `name` in the directory.
    pub fn file(&self, name: &str) -> PathBuf {
        self.path.join(name)
    }

    /// Writes file `name` whole: `write` fills a temporary file in the same directory,
    /// which is synced and renamed over `name` only when all went well. A crash or a full
    /// disk leaves the previous `name` (or none), never a part of the new one.
    pub fn write_atomic(
        &self,
        name: &str,
        write: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
    ) -> std::io::Result<()> {
        write_atomic(&self.file(name), write)
    }
}

/// Removes `path`; one that is not there is fine.
pub(crate) fn remove_if_there(path: &Path) -> std::io::Result<()> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(e),
        _ => Ok(()),
    }
}

/// Removes the `*.partial-<pid>` temporaries of [`write_atomic`] in `dir` and its
/// `snapshots/` folder.
fn remove_partials(dir: &Path) -> std::io::Result<()> {
    for folder in [dir.to_path_buf(), dir.join("snapshots")] {
        let Ok(entries) = std::fs::read_dir(&folder) else {
            continue;
        };
        for e in entries.flatten() {
            if e.file_name().to_string_lossy().contains(".partial-") && e.path().is_file() {
                std::fs::remove_file(e.path())?;
            }
        }
    }
    Ok(())
}

/// Writes `path` whole through a temporary file (see [`OutputDir::write_atomic`]).
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(format!(".partial-{}", std::process::id()));
    let tmp = PathBuf::from(tmp);
    let result = (|| {
        let mut out = BufWriter::with_capacity(1 << 20, File::create(&tmp)?);
        write(&mut out)?;
        let file = out.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// A file written row by row that only ever holds whole rows: rows are buffered and
/// appended in whole rows (when the buffer fills, and at least once a second so that a
/// running output can be watched); a failed append (a full disk) is cut back to the last
/// whole row before the error is returned.
#[derive(Debug)]
pub struct RowFile {
    file: File,
    buffer: Vec<u8>,
    committed: u64,
    /// CRC-32 of the committed bytes, which a checkpoint records ([`RowFile::resume`]).
    crc: crc32fast::Hasher,
    flushed: std::time::Instant,
}

/// Rows are appended to the file once this many bytes are buffered.
const ROW_BUFFER: usize = 64 * 1024;

impl RowFile {
    /// Creates (or empties) `path`.
    pub fn create(path: &Path) -> std::io::Result<Self> {
        Ok(Self::at(File::create(path)?, 0, crc32fast::Hasher::new()))
    }

    /// Rows appended to `file`, which holds `committed` bytes of whole rows whose CRC so
    /// far is `crc`.
    fn at(file: File, committed: u64, crc: crc32fast::Hasher) -> Self {
        RowFile {
            file,
            buffer: Vec::with_capacity(ROW_BUFFER),
            flushed: std::time::Instant::now(),
            committed,
            crc,
        }
    }

    /// Opens `path` to continue after its first `bytes` bytes, whose CRC-32 must be `crc`
    /// (the rows the checkpoint's run wrote, not another run's); what follows them (rows
    /// of steps after a checkpoint) is cut off. Nothing is cut from a file that fails.
    pub fn resume(path: &Path, bytes: u64, crc: u32) -> std::io::Result<Self> {
        let mut file = OpenOptions::new().read(true).write(true).open(path)?;
        if file.metadata()?.len() < bytes {
            return Err(std::io::Error::new(
                std::io::ErrorKind::UnexpectedEof,
                format!(
                    "{} is shorter than the checkpoint's {bytes} bytes",
                    path.display()
                ),
            ));
        }
        let mut hasher = crc32fast::Hasher::new();
        let mut left = bytes;
        let mut chunk = vec![0u8; 1 << 16];
        while left > 0 {
            let n = left.min(chunk.len() as u64) as usize;
            file.read_exact(&mut chunk[..n])?;
            hasher.update(&chunk[..n]);
            left -= n as u64;
        }
        if hasher.clone().finalize() != crc {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!(
                    "{} is not the history this checkpoint continues (its first {bytes} bytes \
                     differ from the ones the checkpoint's run wrote): the directory holds \
                     another run's files",
                    path.display()
                ),
            ));
        }
        file.set_len(bytes)?;
        file.seek(SeekFrom::Start(bytes))?;
        Ok(Self::at(file, bytes, hasher))
    }

    /// Adds one row (its text must end with a newline).
    pub fn row(&mut self, row: &[u8]) -> std::io::Result<()> {
        self.buffer.extend_from_slice(row);
        if self.buffer.len() >= ROW_BUFFER || self.flushed.elapsed().as_secs_f64() >= 1.0 {
            self.flush()?;
        }
        Ok(())
    }

    /// Appends the buffered rows to the file.
    pub fn flush(&mut self) -> std::io::Result<()> {
        if self.buffer.is_empty() {
            return Ok(());
        }
        if let Err(e) = self.file.write_all(&self.buffer) {
            // Keep whole rows only; if even the cut fails, the error is the first one.
            let _ = self.file.set_len(self.committed);
            let _ = self.file.seek(SeekFrom::Start(self.committed));
            self.buffer.clear();
            return Err(e);
        }
        self.committed += self.buffer.len() as u64;
        self.crc.update(&self.buffer);
        self.buffer.clear();
        self.flushed = std::time::Instant::now();
        Ok(())
    }

    /// Bytes on disk (whole rows).
    pub fn committed(&self) -> u64 {
        self.committed
    }

    /// CRC-32 of the bytes on disk.
    pub fn committed_crc(&self) -> u32 {
        self.crc.clone().finalize()
    }
}

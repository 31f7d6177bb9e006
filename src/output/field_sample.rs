//! The points the displacement-field figure draws, read from a run's points files one
//! record at a time: however many points the run holds (every rank's, over MPI), the
//! figure costs memory for the points it draws, not for the run's.

use std::fs::File;
use std::io::{BufRead, BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

/// Points drawn at most: beyond it one point in `every` is drawn, so that a million-point
/// run does not spend its end on a 90 MB picture.
pub const FIELD_POINTS: usize = 50_000;

/// What the figure needs of the final points: the extent of all of them, the largest |u|
/// of all of them, and one point in `every` (in file order over the pieces, from the
/// first) with its |u|.
#[derive(Debug)]
pub struct FieldSample {
    /// One point drawn in this many.
    pub every: usize,
    /// Smallest and largest x, then y, over every point (m).
    pub bounds: [f64; 4],
    /// The largest |u| over every point (m), 0 without points.
    pub top: f64,
    /// The drawn points: deformed position (m) and |u| (m).
    pub drawn: Vec<([f64; 3], f64)>,
}

impl FieldSample {
    /// The sample of a run's final points: `points.vtu`, or over MPI ranks every piece
    /// `points.pvtu` names. `Ok(None)`: the points carry no displacement.
    pub fn read_run(dir: &Path) -> std::io::Result<Option<FieldSample>> {
        let whole = dir.join("points.vtu");
        let parallel = dir.join("points.pvtu");
        let paths = if whole.exists() || !parallel.exists() {
            vec![whole]
        } else {
            let text = std::fs::read_to_string(&parallel)?;
            text.split("Source=\"")
                .skip(1)
                .map(|piece| dir.join(piece.split('"').next().unwrap_or_default()))
                .collect()
        };
        let pieces = paths
            .into_iter()
            .map(Piece::open)
            .collect::<std::io::Result<Vec<Piece>>>()?;
        if pieces.iter().any(|p| p.displacement.is_none()) {
            return Ok(None);
        }
        let total: usize = pieces.iter().map(|p| p.points).sum();
        let mut sample = FieldSample {
            every: total.div_ceil(FIELD_POINTS).max(1),
            bounds: [f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY],
            top: 0.0,
            drawn: Vec::with_capacity(total.min(FIELD_POINTS)),
        };
        let mut index = 0;
        for piece in &pieces {
            let mut xs = piece.vectors(piece.position)?;
            let mut us = piece.vectors(piece.displacement.expect("every piece has them"))?;
            for _ in 0..piece.points {
                let (x, u) = (xs.next()?, us.next()?);
                sample.add(index, x, u);
                index += 1;
            }
        }
        Ok(Some(sample))
    }

    /// Takes the `index`-th point of the run (position `x`, displacement `u`).
    fn add(&mut self, index: usize, x: [f64; 3], u: [f64; 3]) {
        let b = &mut self.bounds;
        (b[0], b[1], b[2], b[3]) = (b[0].min(x[0]), b[1].max(x[0]), b[2].min(x[1]), b[3].max(x[1]));
        let magnitude = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
        self.top = self.top.max(magnitude);
        if index.is_multiple_of(self.every) {
            self.drawn.push((x, magnitude));
        }
    }
}

/// One `.vtu` this crate wrote (`vtk::write_points`): its head read, its appended arrays
/// left on disk.
struct Piece {
    path: PathBuf,
    /// Byte of the file where the appended data begins (after its `_`).
    data_start: u64,
    /// `NumberOfPoints` of the head.
    points: usize,
    /// Offsets of the positions and of the displacements in the appended data.
    position: u64,
    displacement: Option<u64>,
}

/// Bytes of a head at most: a points file's head is a few kB of XML.
const HEAD_LIMIT: u64 = 1 << 20;

impl Piece {
    fn open(path: PathBuf) -> std::io::Result<Piece> {
        // The head is read through a limit: a file of another kind, without the line that
        // ends it, is refused after HEAD_LIMIT bytes, not read whole.
        let mut file = BufReader::new(File::open(&path)?).take(HEAD_LIMIT);
        let mut head = String::new();
        let bad = || not_points(&path);
        // The head is XML lines up to the one that opens the appended data; after that
        // line's end, the data starts at the byte after the first `_`.
        loop {
            let mut line = Vec::new();
            if file.read_until(b'\n', &mut line)? == 0 {
                return Err(bad());
            }
            let line = std::str::from_utf8(&line).map_err(|_| bad())?;
            head.push_str(line);
            if line.contains("<AppendedData encoding=\"raw\">") {
                break;
            }
        }
        let mut skipped = 0u64;
        let mut byte = [0u8];
        loop {
            file.read_exact(&mut byte).map_err(|_| bad())?;
            skipped += 1;
            if byte[0] == b'_' {
                break;
            }
        }
        let data_start = head.len() as u64 + skipped;
        let attribute = |line: &str, name: &str| -> Option<u64> {
            let start = line.find(&format!("{name}=\""))? + name.len() + 2;
            line[start..start + line[start..].find('"')?].parse().ok()
        };
        let array = |name: Option<&str>| -> Option<u64> {
            let line = head.lines().find(|l| {
                l.contains("<DataArray")
                    && match name {
                        Some(n) => l.contains(&format!("Name=\"{n}\"")),
                        None => !l.contains("Name="),
                    }
            })?;
            attribute(line, "offset")
        };
        let points = head
            .lines()
            .find_map(|l| attribute(l, "NumberOfPoints"))
            .ok_or_else(bad)? as usize;
        let position = array(None).ok_or_else(bad)?;
        let displacement = array(Some("displacement"));
        Ok(Piece {
            data_start,
            points,
            position,
            displacement,
            path,
        })
    }

    fn bad(&self) -> std::io::Error {
        not_points(&self.path)
    }

    /// The three-component Float64 array at `offset`, read a record at a time.
    fn vectors(&self, offset: u64) -> std::io::Result<Vectors> {
        let mut file = File::open(&self.path)?;
        file.seek(SeekFrom::Start(self.data_start + offset))?;
        let mut file = BufReader::new(file);
        let mut len = [0u8; 8];
        file.read_exact(&mut len).map_err(|_| self.bad())?;
        let bytes = u64::from_le_bytes(len);
        if bytes != 24 * self.points as u64 {
            return Err(self.bad());
        }
        Ok(Vectors(file))
    }
}

fn not_points(path: &Path) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::InvalidData,
        format!("{} is not a points file of kdmpm", path.display()),
    )
}

/// A three-component Float64 array being read, a record at a time.
struct Vectors(BufReader<File>);

impl Vectors {
    fn next(&mut self) -> std::io::Result<[f64; 3]> {
        let mut record = [0u8; 24];
        self.0.read_exact(&mut record)?;
        Ok(std::array::from_fn(|k| {
            f64::from_le_bytes(record[8 * k..8 * k + 8].try_into().expect("8 bytes"))
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::vtk::{write_frame, write_parallel_frame, Frame};

    /// A fresh directory for one test's files.
    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("kdmpm-field-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// `n` points from `first` on, at x = (index, -index) m, displaced (0, index, 0) mm.
    fn frame(first: usize, n: usize) -> Frame {
        let k = |i: usize| (first + i) as f64;
        Frame {
            id: (0..n).map(|i| (first + i) as u32).collect(),
            material: vec![0; n],
            position: (0..n).map(|i| [k(i), -k(i), 0.0]).collect(),
            displacement: Some((0..n).map(|i| [0.0, 1e-3 * k(i), 0.0]).collect()),
            velocity: vec![[0.0; 3]; n],
            stress: vec![[0.0; 6]; n],
            volume: vec![1.0; n],
            plastic_strain: vec![0.0; n],
            ..Frame::default()
        }
    }

    #[test]
    fn pieces_are_drawn_one_point_in_every_over_their_joint_with_the_extent_of_all() {
        let dir = scratch("pieces");
        // 70 001 points in the two pieces of a pvtu: one drawn in two, counted over the
        // joint (the second piece starts at an odd index).
        let (a, b) = (frame(0, 30_001), frame(30_001, 40_000));
        write_frame(&a, &dir.as_path().join("points_0.vtu")).unwrap();
        write_frame(&b, &dir.as_path().join("points_1.vtu")).unwrap();
        let parts = ["points_0.vtu".to_string(), "points_1.vtu".to_string()];
        write_parallel_frame(&a, &dir.as_path().join("points.pvtu"), &parts).unwrap();
        let s = FieldSample::read_run(dir.as_path())
            .unwrap()
            .expect("displacements kept");
        assert_eq!(s.every, 2);
        assert_eq!(s.bounds, [0.0, 70_000.0, -70_000.0, 0.0]);
        assert_eq!(s.top, 70.0);
        assert_eq!(s.drawn.len(), 35_001);
        assert_eq!(s.drawn[15_001], ([30_002.0, -30_002.0, 0.0], 30.002));
        assert_eq!(s.drawn[35_000].0, [70_000.0, -70_000.0, 0.0]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn points_without_displacements_give_no_sample_and_a_foreign_file_an_error() {
        let dir = scratch("foreign");
        let mut f = frame(0, 10);
        f.displacement = None;
        write_frame(&f, &dir.as_path().join("points.vtu")).unwrap();
        assert!(FieldSample::read_run(dir.as_path()).unwrap().is_none());
        std::fs::write(dir.as_path().join("points.vtu"), "<VTKFile>\n").unwrap();
        let e = FieldSample::read_run(dir.as_path()).unwrap_err();
        assert!(e.to_string().ends_with("is not a points file of kdmpm"), "{e}");
        // A head that never ends is refused at the limit.
        std::fs::write(dir.join("points.vtu"), vec![b'x'; 2 << 20]).unwrap();
        let e = FieldSample::read_run(dir.as_path()).unwrap_err();
        assert!(e.to_string().ends_with("is not a points file of kdmpm"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

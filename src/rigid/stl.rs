//! Reading an STL file into welded vertices and triangles.
//!
//! Both encodings as CAD tools write them: binary (an 80-byte header, a triangle count and
//! 50 bytes a triangle, recognised by its size even when the header starts with `solid`, as
//! some exporters write it) and ASCII (`solid [name]`, then `facet normal`, `outer loop`,
//! three `vertex x y z`, `endloop`, `endfacet`; `endsolid [name]`). ASCII coordinates are read
//! in f64. The facet normals are not used: the winding gives the sense.
//!
//! Corners are welded by value, −0.0 with 0.0: a cube one of whose corners is written `-0`
//! once is still closed. Only a regular file of at most [`MAX_BYTES`] is read (a device such
//! as /dev/zero is endless).

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

/// The largest STL file read: 1 GiB, about 21 million binary triangles.
pub const MAX_BYTES: u64 = 1 << 30;

/// The welded mesh of a file: vertices (m) and each triangle's corner indices, in file
/// order.
pub type Welded = (Vec<[f64; 3]>, Vec<[usize; 3]>);

/// Reads the STL file at `path`: an error says what is wrong with it.
pub fn read(path: &Path) -> Result<Welded, String> {
    let shown = path.display();
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot open {shown}: {e}"))?;
    if !meta.is_file() {
        return Err(format!(
            "{shown} is not a regular file (a device, a pipe or a folder): give an STL file"
        ));
    }
    if meta.len() > MAX_BYTES {
        return Err(format!(
            "{shown} holds {} bytes, more than the {MAX_BYTES} an STL file may have here",
            meta.len()
        ));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    std::fs::File::open(path)
        .map_err(|e| format!("cannot open {shown}: {e}"))?
        .take(MAX_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("cannot read {shown}: {e}"))?;
    let triangles = if is_binary(&bytes) {
        binary(&bytes)
    } else {
        ascii(&bytes).map_err(|e| format!("{shown} is not an STL file: {e}"))?
    };
    if triangles.is_empty() {
        return Err(format!("{shown} holds no triangles"));
    }
    Ok(weld(&triangles))
}

/// A binary file: 84 + 50 n bytes for the n triangles its count gives.
fn is_binary(bytes: &[u8]) -> bool {
    bytes.len() >= 84 && {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        bytes.len() as u64 == 84 + 50 * n
    }
}

fn binary(bytes: &[u8]) -> Vec<[[f64; 3]; 3]> {
    bytes[84..]
        .chunks_exact(50)
        .map(|t| {
            let f = |k: usize| f64::from(f32::from_le_bytes([t[k], t[k + 1], t[k + 2], t[k + 3]]));
            // 12 bytes of normal, then three corners of 12 bytes each.
            std::array::from_fn(|c| std::array::from_fn(|a| f(12 + 12 * c + 4 * a)))
        })
        .collect()
}

fn ascii(bytes: &[u8]) -> Result<Vec<[[f64; 3]; 3]>, String> {
    let text = std::str::from_utf8(bytes)
        .map_err(|_| "neither binary (its size is not 84 + 50 n bytes) nor ASCII text".to_string())?;
    let mut words = text.split_ascii_whitespace().peekable();
    if words.next() != Some("solid") {
        return Err("an ASCII STL starts with `solid`".into());
    }
    // The solid's name, if any, runs to the first facet.
    while words.peek().is_some_and(|w| *w != "facet" && *w != "endsolid") {
        words.next();
    }
    let mut out: Vec<[[f64; 3]; 3]> = Vec::new();
    let expect =
        |words: &mut std::iter::Peekable<std::str::SplitAsciiWhitespace>, w: &str, done: usize| match words
            .next()
        {
            Some(found) if found == w => Ok(()),
            found => Err(format!(
                "expected `{w}` after triangle {done}, found {}",
                found.map_or("the end of the file".into(), |f| format!("`{f}`"))
            )),
        };
    loop {
        match words.next() {
            Some("endsolid") | None => break,
            Some("facet") => {}
            Some(w) => return Err(format!("expected `facet` or `endsolid`, found `{w}`")),
        }
        expect(&mut words, "normal", out.len())?;
        for _ in 0..3 {
            words.next();
        }
        expect(&mut words, "outer", out.len())?;
        expect(&mut words, "loop", out.len())?;
        let mut t = [[0.0; 3]; 3];
        for corner in &mut t {
            expect(&mut words, "vertex", out.len())?;
            for c in corner.iter_mut() {
                let w = words.next().unwrap_or("");
                *c = w
                    .parse()
                    .map_err(|_| format!("`{w}` is not a coordinate (a vertex has three numbers)"))?;
            }
        }
        expect(&mut words, "endloop", out.len())?;
        expect(&mut words, "endfacet", out.len())?;
        out.push(t);
    }
    Ok(out)
}

/// Welds equal corners (−0.0 as 0.0) into shared vertices.
pub(super) fn weld(triangles: &[[[f64; 3]; 3]]) -> Welded {
    let mut index: HashMap<[u64; 3], usize> = HashMap::new();
    let mut vertices = Vec::new();
    let faces = triangles
        .iter()
        .map(|t| {
            t.map(|c| {
                let c = c.map(|x| x + 0.0);
                *index.entry(c.map(f64::to_bits)).or_insert_with(|| {
                    vertices.push(c);
                    vertices.len() - 1
                })
            })
        })
        .collect();
    (vertices, faces)
}

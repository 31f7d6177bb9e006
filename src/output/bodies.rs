//! The rigid bodies in a snapshot (`snapshots/bodies_*.vtu`, the second part of each
//! `points.pvd` entry): each part a filled polygon in 2D and axisymmetric scenes, a cloud of
//! surface points in 3D, with the body's and the part's index as cell data, so that
//! ParaView draws the body moving through the soil.

use crate::output::dir::write_atomic;
use crate::rigid::Outline;
use std::io::Write;
use std::path::Path;

/// VTK's cell types used here.
const VTK_VERTEX: u8 = 1;
const VTK_POLYGON: u8 = 7;

/// Writes `outlines` as a VTK XML unstructured grid (ASCII: a few hundred points).
pub fn write_bodies(path: &Path, outlines: &[Outline]) -> std::io::Result<()> {
    // Cells: a closed outline is one polygon, a cloud one vertex a point.
    let mut cells: Vec<(u8, Vec<usize>, u32, u32)> = Vec::new();
    let mut points: Vec<[f64; 3]> = Vec::new();
    for o in outlines {
        let first = points.len();
        points.extend_from_slice(&o.points);
        if o.closed {
            cells.push((VTK_POLYGON, (first..points.len()).collect(), o.body, o.part));
        } else {
            cells.extend((first..points.len()).map(|k| (VTK_VERTEX, vec![k], o.body, o.part)));
        }
    }
    write_atomic(path, |out| {
        out.write_all(b"<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n")?;
        writeln!(
            out,
            "<UnstructuredGrid><Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
            points.len(),
            cells.len()
        )?;
        out.write_all(b"<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n")?;
        for p in &points {
            // Shortest decimals that read back to the same f64.
            writeln!(out, "{:?} {:?} {:?}", p[0], p[1], p[2])?;
        }
        out.write_all(b"</DataArray></Points>\n<Cells>\n")?;
        out.write_all(b"<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n")?;
        for c in &cells {
            let ids: Vec<String> = c.1.iter().map(usize::to_string).collect();
            writeln!(out, "{}", ids.join(" "))?;
        }
        out.write_all(b"</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n")?;
        let mut end = 0;
        for c in &cells {
            end += c.1.len();
            write!(out, "{end} ")?;
        }
        out.write_all(b"\n</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n")?;
        for c in &cells {
            write!(out, "{} ", c.0)?;
        }
        out.write_all(b"\n</DataArray>\n</Cells>\n<CellData>\n")?;
        for (name, pick) in [("body", 2), ("part", 3)] {
            writeln!(
                out,
                "<DataArray type=\"UInt32\" Name=\"{name}\" format=\"ascii\">"
            )?;
            for c in &cells {
                write!(out, "{} ", if pick == 2 { c.2 } else { c.3 })?;
            }
            out.write_all(b"\n</DataArray>\n")?;
        }
        out.write_all(b"</CellData>\n</Piece></UnstructuredGrid>\n</VTKFile>\n")
    })
}

//! VTK XML `UnstructuredGrid` (.vtu) writer for hexahedral meshes, plus the
//! ParaView collection (.pvd) that ties time frames together.
//!
//! Format: VTK XML file format version 1.0, `byte_order="LittleEndian"`,
//! `header_type="UInt64"`, no compression, data arrays inline with
//! `format="binary"`: each array is the base64 encoding of
//! `[u64 byte count (LE)][raw little-endian values]` (header and payload encoded as
//! one base64 stream, as VTK itself writes uncompressed inline binary). Float64
//! values are therefore stored bit-exactly.
//!
//! Both writers go through [`super::atomic`], so a crash never leaves a partial
//! file behind; the .pvd is meant to be rewritten after every completed frame.

use std::fmt::Write as _;
use std::io::{self, Write};
use std::path::Path;

use super::atomic::{write_atomic, write_atomic_with};

/// VTK cell type id of the linear 8-node hexahedron.
pub const VTK_HEXAHEDRON: u8 = 12;

/// One named data array attached to points or cells.
/// `data.len()` must equal `components * n` (n = number of points or cells).
#[derive(Clone, Copy, Debug)]
pub enum DataArray<'a> {
    F64 {
        name: &'a str,
        components: usize,
        data: &'a [f64],
    },
    I32 {
        name: &'a str,
        components: usize,
        data: &'a [i32],
    },
    U8 {
        name: &'a str,
        components: usize,
        data: &'a [u8],
    },
}

impl<'a> DataArray<'a> {
    pub fn name(&self) -> &'a str {
        match *self {
            DataArray::F64 { name, .. }
            | DataArray::I32 { name, .. }
            | DataArray::U8 { name, .. } => name,
        }
    }

    pub fn components(&self) -> usize {
        match *self {
            DataArray::F64 { components, .. }
            | DataArray::I32 { components, .. }
            | DataArray::U8 { components, .. } => components,
        }
    }

    /// Number of scalar values in `data`.
    pub fn len(&self) -> usize {
        match *self {
            DataArray::F64 { data, .. } => data.len(),
            DataArray::I32 { data, .. } => data.len(),
            DataArray::U8 { data, .. } => data.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn vtk_type(&self) -> &'static str {
        match self {
            DataArray::F64 { .. } => "Float64",
            DataArray::I32 { .. } => "Int32",
            DataArray::U8 { .. } => "UInt8",
        }
    }
}

/// One time frame of a hexahedral mesh.
#[derive(Clone, Debug)]
pub struct VtuFrame<'a> {
    pub points: &'a [[f64; 3]],
    pub hexahedra: &'a [[u32; 8]],
    pub point_data: Vec<DataArray<'a>>,
    pub cell_data: Vec<DataArray<'a>>,
    /// Written as FieldData array `TimeValue` (Float64, 1 tuple) when present.
    pub time: Option<f64>,
}

/// One entry of a .pvd collection. `file` is relative to the .pvd's directory.
#[derive(Clone, Debug, PartialEq)]
pub struct PvdEntry {
    pub time: f64,
    pub file: String,
}

fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg)
}

fn validate_arrays(kind: &str, arrays: &[DataArray], n: usize) -> io::Result<()> {
    for (i, a) in arrays.iter().enumerate() {
        let name = a.name();
        if name.is_empty() {
            return Err(invalid(format!("vtu: {kind} array #{i} has an empty name")));
        }
        if arrays[..i].iter().any(|b| b.name() == name) {
            return Err(invalid(format!(
                "vtu: duplicate {kind} array name '{name}'"
            )));
        }
        let c = a.components();
        if c == 0 {
            return Err(invalid(format!(
                "vtu: {kind} array '{name}' has 0 components"
            )));
        }
        let expected = c.checked_mul(n);
        if expected != Some(a.len()) {
            return Err(invalid(format!(
                "vtu: {kind} array '{name}' has {} values, expected {c} components x {n} = {}",
                a.len(),
                c.saturating_mul(n)
            )));
        }
    }
    Ok(())
}

fn validate(frame: &VtuFrame) -> io::Result<()> {
    let np = frame.points.len();
    for (e, hex) in frame.hexahedra.iter().enumerate() {
        if let Some(&v) = hex.iter().find(|&&v| v as usize >= np) {
            return Err(invalid(format!(
                "vtu: hexahedron {e} references point {v} but there are only {np} points"
            )));
        }
    }
    validate_arrays("point data", &frame.point_data, np)?;
    validate_arrays("cell data", &frame.cell_data, frame.hexahedra.len())?;
    Ok(())
}

/// Escape a string for use inside a double-quoted XML attribute.
fn xml_attr(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\n' => out.push_str("&#10;"),
            '\r' => out.push_str("&#13;"),
            '\t' => out.push_str("&#9;"),
            c => out.push(c),
        }
    }
    out
}

// ---------------------------------------------------------------------------
// base64 (RFC 4648, standard alphabet, with '=' padding): the `base64` crate
// ---------------------------------------------------------------------------

use base64::engine::general_purpose::STANDARD as BASE64;
use base64::Engine as _;

/// Base64 (RFC 4648, padded) of `bytes`.
pub fn base64_encode(bytes: &[u8]) -> String {
    BASE64.encode(bytes)
}

/// Write one binary block `base64([u64 LE byte count][payload])`, where the
/// payload is `n_values` values of `size` bytes each produced by `fill`, which
/// appends the little-endian bytes of values `[start, end)` to a scratch buffer.
fn write_block(
    w: &mut dyn Write,
    n_values: usize,
    size: usize,
    mut fill: impl FnMut(usize, usize, &mut Vec<u8>),
) -> io::Result<()> {
    const CHUNK: usize = 3 * 1024; // values per staging chunk
    let nbytes = (n_values * size) as u64;
    // one base64 stream over the count and the payload; the encoder buffers its output
    let mut enc =
        base64::write::EncoderWriter::new(io::BufWriter::with_capacity(1 << 15, w), &BASE64);
    enc.write_all(&nbytes.to_le_bytes())?;
    let mut scratch = Vec::with_capacity(CHUNK * size);
    let mut start = 0;
    while start < n_values {
        let end = (start + CHUNK).min(n_values);
        scratch.clear();
        fill(start, end, &mut scratch);
        debug_assert_eq!(scratch.len(), (end - start) * size);
        enc.write_all(&scratch)?;
        start = end;
    }
    let mut inner = enc.finish()?;
    inner.flush()
}

fn write_f64_block(w: &mut dyn Write, data: &[f64]) -> io::Result<()> {
    write_block(w, data.len(), 8, |s, e, buf| {
        for v in &data[s..e] {
            buf.extend_from_slice(&v.to_le_bytes());
        }
    })
}

fn write_i32_block(w: &mut dyn Write, data: &[i32]) -> io::Result<()> {
    write_block(w, data.len(), 4, |s, e, buf| {
        for v in &data[s..e] {
            buf.extend_from_slice(&v.to_le_bytes());
        }
    })
}

fn write_u8_block(w: &mut dyn Write, data: &[u8]) -> io::Result<()> {
    write_block(w, data.len(), 1, |s, e, buf| {
        buf.extend_from_slice(&data[s..e])
    })
}

/// `<DataArray ...>` opening tag; `extra` holds additional attributes.
fn open_array(
    w: &mut dyn Write,
    indent: &str,
    ty: &str,
    name: &str,
    components: usize,
    extra: &str,
) -> io::Result<()> {
    write!(
        w,
        "{indent}<DataArray type=\"{ty}\" Name=\"{}\" NumberOfComponents=\"{components}\"{extra} format=\"binary\">\n{indent}  ",
        xml_attr(name)
    )
}

fn close_array(w: &mut dyn Write, indent: &str) -> io::Result<()> {
    write!(w, "\n{indent}</DataArray>\n")
}

fn write_data_array(w: &mut dyn Write, indent: &str, a: &DataArray) -> io::Result<()> {
    open_array(w, indent, a.vtk_type(), a.name(), a.components(), "")?;
    match *a {
        DataArray::F64 { data, .. } => write_f64_block(w, data)?,
        DataArray::I32 { data, .. } => write_i32_block(w, data)?,
        DataArray::U8 { data, .. } => write_u8_block(w, data)?,
    }
    close_array(w, indent)
}

/// Stream a complete .vtu document for `frame` into `w` (validated first, so
/// nothing is written when the frame is inconsistent).
pub fn write_vtu_to(w: &mut dyn Write, frame: &VtuFrame) -> io::Result<()> {
    validate(frame)?;
    write_vtu_parts(w, frame, &cells_xml(frame.hexahedra)?)
}

/// The `<Cells>` element of a .vtu document of `hexahedra` (connectivity, offsets, types):
/// the same bytes in every frame of a run, so that a run encodes it once
/// ([`write_vtu_with_cells`]).
pub fn cells_xml(hexahedra: &[[u32; 8]]) -> io::Result<Vec<u8>> {
    let mut out = Vec::new();
    let w: &mut dyn Write = &mut out;
    let nc = hexahedra.len();
    w.write_all(b"      <Cells>\n")?;
    open_array(w, "        ", "Int64", "connectivity", 1, "")?;
    write_block(w, nc * 8, 8, |s, e, buf| {
        for k in s..e {
            buf.extend_from_slice(&i64::from(hexahedra[k / 8][k % 8]).to_le_bytes());
        }
    })?;
    close_array(w, "        ")?;
    open_array(w, "        ", "Int64", "offsets", 1, "")?;
    write_block(w, nc, 8, |s, e, buf| {
        for k in s..e {
            buf.extend_from_slice(&(8 * (k as i64 + 1)).to_le_bytes());
        }
    })?;
    close_array(w, "        ")?;
    open_array(w, "        ", "UInt8", "types", 1, "")?;
    write_block(w, nc, 1, |s, e, buf| {
        buf.resize(buf.len() + (e - s), VTK_HEXAHEDRON)
    })?;
    close_array(w, "        ")?;
    w.write_all(b"      </Cells>\n")?;
    Ok(out)
}

/// Atomically write `frame` to `path` with its `<Cells>` element `cells` encoded beforehand
/// ([`cells_xml`] of `frame.hexahedra`): the bytes of [`write_vtu`].
pub fn write_vtu_with_cells(path: &Path, frame: &VtuFrame, cells: &[u8]) -> io::Result<()> {
    validate(frame)?;
    write_atomic_with(path, |w| write_vtu_parts(w, frame, cells))
}

/// The document of a validated `frame` with its `<Cells>` element `cells`.
fn write_vtu_parts(w: &mut dyn Write, frame: &VtuFrame, cells: &[u8]) -> io::Result<()> {
    let np = frame.points.len();
    let nc = frame.hexahedra.len();

    w.write_all(b"<?xml version=\"1.0\"?>\n")?;
    w.write_all(
        b"<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n",
    )?;
    w.write_all(b"  <UnstructuredGrid>\n")?;
    if let Some(t) = frame.time {
        w.write_all(b"    <FieldData>\n")?;
        open_array(
            w,
            "      ",
            "Float64",
            "TimeValue",
            1,
            " NumberOfTuples=\"1\"",
        )?;
        write_f64_block(w, &[t])?;
        close_array(w, "      ")?;
        w.write_all(b"    </FieldData>\n")?;
    }
    writeln!(
        w,
        "    <Piece NumberOfPoints=\"{np}\" NumberOfCells=\"{nc}\">"
    )?;

    for (tag, arrays) in [
        ("PointData", &frame.point_data),
        ("CellData", &frame.cell_data),
    ] {
        if arrays.is_empty() {
            continue;
        }
        writeln!(w, "      <{tag}>")?;
        for a in arrays.iter() {
            write_data_array(w, "        ", a)?;
        }
        writeln!(w, "      </{tag}>")?;
    }

    w.write_all(b"      <Points>\n")?;
    open_array(w, "        ", "Float64", "Points", 3, "")?;
    let pts = frame.points;
    write_block(w, np * 3, 8, |s, e, buf| {
        for k in s..e {
            buf.extend_from_slice(&pts[k / 3][k % 3].to_le_bytes());
        }
    })?;
    close_array(w, "        ")?;
    w.write_all(b"      </Points>\n")?;
    w.write_all(cells)?;
    w.write_all(b"    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n")?;
    Ok(())
}

/// The whole .vtu file as bytes, or an `InvalidInput` error naming the
/// offending array when lengths are inconsistent.
pub fn try_vtu_bytes(frame: &VtuFrame) -> io::Result<Vec<u8>> {
    let mut out = Vec::new();
    write_vtu_to(&mut out, frame)?;
    Ok(out)
}

/// Atomically write `frame` to `path` (validated before anything is created).
pub fn write_vtu(path: &Path, frame: &VtuFrame) -> io::Result<()> {
    validate(frame)?;
    write_atomic_with(path, |w| write_vtu_to(w, frame))
}

/// Shortest round-trip decimal for `x`, exponent form outside [1e-4, 1e16).
fn fmt_f64(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || (1e-4..1e16).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// The .pvd collection document as a string.
pub fn pvd_string(entries: &[PvdEntry]) -> io::Result<String> {
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\"?>\n");
    s.push_str("<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n");
    s.push_str("  <Collection>\n");
    for (i, e) in entries.iter().enumerate() {
        if !e.time.is_finite() {
            return Err(invalid(format!(
                "pvd: entry #{i} ('{}') has non-finite time {}",
                e.file, e.time
            )));
        }
        if e.file.is_empty() {
            return Err(invalid(format!("pvd: entry #{i} has an empty file name")));
        }
        let _ = writeln!(
            s,
            "    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>",
            fmt_f64(e.time),
            xml_attr(&e.file)
        );
    }
    s.push_str("  </Collection>\n</VTKFile>\n");
    Ok(s)
}

/// Atomically (re)write the .pvd collection at `path`.
pub fn write_pvd(path: &Path, entries: &[PvdEntry]) -> io::Result<()> {
    let s = pvd_string(entries)?;
    write_atomic(path, s.as_bytes())
}

/// Decodes standard base64 (RFC 4648, with padding; ASCII whitespace between the characters
/// is skipped, as XML readers allow); `None` on malformed input.
pub fn base64_decode(text: &str) -> Option<Vec<u8>> {
    let bytes: Vec<u8> = text.bytes().filter(|c| !c.is_ascii_whitespace()).collect();
    BASE64.decode(bytes).ok()
}

/// Reads a Float64 point-data array of one of our own `.vtu` files (inline binary,
/// `header_type="UInt64"`, as written by [`write_vtu`]): `(values, components, points)`.
/// Errors name the file and what is wrong.
pub fn read_point_data_f64(
    path: &Path,
    name: &str,
) -> crate::error::Result<(Vec<f64>, usize, usize)> {
    read_array(path, "PointData", name)
}

/// Reads a cell-data array (Float64 or Int32, converted to `f64`) of one of our own `.vtu`
/// files: `(values, components, cells)`.
pub fn read_cell_data(path: &Path, name: &str) -> crate::error::Result<(Vec<f64>, usize, usize)> {
    read_array(path, "CellData", name)
}

fn read_array(
    path: &Path,
    section: &str,
    name: &str,
) -> crate::error::Result<(Vec<f64>, usize, usize)> {
    let text = std::fs::read_to_string(path).map_err(|e| crate::error::Error::io(path, e))?;
    parse_array(&text, &path.display().to_string(), section, name)
}

/// [`read_point_data_f64`] and [`read_cell_data`] on a file's text (`section`: `PointData` or
/// `CellData`); errors name `file`.
pub fn parse_array(
    text: &str,
    file: &str,
    section: &str,
    name: &str,
) -> crate::error::Result<(Vec<f64>, usize, usize)> {
    let mut arrays = parse_arrays(text, file, &[(section, name)])?;
    arrays.remove(0)
}

/// Several arrays of one file's text, the XML parsed once: each `(section, name)` as
/// [`parse_array`] reads it (an error for malformed XML, else a result per array).
#[allow(clippy::type_complexity)]
pub fn parse_arrays(
    text: &str,
    file: &str,
    arrays: &[(&str, &str)],
) -> crate::error::Result<Vec<crate::error::Result<(Vec<f64>, usize, usize)>>> {
    use crate::error::{Error, Location};
    let doc = roxmltree::Document::parse(text)
        .map_err(|e| Error::input(file, Location::None, format!("malformed XML: {e}")))?;
    Ok(arrays
        .iter()
        .map(|&(section, name)| array_of(&doc, file, section, name))
        .collect())
}

fn array_of(
    doc: &roxmltree::Document,
    file: &str,
    section: &str,
    name: &str,
) -> crate::error::Result<(Vec<f64>, usize, usize)> {
    use crate::error::{Error, Location};
    let bad = |m: String| Error::input(file, Location::None, m);
    let piece = doc
        .descendants()
        .find(|n| n.has_tag_name("Piece"))
        .ok_or_else(|| bad("no <Piece>".into()))?;
    let count_attr = if section == "PointData" {
        "NumberOfPoints"
    } else {
        "NumberOfCells"
    };
    let count: usize = piece
        .attribute(count_attr)
        .and_then(|v| v.parse().ok())
        .ok_or_else(|| bad(format!("<Piece> lacks {count_attr}")))?;
    let arr = piece
        .descendants()
        .filter(|n| n.has_tag_name(section))
        .flat_map(|pd| pd.children())
        .find(|n| n.has_tag_name("DataArray") && n.attribute("Name") == Some(name))
        .ok_or_else(|| bad(format!("no {section} array `{name}`")))?;
    let comps: usize = arr
        .attribute("NumberOfComponents")
        .and_then(|v| v.parse().ok())
        .unwrap_or(1);
    let width = match arr.attribute("type") {
        Some("Float64") => 8,
        Some("Int32") => 4,
        other => {
            return Err(bad(format!(
                "array `{name}` has type {other:?} (Float64 or Int32 expected)"
            )))
        }
    };
    let body = arr.text().unwrap_or("");
    let values: Vec<f64> = match arr.attribute("format") {
        Some("binary") => {
            let raw = base64_decode(body)
                .ok_or_else(|| bad(format!("array `{name}`: malformed base64")))?;
            if raw.len() < 8 {
                return Err(bad(format!("array `{name}`: truncated")));
            }
            let n = u64::from_le_bytes(raw[..8].try_into().unwrap());
            if raw.len() as u64 - 8 != n || n % width as u64 != 0 {
                return Err(bad(format!(
                    "array `{name}`: byte count {n} does not match the data"
                )));
            }
            if width == 8 {
                raw[8..]
                    .chunks_exact(8)
                    .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
                    .collect()
            } else {
                raw[8..]
                    .chunks_exact(4)
                    .map(|c| i32::from_le_bytes(c.try_into().unwrap()) as f64)
                    .collect()
            }
        }
        Some("ascii") => body
            .split_whitespace()
            .map(|t| {
                t.parse::<f64>()
                    .map_err(|_| bad(format!("array `{name}`: `{t}` is not a number")))
            })
            .collect::<crate::error::Result<_>>()?,
        other => {
            return Err(bad(format!(
                "array `{name}`: format {other:?} is not supported (binary or ascii)"
            )))
        }
    };
    if Some(values.len()) != comps.checked_mul(count) {
        return Err(bad(format!(
            "array `{name}` has {} values for {count} x {comps}",
            values.len()
        )));
    }
    Ok((values, comps, count))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b64_decode(s: &str) -> Vec<u8> {
        let val = |c: u8| -> u32 {
            match c {
                b'A'..=b'Z' => (c - b'A') as u32,
                b'a'..=b'z' => (c - b'a') as u32 + 26,
                b'0'..=b'9' => (c - b'0') as u32 + 52,
                b'+' => 62,
                b'/' => 63,
                _ => panic!("bad base64 char {c}"),
            }
        };
        let bytes: Vec<u8> = s.bytes().filter(|c| !c.is_ascii_whitespace()).collect();
        assert_eq!(bytes.len() % 4, 0, "base64 length not multiple of 4");
        let mut out = Vec::new();
        for q in bytes.chunks(4) {
            let pad = q.iter().filter(|&&c| c == b'=').count();
            let mut n = 0u32;
            for &c in q {
                n = (n << 6) | if c == b'=' { 0 } else { val(c) };
            }
            let b = [(n >> 16) as u8, (n >> 8) as u8, n as u8];
            out.extend_from_slice(&b[..3 - pad]);
        }
        out
    }

    #[test]
    fn base64_rfc4648_vectors() {
        let cases = [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ];
        for (plain, enc) in cases {
            assert_eq!(base64_encode(plain.as_bytes()), enc, "encode {plain:?}");
            assert_eq!(b64_decode(enc), plain.as_bytes(), "decode {enc:?}");
        }
        // full alphabet + high bytes
        assert_eq!(base64_encode(&[0xfb, 0xff, 0xbf]), "+/+/");
    }

    #[test]
    fn base64_streaming_matches_oneshot() {
        let data: Vec<u8> = (0..100_000u32)
            .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
            .collect();
        let oneshot = base64_encode(&data);
        for split in [1usize, 2, 4, 5, 7, 3000, 50_001] {
            // the writer `write_block` uses, fed in pieces of every size
            let mut enc = base64::write::EncoderWriter::new(Vec::new(), &BASE64);
            for c in data.chunks(split) {
                enc.write_all(c).unwrap();
            }
            let out = enc.finish().unwrap();
            assert_eq!(String::from_utf8(out).unwrap(), oneshot, "split {split}");
        }
        assert_eq!(b64_decode(&oneshot), data);
    }

    /// Extract the text content of every `<DataArray ... Name="name" ...>`.
    fn arrays(doc: &str) -> Vec<(String, String, String)> {
        let mut res = Vec::new();
        let mut rest = doc;
        while let Some(i) = rest.find("<DataArray ") {
            rest = &rest[i..];
            let tag_end = rest.find('>').unwrap();
            let tag = &rest[..tag_end];
            let attr = |k: &str| {
                let key = format!("{k}=\"");
                let s = tag.find(&key).unwrap() + key.len();
                tag[s..s + tag[s..].find('"').unwrap()].to_string()
            };
            let close = rest.find("</DataArray>").unwrap();
            let body = rest[tag_end + 1..close].trim().to_string();
            res.push((attr("Name"), attr("type"), body));
            rest = &rest[close..];
        }
        res
    }

    /// Decode one binary block: check the UInt64 header and return the payload.
    fn payload(body: &str) -> Vec<u8> {
        let raw = b64_decode(body);
        let n = u64::from_le_bytes(raw[..8].try_into().unwrap()) as usize;
        assert_eq!(raw.len(), 8 + n, "header byte count mismatch");
        raw[8..].to_vec()
    }

    fn f64s(b: &[u8]) -> Vec<f64> {
        b.chunks(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect()
    }
    fn i64s(b: &[u8]) -> Vec<i64> {
        b.chunks(8)
            .map(|c| i64::from_le_bytes(c.try_into().unwrap()))
            .collect()
    }
    fn i32s(b: &[u8]) -> Vec<i32> {
        b.chunks(4)
            .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
            .collect()
    }

    /// Two unit hexes sharing a face: 12 points.
    fn two_hex() -> (Vec<[f64; 3]>, Vec<[u32; 8]>) {
        let mut pts = Vec::new();
        for k in 0..2 {
            for j in 0..2 {
                for i in 0..3 {
                    pts.push([i as f64, j as f64, k as f64]);
                }
            }
        }
        let id = |i: u32, j: u32, k: u32| i + 3 * j + 6 * k;
        let hexes = (0..2u32)
            .map(|i| {
                [
                    id(i, 0, 0),
                    id(i + 1, 0, 0),
                    id(i + 1, 1, 0),
                    id(i, 1, 0),
                    id(i, 0, 1),
                    id(i + 1, 0, 1),
                    id(i + 1, 1, 1),
                    id(i, 1, 1),
                ]
            })
            .collect();
        (pts, hexes)
    }

    #[test]
    fn base64_decode_inverts_encode_and_rejects_garbage() {
        for len in 0..40usize {
            let bytes: Vec<u8> = (0..len).map(|i| (i * 37 + 11) as u8).collect();
            assert_eq!(base64_decode(&base64_encode(&bytes)).unwrap(), bytes);
        }
        assert!(base64_decode("abc").is_none());
        assert!(base64_decode("ab$=").is_none());
    }

    /// A frame of `pts` and `hexes` with point data `displacement` (3 components) only.
    fn displacement_frame<'a>(
        pts: &'a [[f64; 3]],
        hexes: &'a [[u32; 8]],
        disp: &'a [f64],
        time: Option<f64>,
    ) -> VtuFrame<'a> {
        VtuFrame {
            points: pts,
            hexahedra: hexes,
            point_data: vec![DataArray::F64 {
                name: "displacement",
                components: 3,
                data: disp,
            }],
            cell_data: vec![],
            time,
        }
    }

    /// A run's frames are written with their `<Cells>` element encoded once: the bytes of a
    /// file written in one go; a frame whose cells do not fit its points is still refused.
    #[test]
    fn cells_encoded_once_give_the_same_file() {
        let (pts, hexes) = two_hex();
        let disp: Vec<f64> = (0..pts.len() * 3).map(|i| i as f64 * 1e-4).collect();
        let frame = displacement_frame(&pts, &hexes, &disp, Some(0.25));
        let dir = std::env::temp_dir().join(format!("vtu-cells-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (a, b) = (dir.join("a.vtu"), dir.join("b.vtu"));
        write_vtu(&a, &frame).unwrap();
        let cells = cells_xml(&hexes).unwrap();
        write_vtu_with_cells(&b, &frame, &cells).unwrap();
        assert!(std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap());
        let short = &pts[..pts.len() - 1];
        let bad = VtuFrame {
            points: short,
            point_data: vec![],
            ..frame
        };
        let e = write_vtu_with_cells(&dir.join("c.vtu"), &bad, &cells).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput, "{e}");
        assert!(!dir.join("c.vtu").exists());
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn read_point_data_returns_the_written_bits() {
        let (pts, hexes) = two_hex();
        let disp: Vec<f64> = (0..pts.len() * 3)
            .map(|i| (i as f64 + 0.1).ln() * 1e-3)
            .collect();
        let frame = displacement_frame(&pts, &hexes, &disp, None);
        let dir = std::env::temp_dir().join(format!("vtu-read-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("f.vtu");
        write_vtu(&path, &frame).unwrap();
        let (v, c, n) = read_point_data_f64(&path, "displacement").unwrap();
        assert_eq!((c, n), (3, pts.len()));
        assert!(v.iter().zip(&disp).all(|(a, b)| a.to_bits() == b.to_bits()));
        let e = read_point_data_f64(&path, "velocity")
            .unwrap_err()
            .to_string();
        assert!(e.contains("f.vtu") && e.contains("velocity"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn round_trip_tiny_frame() {
        let (mut pts, hexes) = two_hex();
        // awkward values to prove bit-exactness
        pts[5][0] = 0.1 + 0.2;
        pts[7][2] = -1.0e-300;
        pts[11][1] = f64::MIN_POSITIVE / 3.0; // subnormal
        let disp: Vec<f64> = (0..pts.len() * 3)
            .map(|i| (i as f64).sqrt() * 1e-3 - 0.5e-17)
            .collect();
        let mat = [1i32, -7];
        let flags = [0u8, 255];
        let t = 0.001234567890123;
        let frame = VtuFrame {
            points: &pts,
            hexahedra: &hexes,
            point_data: vec![DataArray::F64 {
                name: "displacement",
                components: 3,
                data: &disp,
            }],
            cell_data: vec![
                DataArray::I32 {
                    name: "material",
                    components: 1,
                    data: &mat,
                },
                DataArray::U8 {
                    name: "broken",
                    components: 1,
                    data: &flags,
                },
            ],
            time: Some(t),
        };
        let bytes = try_vtu_bytes(&frame).unwrap();
        let doc = String::from_utf8(bytes).unwrap();
        assert!(doc.contains("header_type=\"UInt64\""));
        assert!(doc.contains("<Piece NumberOfPoints=\"12\" NumberOfCells=\"2\">"));
        let a = arrays(&doc);
        let names: Vec<&str> = a.iter().map(|x| x.0.as_str()).collect();
        assert_eq!(
            names,
            [
                "TimeValue",
                "displacement",
                "material",
                "broken",
                "Points",
                "connectivity",
                "offsets",
                "types"
            ]
        );
        let get = |n: &str| payload(&a.iter().find(|x| x.0 == n).unwrap().2);

        assert_eq!(f64s(&get("TimeValue"))[0].to_bits(), t.to_bits());
        let d = f64s(&get("displacement"));
        assert_eq!(
            d.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            disp.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
        assert_eq!(i32s(&get("material")), mat);
        assert_eq!(get("broken"), flags);
        let p = f64s(&get("Points"));
        let flat: Vec<u64> = pts.iter().flatten().map(|v| v.to_bits()).collect();
        assert_eq!(p.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), flat);
        let conn: Vec<i64> = hexes.iter().flatten().map(|&v| v as i64).collect();
        assert_eq!(i64s(&get("connectivity")), conn);
        assert_eq!(i64s(&get("offsets")), [8, 16]);
        assert_eq!(get("types"), [12, 12]);
        assert_eq!(a.iter().find(|x| x.0 == "types").unwrap().1, "UInt8");
        assert_eq!(a.iter().find(|x| x.0 == "material").unwrap().1, "Int32");
    }

    #[test]
    fn no_time_no_fielddata_and_empty_mesh() {
        let frame = VtuFrame {
            points: &[],
            hexahedra: &[],
            point_data: vec![],
            cell_data: vec![],
            time: None,
        };
        let doc = String::from_utf8(try_vtu_bytes(&frame).unwrap()).unwrap();
        assert!(!doc.contains("FieldData"));
        assert!(!doc.contains("<PointData>"));
        let a = arrays(&doc);
        assert_eq!(a.len(), 4);
        for (_, _, body) in &a {
            assert!(payload(body).is_empty());
        }
    }

    #[test]
    fn length_validation_errors() {
        let (pts, hexes) = two_hex();
        let short = vec![0.0; pts.len() * 3 - 1];
        let mat = [1i32, 2, 3];
        let frame = VtuFrame {
            points: &pts,
            hexahedra: &hexes,
            point_data: vec![DataArray::F64 {
                name: "displacement",
                components: 3,
                data: &short,
            }],
            cell_data: vec![],
            time: None,
        };
        let e = try_vtu_bytes(&frame).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        assert!(e.to_string().contains("'displacement'"), "{e}");

        let frame = VtuFrame {
            points: &pts,
            hexahedra: &hexes,
            point_data: vec![],
            cell_data: vec![DataArray::I32 {
                name: "material",
                components: 1,
                data: &mat,
            }],
            time: None,
        };
        let e = try_vtu_bytes(&frame).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        assert!(e.to_string().contains("'material'"), "{e}");

        let frame = VtuFrame {
            points: &pts,
            hexahedra: &hexes,
            point_data: vec![],
            cell_data: vec![DataArray::U8 {
                name: "zero",
                components: 0,
                data: &[],
            }],
            time: None,
        };
        assert!(try_vtu_bytes(&frame)
            .unwrap_err()
            .to_string()
            .contains("'zero'"));

        let bad_hex = [[0u32, 1, 2, 3, 4, 5, 6, 12]];
        let frame = VtuFrame {
            points: &pts,
            hexahedra: &bad_hex,
            point_data: vec![],
            cell_data: vec![],
            time: None,
        };
        let e = try_vtu_bytes(&frame).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        assert!(e.to_string().contains("point 12"), "{e}");

        // write_vtu must not create the file on validation failure
        let dir = std::env::temp_dir().join(format!("sticky_lips_vtu_val_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("bad.vtu");
        assert!(write_vtu(&p, &frame).is_err());
        assert!(!p.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn name_escaping() {
        let (pts, hexes) = two_hex();
        let mat = [1i32, 2];
        let frame = VtuFrame {
            points: &pts,
            hexahedra: &hexes,
            point_data: vec![],
            cell_data: vec![DataArray::I32 {
                name: "a\"<&>b",
                components: 1,
                data: &mat,
            }],
            time: None,
        };
        let doc = String::from_utf8(try_vtu_bytes(&frame).unwrap()).unwrap();
        assert!(doc.contains("Name=\"a&quot;&lt;&amp;&gt;b\""));
    }

    #[test]
    fn pvd_document_and_files() {
        let entries = vec![
            PvdEntry {
                time: 0.0,
                file: "frame_000000.vtu".into(),
            },
            PvdEntry {
                time: 1e-5,
                file: "frame_000001.vtu".into(),
            },
            PvdEntry {
                time: 0.1 + 0.2,
                file: "frame_000002.vtu".into(),
            },
        ];
        let s = pvd_string(&entries).unwrap();
        assert!(
            s.contains("<DataSet timestep=\"0\" group=\"\" part=\"0\" file=\"frame_000000.vtu\"/>"),
            "{s}"
        );
        assert!(s.contains("timestep=\"1e-5\""), "{s}");
        assert!(s.contains("timestep=\"0.30000000000000004\""), "{s}");
        assert_eq!("1e-5".parse::<f64>().unwrap(), 1e-5);

        let bad = [PvdEntry {
            time: f64::NAN,
            file: "x.vtu".into(),
        }];
        assert_eq!(
            pvd_string(&bad).unwrap_err().kind(),
            io::ErrorKind::InvalidInput
        );

        let dir = std::env::temp_dir().join(format!("sticky_lips_pvd_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("frames.pvd");
        write_pvd(&p, &entries[..1]).unwrap();
        write_pvd(&p, &entries).unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), s);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    // ---- committed fixture verification/reference/vtu_fixture -------------
    // Read independently by meshio in scripts/check_outputs.py. Regenerate with
    //   cargo test --lib io::vtu::tests::regenerate_vtu_fixture -- --ignored

    fn repo_fixture_dir() -> std::path::PathBuf {
        let root = std::env::var_os("STICKY_LIPS_REPO")
            .map(std::path::PathBuf::from)
            .unwrap_or_else(|| std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")));
        root.join("verification")
            .join("reference")
            .join("vtu_fixture")
    }

    const FIXTURE_FILES: [&str; 5] = [
        "frames.pvd",
        "frame_000000.vtu",
        "frame_000001.vtu",
        "final.vtu",
        "summary.json",
    ];

    /// 2 frames of a 2-hex mesh (3x2x2 points, 0.01 m spacing), material [0, 1],
    /// frame f at t = [0, 1e-3][f] with u_i = (1e-3 f) [(i+1), -(i+1)/3, 0.1+0.2].
    fn generate_fixture(dir: &Path) -> io::Result<()> {
        std::fs::create_dir_all(dir)?;
        let mut reference = Vec::new();
        for k in 0..2 {
            for j in 0..2 {
                for i in 0..3 {
                    reference.push([i as f64 * 0.01, j as f64 * 0.01, k as f64 * 0.01]);
                }
            }
        }
        let (_, hexes) = two_hex();
        let material = [0i32, 1];
        let times = [0.0, 1.0e-3];
        let mut entries = Vec::new();
        let mut last = (Vec::new(), Vec::new());
        for (f, &t) in times.iter().enumerate() {
            let disp: Vec<f64> = (0..reference.len())
                .flat_map(|i| {
                    let s = 1e-3 * f as f64;
                    let n = (i + 1) as f64;
                    [s * n, s * (-n / 3.0), s * (0.1 + 0.2)]
                })
                .collect();
            let pts: Vec<[f64; 3]> = reference
                .iter()
                .enumerate()
                .map(|(i, r)| {
                    [
                        r[0] + disp[3 * i],
                        r[1] + disp[3 * i + 1],
                        r[2] + disp[3 * i + 2],
                    ]
                })
                .collect();
            let frame = VtuFrame {
                points: &pts,
                hexahedra: &hexes,
                point_data: vec![DataArray::F64 {
                    name: "displacement",
                    components: 3,
                    data: &disp,
                }],
                cell_data: vec![DataArray::I32 {
                    name: "material",
                    components: 1,
                    data: &material,
                }],
                time: Some(t),
            };
            let name = format!("frame_{f:06}.vtu");
            write_vtu(&dir.join(&name), &frame)?;
            entries.push(PvdEntry {
                time: t,
                file: name,
            });
            write_pvd(&dir.join("frames.pvd"), &entries)?;
            last = (pts, disp);
        }
        let frame = VtuFrame {
            points: &last.0,
            hexahedra: &hexes,
            point_data: vec![DataArray::F64 {
                name: "displacement",
                components: 3,
                data: &last.1,
            }],
            cell_data: vec![DataArray::I32 {
                name: "material",
                components: 1,
                data: &material,
            }],
            time: Some(times[1]),
        };
        write_vtu(&dir.join("final.vtu"), &frame)?;
        let summary = r#"{
  "steps": 10,
  "simulated_time": 0.001,
  "wall_time": 0.01,
  "element_updates_per_second": 2000.0,
  "precision": "f64",
  "threads": 1,
  "critical_time_step": 0.0001,
  "energy": {
    "time": [0.0, 0.0005, 0.001],
    "kinetic": [0.0, 1.0e-9, 2.0e-9],
    "strain": [0.0, 1.0e-9, 4.0e-9]
  }
}
"#;
        write_atomic(&dir.join("summary.json"), summary.as_bytes())
    }

    #[test]
    #[ignore = "rewrites the committed fixture; run explicitly"]
    fn regenerate_vtu_fixture() {
        generate_fixture(&repo_fixture_dir()).unwrap();
    }

    /// The writer's output must stay byte-identical to the committed fixture
    /// that scripts/check_outputs.py proves readable by meshio.
    #[test]
    fn committed_fixture_is_up_to_date() {
        let committed = repo_fixture_dir();
        let tmp =
            std::env::temp_dir().join(format!("sticky_lips_vtu_fixture_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&tmp);
        generate_fixture(&tmp).unwrap();
        for f in FIXTURE_FILES {
            let want = std::fs::read(tmp.join(f)).unwrap();
            let have = std::fs::read(committed.join(f)).unwrap_or_else(|e| {
                panic!(
                    "{}: {e} (regenerate with --ignored regenerate_vtu_fixture)",
                    committed.join(f).display()
                )
            });
            assert!(
                have == want,
                "{f} differs from the writer's output; regenerate the fixture"
            );
        }
        std::fs::remove_dir_all(&tmp).unwrap();
    }
}

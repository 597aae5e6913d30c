//! STL, binary and ASCII.
//!
//! Binary: an 80-byte header, a little-endian u32 triangle count, then 50 bytes per
//! triangle (normal, three corners as f32, a u16 attribute). ASCII: `solid name`, then
//! `facet normal nx ny nz / outer loop / vertex x y z (x3) / endloop / endfacet`, then
//! `endsolid`. STL does not share vertices, so both readers weld corners at exactly equal
//! positions. We parse ASCII ourselves: stl_io rejects `solid` with no name (docs/constants.md).

use super::{ParseError, ParseErrorKind, Place, Welder, at_line, parse_coord};
use crate::mesh::Mesh;

const HEADER: usize = 80;
const RECORD: usize = 50;

/// True when the size is exactly what a binary STL's triangle count says: the one test
/// that tells binary from ASCII whatever the header's first word is.
pub fn is_binary_size(bytes: &[u8]) -> bool {
    match binary_count(bytes) {
        Some(n) => (HEADER + 4) as u64 + RECORD as u64 * u64::from(n) == bytes.len() as u64,
        None => false,
    }
}

/// True when the file starts with the word `solid` and its opening is plain text.
pub fn looks_ascii(bytes: &[u8]) -> bool {
    let start = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(bytes.len());
    let rest = &bytes[start..];
    let head = &rest[..rest.len().min(5)];
    if !head.eq_ignore_ascii_case(b"solid") {
        return false;
    }
    if rest.len() > 5 && !rest[5].is_ascii_whitespace() {
        return false;
    }
    // A binary header may start with "solid" too; its record bytes soon give it away.
    rest.iter()
        .take(1024)
        .all(|&b| b.is_ascii_graphic() || b.is_ascii_whitespace() || b >= 0x80)
}

fn binary_count(bytes: &[u8]) -> Option<u32> {
    let raw: [u8; 4] = bytes.get(HEADER..HEADER + 4)?.try_into().ok()?;
    Some(u32::from_le_bytes(raw))
}

/// Reads an STL, binary or ASCII (told apart by size, then by content).
pub fn read(bytes: &[u8]) -> Result<Mesh, ParseError> {
    if !is_binary_size(bytes) && looks_ascii(bytes) {
        read_ascii(bytes)
    } else {
        read_binary(bytes)
    }
}

/// Reads a binary STL.
pub fn read_binary(bytes: &[u8]) -> Result<Mesh, ParseError> {
    let Some(count) = binary_count(bytes) else {
        return Err(ParseError::file(ParseErrorKind::Syntax(format!(
            "{} bytes: too short for a binary STL (an 80-byte header and a 4-byte count), \
             and not an ASCII STL (which starts with \"solid\")",
            bytes.len()
        ))));
    };
    let count = count as usize;
    let need = (HEADER + 4) as u64 + RECORD as u64 * count as u64;
    if (bytes.len() as u64) < need {
        // Where the first incomplete triangle starts.
        let whole = (bytes.len() - HEADER - 4) / RECORD;
        return Err(ParseError::new(
            Place::Byte((HEADER + 4 + whole * RECORD) as u64),
            ParseErrorKind::Truncated {
                promised: format!("{count} triangles"),
                expected: need,
                actual: bytes.len() as u64,
            },
        ));
    }
    let mut welder = Welder::with_capacity(count);
    for (i, rec) in bytes[HEADER + 4..]
        .chunks_exact(RECORD)
        .take(count)
        .enumerate()
    {
        let base = HEADER + 4 + i * RECORD;
        let mut corners = [[0f32; 3]; 3];
        for (k, c) in corners.iter_mut().enumerate() {
            for (j, v) in c.iter_mut().enumerate() {
                let off = 12 + k * 12 + j * 4;
                let raw = [rec[off], rec[off + 1], rec[off + 2], rec[off + 3]];
                *v = f32::from_le_bytes(raw);
                if !v.is_finite() {
                    return Err(ParseError::new(
                        Place::Byte((base + off) as u64),
                        ParseErrorKind::BadNumber {
                            field: format!("triangle {i} coordinate"),
                            token: v.to_string(),
                        },
                    ));
                }
            }
        }
        welder.triangle(corners)?;
    }
    Ok(welder.finish())
}

/// Whitespace-separated tokens with their 1-based line numbers.
fn tokens(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.split('\n')
        .enumerate()
        .flat_map(|(i, line)| line.split_ascii_whitespace().map(move |t| (i + 1, t)))
}

/// Reads an ASCII STL (one or more `solid` blocks; polygons with more than three corners
/// are fanned into triangles).
pub fn read_ascii(bytes: &[u8]) -> Result<Mesh, ParseError> {
    let text = match std::str::from_utf8(bytes) {
        Ok(t) => t,
        Err(e) => {
            let line = 1 + bytes[..e.valid_up_to()]
                .iter()
                .filter(|&&b| b == b'\n')
                .count();
            return Err(ParseError::new(Place::Line(line), ParseErrorKind::NotText));
        }
    };
    let mut welder = Welder::with_capacity(text.len() / 200);
    let mut toks = tokens(text).peekable();
    let mut solids = 0usize;
    let mut last_line = 1;
    let mut in_solid = false;
    let mut loop_pts: Vec<[f32; 3]> = Vec::with_capacity(3);
    // 0: between facets, 1: after `facet`, 2: in `outer loop`, 3: after `endloop`.
    let mut facet_state = 0u8;
    while let Some((line, tok)) = toks.next() {
        last_line = line;
        // Keywords are matched without case and without allocating (20+ tokens a facet).
        let kw = [
            "solid", "endsolid", "facet", "outer", "vertex", "endloop", "endfacet",
        ]
        .into_iter()
        .find(|k| k.eq_ignore_ascii_case(tok))
        .unwrap_or("");
        match (kw, in_solid, facet_state) {
            ("solid", false, _) => {
                in_solid = true;
                solids += 1;
                // The name is the rest of the line.
                while toks.next_if(|&(l, _)| l == line).is_some() {}
            }
            ("endsolid", true, 0) => {
                in_solid = false;
                while toks.next_if(|&(l, _)| l == line).is_some() {}
            }
            ("facet", true, 0) => {
                facet_state = 1;
                // `normal nx ny nz`: we recompute normals from the winding, so only check
                // that the numbers are numbers.
                if toks
                    .next_if(|&(_, t)| t.eq_ignore_ascii_case("normal"))
                    .is_some()
                {
                    for _ in 0..3 {
                        match toks.next() {
                            Some((l, t)) => {
                                t.parse::<f32>().map_err(|_| {
                                    ParseError::new(
                                        Place::Line(l),
                                        ParseErrorKind::BadNumber {
                                            field: "facet normal".into(),
                                            token: t.to_string(),
                                        },
                                    )
                                })?;
                            }
                            None => return Err(at_line(line, "file ends inside a facet normal")),
                        }
                    }
                }
            }
            ("outer", true, 1) => match toks.next() {
                Some((_, t)) if t.eq_ignore_ascii_case("loop") => {
                    facet_state = 2;
                    loop_pts.clear();
                }
                _ => return Err(at_line(line, "expected \"outer loop\"")),
            },
            ("vertex", true, 2) => {
                let mut p = [0f32; 3];
                for v in &mut p {
                    match toks.next() {
                        Some((l, t)) => *v = parse_coord(t, l)?,
                        None => return Err(at_line(line, "file ends inside a vertex")),
                    }
                }
                loop_pts.push(p);
            }
            ("endloop", true, 2) => {
                if loop_pts.len() < 3 {
                    return Err(at_line(
                        line,
                        format!("a facet loop has {} vertices; needs 3", loop_pts.len()),
                    ));
                }
                for k in 1..loop_pts.len() - 1 {
                    welder.triangle([loop_pts[0], loop_pts[k], loop_pts[k + 1]])?;
                }
                facet_state = 3;
            }
            ("endfacet", true, 3) => facet_state = 0,
            _ => {
                let expected = match (in_solid, facet_state) {
                    (false, _) => "\"solid\"",
                    (true, 0) => "\"facet\" or \"endsolid\"",
                    (true, 1) => "\"outer loop\"",
                    (true, 2) => "\"vertex\" or \"endloop\"",
                    _ => "\"endfacet\"",
                };
                return Err(at_line(
                    line,
                    format!("unexpected {tok:?}, expected {expected}"),
                ));
            }
        }
    }
    if solids == 0 {
        return Err(at_line(last_line, "no \"solid\" in an ASCII STL"));
    }
    if in_solid {
        return Err(at_line(
            last_line,
            "file ends before \"endsolid\" (truncated?)",
        ));
    }
    Ok(welder.finish())
}

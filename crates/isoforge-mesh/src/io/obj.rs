//! Wavefront OBJ: `v x y z` vertices and `f` faces.
//!
//! Faces may name corners as `i`, `i/t`, `i//n` or `i/t/n`; negative indices count back
//! from the last vertex defined so far; polygons are fanned into triangles. Texture
//! coordinates, normals, groups and materials are skipped.

use super::{
    ParseError, ParseErrorKind, Place, at_line, parse_coord, text_lines, too_many_vertices,
};
use crate::mesh::Mesh;

/// True when a file's opening lines look like OBJ (for files without a known extension).
pub fn looks_like_obj(bytes: &[u8]) -> bool {
    let head = &bytes[..bytes.len().min(4096)];
    let Ok(text) = std::str::from_utf8(head) else {
        // The cut may land inside a multi-byte character; judge by what decodes.
        return false;
    };
    text.lines()
        .any(|l| l.starts_with("v ") || l.starts_with("f ") || l.starts_with("vn "))
}

/// Reads an OBJ file.
pub fn read(bytes: &[u8]) -> Result<Mesh, ParseError> {
    let mut mesh = Mesh::default();
    let mut corners: Vec<u32> = Vec::with_capacity(8);
    for item in text_lines(bytes) {
        let (line, text) = item?;
        let text = text.split('#').next().unwrap_or("");
        let mut toks = text.split_ascii_whitespace();
        let Some(kw) = toks.next() else { continue };
        match kw {
            "v" => {
                let mut p = [0f32; 3];
                for v in &mut p {
                    let t = toks
                        .next()
                        .ok_or_else(|| at_line(line, "a vertex needs x, y and z"))?;
                    *v = parse_coord(t, line)?;
                }
                // An optional w (or r g b vertex colours) may follow: ignored.
                if mesh.vertices.len() >= u32::MAX as usize {
                    return Err(too_many_vertices(Place::Line(line)));
                }
                mesh.vertices.push(p);
            }
            "f" => {
                corners.clear();
                for t in toks {
                    corners.push(resolve(t, mesh.vertices.len(), line)?);
                }
                if corners.len() < 3 {
                    return Err(at_line(
                        line,
                        format!("a face has {} corners; needs at least 3", corners.len()),
                    ));
                }
                for k in 1..corners.len() - 1 {
                    mesh.triangles
                        .push([corners[0], corners[k], corners[k + 1]]);
                }
            }
            // Everything else (vt, vn, vp, o, g, s, l, p, usemtl, mtllib, ...) carries no
            // geometry we keep.
            _ => {}
        }
    }
    Ok(mesh)
}

/// Turns one face corner (`i`, `i/t`, `i//n`, `i/t/n`) into a 0-based vertex index.
fn resolve(token: &str, defined: usize, line: usize) -> Result<u32, ParseError> {
    let first = token.split('/').next().unwrap_or("");
    let bad = || {
        ParseError::new(
            Place::Line(line),
            ParseErrorKind::BadIndex {
                token: token.to_string(),
                vertices: defined,
            },
        )
    };
    let idx: i64 = first.parse().map_err(|_| bad())?;
    let zero_based = if idx > 0 {
        idx - 1
    } else if idx < 0 {
        defined as i64 + idx
    } else {
        return Err(at_line(line, "vertex index 0 (OBJ counts from 1)"));
    };
    if zero_based < 0 || zero_based >= defined as i64 {
        return Err(bad());
    }
    Ok(zero_based as u32)
}

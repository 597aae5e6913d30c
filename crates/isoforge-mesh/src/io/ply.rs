//! PLY (Stanford polygon format): an ASCII header of elements and properties, then the
//! body in ASCII, binary little-endian or binary big-endian.
//!
//! We keep the `vertex` element's `x y z` (float or double, or any numeric type) and the
//! `face` element's index list (`vertex_indices` or `vertex_index`, any count and item
//! type); polygons are fanned into triangles. Every other element and property is read
//! past and dropped.

use super::{ParseError, ParseErrorKind, Place, at_line, too_many_vertices};
use crate::mesh::Mesh;

/// A PLY scalar type.
#[derive(Copy, Clone, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

#[derive(Debug)]
enum Property {
    Scalar(String, Scalar),
    List(String, Scalar, Scalar),
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

#[derive(Copy, Clone, Debug, PartialEq)]
enum Encoding {
    Ascii,
    LittleEndian,
    BigEndian,
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset where the body starts.
    body: usize,
    /// Line number of the body's first line (for ASCII bodies).
    body_line: usize,
}

fn parse_header(bytes: &[u8]) -> Result<Header, ParseError> {
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut pos = 0;
    let mut line = 0;
    loop {
        line += 1;
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(at_line(line, "the header has no \"end_header\" line"));
        };
        let raw = &bytes[pos..pos + len];
        pos += len + 1;
        let text = std::str::from_utf8(raw)
            .map_err(|_| at_line(line, "PLY header is not text"))?
            .trim_end_matches('\r');
        let toks: Vec<&str> = text.split_ascii_whitespace().collect();
        match toks.as_slice() {
            ["ply"] if line == 1 => {}
            _ if line == 1 => return Err(at_line(1, "a PLY file starts with \"ply\"")),
            ["format", fmt, _version] => {
                encoding = Some(match *fmt {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::LittleEndian,
                    "binary_big_endian" => Encoding::BigEndian,
                    _ => return Err(at_line(line, format!("unknown PLY format {fmt:?}"))),
                });
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["element", name, count] => {
                let count = count.parse().map_err(|_| {
                    at_line(
                        line,
                        format!("element count {count:?} is not a whole number"),
                    )
                })?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            ["property", "list", count_ty, item_ty, name] => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| at_line(line, "a property before any element"))?;
                let c = int_type(count_ty, line)?;
                let i = Scalar::parse(item_ty)
                    .ok_or_else(|| at_line(line, format!("unknown type {item_ty:?}")))?;
                el.props.push(Property::List(name.to_string(), c, i));
            }
            ["property", ty, name] => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| at_line(line, "a property before any element"))?;
                let t = Scalar::parse(ty)
                    .ok_or_else(|| at_line(line, format!("unknown type {ty:?}")))?;
                el.props.push(Property::Scalar(name.to_string(), t));
            }
            ["end_header"] => break,
            _ => return Err(at_line(line, format!("unexpected header line {text:?}"))),
        }
    }
    let encoding = encoding.ok_or_else(|| at_line(line, "the header has no \"format\" line"))?;
    Ok(Header {
        encoding,
        elements,
        body: pos,
        body_line: line + 1,
    })
}

fn int_type(name: &str, line: usize) -> Result<Scalar, ParseError> {
    match Scalar::parse(name) {
        Some(Scalar::F32 | Scalar::F64) => Err(at_line(
            line,
            format!("a list count must be an integer type, not {name:?}"),
        )),
        Some(t) => Ok(t),
        None => Err(at_line(line, format!("unknown type {name:?}"))),
    }
}

/// A binary body that ends before `need` more bytes of `promised`.
fn truncated(body: &Body<'_>, at: Place, promised: String, need: usize) -> ParseError {
    ParseError::new(
        at,
        ParseErrorKind::Truncated {
            promised,
            expected: (body.pos as u64).saturating_add(need as u64),
            actual: body.bytes.len() as u64,
        },
    )
}

/// A structural problem at a place in the body.
fn syntax(at: Place, what: impl std::fmt::Display) -> ParseError {
    ParseError::new(at, ParseErrorKind::Syntax(what.to_string()))
}

/// Reads body values one at a time, whatever the encoding.
struct Body<'a> {
    bytes: &'a [u8],
    pos: usize,
    encoding: Encoding,
    line: usize,
}

impl Body<'_> {
    fn place(&self) -> Place {
        match self.encoding {
            Encoding::Ascii => Place::Line(self.line),
            _ => Place::Byte(self.pos as u64),
        }
    }

    fn value(&mut self, ty: Scalar) -> Result<f64, ParseError> {
        if self.encoding == Encoding::Ascii {
            return self.ascii_value(ty);
        }
        let n = ty.size();
        let Some(raw) = self.bytes.get(self.pos..self.pos + n) else {
            return Err(truncated(self, self.place(), "another value".into(), n));
        };
        let mut b = [0u8; 8];
        b[..n].copy_from_slice(raw);
        if self.encoding == Encoding::BigEndian {
            b[..n].reverse();
        }
        self.pos += n;
        Ok(match ty {
            Scalar::I8 => f64::from(b[0] as i8),
            Scalar::U8 => f64::from(b[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F64 => f64::from_le_bytes(b),
        })
    }

    fn ascii_value(&mut self, ty: Scalar) -> Result<f64, ParseError> {
        // Skip whitespace, counting lines.
        while let Some(&c) = self.bytes.get(self.pos) {
            if c == b'\n' {
                self.line += 1;
            } else if !c.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
        }
        let start = self.pos;
        while self
            .bytes
            .get(self.pos)
            .is_some_and(|c| !c.is_ascii_whitespace())
        {
            self.pos += 1;
        }
        if start == self.pos {
            return Err(syntax(
                self.place(),
                "file ends inside the PLY body (truncated?)",
            ));
        }
        let tok = std::str::from_utf8(&self.bytes[start..self.pos])
            .map_err(|_| syntax(self.place(), "not text (invalid UTF-8)"))?;
        let v: f64 = tok
            .parse()
            .map_err(|_| syntax(self.place(), format!("{tok:?} is not a number")))?;
        if !matches!(ty, Scalar::F32 | Scalar::F64) && v.fract() != 0.0 {
            return Err(syntax(
                self.place(),
                format!("{tok:?} is not a whole number"),
            ));
        }
        Ok(v)
    }

    /// Bytes left, for sanity checks of counts before reserving memory.
    fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }
}

/// Reads a PLY file.
pub fn read(bytes: &[u8]) -> Result<Mesh, ParseError> {
    let header = parse_header(bytes)?;
    let vertex_count = header
        .elements
        .iter()
        .find(|e| e.name == "vertex")
        .map_or(0, |e| e.count);
    let mut body = Body {
        bytes,
        pos: header.body,
        encoding: header.encoding,
        line: header.body_line,
    };
    let mut mesh = Mesh::default();
    let mut corners: Vec<u32> = Vec::new();
    for el in &header.elements {
        // Every instance takes at least this many bytes (binary) or one byte (ASCII): a
        // count the file cannot hold is an error before anything is reserved.
        let min_size = match header.encoding {
            Encoding::Ascii => 1,
            _ => el
                .props
                .iter()
                .map(|p| match p {
                    Property::Scalar(_, t) => t.size(),
                    Property::List(_, c, _) => c.size(),
                })
                .sum::<usize>(),
        };
        let need = (el.count as u128) * (min_size as u128);
        if need > body.remaining() as u128 {
            return Err(ParseError::new(
                body.place(),
                ParseErrorKind::Truncated {
                    promised: format!("{} {} elements", el.count, el.name),
                    expected: u64::try_from(need + body.pos as u128).unwrap_or(u64::MAX),
                    actual: bytes.len() as u64,
                },
            ));
        }
        if el.name == "vertex" {
            let xyz = ["x", "y", "z"].map(|axis| {
                el.props
                    .iter()
                    .position(|p| matches!(p, Property::Scalar(n, _) if n == axis))
            });
            let [Some(ix), Some(iy), Some(iz)] = xyz else {
                return Err(ParseError::file(ParseErrorKind::Syntax(
                    "the vertex element lacks an x, y or z property".into(),
                )));
            };
            if el.count > u32::MAX as usize {
                return Err(too_many_vertices(Place::File));
            }
            mesh.vertices.reserve(el.count);
            for i in 0..el.count {
                let mut p = [0f32; 3];
                for (k, prop) in el.props.iter().enumerate() {
                    let at = body.place();
                    let v = read_property(&mut body, prop)?;
                    let axis = [ix, iy, iz].iter().position(|&a| a == k);
                    if let (Some(a), Some(v)) = (axis, v) {
                        let f = v as f32;
                        if !f.is_finite() {
                            return Err(ParseError::new(
                                at,
                                ParseErrorKind::BadNumber {
                                    field: format!("vertex {i} coordinate"),
                                    token: v.to_string(),
                                },
                            ));
                        }
                        p[a] = f;
                    }
                }
                mesh.vertices.push(p);
            }
        } else if el.name == "face" {
            let list = el
                .props
                .iter()
                .position(|p| {
                    matches!(p, Property::List(n, _, _) if n == "vertex_indices" || n == "vertex_index")
                })
                .or_else(|| el.props.iter().position(|p| matches!(p, Property::List(..))))
                .ok_or_else(|| {
                    ParseError::file(ParseErrorKind::Syntax(
                        "the face element has no index list".into(),
                    ))
                })?;
            mesh.triangles.reserve(el.count.min(1 << 24));
            for f in 0..el.count {
                for (k, prop) in el.props.iter().enumerate() {
                    if k != list {
                        read_property(&mut body, prop)?;
                        continue;
                    }
                    let Property::List(_, count_ty, item_ty) = prop else {
                        continue;
                    };
                    let at = body.place();
                    let n = body.value(*count_ty)?;
                    if n < 3.0 {
                        return Err(syntax(at, format!("face {f} has {n} corners; needs 3")));
                    }
                    let n = n as usize;
                    if header.encoding != Encoding::Ascii && n * item_ty.size() > body.remaining() {
                        let need = n.saturating_mul(item_ty.size());
                        return Err(truncated(
                            &body,
                            at,
                            format!("face {f} with {n} corners"),
                            need,
                        ));
                    }
                    corners.clear();
                    for _ in 0..n {
                        let at = body.place();
                        let v = body.value(*item_ty)?;
                        if !(v >= 0.0 && v < vertex_count as f64) || v.fract() != 0.0 {
                            return Err(ParseError::new(
                                at,
                                ParseErrorKind::BadIndex {
                                    token: v.to_string(),
                                    vertices: vertex_count,
                                },
                            ));
                        }
                        corners.push(v as u32);
                    }
                    for j in 1..n - 1 {
                        mesh.triangles
                            .push([corners[0], corners[j], corners[j + 1]]);
                    }
                }
            }
        } else {
            for _ in 0..el.count {
                for prop in &el.props {
                    read_property(&mut body, prop)?;
                }
            }
        }
    }
    if !header.elements.iter().any(|e| e.name == "vertex") {
        return Err(ParseError::file(ParseErrorKind::Syntax(
            "the file has no vertex element".into(),
        )));
    }
    Ok(mesh)
}

/// Reads one property; returns its value for a scalar, `None` for a skipped list.
fn read_property(body: &mut Body<'_>, prop: &Property) -> Result<Option<f64>, ParseError> {
    match prop {
        Property::Scalar(_, t) => body.value(*t).map(Some),
        Property::List(_, c, t) => {
            let at = body.place();
            let n = body.value(*c)?;
            if n < 0.0 {
                return Err(syntax(at, format!("a list count is {n}")));
            }
            let n = n as usize;
            if body.encoding != Encoding::Ascii && n.saturating_mul(t.size()) > body.remaining() {
                let need = n.saturating_mul(t.size());
                return Err(truncated(body, at, format!("a list of {n} items"), need));
            }
            for _ in 0..n {
                body.value(*t)?;
            }
            Ok(None)
        }
    }
}

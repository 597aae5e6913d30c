//! 3MF: a zip package whose model part (`3D/3dmodel.model`) is XML with, per `<object>`,
//! `<vertex x y z/>` and `<triangle v1 v2 v3/>` lists (indices local to the object), and a
//! `<build>` of items placing objects with affine transforms.
//!
//! The reader instantiates every build item (following `<component>` references, with
//! their transforms) and merges the result into one mesh; without a build it merges every
//! object. Units other than millimetres are converted. The XML is scanned by a small tag
//! reader written for this: 3MF model files are plain elements and attributes.

use std::collections::HashMap;
use std::io::{Cursor, Read, Write};

use super::{ParseError, fmt_coord};
use crate::mesh::Mesh;

/// The model part's largest accepted size once inflated: a guard against zip bombs.
const MAX_MODEL_BYTES: u64 = 4 << 30;
/// How deep components may nest (a cycle would otherwise recurse forever).
const MAX_COMPONENT_DEPTH: usize = 32;
/// How many object instances a package may place: components referring twice to parts that
/// refer twice to parts... grow exponentially, so a small file could otherwise take hours.
const MAX_INSTANCES: usize = 1_000_000;

/// A row-vector affine transform as 3MF writes it: `p' = p * M`, 12 numbers
/// `m00 m01 m02 m10 m11 m12 m20 m21 m22 m30 m31 m32`.
type Affine = [f64; 12];
const IDENTITY: Affine = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0];

fn apply(m: &Affine, p: [f32; 3]) -> [f64; 3] {
    let [x, y, z] = p.map(f64::from);
    [0, 1, 2].map(|j| x * m[j] + y * m[3 + j] + z * m[6 + j] + m[9 + j])
}

/// `a` then `b`.
fn compose(a: &Affine, b: &Affine) -> Affine {
    let mut out = [0.0; 12];
    for r in 0..4 {
        for j in 0..3 {
            let lin = (0..3).map(|k| a[r * 3 + k] * b[k * 3 + j]).sum::<f64>();
            out[r * 3 + j] = lin + if r == 3 { b[9 + j] } else { 0.0 };
        }
    }
    out
}

#[derive(Default)]
struct Object {
    mesh: Mesh,
    components: Vec<(String, Affine)>,
}

/// Reads a 3MF package.
pub fn read(bytes: &[u8]) -> Result<Mesh, ParseError> {
    let mut zip = zip::ZipArchive::new(Cursor::new(bytes))
        .map_err(|e| ParseError(format!("not a readable zip package: {e}")))?;
    let part = model_part_name(&mut zip)?;
    let mut entry = zip
        .by_name(&part)
        .map_err(|e| ParseError(format!("{part}: {e}")))?;
    let mut xml = Vec::new();
    (&mut entry)
        .take(MAX_MODEL_BYTES)
        .read_to_end(&mut xml)
        .map_err(|e| ParseError(format!("{part}: cannot inflate: {e}")))?;
    let text = std::str::from_utf8(&xml)
        .map_err(|e| ParseError(format!("{part}: not UTF-8 at byte {}", e.valid_up_to())))?;
    parse_model(text).map_err(|e| ParseError(format!("{part}: {e}")))
}

/// The model part: the target of the package's 3D-model relationship, or the usual name.
fn model_part_name(zip: &mut zip::ZipArchive<Cursor<&[u8]>>) -> Result<String, ParseError> {
    let names: Vec<String> = zip
        .file_names()
        .filter_map(|n| n.ok().map(|n| n.into_owned()))
        .collect();
    if let Ok(mut rels) = zip.by_name("_rels/.rels") {
        let mut text = String::new();
        if rels.read_to_string(&mut text).is_ok() {
            for tag in Tags::new(&text).flatten() {
                if tag.name == "Relationship"
                    && tag.attr("Type").is_some_and(|t| t.ends_with("/3dmodel"))
                    && let Some(target) = tag.attr("Target")
                {
                    let target = target.trim_start_matches('/');
                    if names.iter().any(|n| n == target) {
                        return Ok(target.to_string());
                    }
                }
            }
        }
    }
    names
        .iter()
        .find(|n| n.eq_ignore_ascii_case("3D/3dmodel.model"))
        .or_else(|| names.iter().find(|n| n.ends_with(".model")))
        .cloned()
        .ok_or_else(|| ParseError("no 3D model part (3D/3dmodel.model) in the package".into()))
}

fn line_of(text: &str, offset: usize) -> usize {
    1 + text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

/// Parses the model XML into one mesh.
fn parse_model(text: &str) -> Result<Mesh, ParseError> {
    let err = |off: usize, what: String| ParseError(format!("line {}: {what}", line_of(text, off)));
    let mut objects: HashMap<String, Object> = HashMap::new();
    let mut order: Vec<String> = Vec::new();
    let mut items: Vec<(String, Affine)> = Vec::new();
    let mut current: Option<String> = None;
    let mut scale = 1.0f64;
    for tag in Tags::new(text) {
        let tag = tag.map_err(|(off, what)| err(off, what))?;
        match (tag.name, tag.kind) {
            ("model", TagKind::Open | TagKind::Empty) => {
                scale = match tag.attr("unit").unwrap_or("millimeter") {
                    "micron" => 0.001,
                    "millimeter" => 1.0,
                    "centimeter" => 10.0,
                    "inch" => 25.4,
                    "foot" => 304.8,
                    "meter" => 1000.0,
                    u => return Err(err(tag.offset, format!("unknown unit {u:?}"))),
                };
            }
            ("object", TagKind::Open | TagKind::Empty) => {
                let id = tag
                    .attr("id")
                    .ok_or_else(|| err(tag.offset, "an object without an id".into()))?
                    .to_string();
                if objects.contains_key(&id) {
                    return Err(err(tag.offset, format!("object id {id:?} is used twice")));
                }
                objects.insert(id.clone(), Object::default());
                order.push(id.clone());
                current = (tag.kind == TagKind::Open).then_some(id);
            }
            ("object", TagKind::Close) => current = None,
            ("vertex", _) => {
                let obj = current_object(&mut objects, &current, &tag, &err)?;
                let mut p = [0f32; 3];
                for (v, axis) in p.iter_mut().zip(["x", "y", "z"]) {
                    let raw = tag
                        .attr(axis)
                        .ok_or_else(|| err(tag.offset, format!("a vertex without {axis}")))?;
                    *v = raw
                        .trim()
                        .parse::<f32>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| {
                            err(
                                tag.offset,
                                format!("vertex {axis}={raw:?} is not a finite number"),
                            )
                        })?;
                }
                obj.mesh.vertices.push(p);
            }
            ("triangle", _) => {
                let obj = current_object(&mut objects, &current, &tag, &err)?;
                let n = obj.mesh.vertices.len();
                let mut t = [0u32; 3];
                for (v, key) in t.iter_mut().zip(["v1", "v2", "v3"]) {
                    let raw = tag
                        .attr(key)
                        .ok_or_else(|| err(tag.offset, format!("a triangle without {key}")))?;
                    *v = raw
                        .trim()
                        .parse::<u32>()
                        .ok()
                        .filter(|&i| (i as usize) < n)
                        .ok_or_else(|| {
                            err(
                                tag.offset,
                                format!("triangle {key}={raw:?} is not a vertex index (the object has {n} vertices)"),
                            )
                        })?;
                }
                obj.mesh.triangles.push(t);
            }
            ("component", _) => {
                let target = tag
                    .attr("objectid")
                    .ok_or_else(|| err(tag.offset, "a component without objectid".into()))?
                    .to_string();
                let m = transform(&tag).map_err(|w| err(tag.offset, w))?;
                let obj = current_object(&mut objects, &current, &tag, &err)?;
                obj.components.push((target, m));
            }
            ("item", _) => {
                let target = tag
                    .attr("objectid")
                    .ok_or_else(|| err(tag.offset, "a build item without objectid".into()))?
                    .to_string();
                let m = transform(&tag).map_err(|w| err(tag.offset, w))?;
                items.push((target, m));
            }
            _ => {}
        }
    }
    if items.is_empty() {
        // No build: take every object that is not a part of another as placed.
        let used: std::collections::HashSet<&str> = objects
            .values()
            .flat_map(|o| o.components.iter().map(|(id, _)| id.as_str()))
            .collect();
        items = order
            .iter()
            .filter(|id| !used.contains(id.as_str()))
            .map(|id| (id.clone(), IDENTITY))
            .collect();
    }
    let mut out = Mesh::default();
    let unit = [
        scale, 0.0, 0.0, 0.0, scale, 0.0, 0.0, 0.0, scale, 0.0, 0.0, 0.0,
    ];
    let mut budget = MAX_INSTANCES;
    for (id, m) in &items {
        instantiate(&objects, id, &compose(m, &unit), 0, &mut budget, &mut out)?;
    }
    Ok(out)
}

fn current_object<'a>(
    objects: &'a mut HashMap<String, Object>,
    current: &Option<String>,
    tag: &Tag<'_>,
    err: &impl Fn(usize, String) -> ParseError,
) -> Result<&'a mut Object, ParseError> {
    current
        .as_ref()
        .and_then(|id| objects.get_mut(id))
        .ok_or_else(|| err(tag.offset, format!("<{}> outside an <object>", tag.name)))
}

fn transform(tag: &Tag<'_>) -> Result<Affine, String> {
    let Some(raw) = tag.attr("transform") else {
        return Ok(IDENTITY);
    };
    let nums: Vec<f64> = raw
        .split_ascii_whitespace()
        .map(|t| t.parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(|| format!("transform {raw:?} is not twelve numbers"))?;
    nums.try_into()
        .map_err(|_| format!("transform {raw:?} is not twelve numbers"))
}

fn instantiate(
    objects: &HashMap<String, Object>,
    id: &str,
    m: &Affine,
    depth: usize,
    budget: &mut usize,
    out: &mut Mesh,
) -> Result<(), ParseError> {
    if *budget == 0 {
        return Err(ParseError(format!(
            "the build places more than {MAX_INSTANCES} object instances"
        )));
    }
    *budget -= 1;
    if depth > MAX_COMPONENT_DEPTH {
        return Err(ParseError(format!(
            "components nest deeper than {MAX_COMPONENT_DEPTH} levels at object {id:?} (a cycle?)"
        )));
    }
    let obj = objects.get(id).ok_or_else(|| {
        ParseError(format!(
            "a reference to object {id:?}, which does not exist"
        ))
    })?;
    let base = u32::try_from(out.vertices.len())
        .map_err(|_| ParseError("more than 2^32 vertices".into()))?;
    let mut placed = Vec::with_capacity(obj.mesh.vertices.len());
    for &p in &obj.mesh.vertices {
        let q = apply(m, p).map(|v| v as f32);
        if q.iter().any(|v| !v.is_finite()) {
            return Err(ParseError(format!(
                "object {id:?}: a transformed vertex is not finite"
            )));
        }
        placed.push(q);
    }
    out.vertices.extend(placed);
    // A mirroring transform turns the winding inside out; flip it back.
    let det = m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6])
        + m[2] * (m[3] * m[7] - m[4] * m[6]);
    out.triangles.extend(obj.mesh.triangles.iter().map(|t| {
        let t = t.map(|i| i + base);
        if det < 0.0 { [t[0], t[2], t[1]] } else { t }
    }));
    for (child, cm) in &obj.components {
        instantiate(objects, child, &compose(cm, m), depth + 1, budget, out)?;
    }
    Ok(())
}

#[derive(Copy, Clone, Debug, PartialEq)]
enum TagKind {
    Open,
    Close,
    Empty,
}

/// One XML element tag, with its namespace prefix dropped.
struct Tag<'a> {
    name: &'a str,
    kind: TagKind,
    attrs: &'a str,
    offset: usize,
}

impl<'a> Tag<'a> {
    /// An attribute's raw value (entities are left as written: 3MF numbers have none).
    fn attr(&self, key: &str) -> Option<&'a str> {
        let mut rest = self.attrs;
        loop {
            rest = rest.trim_start();
            let eq = rest.find('=')?;
            let name = rest[..eq].trim();
            let after = rest[eq + 1..].trim_start();
            let quote = after.chars().next()?;
            if quote != '"' && quote != '\'' {
                return None;
            }
            let end = after[1..].find(quote)?;
            let value = &after[1..1 + end];
            let local = name.rsplit(':').next().unwrap_or(name);
            if local == key {
                return Some(value);
            }
            rest = &after[end + 2..];
        }
    }
}

/// Element tags of an XML text in order; comments, declarations and CDATA are skipped.
struct Tags<'a> {
    text: &'a str,
    pos: usize,
}

impl<'a> Tags<'a> {
    fn new(text: &'a str) -> Self {
        Tags { text, pos: 0 }
    }
}

impl<'a> Iterator for Tags<'a> {
    type Item = Result<Tag<'a>, (usize, String)>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            let start = self.pos + self.text[self.pos..].find('<')?;
            let rest = &self.text[start..];
            let skip_to = |end: &str| rest.find(end).map(|e| start + e + end.len());
            let skipped = if rest.starts_with("<!--") {
                Some(skip_to("-->"))
            } else if rest.starts_with("<![CDATA[") {
                Some(skip_to("]]>"))
            } else if rest.starts_with("<?") {
                Some(skip_to("?>"))
            } else if rest.starts_with("<!") {
                Some(skip_to(">"))
            } else {
                None
            };
            if let Some(end) = skipped {
                let Some(end) = end else {
                    self.pos = self.text.len();
                    return Some(Err((start, "unterminated comment or declaration".into())));
                };
                self.pos = end;
                continue;
            }
            // Find the closing '>' outside quoted attribute values.
            let mut quote = None;
            let mut close = None;
            for (i, c) in rest.char_indices().skip(1) {
                match (quote, c) {
                    (None, '"' | '\'') => quote = Some(c),
                    (Some(q), c) if c == q => quote = None,
                    (None, '>') => {
                        close = Some(i);
                        break;
                    }
                    _ => {}
                }
            }
            let Some(close) = close else {
                self.pos = self.text.len();
                return Some(Err((start, "a tag is not closed (truncated?)".into())));
            };
            self.pos = start + close + 1;
            let mut inner = &rest[1..close];
            let kind = if let Some(s) = inner.strip_prefix('/') {
                inner = s;
                TagKind::Close
            } else if let Some(s) = inner.strip_suffix('/') {
                inner = s;
                TagKind::Empty
            } else {
                TagKind::Open
            };
            let name_end = inner
                .find(|c: char| c.is_ascii_whitespace())
                .unwrap_or(inner.len());
            let qname = &inner[..name_end];
            let name = qname.rsplit(':').next().unwrap_or(qname);
            return Some(Ok(Tag {
                name,
                kind,
                attrs: &inner[name_end..],
                offset: start,
            }));
        }
    }
}

const CONTENT_TYPES: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types"><Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/><Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/></Types>
"#;

const RELS: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships"><Relationship Target="/3D/3dmodel.model" Id="rel0" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/></Relationships>
"#;

/// Writes a minimal valid 3MF package: content types, the root relationship, and one
/// object in millimetres placed by one build item.
pub fn write(mesh: &Mesh, w: &mut dyn Write) -> std::io::Result<()> {
    let to_io = |e: zip::result::ZipError| std::io::Error::other(e.to_string());
    let mut zip = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let deflate = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    zip.start_file("[Content_Types].xml", deflate)
        .map_err(to_io)?;
    zip.write_all(CONTENT_TYPES.as_bytes())?;
    zip.start_file("_rels/.rels", deflate).map_err(to_io)?;
    zip.write_all(RELS.as_bytes())?;
    zip.start_file("3D/3dmodel.model", deflate).map_err(to_io)?;
    let mut buf = String::with_capacity(1 << 16);
    buf.push_str(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<model unit=\"millimeter\" \
         xml:lang=\"en-US\" xmlns=\"http://schemas.microsoft.com/3dmanufacturing/core/2015/02\">\n\
         <resources>\n<object id=\"1\" type=\"model\">\n<mesh>\n<vertices>\n",
    );
    for p in &mesh.vertices {
        buf.push_str(&format!(
            "<vertex x=\"{}\" y=\"{}\" z=\"{}\"/>\n",
            fmt_coord(p[0]),
            fmt_coord(p[1]),
            fmt_coord(p[2])
        ));
        if buf.len() > 1 << 16 {
            zip.write_all(buf.as_bytes())?;
            buf.clear();
        }
    }
    buf.push_str("</vertices>\n<triangles>\n");
    for t in &mesh.triangles {
        buf.push_str(&format!(
            "<triangle v1=\"{}\" v2=\"{}\" v3=\"{}\"/>\n",
            t[0], t[1], t[2]
        ));
        if buf.len() > 1 << 16 {
            zip.write_all(buf.as_bytes())?;
            buf.clear();
        }
    }
    buf.push_str(
        "</triangles>\n</mesh>\n</object>\n</resources>\n<build>\n<item objectid=\"1\"/>\n\
         </build>\n</model>\n",
    );
    zip.write_all(buf.as_bytes())?;
    let bytes = zip.finish().map_err(to_io)?.into_inner();
    w.write_all(&bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tags_and_attributes() {
        let xml = r#"<?xml version="1.0"?><!-- c --><m:vertex x="1" y='2' z="3"/><a b="x>y">"#;
        let tags: Vec<_> = Tags::new(xml).map(|t| t.unwrap()).collect();
        assert_eq!(tags.len(), 2);
        assert_eq!(tags[0].name, "vertex");
        assert_eq!(tags[0].kind, TagKind::Empty);
        assert_eq!(tags[0].attr("y"), Some("2"));
        assert_eq!(tags[1].attr("b"), Some("x>y"));
    }

    #[test]
    fn components_and_transforms_are_applied() {
        let xml = r#"<model unit="centimeter"><resources>
            <object id="1"><mesh><vertices><vertex x="0" y="0" z="0"/><vertex x="1" y="0" z="0"/>
            <vertex x="0" y="1" z="0"/></vertices><triangles><triangle v1="0" v2="1" v3="2"/></triangles></mesh></object>
            <object id="2"><components><component objectid="1" transform="1 0 0 0 1 0 0 0 1 5 0 0"/></components></object>
            </resources><build><item objectid="2" transform="1 0 0 0 1 0 0 0 1 0 0 1"/></build></model>"#;
        let m = parse_model(xml).unwrap();
        assert_eq!(
            m.vertices,
            vec![[50.0, 0.0, 10.0], [60.0, 0.0, 10.0], [50.0, 10.0, 10.0]]
        );
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn mirrored_items_keep_outward_winding() {
        let xml = r#"<model><resources><object id="1"><mesh><vertices><vertex x="0" y="0" z="0"/>
            <vertex x="1" y="0" z="0"/><vertex x="0" y="1" z="0"/></vertices><triangles>
            <triangle v1="0" v2="1" v3="2"/></triangles></mesh></object></resources>
            <build><item objectid="1" transform="-1 0 0 0 1 0 0 0 1 0 0 0"/></build></model>"#;
        assert_eq!(parse_model(xml).unwrap().triangles, vec![[0, 2, 1]]);
    }

    #[test]
    fn component_cycles_are_an_error() {
        let xml = r#"<model><resources><object id="1"><components><component objectid="2"/></components></object>
            <object id="2"><components><component objectid="1"/></components></object></resources>
            <build><item objectid="1"/></build></model>"#;
        assert!(parse_model(xml).unwrap_err().0.contains("nest deeper"));
    }

    #[test]
    fn bad_index_names_the_line() {
        let xml = "<model><resources><object id=\"1\"><mesh><vertices>\n<vertex x=\"0\" y=\"0\" z=\"0\"/>\n</vertices><triangles>\n<triangle v1=\"0\" v2=\"0\" v3=\"7\"/>";
        let e = parse_model(xml).unwrap_err().0;
        assert!(e.starts_with("line 4:"), "{e}");
    }
}

//! 3MF: a zip package whose model part (`3D/3dmodel.model`) is XML with, per `<object>`,
//! `<vertex x y z/>` and `<triangle v1 v2 v3/>` lists (indices local to the object), and a
//! `<build>` of items placing objects with affine transforms.
//!
//! The reader instantiates every build item (following `<component>` references, with
//! their transforms) and merges the result into one mesh; without a build it merges every
//! object. Units other than millimetres are converted.
//!
//! The XML is read by quick-xml as a stream from the inflating zip entry, so the model text
//! is never held whole in memory. Hostile packages are refused with typed errors, never
//! expanded: a `<!DOCTYPE>` (where entity bombs live) is an error, only XML's own entities
//! and character references are decoded, inflated bytes and elements are counted against
//! limits, and entry names are only looked up in the archive, never used as paths.

use std::borrow::Cow;
use std::collections::HashMap;
use std::io::{BufRead, BufReader, Cursor, Read};

use quick_xml::events::{BytesStart, Event};

use super::{ParseError, ParseErrorKind, Place, too_many_vertices};
use crate::mesh::Mesh;

/// The model part's largest accepted size once inflated: a guard against zip bombs that
/// still admits a 20-million-triangle model (about 1.3 GB of XML at ~45 bytes a vertex
/// and ~40 a triangle); isoforge itself writes ~25 bytes per triangle at depth 10.
const MAX_MODEL_BYTES: u64 = 2 << 30;
/// The relationships part is a few hundred bytes; more is not a 3MF package.
const MAX_RELS_BYTES: u64 = 1 << 20;
/// XML elements in the model part at most: every vertex and triangle is one, so this
/// bounds the memory of what is read (12 bytes each in the mesh) at 600 MB.
const MAX_ELEMENTS: u64 = 50_000_000;
/// Vertices and triangles in the placed result at most: components repeat their parts,
/// so the output can outgrow the file; the same 600 MB bound as [`MAX_ELEMENTS`].
const MAX_PLACED: u64 = MAX_ELEMENTS;
/// How deep components may nest (a cycle would otherwise recurse forever).
const MAX_COMPONENT_DEPTH: usize = 32;
/// How many object instances a package may place: components referring twice to parts that
/// refer twice to parts... grow exponentially, so a small file could otherwise take hours.
const MAX_INSTANCES: usize = 1_000_000;

/// Deflate level for written packages. Model XML is repetitive; see `benches/meshio.rs`
/// write_1m/3mf for the time this choice costs.
pub(crate) const DEFLATE_LEVEL: i64 = 1;

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

/// What a package may make the reader do at most.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Limits {
    /// Inflated bytes of model XML.
    pub model_bytes: u64,
    /// XML elements in the model part.
    pub elements: u64,
    /// Vertices and triangles placed in the result.
    pub placed: u64,
}

impl Limits {
    /// The limits [`read`] applies.
    pub(crate) const DEFAULT: Limits = Limits {
        model_bytes: MAX_MODEL_BYTES,
        elements: MAX_ELEMENTS,
        placed: MAX_PLACED,
    };
}

/// Reads a 3MF package.
pub fn read(bytes: &[u8]) -> Result<Mesh, ParseError> {
    read_with(bytes, &Limits::DEFAULT)
}

/// Reads a 3MF package within `limits`.
pub(crate) fn read_with(bytes: &[u8], limits: &Limits) -> Result<Mesh, ParseError> {
    let zip_error =
        |e: &dyn std::fmt::Display| ParseError::file(ParseErrorKind::Zip(e.to_string()));
    let mut zip = zip::ZipArchive::new(Cursor::new(bytes)).map_err(|e| zip_error(&e))?;
    let part = model_part_name(&mut zip)?;
    let entry = zip.by_name(&part).map_err(|e| {
        ParseError::new(
            Place::Entry {
                name: part.clone(),
                line: None,
            },
            ParseErrorKind::Zip(e.to_string()),
        )
    })?;
    // The declared size may lie; the metered reader counts what really inflates.
    if entry.size() > limits.model_bytes {
        return Err(ParseError::new(
            Place::Entry {
                name: part,
                line: None,
            },
            too_large_xml(limits.model_bytes),
        ));
    }
    let source = Metered::new(BufReader::with_capacity(1 << 16, entry), limits.model_bytes);
    parse_model(source, &part, limits)
}

fn too_large_xml(limit: u64) -> ParseErrorKind {
    ParseErrorKind::TooLarge {
        what: "bytes of inflated model XML",
        limit,
    }
}

/// The model part: the target of the package's 3D-model relationship, or the usual name.
/// Names are looked up among the archive's entries only: a target like `../../x` names no
/// entry and is ignored; nothing is ever opened outside the archive.
fn model_part_name(zip: &mut zip::ZipArchive<Cursor<&[u8]>>) -> Result<String, ParseError> {
    let names: Vec<String> = zip
        .file_names()
        .filter_map(|n| n.ok().map(|n| n.into_owned()))
        .collect();
    if let Ok(rels) = zip.by_name("_rels/.rels")
        && let Some(target) = model_relationship(rels)
    {
        let target = target.trim_start_matches('/');
        if names.iter().any(|n| n == target) {
            return Ok(target.to_string());
        }
    }
    names
        .iter()
        .find(|n| n.eq_ignore_ascii_case("3D/3dmodel.model"))
        .or_else(|| names.iter().find(|n| n.ends_with(".model")))
        .cloned()
        .ok_or_else(|| {
            ParseError::file(ParseErrorKind::Syntax(
                "no 3D model part (3D/3dmodel.model) in the package".into(),
            ))
        })
}

/// The target of the first 3D-model relationship in a relationships part. A damaged or
/// hostile part gives `None`: the usual model name is tried instead.
fn model_relationship(rels: impl Read) -> Option<String> {
    let mut reader = quick_xml::Reader::from_reader(BufReader::new(rels.take(MAX_RELS_BYTES)));
    let mut buf = Vec::new();
    loop {
        match reader.read_event_into(&mut buf).ok()? {
            Event::Start(e) | Event::Empty(e) if e.local_name().as_ref() == "Relationship" => {
                let [ty, target] = attrs(&e, ["Type", "Target"]).ok()?;
                if ty.is_some_and(|t| t.ends_with("/3dmodel")) {
                    return target.map(Cow::into_owned);
                }
            }
            Event::DocType(_) | Event::Eof => return None,
            _ => {}
        }
        buf.clear();
    }
}

/// A buffered reader that counts the lines and bytes the XML parser has consumed, and fails
/// once more than `limit` bytes have been read.
struct Metered<R> {
    inner: R,
    lines: usize,
    bytes: u64,
    limit: u64,
}

impl<R: BufRead> Metered<R> {
    fn new(inner: R, limit: u64) -> Self {
        Metered {
            inner,
            lines: 1,
            bytes: 0,
            limit,
        }
    }
}

impl<R: BufRead> Read for Metered<R> {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        let n = {
            let buf = self.fill_buf()?;
            let n = buf.len().min(out.len());
            out[..n].copy_from_slice(&buf[..n]);
            n
        };
        self.consume(n);
        Ok(n)
    }
}

impl<R: BufRead> BufRead for Metered<R> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        let buf = self.inner.fill_buf()?;
        if self.bytes >= self.limit && !buf.is_empty() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::FileTooLarge,
                "the inflated model is larger than the limit",
            ));
        }
        Ok(buf)
    }

    fn consume(&mut self, amt: usize) {
        // The parser consumes only what `fill_buf` showed it, so this reads nothing new.
        if amt > 0
            && let Ok(buf) = self.inner.fill_buf()
        {
            let amt = amt.min(buf.len());
            self.lines += buf[..amt].iter().filter(|&&b| b == b'\n').count();
        }
        self.bytes += amt as u64;
        self.inner.consume(amt);
    }
}

/// A quick-xml failure as ours: a limit hit while inflating, a damaged zip stream, or
/// XML that is not well formed.
fn xml_error(e: quick_xml::Error, limit: u64) -> ParseErrorKind {
    match e {
        quick_xml::Error::Io(io) if io.kind() == std::io::ErrorKind::FileTooLarge => {
            too_large_xml(limit)
        }
        quick_xml::Error::Io(io) => ParseErrorKind::Zip(io.to_string()),
        other => ParseErrorKind::Xml(other.to_string()),
    }
}

/// The values of the attributes named `keys` (by local name, any namespace prefix), in one
/// pass, with entities and character references decoded; `None` where absent.
fn attrs<'a, const N: usize>(
    e: &'a BytesStart<'_>,
    keys: [&str; N],
) -> Result<[Option<Cow<'a, str>>; N], ParseErrorKind> {
    let mut out = [const { None }; N];
    for a in e.attributes() {
        let a = a.map_err(|err| ParseErrorKind::Xml(err.to_string()))?;
        let local = a.key.local_name();
        if let Some(i) = keys.iter().position(|k| *k == local.as_ref()) {
            let value = a
                .normalized_value(quick_xml::XmlVersion::Implicit1_0)
                .map_err(|err| ParseErrorKind::Xml(err.to_string()))?;
            out[i] = Some(value);
        }
    }
    Ok(out)
}

/// One attribute's value, if present.
fn attr<'a>(e: &'a BytesStart<'_>, key: &str) -> Result<Option<Cow<'a, str>>, ParseErrorKind> {
    let [v] = attrs(e, [key])?;
    Ok(v)
}

/// The values of attributes that must all be present.
fn required<'a, const N: usize>(
    e: &'a BytesStart<'_>,
    keys: [&str; N],
) -> Result<[Cow<'a, str>; N], ParseErrorKind> {
    let found = attrs(e, keys)?;
    if let Some(i) = found.iter().position(Option::is_none) {
        return Err(ParseErrorKind::Syntax(format!(
            "a <{}> without {}",
            e.local_name().as_ref(),
            keys[i]
        )));
    }
    Ok(found.map(Option::unwrap_or_default))
}

/// What the model part holds, as read.
#[derive(Default)]
struct Model {
    /// Objects in file order, found by id through `ids`.
    objects: Vec<Object>,
    ids: HashMap<String, usize>,
    order: Vec<String>,
    items: Vec<(String, Affine)>,
    /// The object being read (by index, so millions of vertex tags cost no hashing).
    current: Option<usize>,
    /// Millimetres per model unit.
    scale: f64,
}

impl Model {
    fn current(&mut self, name: &str) -> Result<&mut Object, ParseErrorKind> {
        self.current
            .and_then(|i| self.objects.get_mut(i))
            .ok_or_else(|| ParseErrorKind::Syntax(format!("<{name}> outside an <object>")))
    }

    /// Takes one start or empty element.
    fn element(&mut self, e: &BytesStart<'_>, empty: bool) -> Result<(), ParseErrorKind> {
        let name = e.local_name();
        match name.as_ref() {
            "model" => {
                self.scale = match attr(e, "unit")?.as_deref().unwrap_or("millimeter") {
                    "micron" => 0.001,
                    "millimeter" => 1.0,
                    "centimeter" => 10.0,
                    "inch" => 25.4,
                    "foot" => 304.8,
                    "meter" => 1000.0,
                    u => return Err(ParseErrorKind::Syntax(format!("unknown unit {u:?}"))),
                };
            }
            "object" => {
                let [id] = required(e, ["id"])?;
                let id = id.into_owned();
                if self.ids.contains_key(&id) {
                    return Err(ParseErrorKind::Syntax(format!(
                        "object id {id:?} is used twice"
                    )));
                }
                self.ids.insert(id.clone(), self.objects.len());
                self.objects.push(Object::default());
                self.order.push(id);
                self.current = (!empty).then_some(self.objects.len() - 1);
            }
            "vertex" => {
                let mut p = [0f32; 3];
                let raw = required(e, ["x", "y", "z"])?;
                for ((v, raw), field) in p
                    .iter_mut()
                    .zip(raw)
                    .zip(["vertex x", "vertex y", "vertex z"])
                {
                    *v = raw
                        .trim()
                        .parse::<f32>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| ParseErrorKind::BadNumber {
                            field: field.into(),
                            token: raw.into_owned(),
                        })?;
                }
                let obj = self.current("vertex")?;
                if obj.mesh.vertices.len() >= u32::MAX as usize {
                    return Err(too_many_vertices(Place::File).kind);
                }
                obj.mesh.vertices.push(p);
            }
            "triangle" => {
                let n = self.current("triangle")?.mesh.vertices.len();
                let mut t = [0u32; 3];
                for (v, raw) in t.iter_mut().zip(required(e, ["v1", "v2", "v3"])?) {
                    *v = raw
                        .trim()
                        .parse::<u32>()
                        .ok()
                        .filter(|&i| (i as usize) < n)
                        .ok_or_else(|| ParseErrorKind::BadIndex {
                            token: raw.into_owned(),
                            vertices: n,
                        })?;
                }
                self.current("triangle")?.mesh.triangles.push(t);
            }
            "component" => {
                let [target] = required(e, ["objectid"])?;
                let target = target.into_owned();
                let m = transform(e)?;
                self.current("component")?.components.push((target, m));
            }
            "item" => {
                let [target] = required(e, ["objectid"])?;
                let target = target.into_owned();
                let m = transform(e)?;
                self.items.push((target, m));
            }
            _ => {}
        }
        Ok(())
    }
}

/// Parses the model XML into one mesh; `part` names the entry in errors.
fn parse_model<R: BufRead>(
    source: Metered<R>,
    part: &str,
    limits: &Limits,
) -> Result<Mesh, ParseError> {
    let mut reader = quick_xml::Reader::from_reader(source);
    let mut model = Model {
        scale: 1.0,
        ..Model::default()
    };
    let mut buf = Vec::new();
    let mut elements = 0u64;
    loop {
        let line = reader.get_ref().lines;
        let at = |line| Place::Entry {
            name: part.to_string(),
            line: Some(line),
        };
        let event = reader.read_event_into(&mut buf).map_err(|e| {
            ParseError::new(at(reader.get_ref().lines), xml_error(e, limits.model_bytes))
        })?;
        let done = match event {
            Event::Start(ref e) | Event::Empty(ref e) => {
                elements += 1;
                if elements > limits.elements {
                    return Err(ParseError::new(
                        at(line),
                        ParseErrorKind::TooLarge {
                            what: "XML elements",
                            limit: limits.elements,
                        },
                    ));
                }
                let empty = matches!(event, Event::Empty(_));
                model
                    .element(e, empty)
                    .map_err(|kind| ParseError::new(at(line), kind))?;
                false
            }
            Event::End(ref e) => {
                if e.local_name().as_ref() == "object" {
                    model.current = None;
                }
                false
            }
            Event::DocType(_) => return Err(ParseError::new(at(line), ParseErrorKind::Doctype)),
            Event::Eof => true,
            // Text, CDATA, comments, processing instructions and entity references between
            // elements carry no geometry.
            _ => false,
        };
        if done {
            break;
        }
        buf.clear();
    }
    place_items(model, limits.placed).map_err(|kind| {
        ParseError::new(
            Place::Entry {
                name: part.to_string(),
                line: None,
            },
            kind,
        )
    })
}

/// Instantiates the build items (or, without a build, every object no other one uses) into
/// one mesh in millimetres.
fn place_items(model: Model, max_placed: u64) -> Result<Mesh, ParseErrorKind> {
    let mut items = model.items;
    if items.is_empty() {
        let used: std::collections::HashSet<&str> = model
            .objects
            .iter()
            .flat_map(|o| o.components.iter().map(|(id, _)| id.as_str()))
            .collect();
        items = model
            .order
            .iter()
            .filter(|id| !used.contains(id.as_str()))
            .map(|id| (id.clone(), IDENTITY))
            .collect();
    }
    let mut out = Mesh::default();
    let s = model.scale;
    let unit = [s, 0.0, 0.0, 0.0, s, 0.0, 0.0, 0.0, s, 0.0, 0.0, 0.0];
    let mut budget = Budget {
        instances: MAX_INSTANCES,
        placed: max_placed,
    };
    for (id, m) in &items {
        instantiate(
            (&model.objects, &model.ids),
            id,
            &compose(m, &unit),
            0,
            &mut budget,
            &mut out,
        )?;
    }
    Ok(out)
}

fn transform(e: &BytesStart<'_>) -> Result<Affine, ParseErrorKind> {
    let Some(raw) = attr(e, "transform")? else {
        return Ok(IDENTITY);
    };
    let bad = || ParseErrorKind::Syntax(format!("transform {raw:?} is not twelve numbers"));
    let nums: Vec<f64> = raw
        .split_ascii_whitespace()
        .map(|t| t.parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(bad)?;
    nums.try_into().map_err(|_| bad())
}

/// What placing objects may still do.
struct Budget {
    /// Object instances left.
    instances: usize,
    /// The most vertices and triangles the result may hold.
    placed: u64,
}

fn instantiate(
    objects: (&[Object], &HashMap<String, usize>),
    id: &str,
    m: &Affine,
    depth: usize,
    budget: &mut Budget,
    out: &mut Mesh,
) -> Result<(), ParseErrorKind> {
    if budget.instances == 0 {
        return Err(ParseErrorKind::TooLarge {
            what: "placed object instances",
            limit: MAX_INSTANCES as u64,
        });
    }
    budget.instances -= 1;
    if depth > MAX_COMPONENT_DEPTH {
        return Err(ParseErrorKind::Syntax(format!(
            "components nest deeper than {MAX_COMPONENT_DEPTH} levels at object {id:?} (a cycle?)"
        )));
    }
    let obj = objects
        .1
        .get(id)
        .and_then(|&i| objects.0.get(i))
        .ok_or_else(|| {
            ParseErrorKind::Syntax(format!(
                "a reference to object {id:?}, which does not exist"
            ))
        })?;
    let placed_total = (out.vertices.len() + obj.mesh.vertices.len()) as u64
        + (out.triangles.len() + obj.mesh.triangles.len()) as u64;
    if placed_total > budget.placed {
        return Err(ParseErrorKind::TooLarge {
            what: "placed vertices and triangles",
            limit: budget.placed,
        });
    }
    let base =
        u32::try_from(out.vertices.len()).map_err(|_| too_many_vertices(Place::File).kind)?;
    let mut placed = Vec::with_capacity(obj.mesh.vertices.len());
    for &p in &obj.mesh.vertices {
        let q = apply(m, p).map(|v| v as f32);
        if q.iter().any(|v| !v.is_finite()) {
            return Err(ParseErrorKind::Syntax(format!(
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

pub(crate) const CONTENT_TYPES: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types"><Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/><Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/></Types>
"#;

pub(crate) const RELS: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships"><Relationship Target="/3D/3dmodel.model" Id="rel0" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/></Relationships>
"#;

/// The model part's opening, up to the first vertex.
pub(crate) const MODEL_HEAD: &str = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<model unit=\"millimeter\" \
     xml:lang=\"en-US\" xmlns=\"http://schemas.microsoft.com/3dmanufacturing/core/2015/02\">\n\
     <resources>\n<object id=\"1\" type=\"model\">\n<mesh>\n<vertices>\n";

/// The model part's closing, after the last triangle: one build item places the object.
pub(crate) const MODEL_TAIL: &str = "</triangles>\n</mesh>\n</object>\n</resources>\n<build>\n\
     <item objectid=\"1\"/>\n</build>\n</model>\n";

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(xml: &str) -> Result<Mesh, ParseError> {
        parse_model(
            Metered::new(xml.as_bytes(), MAX_MODEL_BYTES),
            "3D/3dmodel.model",
            &Limits::DEFAULT,
        )
    }

    #[test]
    fn attributes_decode_entities_and_ignore_prefixes() {
        let xml = r#"<?xml version="1.0"?><!-- c --><m:model><m:resources><m:object id="a&amp;b">
            <m:mesh><m:vertices><m:vertex x="&#49;" y='2' z="3"/><m:vertex x="0" y="0" z="0"/>
            <m:vertex x="1" y="1" z="0"/></m:vertices><m:triangles><m:triangle v1="0" v2="1" v3="&#x32;"/>
            </m:triangles></m:mesh></m:object></m:resources><m:build><m:item objectid="a&amp;b"/></m:build></m:model>"#;
        let m = parse(xml).unwrap();
        assert_eq!(m.vertices[0], [1.0, 2.0, 3.0]);
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn components_and_transforms_are_applied() {
        let xml = r#"<model unit="centimeter"><resources>
            <object id="1"><mesh><vertices><vertex x="0" y="0" z="0"/><vertex x="1" y="0" z="0"/>
            <vertex x="0" y="1" z="0"/></vertices><triangles><triangle v1="0" v2="1" v3="2"/></triangles></mesh></object>
            <object id="2"><components><component objectid="1" transform="1 0 0 0 1 0 0 0 1 5 0 0"/></components></object>
            </resources><build><item objectid="2" transform="1 0 0 0 1 0 0 0 1 0 0 1"/></build></model>"#;
        let m = parse(xml).unwrap();
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
        assert_eq!(parse(xml).unwrap().triangles, vec![[0, 2, 1]]);
    }

    #[test]
    fn component_cycles_are_an_error() {
        let xml = r#"<model><resources><object id="1"><components><component objectid="2"/></components></object>
            <object id="2"><components><component objectid="1"/></components></object></resources>
            <build><item objectid="1"/></build></model>"#;
        let e = parse(xml).unwrap_err();
        assert!(
            matches!(&e.kind, ParseErrorKind::Syntax(m) if m.contains("nest deeper")),
            "{e}"
        );
    }

    #[test]
    fn bad_index_names_the_line_and_the_count() {
        let xml = "<model><resources><object id=\"1\"><mesh><vertices>\n<vertex x=\"0\" y=\"0\" z=\"0\"/>\n</vertices><triangles>\n<triangle v1=\"0\" v2=\"0\" v3=\"7\"/>";
        let e = parse(xml).unwrap_err();
        assert_eq!(
            e.at,
            Place::Entry {
                name: "3D/3dmodel.model".into(),
                line: Some(4)
            },
            "{e}"
        );
        assert_eq!(
            e.kind,
            ParseErrorKind::BadIndex {
                token: "7".into(),
                vertices: 1
            }
        );
        assert!(e.to_string().starts_with("3D/3dmodel.model line 4:"), "{e}");
    }

    #[test]
    fn the_metered_reader_counts_lines_and_stops_at_its_limit() {
        let text = b"a\nb\nc\n".repeat(10);
        let mut m = Metered::new(&text[..], 1 << 20);
        let mut all = Vec::new();
        m.read_to_end(&mut all).unwrap();
        assert_eq!((all.len(), m.lines), (text.len(), 31));
        let mut m = Metered::new(&text[..], 7);
        let err = m.read_to_end(&mut Vec::new()).unwrap_err();
        assert_eq!(err.kind(), std::io::ErrorKind::FileTooLarge);
    }
}

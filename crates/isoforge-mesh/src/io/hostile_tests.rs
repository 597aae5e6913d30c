//! Hostile 3MF packages: each is refused with the typed error that names its trick, or read
//! correctly, and none makes the reader expand, inflate or look outside the archive.

use std::io::Write;

use super::threemf::{Limits, read_with};
use super::*;

/// A vertex list and one triangle, for bodies of test models.
const TRIANGLE: &str = r#"<object id="1"><mesh><vertices><vertex x="0" y="0" z="0"/>
<vertex x="1" y="0" z="0"/><vertex x="0" y="1" z="0"/></vertices><triangles>
<triangle v1="0" v2="1" v3="2"/></triangles></mesh></object>"#;

fn model(resources: &str) -> String {
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<model unit=\"millimeter\">\
         <resources>{resources}</resources></model>"
    )
}

/// A zip package of the given entries, deflated.
fn package(entries: &[(&str, &[u8])]) -> Vec<u8> {
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let opts = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    for (name, bytes) in entries {
        zip.start_file(*name, opts).unwrap();
        zip.write_all(bytes).unwrap();
    }
    zip.finish().unwrap().into_inner()
}

fn model_package(xml: &str) -> Vec<u8> {
    package(&[("3D/3dmodel.model", xml.as_bytes())])
}

fn kind_of(bytes: &[u8]) -> ParseErrorKind {
    match decode(bytes, MeshFormat::ThreeMf) {
        Err(e) => e.kind,
        Ok(m) => panic!("expected an error, read {} triangles", m.triangles.len()),
    }
}

#[test]
fn an_entity_bomb_is_refused_not_expanded() {
    // Ten levels of ten copies: 10^10 "lol"s if expanded.
    let mut dtd = String::from("<!ENTITY l0 \"lol\">");
    for i in 1..10 {
        let refs = format!("&l{};", i - 1).repeat(10);
        dtd += &format!("<!ENTITY l{i} \"{refs}\">");
    }
    let xml = format!(
        "<?xml version=\"1.0\"?>\n<!DOCTYPE model [{dtd}]>\n<model><resources>\
         <object id=\"&l9;\"/></resources></model>"
    );
    assert_eq!(kind_of(&model_package(&xml)), ParseErrorKind::Doctype);
}

#[test]
fn undefined_entities_are_errors_and_xml_entities_are_decoded() {
    let xml = model(&TRIANGLE.replace("x=\"1\"", "x=\"&lol;\""));
    assert!(matches!(
        kind_of(&model_package(&xml)),
        ParseErrorKind::Xml(_)
    ));
    // Character references and XML's own entities in attribute values are decoded.
    let xml = model(
        &TRIANGLE
            .replace("x=\"1\"", "x=\"&#49;&#x2E;5\"")
            .replace("id=\"1\"", "id=\"a&amp;&lt;b&gt;\""),
    );
    let m = decode(&model_package(&xml), MeshFormat::ThreeMf).unwrap();
    assert_eq!(m.vertices[1], [1.5, 0.0, 0.0]);
    assert_eq!(m.triangles.len(), 1);
}

#[test]
fn cdata_and_comments_hold_no_geometry() {
    let body = TRIANGLE.replace(
        "<vertex x=\"1\"",
        "<![CDATA[<vertex x=\"9\" y=\"9\" z=\"9\"/>]]><!-- <vertex x=\"8\" y=\"8\" z=\"8\"/> -->\
         <vertex x=\"1\"",
    );
    let m = decode(&model_package(&model(&body)), MeshFormat::ThreeMf).unwrap();
    assert_eq!(m.vertices.len(), 3);
    assert!(m.vertices.iter().all(|v| v[0] < 2.0));
}

#[test]
fn a_declared_size_over_the_limit_is_refused_before_inflating() {
    let bytes = model_package(&model(TRIANGLE));
    let limits = Limits {
        model_bytes: 100,
        ..Limits::DEFAULT
    };
    let e = read_with(&bytes, &limits).unwrap_err();
    assert_eq!(
        e.kind,
        ParseErrorKind::TooLarge {
            what: "bytes of inflated model XML",
            limit: 100
        }
    );
}

/// Offsets of the uncompressed-size fields of the first entry: in its local header (offset
/// 22) and in its central directory record (offset 24 from the record's signature).
fn size_fields(bytes: &[u8]) -> (usize, usize) {
    let central = bytes
        .windows(4)
        .position(|w| w == b"PK\x01\x02")
        .expect("a central directory");
    (22, central + 24)
}

#[test]
fn an_entry_that_inflates_past_its_declared_size_is_stopped_at_the_limit() {
    // Many vertices: inflates to far more than the limit the size fields are set under.
    let extra = "<vertex x=\"0\" y=\"0\" z=\"0\"/>\n".repeat(2000);
    let body = TRIANGLE.replace("<vertex x=\"1\"", &format!("{extra}<vertex x=\"1\""));
    let xml = model(&body);
    let mut bytes = model_package(&xml);
    // The package says the entry inflates to 50 bytes; it is a lie.
    let (local, central) = size_fields(&bytes);
    for at in [local, central] {
        bytes[at..at + 4].copy_from_slice(&50u32.to_le_bytes());
    }
    let limits = Limits {
        model_bytes: 4096,
        ..Limits::DEFAULT
    };
    let kind = read_with(&bytes, &limits).unwrap_err().kind;
    // Either the zip reader notices the lie, or our meter stops at the limit; it never
    // inflates the whole entry into a mesh.
    assert!(
        matches!(
            kind,
            ParseErrorKind::TooLarge { limit: 4096, .. } | ParseErrorKind::Zip(_)
        ),
        "{kind:?}"
    );
    // Without the size lie, the same entry is over the limit by its own count.
    let honest = model_package(&xml);
    assert_eq!(
        read_with(&honest, &limits).unwrap_err().kind,
        ParseErrorKind::TooLarge {
            what: "bytes of inflated model XML",
            limit: 4096
        }
    );
}

#[test]
fn huge_element_counts_are_refused() {
    let many = format!(
        "<object id=\"1\"><mesh><vertices>{}</vertices></mesh></object>",
        "<vertex x=\"0\" y=\"0\" z=\"0\"/>".repeat(500)
    );
    let limits = Limits {
        elements: 100,
        ..Limits::DEFAULT
    };
    let e = read_with(&model_package(&model(&many)), &limits).unwrap_err();
    assert_eq!(
        e.kind,
        ParseErrorKind::TooLarge {
            what: "XML elements",
            limit: 100
        }
    );
    // Components that repeat a part: few elements, many placed triangles.
    let mut objects = String::from(TRIANGLE);
    for level in 2..12 {
        let child = level - 1;
        objects += &format!(
            "<object id=\"{level}\"><components><component objectid=\"{child}\"/>\
             <component objectid=\"{child}\"/></components></object>"
        );
    }
    let xml = format!(
        "<model><resources>{objects}</resources><build><item objectid=\"11\"/></build></model>"
    );
    let limits = Limits {
        placed: 1000,
        ..Limits::DEFAULT
    };
    let e = read_with(&model_package(&xml), &limits).unwrap_err();
    assert_eq!(
        e.kind,
        ParseErrorKind::TooLarge {
            what: "placed vertices and triangles",
            limit: 1000
        }
    );
    // The same file within the default limits: 2^10 copies of the triangle.
    let m = decode(&model_package(&xml), MeshFormat::ThreeMf).unwrap();
    assert_eq!(m.triangles.len(), 1024);
}

#[test]
fn truncated_packages_are_clean_errors() {
    let bytes = model_package(&model(TRIANGLE));
    for cut in [bytes.len() / 2, bytes.len() - 10, 30] {
        let kind = kind_of(&bytes[..cut]);
        assert!(
            matches!(kind, ParseErrorKind::Zip(_)),
            "cut {cut}: {kind:?}"
        );
    }
    // A damaged deflate stream with an intact directory: an error of the entry.
    let mut bad = bytes.clone();
    let data = 30 + "3D/3dmodel.model".len();
    for b in &mut bad[data + 5..data + 25] {
        *b ^= 0x5a;
    }
    let e = decode(&bad, MeshFormat::ThreeMf).unwrap_err();
    assert!(
        matches!(e.kind, ParseErrorKind::Zip(_) | ParseErrorKind::Xml(_)),
        "{e}"
    );
}

#[test]
fn dot_dot_names_never_reach_the_file_system() {
    let dir = tempfile::tempdir().unwrap();
    // A real model file outside the archive, which a careless reader would follow.
    let outside = dir.path().join("outside.model");
    std::fs::write(&outside, model(TRIANGLE)).unwrap();
    let rels = format!(
        "<Relationships><Relationship Target=\"/../../..{}\" Id=\"r\" \
         Type=\"http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel\"/></Relationships>",
        outside.display()
    );
    let bytes = package(&[
        ("_rels/.rels", rels.as_bytes()),
        ("readme.txt", b"nothing here"),
    ]);
    let kind = kind_of(&bytes);
    assert!(
        matches!(&kind, ParseErrorKind::Syntax(m) if m.contains("no 3D model part")),
        "{kind:?}"
    );
    // An entry whose own name climbs out is read from the archive like any other.
    let bytes = package(&[("../../escape.model", model(TRIANGLE).as_bytes())]);
    let m = decode(&bytes, MeshFormat::ThreeMf).unwrap();
    assert_eq!(m.triangles.len(), 1);
    assert!(!dir.path().join("escape.model").exists());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn bytes_that_are_not_utf8_are_an_xml_error() {
    let mut xml = model(TRIANGLE).into_bytes();
    let at = xml.iter().position(|&b| b == b'1').unwrap();
    xml[at] = 0xff;
    let bytes = package(&[("3D/3dmodel.model", &xml)]);
    let e = decode(&bytes, MeshFormat::ThreeMf).unwrap_err();
    assert!(
        matches!(
            e.kind,
            ParseErrorKind::Xml(_) | ParseErrorKind::BadNumber { .. }
        ),
        "{e}"
    );
}

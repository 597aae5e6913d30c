//! Readers and writers: round trips, the awkward corners of each format, and no panic on
//! any input.

use proptest::prelude::*;

use super::*;
use crate::check::check;
use crate::samples::{cube, merge, tetrahedron, uv_sphere};

const ALL: [MeshFormat; 5] = [
    MeshFormat::Stl,
    MeshFormat::StlAscii,
    MeshFormat::ThreeMf,
    MeshFormat::Obj,
    MeshFormat::Ply,
];

fn bytes_of(mesh: &Mesh, format: MeshFormat) -> Vec<u8> {
    let mut out = Vec::new();
    encode(mesh, format, &mut out).unwrap();
    out
}

/// The mesh as a list of triangles by position: equal for meshes that differ only in how
/// vertices are numbered.
fn soup(m: &Mesh) -> Vec<[[u32; 3]; 3]> {
    m.triangles
        .iter()
        .map(|t| t.map(|i| m.vertices[i as usize].map(|v| (v + 0.0).to_bits())))
        .collect()
}

fn err_of(bytes: &[u8], name: &str) -> String {
    read_mesh_bytes(bytes, name).unwrap_err().to_string()
}

/// The typed parse error of bytes that must fail to parse.
fn parse_err_of(bytes: &[u8], name: &str) -> ParseError {
    match read_mesh_bytes(bytes, name) {
        Err(MeshIoError::Parse { error, path }) => {
            assert_eq!(path, name);
            error
        }
        other => panic!("{name}: expected a parse error, got {other:?}"),
    }
}

#[test]
fn every_format_round_trips() {
    let mut odd = merge(uv_sphere(3.25, 7, 5), &tetrahedron());
    odd.vertices[3][0] = -0.0;
    odd.vertices[4][1] = 1.0e-30;
    odd.vertices[5][2] = -123456.79;
    for mesh in [cube(10.0), odd] {
        for format in ALL {
            let bytes = bytes_of(&mesh, format);
            assert_eq!(
                MeshFormat::sniff(&bytes).is_some(),
                format != MeshFormat::Obj
            );
            let back = read_mesh_bytes(&bytes, &format!("m.{}", format.name())).unwrap();
            assert_eq!(soup(&back), soup(&mesh), "{format:?}");
            if format != MeshFormat::Stl && format != MeshFormat::StlAscii {
                // Indexed formats keep the numbering too.
                let fixed: Vec<_> = mesh.vertices.iter().map(|p| p.map(|v| v + 0.0)).collect();
                assert_eq!(back.vertices, fixed, "{format:?}");
                assert_eq!(back.triangles, mesh.triangles, "{format:?}");
            }
        }
    }
}

#[test]
fn streaming_writers_match_the_whole_mesh_writers() {
    use crate::sink::MeshSink;
    // The mesher's order: vertices and triangles interleaved, each triangle right after
    // its last vertex, counts unknown until the end.
    let mesh = merge(uv_sphere(3.25, 9, 6), &cube(2.0));
    let mut last_use: Vec<Vec<usize>> = vec![Vec::new(); mesh.vertices.len()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let last = tri.iter().copied().max().unwrap_or(0) as usize;
        last_use[last].push(t);
    }
    let spill = tempfile::tempdir().unwrap();
    for format in ALL {
        let mut w = stream::MeshWriter::streaming(format, Vec::new(), spill.path()).unwrap();
        for (v, tris) in last_use.iter().enumerate() {
            w.vertex(mesh.vertices[v]).unwrap();
            for &t in tris {
                let tri = mesh.triangles[t];
                let corners = tri.map(|i| mesh.vertices[i as usize]);
                w.triangle(tri, corners).unwrap();
            }
        }
        let bytes = w.finish().unwrap();
        let back = read_mesh_bytes(&bytes, &format!("m.{}", format.name())).unwrap();
        let mut got = soup(&back);
        let mut want = soup(&mesh);
        got.sort_unstable();
        want.sort_unstable();
        assert_eq!(got, want, "{format:?}");
        if format != MeshFormat::Stl && format != MeshFormat::StlAscii {
            assert_eq!(back.triangles.len(), mesh.triangles.len(), "{format:?}");
        }
        // The spill files are unnamed: nothing is left in the folder.
        assert_eq!(std::fs::read_dir(spill.path()).unwrap().count(), 0);
    }
}

#[test]
fn stl_readers_weld_to_a_closed_mesh() {
    for format in [MeshFormat::Stl, MeshFormat::StlAscii] {
        let back = read_mesh_bytes(&bytes_of(&cube(1.0), format), "c.stl").unwrap();
        assert_eq!(back.vertices.len(), 8);
        assert!(check(&back).is_closed_manifold());
    }
}

#[test]
fn negative_zero_welds_with_zero() {
    let mut text = String::from_utf8(bytes_of(&cube(1.0), MeshFormat::StlAscii)).unwrap();
    text = text.replacen("vertex 0 0 0", "vertex -0 0 -0.0", 1);
    let m = read_mesh_bytes(text.as_bytes(), "c.stl").unwrap();
    assert_eq!(m.vertices.len(), 8);
    assert!(check(&m).is_closed_manifold());
}

#[test]
fn ascii_stl_without_a_name_and_with_odd_spacing() {
    let text = "solid\n facet normal 0 0 1\n  outer loop\n vertex 0 0 0\n\tvertex 1 0 0\r\n \
                VERTEX 0 1 0\n endloop\n endfacet\nendsolid\n";
    let m = read_mesh_bytes(text.as_bytes(), "t.stl").unwrap();
    assert_eq!(m.triangles, vec![[0, 1, 2]]);
}

#[test]
fn binary_stl_whose_header_says_solid_is_binary() {
    let mut bytes = bytes_of(&cube(1.0), MeshFormat::Stl);
    bytes[..12].copy_from_slice(b"solid cube  ");
    let m = read_mesh_bytes(&bytes, "c.stl").unwrap();
    assert_eq!(m.triangles.len(), 12);
}

#[test]
fn truncated_binary_stl_names_the_byte() {
    let bytes = bytes_of(&cube(1.0), MeshFormat::Stl);
    let e = err_of(&bytes[..84 + 50 * 5 + 17], "cut.stl");
    assert!(e.starts_with("cut.stl: byte 334: truncated"), "{e}");
    assert!(e.contains("12 triangles"), "{e}");
    let e = parse_err_of(&bytes[..84 + 50 * 5 + 17], "cut.stl");
    assert_eq!(e.at, Place::Byte(334));
    assert!(
        matches!(
            e.kind,
            ParseErrorKind::Truncated {
                expected: 684,
                actual: 351,
                ..
            }
        ),
        "{e}"
    );
    let e = err_of(&bytes[..40], "short.stl");
    assert!(e.contains("too short"), "{e}");
}

#[test]
fn nan_coordinates_are_rejected_with_a_place() {
    let mut bytes = bytes_of(&cube(1.0), MeshFormat::Stl);
    let off = 84 + 50 * 2 + 12 + 4;
    bytes[off..off + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let e = err_of(&bytes, "nan.stl");
    assert!(
        e.contains(&format!("byte {off}")) && e.contains("triangle 2"),
        "{e}"
    );
    let e = parse_err_of(&bytes, "nan.stl");
    assert_eq!(e.at, Place::Byte(off as u64));
    assert!(matches!(e.kind, ParseErrorKind::BadNumber { .. }), "{e}");
    let e = err_of(b"v 0 0 0\nv nan 1 2\nv 0 1 0\nf 1 2 3\n", "n.obj");
    assert!(e.starts_with("n.obj: line 2:"), "{e}");
    let e = parse_err_of(b"v 0 0 0\nv nan 1 2\nv 0 1 0\nf 1 2 3\n", "n.obj");
    assert_eq!(
        (e.at, e.kind),
        (
            Place::Line(2),
            ParseErrorKind::BadNumber {
                field: "coordinate".into(),
                token: "nan".into()
            }
        )
    );
    let e = err_of(
        b"solid x\nfacet normal 0 0 0\nouter loop\nvertex 0 inf 0\n",
        "i.stl",
    );
    assert!(e.starts_with("i.stl: line 4:"), "{e}");
}

#[test]
fn ascii_stl_errors_name_the_line() {
    let e = err_of(
        b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\nendloop\n",
        "a.stl",
    );
    assert!(e.starts_with("a.stl: line 5:"), "{e}");
    let e = err_of(
        b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\n",
        "b.stl",
    );
    assert!(e.contains("line 6") && e.contains("2 vertices"), "{e}");
    let e = err_of(b"solid x\nendsolid\nbanana\n", "c.stl");
    assert!(e.contains("line 3") && e.contains("banana"), "{e}");
    let full = bytes_of(&cube(1.0), MeshFormat::StlAscii);
    let cut = &full[..full.len() - "endsolid isoforge\n".len()];
    assert!(err_of(cut, "d.stl").contains("endsolid"));
}

#[test]
fn obj_faces_in_every_form() {
    let text = "# a quad and a triangle\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 1.0\nvt 0 0\nvn 0 0 1\n\
                o thing\ng part\nusemtl m\nf 1/1/1 2/1/1 3//1 4/1\nv 0 0 1\nf -5 -4 -1\n";
    let m = read_mesh_bytes(text.as_bytes(), "q.obj").unwrap();
    assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 1, 4]]);
    assert_eq!(m.vertices.len(), 5);
}

#[test]
fn obj_bad_indices_name_the_line() {
    let e = parse_err_of(b"v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n", "b.obj");
    assert_eq!(
        (e.at, e.kind),
        (
            Place::Line(5),
            ParseErrorKind::BadIndex {
                token: "4".into(),
                vertices: 3
            }
        )
    );
    let e = err_of(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "z.obj");
    assert!(e.contains("line 4") && e.contains("index 0"), "{e}");
    let e = err_of(b"v 0 0 0\nv 1 0 0\nf 1 2\n", "s.obj");
    assert!(e.contains("line 3") && e.contains("2 corners"), "{e}");
    let e = err_of(b"v 0 0 0\nf 1 -2 1\n", "n.obj");
    assert!(e.contains("line 2") && e.contains("-2"), "{e}");
}

/// A PLY file in a given encoding, with an extra per-vertex property, an extra element,
/// double coordinates and `uint` list counts, to exercise the skipping paths.
fn odd_ply(mesh: &Mesh, format: &str) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat {format} 1.0\ncomment odd\nobj_info x\nelement vertex {}\n\
         property double x\nproperty uchar red\nproperty double y\nproperty double z\n\
         element face {}\nproperty uchar flags\nproperty list uint short vertex_indices\n\
         property list uchar float texcoord\nelement edge 1\nproperty int vertex1\n\
         property int vertex2\nend_header\n",
        mesh.vertices.len(),
        mesh.triangles.len()
    )
    .into_bytes();
    let big = format == "binary_big_endian";
    let num = |out: &mut Vec<u8>, v: f64, size: usize| match (format, size) {
        ("ascii", _) => out.extend_from_slice(format!("{v} ").as_bytes()),
        (_, 8) => out.extend(if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }),
        (_, 4) if v.fract() != 0.0 => out.extend(if big {
            (v as f32).to_be_bytes()
        } else {
            (v as f32).to_le_bytes()
        }),
        (_, 4) => out.extend(if big {
            (v as u32).to_be_bytes()
        } else {
            (v as u32).to_le_bytes()
        }),
        (_, 2) => out.extend(if big {
            (v as i16).to_be_bytes()
        } else {
            (v as i16).to_le_bytes()
        }),
        _ => out.push(v as u8),
    };
    for p in &mesh.vertices {
        num(&mut out, f64::from(p[0]), 8);
        num(&mut out, 200.0, 1);
        num(&mut out, f64::from(p[1]), 8);
        num(&mut out, f64::from(p[2]), 8);
        if format == "ascii" {
            out.push(b'\n');
        }
    }
    for t in &mesh.triangles {
        num(&mut out, 7.0, 1);
        num(&mut out, 3.0, 4);
        for &i in t {
            num(&mut out, f64::from(i), 2);
        }
        num(&mut out, 2.0, 1);
        num(&mut out, 0.5, 4);
        num(&mut out, 0.25, 4);
        if format == "ascii" {
            out.push(b'\n');
        }
    }
    num(&mut out, 0.0, 4);
    num(&mut out, 1.0, 4);
    out
}

#[test]
fn ply_in_all_three_encodings() {
    let mesh = cube(2.5);
    for format in ["ascii", "binary_little_endian", "binary_big_endian"] {
        let bytes = odd_ply(&mesh, format);
        let m = read_mesh_bytes(&bytes, "odd.ply").unwrap_or_else(|e| panic!("{format}: {e}"));
        assert_eq!(m, mesh, "{format}");
    }
}

#[test]
fn ply_errors_say_where() {
    let good = odd_ply(&cube(1.0), "binary_little_endian");
    let e = err_of(&good[..good.len() - 30], "t.ply");
    assert!(e.contains("byte") && e.contains("truncated"), "{e}");
    let e = parse_err_of(&good[..good.len() - 30], "t.ply");
    assert!(matches!(e.at, Place::Byte(_)), "{e}");
    assert!(matches!(e.kind, ParseErrorKind::Truncated { .. }), "{e}");
    let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
                0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n";
    let e = parse_err_of(text.as_bytes(), "r.ply");
    assert_eq!(e.at, Place::Line(13), "{e}");
    assert!(
        matches!(e.kind, ParseErrorKind::BadIndex { vertices: 3, .. }),
        "{e}"
    );
    let e = err_of(
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty fluffy x\n",
        "h.ply",
    );
    assert!(e.contains("line 4") && e.contains("fluffy"), "{e}");
    let e = err_of(
        b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
        "big.ply",
    );
    assert!(e.contains("4000000000"), "{e}");
}

#[test]
fn threemf_of_several_objects_merges_them() {
    let two = merge(cube(1.0), &tetrahedron());
    let bytes = bytes_of(&two, MeshFormat::ThreeMf);
    let m = read_mesh_bytes(&bytes, "x.3mf").unwrap();
    assert_eq!(m, two);
    // And a package with two objects and two build items.
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let opts = zip::write::SimpleFileOptions::default();
    zip.start_file("3D/3dmodel.model", opts).unwrap();
    let xml = r#"<?xml version="1.0"?><model unit="millimeter"><resources>
        <object id="4" type="model"><mesh><vertices><vertex x="0" y="0" z="0"/><vertex x="1" y="0" z="0"/>
        <vertex x="0" y="1" z="0"/><vertex x="0" y="0" z="1"/></vertices><triangles><triangle v1="0" v2="2" v3="1"/>
        <triangle v1="0" v2="1" v3="3"/><triangle v1="0" v2="3" v3="2"/><triangle v1="1" v2="2" v3="3"/></triangles></mesh></object>
        </resources><build><item objectid="4"/><item objectid="4" transform="1 0 0 0 1 0 0 0 1 5 0 0"/></build></model>"#;
    std::io::Write::write_all(&mut zip, xml.as_bytes()).unwrap();
    let bytes = zip.finish().unwrap().into_inner();
    let m = read_mesh_bytes(&bytes, "two.3mf").unwrap();
    let r = check(&m);
    assert_eq!((r.triangles, r.components), (8, 2));
    assert!((r.volume - 2.0 / 6.0).abs() < 1e-9);
}

#[test]
fn threemf_errors() {
    assert!(err_of(b"PK\x03\x04 nonsense", "z.3mf").contains("zip"));
    assert!(matches!(
        parse_err_of(b"PK\x03\x04 nonsense", "z.3mf").kind,
        ParseErrorKind::Zip(_)
    ));
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    zip.start_file("readme.txt", zip::write::SimpleFileOptions::default())
        .unwrap();
    let bytes = zip.finish().unwrap().into_inner();
    assert!(err_of(&bytes, "e.3mf").contains("no 3D model part"));
}

#[test]
fn unknown_content_is_a_clear_error() {
    let e = err_of(b"\x00\x01hello", "what.bin");
    assert!(e.contains("not a mesh file"), "{e}");
    assert_eq!(
        parse_err_of(b"\x00\x01hello", "what.bin").kind,
        ParseErrorKind::UnknownFormat
    );
}

#[test]
fn write_mesh_is_all_or_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.stl");
    write_mesh(&cube(1.0), &path, MeshFormat::Stl).unwrap();
    assert_eq!(std::fs::metadata(&path).unwrap().len(), 84 + 50 * 12);
    assert_eq!(read_mesh(&path).unwrap().triangles.len(), 12);
    // A mesh that cannot be written leaves the old file alone and no temporary behind.
    let bad = Mesh {
        vertices: vec![],
        triangles: vec![[0, 1, 2]],
    };
    assert!(write_mesh(&bad, &path, MeshFormat::Obj).is_err());
    assert_eq!(std::fs::metadata(&path).unwrap().len(), 84 + 50 * 12);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    let e = write_mesh(
        &cube(1.0),
        &dir.path().join("no/such/dir.stl"),
        MeshFormat::Stl,
    );
    assert!(e.unwrap_err().to_string().contains("no/such/dir.stl"));
}

/// The triangle count of the mesh behind [`samples`].
fn samples_mesh_triangles() -> usize {
    merge(uv_sphere(1.0, 5, 4), &tetrahedron()).triangles.len()
}

fn samples() -> Vec<(Vec<u8>, &'static str)> {
    let m = merge(uv_sphere(1.0, 5, 4), &tetrahedron());
    vec![
        (bytes_of(&m, MeshFormat::Stl), "m.stl"),
        (bytes_of(&m, MeshFormat::StlAscii), "m.stl"),
        (bytes_of(&m, MeshFormat::ThreeMf), "m.3mf"),
        (bytes_of(&m, MeshFormat::Obj), "m.obj"),
        (bytes_of(&m, MeshFormat::Ply), "m.ply"),
        (odd_ply(&m, "ascii"), "m.ply"),
        (odd_ply(&m, "binary_big_endian"), "m.ply"),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Random bytes under every name: an error or a mesh, never a panic, and any mesh
    /// returned has indices in range.
    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600), pick in 0usize..6) {
        let name = ["x.stl", "x.obj", "x.ply", "x.3mf", "x", "x.STL"][pick];
        if let Ok(m) = read_mesh_bytes(&bytes, name) {
            prop_assert!(m.has_valid_indices());
        }
        for prefix in [&b"solid "[..], b"ply\nformat ascii 1.0\n", b"PK\x03\x04", b"v 1 2 3\nf "] {
            let mut b = prefix.to_vec();
            b.extend_from_slice(&bytes);
            if let Ok(m) = read_mesh_bytes(&b, name) {
                prop_assert!(m.has_valid_indices());
            }
        }
    }

    /// Every truncation of a valid file: an error or a mesh with valid indices, never a
    /// panic; binary STL, PLY and 3MF truncations are always errors.
    #[test]
    fn truncations_never_panic(which in 0usize..7, cut in 0.0f64..1.0) {
        let (bytes, name) = &samples()[which];
        let at = ((bytes.len() as f64) * cut) as usize;
        match read_mesh_bytes(&bytes[..at], name) {
            Ok(m) => {
                prop_assert!(m.has_valid_indices());
                // OBJ has no end marker; ASCII PLY may lose only trailing whitespace; an
                // ASCII STL cut inside its closing `endsolid` line has lost no facet.
                let whole_ascii_stl = which == 1 && m.triangles.len() == samples_mesh_triangles();
                prop_assert!(matches!(which, 3 | 5) || at == 0 && which == 3 || whole_ascii_stl);
            }
            Err(e) => prop_assert!(e.to_string().starts_with(*name)),
        }
    }

    /// Single corrupted bytes in a valid file: no panic.
    #[test]
    fn corrupted_bytes_never_panic(which in 0usize..7, pos in any::<usize>(), val in any::<u8>()) {
        let (mut bytes, name) = samples()[which].clone();
        let p = pos % bytes.len();
        bytes[p] = val;
        if let Ok(m) = read_mesh_bytes(&bytes, name) {
            prop_assert!(m.has_valid_indices());
        }
    }
}

//! Writes the small mesh files in `fixtures/meshes/` that the `isoforge check` tests read:
//! `cargo run -p isoforge-mesh --example mesh_fixtures -- fixtures/meshes`.

use std::path::Path;

use isoforge_mesh::samples::{cube, cuboid, merge, tetrahedron, uv_sphere};
use isoforge_mesh::{Mesh, MeshFormat, write_mesh};
use isoforge_output::{Options, write_file};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "fixtures/meshes".into());
    let dir = Path::new(&dir);
    std::fs::create_dir_all(dir)?;
    let put =
        |name: &str, mesh: &Mesh, format: MeshFormat| write_mesh(mesh, &dir.join(name), format);

    let c = cube(10.0);
    put("cube_ascii.stl", &c, MeshFormat::StlAscii)?;
    put("cube_binary.stl", &c, MeshFormat::Stl)?;
    put("cube.3mf", &c, MeshFormat::ThreeMf)?;
    put(
        "two_cubes.stl",
        &merge(cube(10.0), &cuboid([20.0; 3], [25.0; 3])),
        MeshFormat::Stl,
    )?;

    let mut open = c.clone();
    open.triangles.drain(2..4); // the top face
    put("open_box.stl", &open, MeshFormat::Stl)?;

    let pair = merge(
        cuboid([0.0; 3], [10.0; 3]),
        &cuboid([10.0, 10.0, 0.0], [20.0, 20.0, 10.0]),
    );
    put("nonmanifold_pair.stl", &pair, MeshFormat::Stl)?;

    let mut flipped = c.clone();
    flipped.triangles[5].swap(1, 2);
    put("flipped_face.stl", &flipped, MeshFormat::Stl)?;

    // A binary STL cut in the middle of its seventh triangle.
    let mut bytes = Vec::new();
    isoforge_mesh::io::encode(&c, MeshFormat::Stl, &mut bytes)?;
    let cut = &bytes[..84 + 50 * 6 + 21];
    write_file(&dir.join("truncated.stl"), cut, Options::default())?;

    put("sphere.ply", &uv_sphere(5.0, 16, 8), MeshFormat::Ply)?;

    // Hand-written text files exercise what our writers never produce: quads, slashes,
    // negative indices, ASCII PLY.
    write_file(
        &dir.join("cube_quads.obj"),
        b"# a 10 mm cube as quads\nv 0 0 0\nv 10 0 0\nv 0 10 0\nv 10 10 0\nv 0 0 10\nv 10 0 10\n\
         v 0 10 10\nv 10 10 10\nvn 0 0 1\n\
         f 1//1 3//1 4//1 2//1\nf 5/1/1 6/1/1 8/1/1 7/1/1\nf 1 2 6 5\nf 3 7 8 4\nf -8 -4 -2 -6\nf 2 4 8 6\n",
        Options::default(),
    )?;
    let t = tetrahedron();
    let mut ply = format!(
        "ply\nformat ascii 1.0\ncomment unit tetrahedron, volume 1/6\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\nelement face {}\n\
         property list uchar int vertex_indices\nend_header\n",
        t.vertices.len(),
        t.triangles.len()
    );
    for v in &t.vertices {
        ply.push_str(&format!("{} {} {}\n", v[0], v[1], v[2]));
    }
    for f in &t.triangles {
        ply.push_str(&format!("3 {} {} {}\n", f[0], f[1], f[2]));
    }
    write_file(
        &dir.join("tetrahedron.ply"),
        ply.as_bytes(),
        Options::default(),
    )?;
    println!("wrote fixtures to {}", dir.display());
    Ok(())
}

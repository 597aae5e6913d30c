//! Small meshes with known answers: a box, a tetrahedron, a UV sphere. They are what the
//! fixtures in `fixtures/meshes/` are made of, what the checker's tests compare against,
//! and what the I/O benchmarks read and write.

use crate::mesh::Mesh;

/// An axis-aligned box from `min` to `max`: 8 vertices, 12 outward-facing triangles.
/// Vertex `i` is the corner whose x, y, z are max where bit 0, 1, 2 of `i` is set.
pub fn cuboid(min: [f32; 3], max: [f32; 3]) -> Mesh {
    let vertices = (0..8)
        .map(|i| [0, 1, 2].map(|a| if i >> a & 1 == 1 { max[a] } else { min[a] }))
        .collect();
    let triangles = vec![
        [0, 2, 3],
        [0, 3, 1], // z = min
        [4, 5, 7],
        [4, 7, 6], // z = max
        [0, 1, 5],
        [0, 5, 4], // y = min
        [2, 6, 7],
        [2, 7, 3], // y = max
        [0, 4, 6],
        [0, 6, 2], // x = min
        [1, 3, 7],
        [1, 7, 5], // x = max
    ];
    Mesh {
        vertices,
        triangles,
    }
}

/// A cube with side `size` from the origin.
pub fn cube(size: f32) -> Mesh {
    cuboid([0.0; 3], [size; 3])
}

/// The tetrahedron with corners at the origin and the three unit points (volume 1/6).
pub fn tetrahedron() -> Mesh {
    Mesh {
        vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    }
}

/// The octahedron with corners at ±1 on each axis (on the unit sphere), wound outwards.
pub fn octahedron() -> Mesh {
    Mesh {
        vertices: vec![
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ],
        triangles: vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ],
    }
}

/// A closed UV sphere: `slices` around the z axis (at least 3), `stacks` from pole to pole
/// (at least 2); `2 * slices * (stacks - 1)` triangles. `uv_sphere(1.0, 1000, 501)` has
/// a million.
pub fn uv_sphere(radius: f32, slices: u32, stacks: u32) -> Mesh {
    let slices = slices.max(3);
    let stacks = stacks.max(2);
    let mut vertices = vec![[0.0, 0.0, radius]];
    for i in 1..stacks {
        let theta = std::f64::consts::PI * f64::from(i) / f64::from(stacks);
        for j in 0..slices {
            let phi = std::f64::consts::TAU * f64::from(j) / f64::from(slices);
            let r = f64::from(radius);
            vertices.push([
                (r * theta.sin() * phi.cos()) as f32,
                (r * theta.sin() * phi.sin()) as f32,
                (r * theta.cos()) as f32,
            ]);
        }
    }
    let south = vertices.len() as u32;
    vertices.push([0.0, 0.0, -radius]);
    let ring = |i: u32, j: u32| 1 + (i - 1) * slices + j % slices;
    let mut triangles = Vec::with_capacity(2 * (slices * (stacks - 1)) as usize);
    for j in 0..slices {
        triangles.push([0, ring(1, j), ring(1, j + 1)]);
    }
    for i in 1..stacks - 1 {
        for j in 0..slices {
            let (a, b) = (ring(i, j), ring(i, j + 1));
            let (c, d) = (ring(i + 1, j), ring(i + 1, j + 1));
            triangles.push([a, c, d]);
            triangles.push([a, d, b]);
        }
    }
    for j in 0..slices {
        triangles.push([south, ring(stacks - 1, j + 1), ring(stacks - 1, j)]);
    }
    Mesh {
        vertices,
        triangles,
    }
}

/// Appends `b` to `a` as a separate part (indices shifted).
pub fn merge(mut a: Mesh, b: &Mesh) -> Mesh {
    let base = a.vertices.len() as u32;
    a.vertices.extend_from_slice(&b.vertices);
    a.triangles
        .extend(b.triangles.iter().map(|t| t.map(|i| i + base)));
    a
}

//! Directions spread over the sphere, and the convex hull of a point set as facets (an
//! incremental hull: each point outside the current hull replaces the facets it sees by
//! a fan from its horizon).

use std::collections::HashSet;

use glam::DVec3;

/// A facet of a convex polytope: the points with `normal · x <= offset`, `normal` unit.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Facet {
    /// The outward unit normal.
    pub normal: DVec3,
    /// The plane's offset along the normal.
    pub offset: f64,
}

/// The vertices of an icosahedron subdivided `levels` times, pushed onto the unit sphere:
/// 12, 42, 162, 642, 2562 directions for levels 0 to 4, evenly spread.
pub fn sphere_directions(levels: u32) -> Vec<DVec3> {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut verts: Vec<DVec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut faces: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid = std::collections::HashMap::new();
        let mut next = Vec::with_capacity(faces.len() * 4);
        let mut midpoint = |a: usize, b: usize, verts: &mut Vec<DVec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                verts.push((verts[a] + verts[b]).normalize());
                verts.len() - 1
            })
        };
        for [a, b, c] in faces {
            let ab = midpoint(a, b, &mut verts);
            let bc = midpoint(b, c, &mut verts);
            let ca = midpoint(c, a, &mut verts);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    verts
}

/// The facets of the convex hull of `points`, or `None` when the points span no volume
/// (fewer than four points off one plane). Points closer to a facet's plane than
/// 1e-10 of the set's size count as on it.
pub fn hull_facets(points: &[DVec3]) -> Option<Vec<Facet>> {
    let faces = hull_faces(points)?;
    Some(
        faces
            .iter()
            .map(|&[a, b, c]| {
                let n = (points[b] - points[a])
                    .cross(points[c] - points[a])
                    .normalize();
                Facet {
                    normal: n,
                    offset: n.dot(points[a]),
                }
            })
            .collect(),
    )
}

/// The hull of `points` as triangles with their planes, or `None` when the points span
/// no volume.
pub fn hull_triangles(points: &[DVec3]) -> Option<Vec<(Facet, [DVec3; 3])>> {
    let faces = hull_faces(points)?;
    Some(
        faces
            .iter()
            .map(|&[a, b, c]| {
                let corners = [points[a], points[b], points[c]];
                let n = (corners[1] - corners[0])
                    .cross(corners[2] - corners[0])
                    .normalize();
                let facet = Facet {
                    normal: n,
                    offset: n.dot(corners[0]),
                };
                (facet, corners)
            })
            .collect(),
    )
}

/// The indices of the points that are vertices of their convex hull (all of them when
/// the points span no volume).
pub fn hull_vertices(points: &[DVec3]) -> Vec<usize> {
    match hull_faces(points) {
        Some(faces) => {
            let mut v: Vec<usize> = faces.iter().flatten().copied().collect();
            v.sort_unstable();
            v.dedup();
            v
        }
        None => (0..points.len()).collect(),
    }
}

/// The hull's triangles, outward by the right-hand rule, as indices into `points`.
fn hull_faces(points: &[DVec3]) -> Option<Vec<[usize; 3]>> {
    if points.len() < 4 {
        return None;
    }
    let (lo, hi) = points.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let eps = 1e-10 * (hi - lo).length().max(f64::MIN_POSITIVE);
    // A first tetrahedron from far-apart points.
    let i0 = (0..points.len()).min_by(|&a, &b| points[a].x.total_cmp(&points[b].x))?;
    let far = |f: &dyn Fn(DVec3) -> f64| {
        (0..points.len()).max_by(|&a, &b| f(points[a]).total_cmp(&f(points[b])))
    };
    let p0 = points[i0];
    let i1 = far(&|p| (p - p0).length_squared())?;
    let p1 = points[i1];
    let axis = (p1 - p0).normalize_or_zero();
    let i2 = far(&|p| (p - p0 - axis * (p - p0).dot(axis)).length_squared())?;
    let p2 = points[i2];
    let normal = (p1 - p0).cross(p2 - p0).normalize_or_zero();
    let i3 = far(&|p| (p - p0).dot(normal).abs())?;
    let p3 = points[i3];
    if (p1 - p0).length() <= eps
        || (p2 - p0 - axis * (p2 - p0).dot(axis)).length() <= eps
        || (p3 - p0).dot(normal).abs() <= eps
    {
        return None;
    }
    let plane = |f: [usize; 3]| {
        let (a, b, c) = (points[f[0]], points[f[1]], points[f[2]]);
        let n = (b - a).cross(c - a);
        let len = n.length();
        if len > 0.0 {
            (n / len, (n / len).dot(a))
        } else {
            (DVec3::ZERO, 0.0)
        }
    };
    let mut faces: Vec<[usize; 3]> = Vec::new();
    let centre = (p0 + p1 + p2 + p3) / 4.0;
    for f in [[i0, i1, i2], [i0, i1, i3], [i0, i2, i3], [i1, i2, i3]] {
        let (n, d) = plane(f);
        faces.push(if n.dot(centre) > d {
            [f[0], f[2], f[1]]
        } else {
            f
        });
    }
    let mut planes: Vec<(DVec3, f64)> = faces.iter().map(|&f| plane(f)).collect();
    let used: HashSet<usize> = [i0, i1, i2, i3].into();
    for (i, &p) in points.iter().enumerate() {
        if used.contains(&i) {
            continue;
        }
        let visible: Vec<usize> = (0..faces.len())
            .filter(|&f| planes[f].0.dot(p) - planes[f].1 > eps)
            .collect();
        if visible.is_empty() {
            continue;
        }
        // The horizon in the order of the visible faces, not a set's: the facets' order
        // is the order the field looks at them in, and a set's order changes from run to
        // run (a hull of two boxes meshed to 40 triangles in one run and 54 in the next).
        let visible_edges: Vec<(usize, usize)> = visible
            .iter()
            .flat_map(|&f| {
                let [a, b, c] = faces[f];
                [(a, b), (b, c), (c, a)]
            })
            .collect();
        let edges: HashSet<(usize, usize)> = visible_edges.iter().copied().collect();
        let horizon: Vec<(usize, usize)> = visible_edges
            .into_iter()
            .filter(|(a, b)| !edges.contains(&(*b, *a)))
            .collect();
        let mut keep = vec![true; faces.len()];
        for &f in &visible {
            keep[f] = false;
        }
        let mut k = 0;
        faces.retain(|_| {
            k += 1;
            keep[k - 1]
        });
        let mut k = 0;
        planes.retain(|_| {
            k += 1;
            keep[k - 1]
        });
        for (a, b) in horizon {
            let f = [a, b, i];
            faces.push(f);
            planes.push(plane(f));
        }
    }
    // A closed surface: every directed edge has its twin (else rounding broke the hull).
    let edges: HashSet<(usize, usize)> = faces
        .iter()
        .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
        .collect();
    let closed = edges.iter().all(|(a, b)| edges.contains(&(*b, *a)));
    closed.then_some(faces)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn icosphere_counts_and_spread() {
        for (level, n) in [(0, 12), (1, 42), (2, 162), (3, 642)] {
            let d = sphere_directions(level);
            assert_eq!(d.len(), n);
            assert!(d.iter().all(|v| (v.length() - 1.0).abs() < 1e-12));
        }
    }

    #[test]
    fn the_same_points_give_the_same_faces_in_the_same_order() {
        // Each HashSet hashes with its own keys, so a horizon read from a set's order came
        // out in a different order almost every time.
        let corners: Vec<DVec3> = (0..16)
            .map(|i| {
                let c = DVec3::new((i & 1) as f64, (i >> 1 & 1) as f64, (i >> 2 & 1) as f64);
                if i < 8 {
                    c
                } else {
                    c * 0.7 + DVec3::new(1.3, 0.4, 0.9)
                }
            })
            .collect();
        let first = hull_faces(&corners).expect("a hull");
        for _ in 0..8 {
            assert_eq!(hull_faces(&corners).expect("a hull"), first);
        }
    }

    #[test]
    fn hull_of_a_cube_with_inner_points() {
        let mut pts = Vec::new();
        for i in 0..8 {
            pts.push(DVec3::new(
                (i & 1) as f64,
                (i >> 1 & 1) as f64,
                (i >> 2 & 1) as f64,
            ));
        }
        pts.push(DVec3::splat(0.5));
        pts.push(DVec3::new(0.2, 0.3, 0.4));
        pts.push(DVec3::new(0.5, 0.5, 1.0)); // on a face
        let f = hull_facets(&pts).expect("a cube");
        assert_eq!(f.len(), 12, "two triangles per face");
        for facet in &f {
            for p in &pts {
                assert!(facet.normal.dot(*p) <= facet.offset + 1e-12);
            }
        }
        let mut v = hull_vertices(&pts);
        v.sort();
        assert_eq!(v, (0..8).collect::<Vec<_>>());
        assert!(hull_facets(&pts[..3]).is_none());
        let flat: Vec<DVec3> = (0..10)
            .map(|i| DVec3::new(i as f64, (i * i) as f64, 0.0))
            .collect();
        assert!(hull_facets(&flat).is_none());
    }
}

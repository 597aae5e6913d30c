//! The checker for a mesh that passes by and is never held: [`StreamCheck`] is a
//! [`MeshSink`] in front of another, judging closed, manifold and oriented as triangles go
//! through, in memory that follows the vertices still open, not the mesh.
//!
//! The test is per vertex: a closed, manifold, consistently oriented mesh is exactly one in
//! which the triangles around every vertex form one closed fan. Triangle (v, a, b),
//! counter-clockwise, turns around v from a to b; its neighbour across the edge v–b, if
//! oriented alike, turns from b onwards. So each vertex collects its (from, to) steps, and
//! when every step's end meets another's start the fan is closed: then it must be one cycle
//! (two cycles are two cones tip to tip), and no later triangle may use the vertex. An
//! edge used by three triangles, or twice in one direction, shows as a step end met twice;
//! a hole, as a fan still open at the end.

use std::collections::HashMap;
use std::io;

use crate::sink::{MeshSink, Tally};

/// The steps around one vertex whose fan is not closed yet.
#[derive(Default)]
struct Fan {
    steps: Vec<(u32, u32)>,
    /// Step ends not yet met by another step's start, plus starts not met by an end.
    loose: u32,
}

/// A sink that checks what passes through it on the way to `inner`.
pub struct StreamCheck<S> {
    inner: S,
    tally: Tally,
    open: HashMap<u32, Fan>,
    /// One bit per vertex: its fan closed.
    closed: Vec<u64>,
    /// Vertices whose fan closed as more than one cycle, or that were used after closing,
    /// or with a step end met twice.
    non_manifold_vertices: u64,
    /// Triangles naming a vertex twice, or a vertex not given yet.
    bad_triangles: u64,
}

/// What [`StreamCheck`] concluded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StreamReport {
    /// Counts, volume, area and bounds of what passed.
    pub tally: Tally,
    /// Every fan closed: no hole.
    pub watertight: bool,
    /// Every vertex one fan, every edge used once each way, no bad triangle.
    pub manifold: bool,
    /// Vertices that no triangle used.
    pub unused_vertices: u64,
    /// Vertices whose fans stayed open (on a hole's rim).
    pub open_vertices: u64,
}

impl StreamReport {
    /// True when the mesh is watertight, manifold and consistently oriented.
    pub fn is_closed_manifold(&self) -> bool {
        self.watertight && self.manifold
    }
}

impl<S: MeshSink> StreamCheck<S> {
    /// Checks on the way to `inner`; the volume is summed around `reference` (a point near
    /// the mesh, for precision).
    pub fn new(inner: S, reference: [f64; 3]) -> Self {
        StreamCheck {
            inner,
            tally: Tally::around(reference),
            open: HashMap::new(),
            closed: Vec::new(),
            non_manifold_vertices: 0,
            bad_triangles: 0,
        }
    }

    fn is_closed(&self, v: u32) -> bool {
        self.closed
            .get(v as usize / 64)
            .is_some_and(|w| w >> (v % 64) & 1 == 1)
    }

    fn close(&mut self, v: u32) {
        let w = v as usize / 64;
        if self.closed.len() <= w {
            self.closed.resize(w + 1, 0);
        }
        self.closed[w] |= 1 << (v % 64);
    }

    /// One step around `v`, from `a` to `b`.
    fn step(&mut self, v: u32, a: u32, b: u32) {
        if self.is_closed(v) {
            // Its fan was whole already: one more triangle makes it two surfaces.
            self.non_manifold_vertices += 1;
            return;
        }
        let fan = self.open.entry(v).or_default();
        let a_met = fan.steps.iter().filter(|s| s.1 == a).count();
        let b_met = fan.steps.iter().filter(|s| s.0 == b).count();
        let starts_at_a = fan.steps.iter().any(|s| s.0 == a);
        let ends_at_b = fan.steps.iter().any(|s| s.1 == b);
        fan.steps.push((a, b));
        if a_met > 1 || b_met > 1 || starts_at_a || ends_at_b {
            // An edge used by three triangles, or twice the same way: this fan can never
            // close properly. Count the vertex once and stop following it.
            self.open.remove(&v);
            self.close(v);
            self.non_manifold_vertices += 1;
            return;
        }
        // Each new step adds a start and an end; each meeting ties two of them.
        fan.loose += 2;
        fan.loose -= 2 * (a_met as u32 + b_met as u32);
        if fan.loose == 0 {
            let one_cycle = is_one_cycle(&fan.steps);
            self.open.remove(&v);
            self.close(v);
            if !one_cycle {
                self.non_manifold_vertices += 1;
            }
        }
    }

    /// The verdicts, and the inner sink.
    pub fn finish(self) -> (StreamReport, S) {
        let mut used_or_open = 0u64;
        for w in &self.closed {
            used_or_open += u64::from(w.count_ones());
        }
        let open_vertices = self.open.len() as u64;
        used_or_open += open_vertices;
        let report = StreamReport {
            tally: self.tally,
            watertight: self.tally.triangles > 0 && open_vertices == 0 && self.bad_triangles == 0,
            manifold: self.non_manifold_vertices == 0 && self.bad_triangles == 0,
            unused_vertices: self.tally.vertices.saturating_sub(used_or_open),
            open_vertices,
        };
        (report, self.inner)
    }
}

/// True when the steps (each start met once, each end met once) form a single cycle.
fn is_one_cycle(steps: &[(u32, u32)]) -> bool {
    let Some(&(first, mut at)) = steps.first() else {
        return false;
    };
    for _ in 1..steps.len() {
        if at == first {
            return false; // closed before using every step: more than one cycle
        }
        match steps.iter().find(|s| s.0 == at) {
            Some(s) => at = s.1,
            None => return false,
        }
    }
    at == first
}

impl<S: MeshSink> MeshSink for StreamCheck<S> {
    fn vertex(&mut self, p: [f32; 3]) -> io::Result<()> {
        self.tally.add_vertex(p);
        self.inner.vertex(p)
    }

    fn triangle(&mut self, t: [u32; 3], corners: [[f32; 3]; 3]) -> io::Result<()> {
        self.tally.add_triangle(corners);
        let [a, b, c] = t;
        if a == b || b == c || c == a || t.iter().any(|&v| u64::from(v) >= self.tally.vertices) {
            self.bad_triangles += 1;
        } else {
            self.step(a, b, c);
            self.step(b, c, a);
            self.step(c, a, b);
        }
        self.inner.triangle(t, corners)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;
    use crate::{check, samples};

    fn stream(mesh: &Mesh) -> StreamReport {
        let mut s = StreamCheck::new(Mesh::default(), [0.0; 3]);
        for &v in &mesh.vertices {
            s.vertex(v).expect("vertex");
        }
        for &t in &mesh.triangles {
            let c = t.map(|i| mesh.vertices.get(i as usize).copied().unwrap_or([0.0; 3]));
            s.triangle(t, c).expect("triangle");
        }
        s.finish().0
    }

    #[test]
    fn agrees_with_the_checker_on_good_and_broken_meshes() {
        let cube = samples::cube(1.0);
        let mut holed = cube.clone();
        holed.triangles.pop();
        let mut flipped = cube.clone();
        flipped.triangles[0].swap(1, 2);
        let mut doubled = cube.clone();
        doubled.triangles.push(doubled.triangles[0]);
        // Two cubes sharing one corner: a pinch point.
        let mut bowtie = samples::cube(1.0);
        let other = samples::cuboid([1.0; 3], [2.0; 3]);
        let base = bowtie.vertices.len() as u32;
        bowtie.vertices.extend(other.vertices.iter().skip(1));
        for t in &other.triangles {
            bowtie
                .triangles
                .push(t.map(|i| if i == 0 { 7 } else { base + i - 1 }));
        }
        let mut repeated = cube.clone();
        repeated.triangles[3] = [1, 1, 2];
        for (name, m) in [
            ("cube", &cube),
            ("sphere", &samples::uv_sphere(1.0, 12, 8)),
            ("holed", &holed),
            ("flipped", &flipped),
            ("doubled", &doubled),
            ("bowtie", &bowtie),
            ("repeated", &repeated),
        ] {
            let full = check(m);
            let s = stream(m);
            assert_eq!(s.is_closed_manifold(), full.is_closed_manifold(), "{name}");
            assert_eq!(
                s.watertight && s.manifold,
                full.watertight && full.manifold,
                "{name}"
            );
            assert_eq!(s.tally.triangles as usize, full.triangles, "{name}");
            // A broken mesh's volume depends on the reference point: compare closed ones.
            if full.is_closed_manifold() {
                assert!((s.tally.volume() - full.volume).abs() < 1e-9, "{name}");
            }
        }
    }
}

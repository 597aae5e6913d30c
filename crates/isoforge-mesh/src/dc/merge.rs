//! Merging above the block level: blocks that became one leaf each (candidates) merge into
//! larger leaves by the same rules as cells inside a block (`topology.rs`, the tolerance),
//! as the slabs of blocks finish.
//!
//! The octree above the blocks is kept only where it matters, in a map from (level,
//! coordinates) to a node's state: `Merged` (one leaf so far; whether it is final depends
//! on its parent), `Failed` (its children stay separate: some block under it has more than
//! one leaf, or the merge test said no) or `Pending` (waiting for its last slab). A node
//! absent from the map has no surface at all. A candidate's final leaf is the highest
//! merged node above it whose parent failed (or the root); until that is known, polygons
//! that touch it wait (see `stream.rs`).
//!
//! The sums that decide a merge come from the children: their QEFs and corner signs. The
//! error test cannot see each crossing any more, so it uses a bound: the largest distance
//! from the new vertex to a child's planes is at most the square root of that child's
//! summed squared distances.

use std::collections::HashMap;
use std::collections::hash_map::Entry;

use glam::DVec3;

use super::leaf::{Candidate, Merging, NO_VERT};
use super::octree::Grid;
use super::qef::Qef;
use super::sampler::Sampler;
use super::topology;

/// A node of the octree above the blocks: level (0 = root) and coordinates at that level.
pub type NodeKey = (u32, [i64; 3]);

/// A node's state.
#[derive(Clone, Copy, Debug)]
pub enum NodeState {
    /// Waiting for its last slab.
    Pending,
    /// One leaf so far, with the global index of its vertex once used.
    Merged {
        /// What decides the next merge.
        leaf: Candidate,
        /// The vertex's global index, or `NO_VERT`.
        id: u32,
    },
    /// Its children stay separate.
    Failed,
}

/// Where a candidate's leaf stands.
#[derive(Clone, Copy, Debug)]
pub enum Resolved {
    /// Not known yet.
    Waiting,
    /// The leaf is this node.
    Leaf(NodeKey),
}

/// The octree above the blocks, as far as merging needs it.
pub struct AboveBlocks {
    grid: Grid,
    merging: Merging,
    nodes: HashMap<NodeKey, NodeState>,
    /// Nodes to decide once their last slab is done.
    pending: Vec<NodeKey>,
}

/// Fraction of a finest cell that vertices keep inside their leaf (as in `leaf.rs`).
const INSET: f64 = 1e-3;

impl AboveBlocks {
    /// Nothing merged yet.
    pub fn new(grid: Grid, merging: Merging) -> Self {
        AboveBlocks {
            grid,
            merging,
            nodes: HashMap::new(),
            pending: Vec::new(),
        }
    }

    fn top(&self) -> u32 {
        self.grid.block_level
    }

    /// The last slab (block z) a node at `level` with z-coordinate `z` covers.
    fn last_slab(&self, level: u32, z: i64) -> i64 {
        ((z + 1) << (self.top() - level)) - 1
    }

    /// Records a finished block: a candidate merges on, a block with other surface makes
    /// every node above it fail; a block without surface changes nothing.
    pub fn add_block(&mut self, coords: [i64; 3], candidate: Option<Candidate>, surface: bool) {
        let top = self.top();
        if let Some(leaf) = candidate {
            self.nodes
                .insert((top, coords), NodeState::Merged { leaf, id: NO_VERT });
            if top > 0 {
                let parent = (top - 1, coords.map(|c| c >> 1));
                if let Entry::Vacant(slot) = self.nodes.entry(parent) {
                    slot.insert(NodeState::Pending);
                    self.pending.push(parent);
                }
            }
        } else if surface {
            self.fail_above(top, coords);
        }
    }

    /// Marks every node above `(level, coords)` failed.
    fn fail_above(&mut self, level: u32, coords: [i64; 3]) {
        let mut key = (level, coords);
        while key.0 > 0 {
            key = (key.0 - 1, key.1.map(|c| c >> 1));
            if matches!(self.nodes.get(&key), Some(NodeState::Failed)) {
                break;
            }
            self.nodes.insert(key, NodeState::Failed);
        }
    }

    /// Decides the nodes whose last slab is `z`, deepest first.
    pub fn finish_slab<S: Sampler>(&mut self, z: i64, sampler: &S, ev: &mut S::Evals) {
        loop {
            // Deepest first: a parent is decided after its children.
            let mut ready: Vec<NodeKey> = self
                .pending
                .iter()
                .copied()
                .filter(|&(l, c)| self.last_slab(l, c[2]) <= z)
                .collect();
            if ready.is_empty() {
                return;
            }
            let top = self.top();
            self.pending
                .retain(|&(l, c)| ((c[2] + 1) << (top - l)) - 1 > z);
            ready.sort_by_key(|k| std::cmp::Reverse(k.0));
            let deepest = ready[0].0;
            for key in ready {
                if key.0 != deepest {
                    // Shallower nodes wait for this round's results.
                    self.pending.push(key);
                    continue;
                }
                self.decide(key, sampler, ev);
            }
        }
    }

    fn decide<S: Sampler>(&mut self, key: NodeKey, sampler: &S, ev: &mut S::Evals) {
        if !matches!(self.nodes.get(&key), Some(NodeState::Pending)) {
            return;
        }
        match self.try_merge(key, sampler, ev) {
            Some(leaf) => {
                self.nodes
                    .insert(key, NodeState::Merged { leaf, id: NO_VERT });
                if key.0 > 0 {
                    let parent = (key.0 - 1, key.1.map(|c| c >> 1));
                    if let Entry::Vacant(slot) = self.nodes.entry(parent) {
                        slot.insert(NodeState::Pending);
                        self.pending.push(parent);
                    }
                }
            }
            None => {
                self.nodes.insert(key, NodeState::Failed);
                self.fail_above(key.0, key.1);
            }
        }
    }

    /// The merged leaf of a node's eight children, if they may merge.
    fn try_merge<S: Sampler>(
        &self,
        (level, coords): NodeKey,
        sampler: &S,
        ev: &mut S::Evals,
    ) -> Option<Candidate> {
        let mut children: [Option<Candidate>; 8] = [None; 8];
        for (c, child) in children.iter_mut().enumerate() {
            let cc = [0, 1, 2].map(|a| coords[a] * 2 + ((c as i64 >> a) & 1));
            match self.nodes.get(&(level + 1, cc)) {
                Some(NodeState::Merged { leaf, .. }) => *child = Some(*leaf),
                Some(NodeState::Failed | NodeState::Pending) => return None,
                None => {} // no surface
            }
        }
        // The centre is a corner of every child: a child without surface has its sign.
        let centre = children.iter().enumerate().find_map(|(c, leaf)| {
            leaf.map(|l| {
                let k = 7 - c; // the child's corner at the parent's centre
                l.signs >> k & 1 == 1
            })
        })?;
        let mut signs27 = 0u32;
        for k in 0..3usize {
            for j in 0..3usize {
                for i in 0..3usize {
                    let c = usize::from(i > 1) | usize::from(j > 1) << 1 | usize::from(k > 1) << 2;
                    let corner = (i - (c & 1)) | (j - (c >> 1 & 1)) << 1 | (k - (c >> 2 & 1)) << 2;
                    let inside = match children[c] {
                        Some(l) => l.signs >> corner & 1 == 1,
                        None => centre,
                    };
                    if inside {
                        signs27 |= 1 << (i + 3 * j + 9 * k);
                    }
                }
            }
        }
        if !topology::collapsible(signs27) {
            return None;
        }
        let grid = &self.grid;
        let blocks = 1i64 << (self.top() - level);
        let cells = blocks * grid.block as i64;
        let lo = DVec3::from(grid.corner(coords.map(|c| c * cells)));
        let size = cells as f64 * grid.cell;
        let inset = grid.cell * INSET;
        let mut qef = Qef::new(lo);
        for leaf in children.iter().flatten() {
            qef.merge(&leaf.qef);
        }
        let (vlo, vhi) = grid.vertex_box(lo.to_array(), size, inset);
        let x = qef.solve_in(DVec3::from(vlo), DVec3::from(vhi));
        for leaf in children.iter().flatten() {
            if leaf.qef.error(x).sqrt() > self.merging.plane {
                return None;
            }
        }
        let g = sampler.grad(ev, &sampler.root(), x.to_array());
        let slope = DVec3::new(g[1], g[2], g[3]).length();
        let distance = g[0].abs() / slope;
        if distance.is_nan() || distance > self.merging.surface {
            return None;
        }
        Some(Candidate {
            signs: topology::parent_pattern(signs27),
            qef,
            vertex: x,
        })
    }

    /// Where the leaf holding the candidate block at `coords` stands.
    pub fn resolve(&self, coords: [i64; 3]) -> Resolved {
        self.resolve_node((self.top(), coords))
    }

    /// The vertex of a merged node and its global index (`NO_VERT` until given one).
    pub fn vertex(&self, key: NodeKey) -> Option<(DVec3, u32)> {
        match self.nodes.get(&key) {
            Some(NodeState::Merged { leaf, id }) => Some((leaf.vertex, *id)),
            _ => None,
        }
    }

    /// Records the global index of a merged node's vertex.
    pub fn set_id(&mut self, key: NodeKey, new: u32) {
        if let Some(NodeState::Merged { id, .. }) = self.nodes.get_mut(&key) {
            *id = new;
        }
    }

    /// Forgets nodes no later slab can ask about: their last slab is before `z − 1` and
    /// their leaf is settled. Every polygon that touched them has been resolved by then, and
    /// the nodes that settle a live node's leaf are above it, so they end later.
    pub fn prune(&mut self, z: i64) {
        let settled: Vec<NodeKey> = self
            .nodes
            .iter()
            .filter(|&(&(l, c), state)| {
                self.last_slab(l, c[2]) < z - 1
                    && match state {
                        NodeState::Failed => true,
                        NodeState::Merged { .. } => {
                            matches!(self.resolve_node((l, c)), Resolved::Leaf(_))
                        }
                        NodeState::Pending => false,
                    }
            })
            .map(|(k, _)| *k)
            .collect();
        for key in &settled {
            self.nodes.remove(key);
        }
    }

    /// Where the leaf holding the merged node `start` stands: the highest merged node above
    /// it whose parent failed, or the root.
    fn resolve_node(&self, start: NodeKey) -> Resolved {
        let mut key = start;
        loop {
            if key.0 == 0 {
                return Resolved::Leaf(key);
            }
            let parent = (key.0 - 1, key.1.map(|c| c >> 1));
            match self.nodes.get(&parent) {
                Some(NodeState::Failed) => return Resolved::Leaf(key),
                Some(NodeState::Merged { .. }) => key = parent,
                Some(NodeState::Pending) | None => return Resolved::Waiting,
            }
        }
    }
}

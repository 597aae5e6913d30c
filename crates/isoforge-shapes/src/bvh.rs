//! A bounding-volume hierarchy over 3D boxes: which items a point or a box comes near, in
//! about log(n) steps. The path sweep keeps its path segments in one, the surfaces their
//! patches.
//!
//! Built once by median splits along the longest side of each node; stored flat with the
//! left child right after its parent.

use glam::DVec3;

/// Items per leaf (a few box tests are cheaper than another level).
const LEAF_ITEMS: usize = 4;

/// An axis-aligned box.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Box3 {
    /// Lowest corner.
    pub min: DVec3,
    /// Highest corner.
    pub max: DVec3,
}

impl Box3 {
    /// Holds nothing; grows by union.
    pub const EMPTY: Box3 = Box3 {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };
    /// The box of some points.
    pub fn around(points: impl IntoIterator<Item = DVec3>) -> Box3 {
        points.into_iter().fold(Box3::EMPTY, |b, p| Box3 {
            min: b.min.min(p),
            max: b.max.max(p),
        })
    }
    /// The smallest box holding both.
    pub fn union(self, o: Box3) -> Box3 {
        Box3 {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }
    /// Grown by `d` on every side.
    pub fn grown(self, d: f64) -> Box3 {
        Box3 {
            min: self.min - DVec3::splat(d),
            max: self.max + DVec3::splat(d),
        }
    }
    /// Squared distance from a point (0 inside).
    pub fn distance_squared(&self, p: DVec3) -> f64 {
        (self.min - p)
            .max(p - self.max)
            .max(DVec3::ZERO)
            .length_squared()
    }
    /// Distance between two boxes (0 when they touch).
    pub fn box_distance(&self, o: &Box3) -> f64 {
        (self.min - o.max)
            .max(o.min - self.max)
            .max(DVec3::ZERO)
            .length()
    }
    /// The centre.
    pub fn centre(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }
}

#[derive(Copy, Clone, Debug)]
struct Node {
    bounds: Box3,
    /// Leaf: first slot in `order`; inner: the right child's index.
    index: u32,
    /// Leaf: item count; inner: 0.
    count: u32,
}

/// The hierarchy over items `0..n`, each with its box.
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    boxes: Vec<Box3>,
}

impl Bvh {
    /// Builds the tree over the given boxes.
    pub fn new(boxes: Vec<Box3>) -> Bvh {
        let mut bvh = Bvh {
            nodes: Vec::new(),
            order: (0..boxes.len() as u32).collect(),
            boxes,
        };
        if !bvh.boxes.is_empty() {
            let n = bvh.boxes.len();
            bvh.build(0, n);
        }
        bvh
    }

    /// The box of item `i`.
    pub fn item_box(&self, i: usize) -> &Box3 {
        &self.boxes[i]
    }

    /// The box around everything.
    pub fn bounds(&self) -> Box3 {
        self.nodes.first().map_or(Box3::EMPTY, |n| n.bounds)
    }

    fn build(&mut self, start: usize, end: usize) -> usize {
        let bounds = self.order[start..end]
            .iter()
            .fold(Box3::EMPTY, |b, &i| b.union(self.boxes[i as usize]));
        let me = self.nodes.len();
        self.nodes.push(Node {
            bounds,
            index: start as u32,
            count: (end - start) as u32,
        });
        if end - start <= LEAF_ITEMS {
            return me;
        }
        let size = bounds.max - bounds.min;
        let axis = if size.x >= size.y && size.x >= size.z {
            0
        } else if size.y >= size.z {
            1
        } else {
            2
        };
        let mid = (start + end) / 2;
        let boxes = &self.boxes;
        self.order[start..end].select_nth_unstable_by(mid - start, |&a, &b| {
            let ka = boxes[a as usize].centre()[axis];
            let kb = boxes[b as usize].centre()[axis];
            ka.total_cmp(&kb)
        });
        self.build(start, mid);
        let right = self.build(mid, end);
        self.nodes[me].index = right as u32;
        self.nodes[me].count = 0;
        me
    }

    /// Calls `f` on every item whose box is within `reach` of `p`.
    pub fn near_point(&self, p: DVec3, reach: f64, f: &mut dyn FnMut(usize)) {
        let r2 = reach * reach;
        self.walk(&mut |b| b.distance_squared(p) <= r2, f);
    }

    /// Calls `f` on every item whose box is within `reach` of the box `q`.
    pub fn near_box(&self, q: &Box3, reach: f64, f: &mut dyn FnMut(usize)) {
        self.walk(&mut |b| b.box_distance(q) <= reach, f);
    }

    /// The smallest distance from the box `q` to any item's box (`inf` without items).
    pub fn box_gap(&self, q: &Box3) -> f64 {
        let mut best = f64::INFINITY;
        let mut stack = Vec::with_capacity(64);
        if !self.nodes.is_empty() {
            stack.push(0usize);
        }
        while let Some(id) = stack.pop() {
            let node = &self.nodes[id];
            if node.bounds.box_distance(q) >= best {
                continue;
            }
            if node.count > 0 {
                let first = node.index as usize;
                for &i in &self.order[first..first + node.count as usize] {
                    best = best.min(self.boxes[i as usize].box_distance(q));
                }
            } else {
                stack.push(node.index as usize);
                stack.push(id + 1);
            }
        }
        best
    }

    /// The smallest `f(item)` over all items, visiting nearest boxes first and skipping
    /// every box farther from `p` than the best found: `f` must be at least the distance
    /// from `p` to the item's box (a branch-and-bound nearest search).
    pub fn min_search(&self, p: DVec3, f: &mut dyn FnMut(usize) -> f64) -> f64 {
        let mut best = f64::INFINITY;
        let mut stack: Vec<(f64, usize)> = Vec::with_capacity(64);
        if !self.nodes.is_empty() {
            stack.push((self.nodes[0].bounds.distance_squared(p), 0));
        }
        while let Some((d2, id)) = stack.pop() {
            if d2 >= best * best {
                continue;
            }
            let node = &self.nodes[id];
            if node.count > 0 {
                let first = node.index as usize;
                for &i in &self.order[first..first + node.count as usize] {
                    if self.boxes[i as usize].distance_squared(p) < best * best {
                        best = best.min(f(i as usize));
                    }
                }
            } else {
                let (l, r) = (id + 1, node.index as usize);
                let dl = self.nodes[l].bounds.distance_squared(p);
                let dr = self.nodes[r].bounds.distance_squared(p);
                // The nearer child is popped first.
                if dl <= dr {
                    stack.push((dr, r));
                    stack.push((dl, l));
                } else {
                    stack.push((dl, l));
                    stack.push((dr, r));
                }
            }
        }
        best
    }

    /// Calls `f` on every item whose box passes `keep`, descending only into nodes whose
    /// box passes it too (so `keep` must hold for a node whenever it holds for any item
    /// inside).
    pub fn visit(&self, keep: &mut dyn FnMut(&Box3) -> bool, f: &mut dyn FnMut(usize)) {
        self.walk(keep, f)
    }

    fn walk(&self, keep: &mut dyn FnMut(&Box3) -> bool, f: &mut dyn FnMut(usize)) {
        let mut stack = [0u32; 64];
        let mut top = 0;
        if self.nodes.is_empty() {
            return;
        }
        stack[0] = 0;
        top += 1;
        while top > 0 {
            top -= 1;
            let id = stack[top] as usize;
            let node = &self.nodes[id];
            if !keep(&node.bounds) {
                continue;
            }
            if node.count > 0 {
                let first = node.index as usize;
                for &i in &self.order[first..first + node.count as usize] {
                    if keep(&self.boxes[i as usize]) {
                        f(i as usize);
                    }
                }
            } else if top + 2 <= stack.len() {
                stack[top] = (id + 1) as u32;
                stack[top + 1] = node.index;
                top += 2;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn queries_agree_with_a_scan() {
        let boxes: Vec<Box3> = (0..500)
            .map(|i| {
                let c = DVec3::new(
                    (i as f64 * 0.37).sin() * 10.0,
                    (i as f64 * 0.71).cos() * 10.0,
                    (i as f64 * 0.13).sin() * 3.0,
                );
                Box3 {
                    min: c,
                    max: c + DVec3::splat(0.3),
                }
            })
            .collect();
        let bvh = Bvh::new(boxes.clone());
        for k in 0..50 {
            let p = DVec3::new(k as f64 * 0.4 - 10.0, (k as f64).sin() * 8.0, 0.0);
            let mut found = Vec::new();
            bvh.near_point(p, 1.5, &mut |i| found.push(i));
            found.sort();
            let expect: Vec<usize> = (0..boxes.len())
                .filter(|&i| boxes[i].distance_squared(p) <= 2.25)
                .collect();
            assert_eq!(found, expect);
            let q = Box3 {
                min: p,
                max: p + DVec3::ONE,
            };
            let gap = boxes
                .iter()
                .map(|b| b.box_distance(&q))
                .fold(f64::INFINITY, f64::min);
            assert!((bvh.box_gap(&q) - gap).abs() < 1e-12);
        }
    }
}

//! `Context`: the hash-consed arena a shape is deduplicated into before it becomes a tape.

use crate::shape::Shape;

/// A node in a [`Context`].
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeId(pub u32);

/// An arena of unique nodes: inserting an operation that already exists returns the
/// existing node (hash-consing), and operations on constants are folded.
#[derive(Default)]
pub struct Context {}

impl Context {
    /// An empty arena.
    pub fn new() -> Self {
        todo!("isoforge-field helper")
    }
    /// Inserts a shape's whole graph; returns its root.
    pub fn import(&mut self, shape: &Shape) -> NodeId {
        let _ = shape;
        todo!("isoforge-field helper")
    }
    /// The number of unique nodes.
    pub fn len(&self) -> usize {
        todo!("isoforge-field helper")
    }
    /// True when there are no nodes.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

//! What the library knows about the shapes a script has built, beyond their graphs: which
//! are exact distances (so `offset` and `shell` can be plain arithmetic on them) and, for
//! `hull`, which are convex solids of a known kind.
//!
//! Facts are kept per script run, keyed by the shape's node ([`Shape::id`]); the shape is
//! kept alive with its facts so the address cannot be reused by another shape during the
//! run. A shape the table does not know (built with operators or the classic library) is
//! simply a field: everything still works on it, through the general paths.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use isoforge_field::Shape;
use isoforge_shapes::hull::Convex;

/// What is known about one shape.
#[derive(Clone, Debug, Default)]
pub struct Fact {
    /// The field is a signed distance (its gradient has length 1 wherever defined).
    pub distance: bool,
    /// The solid is this convex body (for exact hulls).
    pub convex: Option<Convex>,
}

/// The facts of one script run.
#[derive(Default)]
pub struct Facts {
    by_id: HashMap<usize, (Shape, Fact)>,
}

/// Shared between the library's callbacks.
pub type SharedFacts = Arc<Mutex<Facts>>;

impl Facts {
    /// Records a fact about `s` and returns `s`.
    pub fn note(&mut self, s: Shape, fact: Fact) -> Shape {
        if fact.distance || fact.convex.is_some() {
            self.by_id.insert(s.id(), (s.clone(), fact));
        }
        s
    }

    /// What is known about `s` (nothing, for a shape the table has not seen).
    pub fn of(&self, s: &Shape) -> Fact {
        self.by_id
            .get(&s.id())
            .map(|(_, f)| f.clone())
            .unwrap_or_default()
    }

    /// True when `s` is known to be a distance field.
    pub fn is_distance(&self, s: &Shape) -> bool {
        self.by_id.get(&s.id()).is_some_and(|(_, f)| f.distance)
    }
}

/// Locks the table (a poisoned lock only means an earlier callback panicked).
pub fn lock(f: &SharedFacts) -> std::sync::MutexGuard<'_, Facts> {
    f.lock().unwrap_or_else(|e| e.into_inner())
}

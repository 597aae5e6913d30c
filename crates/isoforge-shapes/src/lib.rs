//! The isoforge shape library: the classic function-based primitives, transforms and
//! combinations, and curve followers, all built as [`isoforge_field::Shape`] graphs.

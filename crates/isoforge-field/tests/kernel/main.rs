//! The field kernel's test suite: one binary, one module per subject.
//!
//! `common` holds a reference evaluator (a direct walk of the `Shape` tree with the f64
//! math of `eval::scalar`), a test custom field, and proptest strategies for random
//! expressions and boxes.

mod common;
mod conformance;
mod context;
mod custom;
mod enclose;
mod laws;
mod region;
mod vm;

//! Evaluators on a [`crate::Tape`].

pub mod batch;
pub mod enclose;
pub mod grad;
pub mod interval;
pub mod interval_grad;
pub mod point;
pub mod scalar;
pub mod trig;

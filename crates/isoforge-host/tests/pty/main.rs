//! The host end to end: the streamer drives the fake printer over a real pseudo-terminal,
//! with faults, pause/resume/cancel, and interrupted jobs resumed from their journal. One
//! test binary, one module per concern.

mod control;
mod faults;
mod resume;
mod support;

//! Printing over serial for isoforge.

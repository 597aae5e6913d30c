//! One module per subcommand.

pub mod check;
pub mod check_gcode;
pub mod fake_printer;
pub mod info;
pub mod mesh;
pub mod print;
pub mod render;
pub mod slice;
pub mod studio;

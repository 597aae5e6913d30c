//! The sandboxed Rhai engine a model script runs in.

use isoforge_field::Shape;
use rhai::module_resolvers::DummyModuleResolver;
use rhai::{Dynamic, Engine};

use crate::files::ScriptFolder;
use crate::params::Shared;

/// Operations a script may run. The classic and benchmark models need a few thousand, a
/// curve follower's closure at most about 150 thousand (4096 frame samples, three calls
/// each), a loop placing ten thousand shapes a few hundred thousand. An endless loop hits
/// this in about 0.2 s in a release build (2.5 s in a debug build) and gets a clear error.
pub const MAX_OPERATIONS: u64 = 1_000_000;

/// Nested function calls. Rhai needs a few kilobytes of native stack per level in debug
/// builds; the script runs on a thread with `SCRIPT_STACK` bytes, ample for this depth.
pub const MAX_CALL_LEVELS: usize = 200;

/// The stack of the thread a script runs on (reserved address space, not memory used).
pub const SCRIPT_STACK: usize = 512 << 20;

/// Longest string, array and object map a script may build.
const MAX_STRING: usize = 1 << 20;
const MAX_ARRAY: usize = 1 << 20;
const MAX_MAP: usize = 1 << 16;

/// Builds an engine with the library, limits and no way out of the sandbox; the only
/// files it can read are in `folder` (the script's own).
pub fn build(shared: &Shared, folder: &ScriptFolder) -> Engine {
    let mut engine = Engine::new();
    // Without this rhai runs its own `/` and `^` on numbers and ignores ours (9/4 == 2).
    engine.set_fast_operators(false);
    engine.set_max_operations(MAX_OPERATIONS);
    engine.set_max_call_levels(MAX_CALL_LEVELS);
    engine.set_max_expr_depths(256, 256);
    engine.set_max_string_size(MAX_STRING);
    engine.set_max_array_size(MAX_ARRAY);
    engine.set_max_map_size(MAX_MAP);
    // No `import`: a model reads no other files (only `image(..)` from its own folder).
    engine.set_module_resolver(DummyModuleResolver::new());
    engine.disable_symbol("import");
    engine.disable_symbol("eval");
    // stdout belongs to `--json`: script output goes to stderr.
    engine.on_print(|s| eprintln!("{s}"));
    engine.on_debug(|s, _, pos| eprintln!("{pos:?}: {s}"));
    engine.register_type_with_name::<Shape>("Shape");
    engine.register_fn("to_string", |s: &mut Shape| format!("{s:?}"));
    engine.register_fn("to_debug", |s: &mut Shape| format!("{s:?}"));
    register_coordinates(&mut engine);
    crate::ops::register(&mut engine);
    crate::library::register(&mut engine);
    crate::sweeps::register(&mut engine);
    crate::textures::register(&mut engine, folder);
    crate::surfaces::register(&mut engine);
    crate::params::register(&mut engine, shared);
    engine
}

/// `x`, `y`, `z`, `PI` and `E` through a variable resolver, because script functions
/// cannot see the global scope: `fn Sphere(a) { x^2 + y^2 + z^2 - a^2 }` must work.
/// A script's own variable of the same name wins (`let x = 3;`, `fn f(x) {..}`).
#[allow(deprecated)] // on_var is marked volatile, not deprecated, in rhai 1.27.
fn register_coordinates(engine: &mut Engine) {
    engine.on_var(|name, index, context| {
        if index > 0 || context.scope().contains(name) {
            return Ok(None);
        }
        Ok(match name {
            "x" => Some(Dynamic::from(Shape::x())),
            "y" => Some(Dynamic::from(Shape::y())),
            "z" => Some(Dynamic::from(Shape::z())),
            "PI" => Some(Dynamic::from_float(std::f64::consts::PI)),
            "E" => Some(Dynamic::from_float(std::f64::consts::E)),
            _ => None,
        })
    });
}

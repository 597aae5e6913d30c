//! The sandboxed Rhai engine a model script runs in.

use isoforge_field::Shape;
use std::sync::atomic::{AtomicBool, Ordering};

use rhai::module_resolvers::DummyModuleResolver;
use rhai::{Dynamic, Engine};

use std::sync::Arc;

use std::time::Instant;

use crate::facts::SharedFacts;
use crate::files::ScriptFolder;
use crate::import::Imports;
use crate::params::Shared;
use crate::{RuntimeCause, ScriptLimits};

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

/// Longest string, array and object map a script may build (rhai counts what is nested
/// inside an array or map towards these too).
pub const MAX_STRING: usize = 1 << 20;
/// Longest array (elements, nested arrays' included).
pub const MAX_ARRAY: usize = 1 << 20;
/// Largest object map (entries).
pub const MAX_MAP: usize = 1 << 16;

/// How often (in operations) the wall clock is read, and 16 times that the process's
/// memory (`/proc/self/statm`, a few microseconds). One operation may copy a million-element
/// array (about 12 ms): checking every 1024 operations let a 2 s limit stop a copying loop
/// only after 7 s; every 16 bounds the overshoot near 0.2 s, and a clock read (about 20 ns)
/// per 16 operations is under 2% of the cheapest loop's time.
const CHECK_EVERY: u64 = 16;

/// Whether a script's `print()` and `debug()` reach stderr (see [`echo_prints`]).
static ECHO_PRINTS: AtomicBool = AtomicBool::new(true);

/// Lets a script's `print()` and `debug()` through to stderr, or silences them (`--quiet`).
/// Process-wide, like stderr itself: scripts never write to stdout.
pub fn echo_prints(on: bool) {
    ECHO_PRINTS.store(on, Ordering::Relaxed);
}

/// Builds an engine with the library, limits and no way out of the sandbox; the only
/// files it can read are in `folder` (the script's own) and the meshes `import_stl` fences.
pub fn build(
    shared: &Shared,
    facts: &SharedFacts,
    imports: &Arc<Imports>,
    limits: &ScriptLimits,
    folder: &ScriptFolder,
) -> Engine {
    let mut engine = Engine::new();
    // Without this rhai runs its own `/` and `^` on numbers and ignores ours (9/4 == 2).
    engine.set_fast_operators(false);
    engine.set_max_operations(MAX_OPERATIONS);
    engine.set_max_call_levels(MAX_CALL_LEVELS);
    engine.set_max_expr_depths(256, 256);
    engine.set_max_string_size(MAX_STRING);
    engine.set_max_array_size(MAX_ARRAY);
    engine.set_max_map_size(MAX_MAP);
    watch(&mut engine, limits);
    // No `import`: a model reads no other files (only `image(..)` from its own folder and
    // meshes through `import_stl`).
    engine.set_module_resolver(DummyModuleResolver::new());
    engine.disable_symbol("import");
    engine.disable_symbol("eval");
    // stdout belongs to `--json`: script output goes to stderr.
    engine.on_print(|s| {
        if ECHO_PRINTS.load(Ordering::Relaxed) {
            eprintln!("{s}");
        }
    });
    engine.on_debug(|s, _, pos| {
        if ECHO_PRINTS.load(Ordering::Relaxed) {
            eprintln!("{pos:?}: {s}");
        }
    });
    engine.register_type_with_name::<Shape>("Shape");
    engine.register_fn("to_string", |s: &mut Shape| format!("{s:?}"));
    engine.register_fn("to_debug", |s: &mut Shape| format!("{s:?}"));
    register_coordinates(&mut engine);
    crate::ops::register(&mut engine);
    crate::library::register(&mut engine);
    crate::modern::register(&mut engine, facts);
    crate::volumes::register(&mut engine, facts);
    crate::import::register(&mut engine, imports, facts);
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

/// Stops a script that runs longer than the wall-clock limit or makes the process grow by
/// more than the memory limit. The operation limit alone does not bound time (copying a
/// million-element array is one operation), and rhai's size limits bound each value, not
/// how many of them a script keeps.
fn watch(engine: &mut Engine, limits: &ScriptLimits) {
    let started = Instant::now();
    let baseline = resident_bytes();
    let (seconds, memory) = (limits.max_seconds, limits.max_memory_bytes);
    engine.on_progress(move |ops| {
        if ops % CHECK_EVERY != 0 {
            return None;
        }
        if started.elapsed().as_secs_f64() > seconds {
            return Some(Dynamic::from(RuntimeCause::TimeLimit { seconds }));
        }
        if ops % (16 * CHECK_EVERY) == 0
            && let (Some(now), Some(base)) = (resident_bytes(), baseline)
            && now.saturating_sub(base) > memory
        {
            return Some(Dynamic::from(RuntimeCause::MemoryLimit { bytes: memory }));
        }
        None
    });
}

/// The process's resident memory in bytes, where the system tells it (Linux).
fn resident_bytes() -> Option<u64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    // The page size is 4 KiB on the platforms isoforge builds for (x86-64, AArch64
    // Linux with 4 KiB pages); a larger page only makes the check stricter.
    Some(pages * 4096)
}

//! `import_stl("part.stl")` (also `.3mf`, `.obj`, `.ply`): a mesh file as a signed
//! distance field, read through the project's mesh readers.
//!
//! The one way a script reads a file, so it is fenced: the path is taken relative to the
//! script's folder, must stay inside that folder once resolved (no absolute paths, no
//! `..` or links leading out), and must be a regular file of at most
//! [`MAX_IMPORT_BYTES`]. Every error names the path as written and what was wrong.
//!
//! Importing is done once: a path imported again in the same run gives the same shape
//! (one node in the graph), and a small cache keyed by the file's resolved path, size and
//! modification time lets repeated runs (a studio re-meshing as the script is edited)
//! skip reading and indexing an unchanged file.

use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::SystemTime;

use isoforge_field::Shape;
use isoforge_shapes::mesh_field::{MeshField, mesh_shape};
use rhai::{Dynamic, Engine};

use crate::args::{RhaiResult, fail, type_name};
use crate::facts::{Fact, SharedFacts, lock};

/// The largest mesh file a script may import: 256 MiB is about five million binary STL
/// triangles, beyond what a model needs and what the reader's limits accept.
pub const MAX_IMPORT_BYTES: u64 = 256 << 20;

/// How many imported meshes the cross-run cache keeps.
const CACHE_SIZE: usize = 8;

/// What `import_stl` knows of its run: the script's folder and what it imported.
pub struct Imports {
    folder: PathBuf,
    done: Mutex<HashMap<PathBuf, Shape>>,
}

impl Imports {
    /// Imports for a script at `script` (its folder is the fence).
    pub fn new(script: &Path) -> Arc<Imports> {
        let folder = match script.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        Arc::new(Imports {
            folder,
            done: Mutex::new(HashMap::new()),
        })
    }
}

/// The key of the cross-run cache: the file as resolved, its size and time.
type CacheKey = (PathBuf, u64, Option<SystemTime>);

/// Meshes read by earlier runs, oldest first.
type Cache = Mutex<Vec<(CacheKey, Arc<MeshField>)>>;

fn cache() -> &'static Cache {
    static CACHE: std::sync::OnceLock<Cache> = std::sync::OnceLock::new();
    CACHE.get_or_init(|| Mutex::new(Vec::new()))
}

/// Resolves `given` inside the fence, or says why not.
fn resolve(folder: &Path, given: &str) -> Result<PathBuf, String> {
    let rel = Path::new(given);
    if given.is_empty() {
        return Err("the path is empty".into());
    }
    if rel.is_absolute()
        || rel
            .components()
            .any(|c| matches!(c, Component::Prefix(_) | Component::RootDir))
    {
        return Err(
            "absolute paths are not allowed: give the path relative to the script's folder".into(),
        );
    }
    let fence = folder.canonicalize().map_err(|e| {
        format!(
            "the script's folder {} cannot be read: {e}",
            folder.display()
        )
    })?;
    let full = fence.join(rel);
    let resolved = full
        .canonicalize()
        .map_err(|e| format!("cannot open {}: {e}", full.display()))?;
    if !resolved.starts_with(&fence) {
        return Err(format!(
            "{} is outside the script's folder {}: a script may only read files in its own folder",
            resolved.display(),
            fence.display()
        ));
    }
    Ok(resolved)
}

/// Reads and indexes the mesh at `path` (already resolved), through the cache.
fn load(path: &Path) -> Result<Arc<MeshField>, String> {
    let meta =
        std::fs::metadata(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    if !meta.is_file() {
        return Err(format!("{} is not a regular file", path.display()));
    }
    if meta.len() > MAX_IMPORT_BYTES {
        return Err(format!(
            "{} is {} bytes, more than the {MAX_IMPORT_BYTES} a script may import",
            path.display(),
            meta.len()
        ));
    }
    let key: CacheKey = (path.to_path_buf(), meta.len(), meta.modified().ok());
    if let Some(hit) = cache()
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .iter()
        .find(|(k, _)| *k == key)
        .map(|(_, f)| f.clone())
    {
        return Ok(hit);
    }
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let name = path.display().to_string();
    let mesh = isoforge_mesh::io::read_mesh_bytes(&bytes, &name).map_err(|e| e.to_string())?;
    let vertices: Vec<[f64; 3]> = mesh.vertices.iter().map(|v| v.map(f64::from)).collect();
    let field = MeshField::new(&vertices, &mesh.triangles)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    let field = Arc::new(field);
    let mut c = cache().lock().unwrap_or_else(|e| e.into_inner());
    if c.len() >= CACHE_SIZE {
        c.remove(0);
    }
    c.push((key, field.clone()));
    Ok(field)
}

/// Registers `import_stl`.
pub fn register(engine: &mut Engine, imports: &Arc<Imports>, facts: &SharedFacts) {
    let imports = imports.clone();
    let facts = facts.clone();
    engine.register_fn("import_stl", move |path: Dynamic| -> RhaiResult<Shape> {
        let Ok(given) = path.clone().into_immutable_string() else {
            return Err(fail(format!(
                "import_stl: the path must be a string, not {}",
                type_name(&path)
            )));
        };
        let given = given.to_string();
        let resolved = resolve(&imports.folder, &given)
            .map_err(|why| fail(format!("import_stl(\"{given}\"): {why}")))?;
        let mut done = imports.done.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(s) = done.get(&resolved) {
            return Ok(s.clone());
        }
        let field =
            load(&resolved).map_err(|why| fail(format!("import_stl(\"{given}\"): {why}")))?;
        let shape = lock(&facts).note(
            mesh_shape(field),
            Fact {
                distance: true,
                convex: None,
            },
        );
        done.insert(resolved, shape.clone());
        Ok(shape)
    });
}

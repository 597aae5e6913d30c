//! The HTTP routes: the page and its assets, and the JSON/binary API the page calls.

use std::path::Path;

use axum::Json;
use axum::Router;
use axum::extract::{DefaultBodyLimit, Path as UrlPath, Query, State};
use axum::http::{HeaderValue, StatusCode, header};
use axum::middleware;
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use serde::Deserialize;
use serde_json::json;

use crate::app::App;
use crate::events::{self, MODEL_EXTENSIONS, version};
use crate::folder::FolderError;
use crate::model::{self, Loaded, Problem};
use crate::preview::{self, MAX_PREVIEW_DEPTH};
use crate::printing::{self, PrintError, PrintRequest};
use crate::{access, assets, slicing};

/// The depth an export meshes at when the page does not say: the command line's default.
const EXPORT_DEPTH: u8 = 8;

/// The router, every route behind the access guard.
pub fn router(app: App) -> Router {
    Router::new()
        .route("/", get(index))
        .route("/assets/{name}", get(asset))
        .route("/api/session", get(session))
        .route("/api/file", get(read_file).put(save_file))
        .route("/api/preview", post(preview_mesh))
        .route("/api/slice", post(slice))
        .route("/api/export", post(export))
        .route("/api/ports", get(ports))
        .route("/api/fake-printer", post(start_fake))
        .route("/api/fake-printer/executed", get(fake_executed))
        .route("/api/print", get(print_status).post(print_start))
        .route("/api/print/{action}", post(print_control))
        .route("/api/events", get(events::stream))
        .layer(DefaultBodyLimit::max(BODY_LIMIT))
        .layer(middleware::from_fn_with_state(app.clone(), access::guard))
        .with_state(app)
}

/// An API failure: a status and a JSON body `{"error": ..}` (plus `problem` for a script).
struct ApiError {
    status: StatusCode,
    body: serde_json::Value,
}

impl ApiError {
    fn new(status: StatusCode, message: impl std::fmt::Display) -> ApiError {
        ApiError {
            status,
            body: json!({"error": message.to_string()}),
        }
    }

    fn problem(p: Problem) -> ApiError {
        ApiError {
            status: StatusCode::UNPROCESSABLE_ENTITY,
            body: json!({"error": p.message, "problem": p}),
        }
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        (self.status, Json(self.body)).into_response()
    }
}

impl From<FolderError> for ApiError {
    fn from(e: FolderError) -> ApiError {
        ApiError::new(StatusCode::FORBIDDEN, e)
    }
}

type ApiResult<T> = Result<T, ApiError>;

async fn index() -> Response {
    assets::serve("index.html")
}

async fn asset(UrlPath(name): UrlPath<String>) -> Response {
    assets::serve(&name)
}

async fn session(State(app): State<App>) -> Json<serde_json::Value> {
    Json(json!({
        "model": app.model,
        "files": app.folder.files_with(MODEL_EXTENSIONS),
        "profiles": slicing::profiles(&app.folder),
        "folder": app.folder.root().display().to_string(),
        "maxDepth": MAX_PREVIEW_DEPTH,
    }))
}

#[derive(Deserialize)]
struct FileQuery {
    name: String,
}

/// A model file of the folder (`.rhai` or `.vm`): the editor reads nothing else.
fn model_path(app: &App, name: &str) -> ApiResult<std::path::PathBuf> {
    let path = app.folder.resolve(name)?;
    let ext = Path::new(name)
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    if !MODEL_EXTENSIONS.contains(&ext.as_str()) {
        return Err(ApiError::new(
            StatusCode::FORBIDDEN,
            format!("{name:?}: the editor opens .rhai and .vm models only"),
        ));
    }
    Ok(path)
}

async fn read_file(
    State(app): State<App>,
    Query(q): Query<FileQuery>,
) -> ApiResult<Json<serde_json::Value>> {
    let path = model_path(&app, &q.name)?;
    let text = std::fs::read_to_string(&path)
        .map_err(|e| ApiError::new(StatusCode::NOT_FOUND, format!("{}: {e}", q.name)))?;
    Ok(Json(
        json!({"name": q.name, "text": text, "version": version(&path)}),
    ))
}

#[derive(Deserialize)]
struct SaveRequest {
    name: String,
    text: String,
    /// The version the page's text came from; a different one on disk is a conflict.
    base: Option<String>,
    #[serde(default)]
    force: bool,
}

async fn save_file(
    State(app): State<App>,
    Json(req): Json<SaveRequest>,
) -> ApiResult<Json<serde_json::Value>> {
    let path = model_path(&app, &req.name)?;
    let on_disk = version(&path);
    if !req.force && on_disk.is_some() && on_disk != req.base {
        return Err(ApiError {
            status: StatusCode::CONFLICT,
            body: json!({
                "error": format!("{} was changed on disk by another program since it was loaded", req.name),
                "version": on_disk,
            }),
        });
    }
    isoforge_output::write_file(&path, req.text.as_bytes(), Default::default())
        .map_err(|e| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, e))?;
    Ok(Json(json!({"name": req.name, "version": version(&path)})))
}

/// The model as the page has it: the editor's text and the sliders' values.
#[derive(Deserialize)]
struct ModelRequest {
    name: String,
    text: String,
    #[serde(default)]
    params: Vec<(String, f64)>,
}

impl ModelRequest {
    /// Runs the script on a worker thread (it may take a while; the server's threads must
    /// keep answering).
    async fn load(&self, app: &App) -> ApiResult<Loaded> {
        let path = model_path(app, &self.name)?;
        let (text, params) = (self.text.clone(), self.params.clone());
        tokio::task::spawn_blocking(move || model::load(&path, &text, &params))
            .await
            .map_err(|e| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, e))?
            .map_err(ApiError::problem)
    }
}

#[derive(Deserialize)]
struct PreviewRequest {
    #[serde(flatten)]
    model: ModelRequest,
    depth: u8,
    /// Increasing per edit; the coarse and fine requests of one edit share it.
    job: u64,
}

fn stale() -> ApiError {
    ApiError::new(StatusCode::CONFLICT, "superseded by a newer edit")
}

async fn preview_mesh(
    State(app): State<App>,
    Json(req): Json<PreviewRequest>,
) -> ApiResult<Response> {
    if req.depth > MAX_PREVIEW_DEPTH {
        return Err(ApiError::new(
            StatusCode::BAD_REQUEST,
            format!(
                "depth {} is beyond the preview's {MAX_PREVIEW_DEPTH}",
                req.depth
            ),
        ));
    }
    app.jobs.arrive(req.job);
    let loaded = req.model.load(&app).await?;
    // Only the finest step waits in the lane; the coarse one must be on screen at once.
    let _lane = if req.depth > crate::COARSE_DEPTH {
        let guard = app.fine_lane.lock().await;
        if app.jobs.is_stale(req.job) {
            return Err(stale());
        }
        Some(guard)
    } else {
        None
    };
    if app.jobs.is_stale(req.job) {
        return Err(stale());
    }
    let depth = req.depth;
    let (mesh, facts, loaded) = tokio::task::spawn_blocking(move || {
        preview::mesh(&loaded, depth).map(|(m, f)| (m, f, loaded))
    })
    .await
    .map_err(|e| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, e))?
    .map_err(|e| ApiError::new(StatusCode::BAD_REQUEST, e))?;
    let params: Vec<_> = loaded
        .params
        .iter()
        .map(|p| json!({"name": p.name, "default": p.default, "value": p.value, "range": p.range}))
        .collect();
    let header = json!({
        "facts": facts,
        "params": params,
        "region": [loaded.bounds.min, loaded.bounds.max],
        "job": req.job,
    });
    let bytes = preview::encode(&mesh, &header);
    Ok(([(header::CONTENT_TYPE, "application/octet-stream")], bytes).into_response())
}

#[derive(Deserialize)]
struct SliceRequest {
    #[serde(flatten)]
    model: ModelRequest,
    profile: String,
}

/// The file name beside the model for an output: `heart.rhai` → `heart.gcode`.
fn output_name(model: &str, extension: &str) -> String {
    let stem = Path::new(model)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("model");
    format!("{stem}.{extension}")
}

async fn slice(
    State(app): State<App>,
    Json(req): Json<SliceRequest>,
) -> ApiResult<Json<serde_json::Value>> {
    let profile = slicing::profile(&app.folder, &req.profile)
        .map_err(|e| ApiError::new(StatusCode::BAD_REQUEST, e))?;
    let name = output_name(&req.model.name, "gcode");
    let out = app.folder.resolve(&name)?;
    let loaded = req.model.load(&app).await?;
    let job = tokio::task::spawn_blocking(move || slicing::gcode(&loaded, &profile))
        .await
        .map_err(|e| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, e))?
        .map_err(|e| ApiError::new(StatusCode::UNPROCESSABLE_ENTITY, e))?;
    // Printing reads the file (its journal names it): it is written beside the model.
    let model_file = model_path(&app, &req.model.name)?;
    isoforge_output::write_file(
        &out,
        job.gcode.as_bytes(),
        isoforge_output::Options::with_inputs(&[&model_file]),
    )
    .map_err(|e| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, e))?;
    Ok(Json(json!({
        "file": name,
        "layers": job.stats.layers,
        "filament_mm": job.stats.filament_mm,
        "filament_g": job.stats.filament_g,
        "seconds": job.stats.seconds,
        "gcode": job.gcode,
        "resumable": printing::resumable(&out),
    })))
}

#[derive(Deserialize)]
struct ExportRequest {
    #[serde(flatten)]
    model: ModelRequest,
    format: String,
    depth: Option<u8>,
    profile: Option<String>,
}

async fn export(State(app): State<App>, Json(req): Json<ExportRequest>) -> ApiResult<Response> {
    use isoforge_mesh::MeshFormat;
    let format = req.format.to_ascii_lowercase();
    let mesh_format = match format.as_str() {
        "stl" => Some(MeshFormat::Stl),
        "3mf" => Some(MeshFormat::ThreeMf),
        "gcode" | "sl1" => None,
        other => {
            return Err(ApiError::new(
                StatusCode::BAD_REQUEST,
                format!("{other:?}: export as stl, 3mf, gcode or sl1"),
            ));
        }
    };
    let depth = req.depth.unwrap_or(EXPORT_DEPTH);
    if depth > MAX_PREVIEW_DEPTH {
        return Err(ApiError::new(
            StatusCode::BAD_REQUEST,
            format!(
                "depth {depth}: at most {MAX_PREVIEW_DEPTH} here (the command line goes further)"
            ),
        ));
    }
    let profile = match &req.profile {
        Some(id) if mesh_format.is_none() => Some(
            slicing::profile(&app.folder, id)
                .map_err(|e| ApiError::new(StatusCode::BAD_REQUEST, e))?,
        ),
        _ => None,
    };
    let name = output_name(&req.model.name, &format);
    let loaded = req.model.load(&app).await?;
    let job_name = Path::new(&name)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("job")
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect::<String>();
    let bytes = tokio::task::spawn_blocking(move || -> Result<Vec<u8>, String> {
        match (mesh_format, profile) {
            (Some(f), _) => {
                let (mesh, _) = preview::mesh(&loaded, depth).map_err(|e| e.to_string())?;
                let mut out = Vec::new();
                isoforge_mesh::io::encode(&mesh, f, &mut out).map_err(|e| e.to_string())?;
                Ok(out)
            }
            (None, None) => Err("choose a printer profile to export G-code or SL1".into()),
            (None, Some(p)) if format == "gcode" => slicing::gcode(&loaded, &p)
                .map(|j| j.gcode.into_bytes())
                .map_err(|e| e.to_string()),
            (None, Some(p)) => {
                slicing::sl1_archive(&loaded, &p, &job_name).map_err(|e| e.to_string())
            }
        }
    })
    .await
    .map_err(|e| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, e))?
    .map_err(|e| ApiError::new(StatusCode::UNPROCESSABLE_ENTITY, e))?;
    let mut response =
        ([(header::CONTENT_TYPE, "application/octet-stream")], bytes).into_response();
    if let Ok(v) = HeaderValue::from_str(&format!("attachment; filename=\"{name}\"")) {
        response
            .headers_mut()
            .insert(header::CONTENT_DISPOSITION, v);
    }
    Ok(response)
}

async fn ports(State(app): State<App>) -> Json<serde_json::Value> {
    Json(json!(app.printer.ports()))
}

async fn start_fake(State(app): State<App>) -> ApiResult<Json<serde_json::Value>> {
    let path = app
        .printer
        .start_fake()
        .map_err(|e| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, e))?;
    Ok(Json(json!({"path": path})))
}

async fn fake_executed(State(app): State<App>) -> ApiResult<Json<serde_json::Value>> {
    let executed = app
        .printer
        .fake_executed()
        .ok_or_else(|| ApiError::new(StatusCode::NOT_FOUND, "the fake printer is not started"))?;
    let list: Vec<_> = executed
        .into_iter()
        .map(|(line, command)| json!({"line": line, "command": command}))
        .collect();
    Ok(Json(json!(list)))
}

#[derive(Deserialize)]
struct StatusQuery {
    file: Option<String>,
}

async fn print_status(
    State(app): State<App>,
    Query(q): Query<StatusQuery>,
) -> ApiResult<Json<serde_json::Value>> {
    let resumable = match &q.file {
        Some(name) => printing::resumable(&app.folder.resolve(name)?),
        None => false,
    };
    Ok(Json(
        json!({"status": app.printer.status(), "resumable": resumable}),
    ))
}

#[derive(Deserialize)]
struct PrintStart {
    file: String,
    port: String,
    #[serde(default = "default_baud")]
    baud: u32,
    #[serde(default)]
    resume: bool,
    #[serde(default)]
    restart: bool,
}

fn default_baud() -> u32 {
    115_200
}

async fn print_start(
    State(app): State<App>,
    Json(req): Json<PrintStart>,
) -> ApiResult<Json<serde_json::Value>> {
    let gcode = app.folder.resolve(&req.file)?;
    let request = PrintRequest {
        gcode,
        name: req.file,
        port: req.port,
        baud: req.baud,
        resume: req.resume,
        restart: req.restart,
    };
    let publisher = app.clone();
    let started = tokio::task::spawn_blocking(move || {
        let printer_app = publisher.clone();
        printer_app.printer.start(request, move |s| {
            publisher.publish(&json!({"type": "print", "status": s}));
        })
    })
    .await
    .map_err(|e| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, e))?;
    started.map_err(|e| {
        let status = match e {
            PrintError::Busy | PrintError::Journal(_) => StatusCode::CONFLICT,
            PrintError::UnknownPort(_) => StatusCode::FORBIDDEN,
            _ => StatusCode::UNPROCESSABLE_ENTITY,
        };
        ApiError::new(status, e)
    })?;
    Ok(Json(json!({"status": app.printer.status()})))
}

async fn print_control(
    State(app): State<App>,
    UrlPath(action): UrlPath<String>,
) -> ApiResult<Json<serde_json::Value>> {
    if !matches!(action.as_str(), "pause" | "resume" | "cancel") {
        return Err(ApiError::new(
            StatusCode::NOT_FOUND,
            format!("{action:?}: pause, resume or cancel"),
        ));
    }
    if !app.printer.control(&action) {
        return Err(ApiError::new(StatusCode::CONFLICT, "no print is running"));
    }
    Ok(Json(json!({"status": app.printer.status()})))
}

/// Bytes of a request body the page may send: a script is small, but a pasted one may
/// carry a long table of numbers.
pub const BODY_LIMIT: usize = 8 << 20;

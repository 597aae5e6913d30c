//! isoforge studio: a local web application, served by the `isoforge` binary itself, that
//! takes a person from a model script to a printer on one page: an editor with line
//! numbers and placed errors, a WebGL view refined in steps, a slider per `param(..)`, the
//! mesh's facts, exports (STL, 3MF, G-code, SL1), a layer view of the sliced G-code, and
//! printing to a serial port or a built-in fake printer with live progress.
//!
//! ```no_run
//! use isoforge_studio::{Options, Studio};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let studio = Studio::bind(Options::new("fixtures/classic/heart.rhai".into()))?;
//! println!("open {}", studio.url());
//! let stop = studio.stop_handle(); // stop.stop() from a signal handler ends it
//! studio.serve()?;
//! # Ok(()) }
//! ```
//!
//! The server is axum on tokio. It listens on 127.0.0.1 unless told otherwise (a remote
//! address must be asked for explicitly), and lets in only requests that carry the random
//! token of the printed URL ([`access`]). It reads and writes the model's folder and
//! nothing else ([`folder`]). The libraries are reached through one glue module each:
//! [`model`] (scripts), [`preview`] (meshes), [`slicing`] (profiles, G-code, SL1),
//! [`printing`] (ports, fake printer, print jobs); [`events`] pushes print progress and
//! file changes to the page; the page itself is in `assets/`, compiled in by [`assets`].

pub mod access;
mod app;
mod assets;
pub mod events;
pub mod folder;
pub mod model;
pub mod preview;
pub mod printing;
mod routes;
pub mod slicing;

use std::future::IntoFuture;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use tokio::sync::Notify;

pub use app::App;

/// The coarse preview's depth: 2^6 = 64 cells along the region's longest side; the page
/// shows it at once after an edit, then a finer one. Chosen so every classic model's coarse
/// preview stays under 100 ms from slider to screen (docs/studio.md has the measurements).
pub const COARSE_DEPTH: u8 = 6;

/// How long requests under way may take to finish when the studio is stopped.
const SHUTDOWN_GRACE: std::time::Duration = std::time::Duration::from_secs(2);

/// How to start a studio.
#[derive(Debug, Clone)]
pub struct Options {
    /// The model file to open; its folder is the one the studio works in. A folder may be
    /// given instead: the studio opens its first model, or a new `model.rhai`.
    pub model: PathBuf,
    /// The address to listen on (default 127.0.0.1).
    pub host: IpAddr,
    /// The port (0 picks a free one).
    pub port: u16,
    /// Allow a non-loopback `host`.
    pub allow_remote: bool,
}

impl Options {
    /// Loopback, a free port.
    pub fn new(model: PathBuf) -> Options {
        Options {
            model,
            host: IpAddr::V4(Ipv4Addr::LOCALHOST),
            port: 0,
            allow_remote: false,
        }
    }
}

/// Why the studio could not start.
#[derive(Debug, thiserror::Error)]
pub enum StudioError {
    /// A non-loopback address without `allow_remote`.
    #[error(
        "{0} is not a loopback address: anyone who can reach it and learns the token could \
         drive your printer; pass --allow-remote if that is what you want"
    )]
    RemoteRefused(IpAddr),
    /// The model or its folder cannot be used.
    #[error("{}: {what}", path.display())]
    Model {
        /// The path given.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
    /// The folder cannot be opened.
    #[error(transparent)]
    Folder(#[from] folder::FolderError),
    /// The port cannot be bound, or the runtime not started.
    #[error("{0}")]
    Io(#[from] std::io::Error),
}

/// A studio bound to its address, not yet serving.
pub struct Studio {
    app: App,
    stop: Arc<Notify>,
    listener: std::net::TcpListener,
    url: String,
}

/// The model file a studio opens for a path: the file itself, or in a folder its first
/// model (a new, empty `model.rhai` name when it has none).
fn split_model(path: &Path) -> Result<(PathBuf, String), StudioError> {
    if path.is_dir() {
        let folder = folder::ModelFolder::open(path)?;
        let name = folder
            .files_with(events::MODEL_EXTENSIONS)
            .into_iter()
            .next()
            .unwrap_or_else(|| "model.rhai".to_string());
        return Ok((path.to_path_buf(), name));
    }
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .map(str::to_string)
        .ok_or_else(|| StudioError::Model {
            path: path.to_path_buf(),
            what: "not a file name".into(),
        })?;
    let ext_ok = Path::new(&name)
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| events::MODEL_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()));
    if !ext_ok {
        return Err(StudioError::Model {
            path: path.to_path_buf(),
            what: "the studio opens model scripts (.rhai) and expression files (.vm)".into(),
        });
    }
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !path.exists() {
        return Err(StudioError::Model {
            path: path.to_path_buf(),
            what: "no such file".into(),
        });
    }
    Ok((parent, name))
}

impl Studio {
    /// Checks the options, opens the folder and binds the port.
    pub fn bind(options: Options) -> Result<Studio, StudioError> {
        if !options.host.is_loopback() && !options.allow_remote {
            return Err(StudioError::RemoteRefused(options.host));
        }
        let (dir, name) = split_model(&options.model)?;
        let folder = folder::ModelFolder::open(&dir)?;
        folder.resolve(&name)?;
        let listener = std::net::TcpListener::bind(SocketAddr::new(options.host, options.port))?;
        listener.set_nonblocking(true)?;
        let port = listener.local_addr()?.port();
        let access = access::Access::new(port, !options.host.is_loopback())?;
        let shown_host = match options.host {
            IpAddr::V4(a) if a.is_unspecified() || a.is_loopback() => "127.0.0.1".to_string(),
            IpAddr::V4(a) => a.to_string(),
            IpAddr::V6(a) if a.is_loopback() => "[::1]".to_string(),
            IpAddr::V6(a) => format!("[{a}]"),
        };
        let url = format!("http://{shown_host}:{port}/?token={}", access.token());
        Ok(Studio {
            app: App::new(access, folder, name),
            stop: Arc::new(Notify::new()),
            listener,
            url,
        })
    }

    /// The address to open, token included.
    pub fn url(&self) -> &str {
        &self.url
    }

    /// A handle that ends [`serve`](Self::serve) from any thread.
    pub fn stop_handle(&self) -> StopHandle {
        StopHandle(self.stop.clone())
    }

    /// Serves until stopped through a [`StopHandle`]; then a running print is cancelled
    /// (heaters and motors off) before this returns.
    pub fn serve(self) -> Result<(), StudioError> {
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()?;
        let app = self.app.clone();
        let stop = self.stop.clone();
        runtime.block_on(async move {
            let listener = tokio::net::TcpListener::from_std(self.listener)?;
            let watcher = tokio::spawn(events::watch(self.app.clone()));
            let (stopping, stopped) = tokio::sync::oneshot::channel::<()>();
            let graceful = axum::serve(listener, routes::router(self.app))
                .with_graceful_shutdown(async move {
                    stop.notified().await;
                    let _ = stopping.send(());
                })
                .into_future();
            // An open page holds its event stream open for ever: requests under way get a
            // moment to finish, then the server stops regardless.
            let served = tokio::select! {
                served = graceful => served,
                _ = async {
                    let _ = stopped.await;
                    tokio::time::sleep(SHUTDOWN_GRACE).await;
                } => Ok(()),
            };
            watcher.abort();
            served
        })?;
        app.printer.shut_down();
        // Open event streams keep connections alive; do not wait for them.
        runtime.shutdown_background();
        Ok(())
    }
}

/// Ends a serving studio from another thread (a signal handler, a test).
#[derive(Clone)]
pub struct StopHandle(Arc<Notify>);

impl StopHandle {
    /// Asks the studio to stop; it may be called before `serve` starts.
    pub fn stop(&self) {
        self.0.notify_one();
    }
}

//! The state every request handler shares.

use std::ops::Deref;
use std::sync::Arc;

use tokio::sync::broadcast;

use crate::access::Access;
use crate::folder::ModelFolder;
use crate::preview::Jobs;
use crate::printing::Printer;

/// Events kept for a page that reads them late; progress is sent a few times a second, so
/// this is several seconds' worth.
const EVENT_BACKLOG: usize = 256;

/// A handle to the studio's shared state (cheap to clone).
#[derive(Clone)]
pub struct App(Arc<Inner>);

/// The shared state.
pub struct Inner {
    /// Who may come in.
    pub access: Access,
    /// The only folder read and written.
    pub folder: ModelFolder,
    /// The model opened at start (a file name in `folder`).
    pub model: String,
    /// The preview requests' numbering.
    pub jobs: Jobs,
    /// Fine meshes run one at a time: on two cores a second one would only slow the
    /// coarse preview of the next edit.
    pub fine_lane: tokio::sync::Mutex<()>,
    /// Events for the page (JSON texts).
    pub events: broadcast::Sender<String>,
    /// The printer side.
    pub printer: Printer,
}

impl App {
    /// The state for a studio on `folder` with `model` open.
    pub fn new(access: Access, folder: ModelFolder, model: String) -> App {
        let (events, _) = broadcast::channel(EVENT_BACKLOG);
        App(Arc::new(Inner {
            access,
            folder,
            model,
            jobs: Jobs::default(),
            fine_lane: tokio::sync::Mutex::new(()),
            events,
            printer: Printer::default(),
        }))
    }

    /// Sends an event to every open page (none listening is fine).
    pub fn publish(&self, event: &serde_json::Value) {
        let _ = self.events.send(event.to_string());
    }
}

impl Deref for App {
    type Target = Inner;
    fn deref(&self) -> &Inner {
        &self.0
    }
}

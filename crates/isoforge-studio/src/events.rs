//! Server-sent events to the page: print progress, and model files changed on disk by
//! another editor (found by polling their modification times: a handful of files, twice a
//! second, costs nothing and needs no platform file-watch API).

use std::collections::BTreeMap;
use std::convert::Infallible;
use std::time::{Duration, UNIX_EPOCH};

use axum::extract::State;
use axum::response::sse::{Event, KeepAlive, Sse};
use futures_util::Stream;
use tokio::sync::broadcast;

use crate::app::App;

/// How often the folder is looked at for changed models.
const WATCH_EVERY: Duration = Duration::from_millis(500);

/// The model files the page can open.
pub const MODEL_EXTENSIONS: &[&str] = &["rhai", "vm"];

/// `GET /api/events`: the event stream.
pub async fn stream(State(app): State<App>) -> Sse<impl Stream<Item = Result<Event, Infallible>>> {
    let rx = app.events.subscribe();
    let events = futures_util::stream::unfold(rx, |mut rx| async move {
        loop {
            match rx.recv().await {
                Ok(text) => return Some((Ok(Event::default().data(text)), rx)),
                // A slow page missed some; the next progress event brings it up to date.
                Err(broadcast::error::RecvError::Lagged(_)) => continue,
                Err(broadcast::error::RecvError::Closed) => return None,
            }
        }
    });
    Sse::new(events).keep_alive(KeepAlive::default())
}

/// A file's version as the page compares it: modification time and length. Equal versions
/// mean "the text the page has is the text on disk".
pub fn version(path: &std::path::Path) -> Option<String> {
    let meta = std::fs::metadata(path).ok()?;
    let t = meta.modified().ok()?.duration_since(UNIX_EPOCH).ok()?;
    Some(format!(
        "{}.{:09}-{}",
        t.as_secs(),
        t.subsec_nanos(),
        meta.len()
    ))
}

fn versions(app: &App) -> BTreeMap<String, String> {
    app.folder
        .files_with(MODEL_EXTENSIONS)
        .into_iter()
        .filter_map(|name| {
            let v = version(&app.folder.resolve(&name).ok()?)?;
            Some((name, v))
        })
        .collect()
}

/// Polls the folder's model files and publishes `{"type": "file", name, version}` for each
/// one that changed, forever.
pub async fn watch(app: App) {
    let mut seen = versions(&app);
    loop {
        tokio::time::sleep(WATCH_EVERY).await;
        let now = versions(&app);
        for (name, v) in &now {
            if seen.get(name) != Some(v) {
                app.publish(&serde_json::json!({"type": "file", "name": name, "version": v}));
            }
        }
        seen = now;
    }
}

//! The page: plain HTML, CSS and JavaScript compiled into the binary, so the studio needs
//! no network, no CDN and no build step (the files in `assets/` are what the browser runs).

use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};

/// Name, content type and content of every file the page loads.
const ASSETS: &[(&str, &str, &str)] = &[
    (
        "index.html",
        "text/html; charset=utf-8",
        include_str!("../assets/index.html"),
    ),
    (
        "studio.css",
        "text/css; charset=utf-8",
        include_str!("../assets/studio.css"),
    ),
    (
        "studio.js",
        "text/javascript; charset=utf-8",
        include_str!("../assets/studio.js"),
    ),
    (
        "api.js",
        "text/javascript; charset=utf-8",
        include_str!("../assets/api.js"),
    ),
    (
        "editor.js",
        "text/javascript; charset=utf-8",
        include_str!("../assets/editor.js"),
    ),
    (
        "view3d.js",
        "text/javascript; charset=utf-8",
        include_str!("../assets/view3d.js"),
    ),
    (
        "params.js",
        "text/javascript; charset=utf-8",
        include_str!("../assets/params.js"),
    ),
    (
        "layers.js",
        "text/javascript; charset=utf-8",
        include_str!("../assets/layers.js"),
    ),
    (
        "print.js",
        "text/javascript; charset=utf-8",
        include_str!("../assets/print.js"),
    ),
];

/// The asset by name, or 404.
pub fn serve(name: &str) -> Response {
    match ASSETS.iter().find(|(n, _, _)| *n == name) {
        Some((_, kind, body)) => ([(header::CONTENT_TYPE, *kind)], *body).into_response(),
        None => (StatusCode::NOT_FOUND, "no such asset").into_response(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The page must run offline: nothing it loads may come from another server.
    #[test]
    fn assets_fetch_nothing_from_outside() {
        for (name, _, body) in ASSETS {
            for needle in ["http://", "https://", "//cdn", "@import url("] {
                assert!(!body.contains(needle), "{name} refers to {needle}");
            }
        }
    }
}

//! Who may use the studio: the holder of the random token printed with the URL, asking
//! through a host name that is this server (not a rebound DNS name), from the studio's own
//! page (not another site open in the same browser).
//!
//! A local web server is reachable by every program and every user on the machine, and by
//! every web page the user's browser shows (a page can send requests to 127.0.0.1). The
//! token keeps other users out (they cannot read it from our terminal), the cookie that
//! carries it is `SameSite=Strict` (another site's requests go without it), the Host check
//! defeats DNS rebinding (a foreign name resolved to 127.0.0.1 carries the token-less
//! requests of a foreign page), and a cross-site `Origin` or `Sec-Fetch-Site` is refused
//! outright, token or not.

use axum::extract::{Request, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Redirect, Response};

use crate::app::App;

/// Bytes of randomness in a token: 128 bits, as many as Jupyter's.
const TOKEN_BYTES: usize = 16;

/// The access rules of one running studio.
#[derive(Debug, Clone)]
pub struct Access {
    token: String,
    /// `host:port` values the Host header may take; empty = any (remote access asked for).
    hosts: Vec<String>,
    cookie: String,
}

/// Why a request was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refusal {
    /// The Host header names another server.
    Host,
    /// The request comes from another site's page.
    CrossSite,
    /// No token, or a wrong one.
    Token,
}

impl Access {
    /// Rules for a server on `port`, with a fresh random token. `any_host` drops the Host
    /// check (for `--allow-remote`, where the page is reached by a name we cannot know).
    pub fn new(port: u16, any_host: bool) -> std::io::Result<Access> {
        let mut bytes = [0u8; TOKEN_BYTES];
        getrandom::fill(&mut bytes).map_err(|e| std::io::Error::other(e.to_string()))?;
        let token = bytes.iter().map(|b| format!("{b:02x}")).collect();
        Ok(Access::with_token(token, port, any_host))
    }

    /// Rules with a given token (tests).
    pub fn with_token(token: String, port: u16, any_host: bool) -> Access {
        let hosts = if any_host {
            Vec::new()
        } else {
            ["127.0.0.1", "localhost", "[::1]"]
                .iter()
                .map(|h| format!("{h}:{port}"))
                .collect()
        };
        Access {
            token,
            hosts,
            // Cookies are not kept apart by port: two studios on one machine need two names.
            cookie: format!("isoforge_studio_{port}"),
        }
    }

    /// The token, for the URL printed at start.
    pub fn token(&self) -> &str {
        &self.token
    }

    /// Checks a request's headers and token (from the query or the cookie).
    pub fn check(&self, headers: &HeaderMap, query_token: Option<&str>) -> Result<(), Refusal> {
        let host = headers.get(header::HOST).and_then(|h| h.to_str().ok());
        if !self.hosts.is_empty() && !host.is_some_and(|h| self.hosts.iter().any(|a| a == h)) {
            return Err(Refusal::Host);
        }
        // The printed address opened from another page (a link in a web terminal) carries the
        // token itself: that one cross-site request is the user's own.
        let query_ok = query_token.is_some_and(|t| same_secret(t, &self.token));
        if let Some(site) = headers.get("sec-fetch-site").and_then(|v| v.to_str().ok())
            && site == "cross-site"
            && !query_ok
        {
            return Err(Refusal::CrossSite);
        }
        if let Some(origin) = headers.get(header::ORIGIN) {
            let same = origin
                .to_str()
                .ok()
                .and_then(|o| o.strip_prefix("http://"))
                .is_some_and(|o| host == Some(o));
            if !same {
                return Err(Refusal::CrossSite);
            }
        }
        let from_cookie = cookie_value(headers, &self.cookie);
        let given = [query_token, from_cookie.as_deref()];
        if given.iter().flatten().any(|t| same_secret(t, &self.token)) {
            Ok(())
        } else {
            Err(Refusal::Token)
        }
    }

    /// The `Set-Cookie` value that lets the page's later requests in without the token in
    /// every URL.
    fn set_cookie(&self) -> Option<HeaderValue> {
        HeaderValue::from_str(&format!(
            "{}={}; Path=/; HttpOnly; SameSite=Strict",
            self.cookie, self.token
        ))
        .ok()
    }
}

/// Compares without stopping at the first differing byte, so response times do not tell an
/// attacker how much of a guess was right.
fn same_secret(a: &str, b: &str) -> bool {
    a.len() == b.len()
        && a.bytes()
            .zip(b.bytes())
            .fold(0u8, |acc, (x, y)| acc | (x ^ y))
            == 0
}

fn cookie_value(headers: &HeaderMap, name: &str) -> Option<String> {
    headers
        .get_all(header::COOKIE)
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(';'))
        .filter_map(|pair| pair.trim().split_once('='))
        .find(|(k, _)| *k == name)
        .map(|(_, v)| v.to_string())
}

fn query_token(query: Option<&str>) -> Option<String> {
    query?
        .split('&')
        .filter_map(|kv| kv.split_once('='))
        .find(|(k, _)| *k == "token")
        .map(|(_, v)| v.to_string())
}

/// The middleware in front of every route.
pub async fn guard(State(app): State<App>, request: Request, next: Next) -> Response {
    let token = query_token(request.uri().query());
    if let Err(refusal) = app.access.check(request.headers(), token.as_deref()) {
        return refused(refusal);
    }
    // The first load carries the token in the URL: trade it for a cookie and a clean
    // address, so it does not linger in the address bar or the history.
    if token.is_some() && request.uri().path() == "/" {
        let mut response = Redirect::to("/").into_response();
        if let Some(c) = app.access.set_cookie() {
            response.headers_mut().insert(header::SET_COOKIE, c);
        }
        return response;
    }
    let mut response = next.run(request).await;
    let headers = response.headers_mut();
    // The page is ours alone: no framing by other sites, no guessing of types.
    headers.insert("x-frame-options", HeaderValue::from_static("DENY"));
    headers.insert(
        "x-content-type-options",
        HeaderValue::from_static("nosniff"),
    );
    headers.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    response
}

fn refused(refusal: Refusal) -> Response {
    let (status, text) = match refusal {
        Refusal::Host => (
            StatusCode::MISDIRECTED_REQUEST,
            "this isoforge studio answers only to 127.0.0.1, localhost and [::1]",
        ),
        Refusal::CrossSite => (
            StatusCode::FORBIDDEN,
            "requests from other sites are refused",
        ),
        Refusal::Token => (
            StatusCode::FORBIDDEN,
            "open the address isoforge studio printed: it carries the access token",
        ),
    };
    (status, text).into_response()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn headers(pairs: &[(&'static str, &str)]) -> HeaderMap {
        let mut h = HeaderMap::new();
        for (k, v) in pairs {
            h.append(*k, HeaderValue::from_str(v).unwrap());
        }
        h
    }

    #[test]
    fn token_from_query_or_cookie() {
        let a = Access::with_token("abc".into(), 8000, false);
        let host = ("host", "127.0.0.1:8000");
        assert_eq!(a.check(&headers(&[host]), Some("abc")), Ok(()));
        assert_eq!(a.check(&headers(&[host]), Some("abd")), Err(Refusal::Token));
        assert_eq!(a.check(&headers(&[host]), None), Err(Refusal::Token));
        let c = headers(&[host, ("cookie", "x=1; isoforge_studio_8000=abc")]);
        assert_eq!(a.check(&c, None), Ok(()));
        let other_port = headers(&[host, ("cookie", "isoforge_studio_8001=abc")]);
        assert_eq!(a.check(&other_port, None), Err(Refusal::Token));
    }

    #[test]
    fn foreign_host_and_origin_refused_even_with_the_token() {
        let a = Access::with_token("abc".into(), 8000, false);
        let evil = headers(&[("host", "evil.example:8000")]);
        assert_eq!(a.check(&evil, Some("abc")), Err(Refusal::Host));
        let cross = headers(&[
            ("host", "127.0.0.1:8000"),
            ("origin", "http://evil.example"),
        ]);
        assert_eq!(a.check(&cross, Some("abc")), Err(Refusal::CrossSite));
        let fetch = headers(&[
            ("host", "localhost:8000"),
            ("sec-fetch-site", "cross-site"),
            ("cookie", "isoforge_studio_8000=abc"),
        ]);
        assert_eq!(a.check(&fetch, None), Err(Refusal::CrossSite));
        // A link to the printed address, followed from another page, carries the token.
        assert_eq!(a.check(&fetch, Some("abc")), Ok(()));
        let same = headers(&[
            ("host", "localhost:8000"),
            ("origin", "http://localhost:8000"),
        ]);
        assert_eq!(a.check(&same, Some("abc")), Ok(()));
    }

    #[test]
    fn tokens_are_random_and_long() {
        let a = Access::new(1, false).unwrap();
        let b = Access::new(1, false).unwrap();
        assert_ne!(a.token(), b.token());
        assert_eq!(a.token().len(), 2 * TOKEN_BYTES);
    }
}

//! A running `isoforge studio` for the tests: started on a free port, its URL read from
//! the first line of stdout, stopped with SIGTERM (the orderly way) when dropped.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::{Child, Command, Stdio};

use crate::isoforge_bin;

pub struct StudioProcess {
    child: Child,
    /// The address printed, token included.
    pub url: String,
    /// `127.0.0.1:PORT`.
    pub authority: String,
    /// The token alone.
    pub token: String,
}

impl StudioProcess {
    pub fn start(model: &Path) -> StudioProcess {
        let mut child = Command::new(isoforge_bin())
            .arg("studio")
            .arg(model)
            .args(["--port", "0"])
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("isoforge studio starts");
        let mut first = String::new();
        BufReader::new(child.stdout.take().expect("stdout"))
            .read_line(&mut first)
            .expect("the URL line");
        let url = first.trim().to_string();
        let rest = url.strip_prefix("http://").expect("an http URL");
        let (authority, query) = rest.split_once('/').expect("a path");
        let token = query
            .strip_prefix("?token=")
            .expect("a token in the URL")
            .to_string();
        assert_eq!(token.len(), 32, "{url}");
        StudioProcess {
            child,
            url: url.clone(),
            authority: authority.to_string(),
            token,
        }
    }

    /// Sends a raw HTTP/1.1 request and returns the status code and body.
    pub fn request(
        &self,
        method: &str,
        target: &str,
        headers: &[(&str, &str)],
        body: &str,
    ) -> (u16, String) {
        let mut stream = TcpStream::connect(&self.authority).expect("connects");
        let mut text = format!("{method} {target} HTTP/1.1\r\nconnection: close\r\n");
        if !headers.iter().any(|(k, _)| k.eq_ignore_ascii_case("host")) {
            text.push_str(&format!("host: {}\r\n", self.authority));
        }
        for (k, v) in headers {
            text.push_str(&format!("{k}: {v}\r\n"));
        }
        text.push_str(&format!("content-length: {}\r\n\r\n{body}", body.len()));
        stream.write_all(text.as_bytes()).expect("sends");
        let mut response = String::new();
        stream.read_to_string(&mut response).expect("reads");
        let status = response
            .split(' ')
            .nth(1)
            .and_then(|s| s.parse().ok())
            .expect("a status line");
        let body = response
            .split_once("\r\n\r\n")
            .map(|(_, b)| b.to_string())
            .unwrap_or_default();
        (status, body)
    }
}

impl Drop for StudioProcess {
    fn drop(&mut self) {
        let _ = Command::new("kill")
            .args(["-TERM", &self.child.id().to_string()])
            .status();
        let _ = self.child.wait();
    }
}

//! Shared by the `hostctl ui` tests: start the real binary on the fast virtual device, read the
//! URL it prints, and speak raw HTTP/1.1 to it (so that every header, including a forged `Host`
//! or `Origin`, is exactly what the test writes).

#![allow(dead_code)]

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

/// A running `hostctl ui`.
pub struct Server {
    child: Child,
    /// The URL printed on startup.
    pub url: String,
    /// The bound address.
    pub addr: SocketAddr,
    /// The run's token.
    pub token: String,
}

impl Server {
    /// Starts `hostctl ui --listen 127.0.0.1:0 --fast` plus `extra`, waiting for its URL.
    pub fn start(extra: &[&str]) -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_hostctl"))
            .args(["ui", "--listen", "127.0.0.1:0", "--fast"])
            .args(extra)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start hostctl ui");
        let mut out = BufReader::new(child.stdout.take().expect("stdout"));
        let mut line = String::new();
        out.read_line(&mut line).expect("read the URL line");
        let url = line
            .split_whitespace()
            .find(|w| w.starts_with("http://"))
            .unwrap_or_else(|| panic!("no URL in {line:?}"))
            .to_string();
        // Keep draining stdout so the child never blocks on it.
        std::thread::spawn(move || {
            let mut sink = Vec::new();
            let _ = out.read_to_end(&mut sink);
        });
        let rest = url.strip_prefix("http://").expect("http URL");
        let (hostport, query) = rest.split_once("/?token=").expect("token in the URL");
        Self {
            child,
            addr: hostport.parse().expect("IP:PORT in the URL"),
            token: query.to_string(),
            url,
        }
    }

    /// `Host` value of this server.
    pub fn host(&self) -> String {
        self.addr.to_string()
    }

    /// Sends `head` (request line and headers, without the final blank line) and `body`;
    /// returns the status code and the whole response text.
    pub fn raw(&self, head: &str, body: &str) -> (u16, String) {
        let mut s = TcpStream::connect(self.addr).expect("connect");
        s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
        let req = format!(
            "{head}\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
            body.len()
        );
        s.write_all(req.as_bytes()).expect("send");
        let mut resp = Vec::new();
        // A 101 upgrade keeps the connection open: read what arrives until it pauses.
        let mut buf = [0u8; 65536];
        loop {
            match s.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => {
                    resp.extend_from_slice(&buf[..n]);
                    if resp.starts_with(b"HTTP/1.1 101") {
                        break;
                    }
                }
                Err(_) => break,
            }
        }
        let text = String::from_utf8_lossy(&resp).into_owned();
        let code = text
            .split_whitespace()
            .nth(1)
            .and_then(|c| c.parse().ok())
            .unwrap_or_else(|| panic!("no status line in {text:?}"));
        (code, text)
    }

    /// An authorised `POST /api/cmd` with `json`; returns the status and the JSON answer.
    pub fn cmd(&self, json: &str) -> (u16, serde_json::Value) {
        let (code, text) = self.raw(
            &format!(
                "POST /api/cmd HTTP/1.1\r\nHost: {}\r\nX-Stiffwall-Token: {}\r\nContent-Type: application/json",
                self.host(),
                self.token
            ),
            json,
        );
        let body = text.split_once("\r\n\r\n").map_or("", |(_, b)| b);
        (
            code,
            serde_json::from_str(body).unwrap_or_else(|e| panic!("{e}: {text}")),
        )
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

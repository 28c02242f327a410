//! Shared by the `hostctl ui` tests: start the real binary on the fast virtual device, read the
//! URL it prints, and speak raw HTTP/1.1 to it (so that every header, including a forged `Host`
//! or `Origin`, is exactly what the test writes).

#![allow(dead_code)]

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::PathBuf;
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

    /// The server's process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// A WebSocket on `/ws` as the page opens it (handshake done, response read).
    pub fn ws(&self) -> TcpStream {
        let mut s = TcpStream::connect(self.addr).expect("connect");
        s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
        let h = self.host();
        let req = format!(
            "GET /ws?token={} HTTP/1.1\r\nHost: {h}\r\nOrigin: http://{h}\r\nConnection: Upgrade\r\n\
             Upgrade: websocket\r\nSec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n",
            self.token
        );
        s.write_all(req.as_bytes()).expect("send the upgrade");
        let mut head = Vec::new();
        let mut b = [0u8; 1];
        while !head.ends_with(b"\r\n\r\n") {
            s.read_exact(&mut b).expect("read the upgrade answer");
            head.push(b[0]);
        }
        assert!(
            head.starts_with(b"HTTP/1.1 101"),
            "{}",
            String::from_utf8_lossy(&head)
        );
        s
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

/// Reads one WebSocket frame sent by the server (unmasked): its opcode and payload.
pub fn read_frame(s: &mut TcpStream) -> std::io::Result<(u8, Vec<u8>)> {
    let mut h = [0u8; 2];
    s.read_exact(&mut h)?;
    let len = match h[1] & 0x7f {
        126 => {
            let mut e = [0u8; 2];
            s.read_exact(&mut e)?;
            u64::from(u16::from_be_bytes(e))
        }
        127 => {
            let mut e = [0u8; 8];
            s.read_exact(&mut e)?;
            u64::from_be_bytes(e)
        }
        n => u64::from(n),
    };
    let mut payload = vec![0u8; usize::try_from(len).expect("frame length")];
    s.read_exact(&mut payload)?;
    Ok((h[0] & 0x0f, payload))
}

/// Sends one masked WebSocket frame (as a browser does) of `opcode` with `payload`.
pub fn send_frame(s: &mut TcpStream, opcode: u8, payload: &[u8]) -> std::io::Result<()> {
    let mut f = vec![0x80 | opcode];
    let n = payload.len();
    if n < 126 {
        f.push(0x80 | n as u8);
    } else if n <= 0xffff {
        f.push(0x80 | 126);
        f.extend_from_slice(&(n as u16).to_be_bytes());
    } else {
        f.push(0x80 | 127);
        f.extend_from_slice(&(n as u64).to_be_bytes());
    }
    let key = [0x12, 0x34, 0x56, 0x78];
    f.extend_from_slice(&key);
    f.extend(payload.iter().enumerate().map(|(i, b)| b ^ key[i % 4]));
    s.write_all(&f)
}

/// Reads frames until a close frame (within 10 s: telemetry keeps arriving meanwhile, so a
/// server that never closes fails the test instead of hanging it); returns its code and reason.
pub fn read_close(s: &mut TcpStream) -> (u16, String) {
    let t0 = std::time::Instant::now();
    loop {
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "no close frame within 10 s"
        );
        let (op, p) = read_frame(s).expect("a close frame before the connection ends");
        if op == 8 {
            assert!(p.len() >= 2, "a close frame with a code");
            let code = u16::from_be_bytes([p[0], p[1]]);
            return (code, String::from_utf8_lossy(&p[2..]).into_owned());
        }
    }
}

/// A dry-run tune of the fast virtual maxon-re35 (`hostctl tune --json`), saved as
/// `{tag}-tune.json` in a directory of this test process.
pub fn tune_json(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stiffwall-ui-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{tag}-tune.json"));
    let out = Command::new(env!("CARGO_BIN_EXE_hostctl"))
        .args([
            "tune",
            "--dry-run",
            "--json",
            "--fast",
            "--device",
            "maxon-re35",
        ])
        .output()
        .expect("run hostctl tune");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::write(&path, &out.stdout).unwrap();
    path
}

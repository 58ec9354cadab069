//! A minimal blocking HTTP/1.1 client for talking to a gleaner server on loopback: what the
//! server's integration tests and its benchmark command use (keep-alive connections,
//! `Content-Length` and chunked bodies, multipart uploads). Not a general-purpose client.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::Duration;

/// A response: status, headers (names lower-cased) and body.
#[derive(Debug, Clone)]
pub struct Response {
    /// HTTP status code.
    pub status: u16,
    /// Headers in order, names lower-cased.
    pub headers: Vec<(String, String)>,
    /// The body.
    pub body: Vec<u8>,
}

impl Response {
    /// A header's value (name in any case).
    pub fn header(&self, name: &str) -> Option<&str> {
        let name = name.to_ascii_lowercase();
        self.headers
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| v.as_str())
    }

    /// The body as text (lossy).
    pub fn text(&self) -> String {
        String::from_utf8_lossy(&self.body).into_owned()
    }

    /// The body parsed as JSON.
    pub fn json(&self) -> serde_json::Result<serde_json::Value> {
        serde_json::from_slice(&self.body)
    }
}

/// One part of a multipart form.
#[derive(Debug, Clone)]
pub enum Part {
    /// A text field: name, value.
    Text(String, String),
    /// A file: field name, file name, content.
    File(String, String, Vec<u8>),
}

/// A multipart/form-data body and its content type.
pub fn multipart(parts: &[Part]) -> (String, Vec<u8>) {
    let boundary = "gleaner-test-boundary-7f3a9c";
    let mut body = Vec::new();
    for p in parts {
        body.extend_from_slice(format!("--{boundary}\r\n").as_bytes());
        match p {
            Part::Text(name, value) => {
                body.extend_from_slice(
                    format!("Content-Disposition: form-data; name=\"{name}\"\r\n\r\n{value}\r\n")
                        .as_bytes(),
                );
            }
            Part::File(name, file, bytes) => {
                body.extend_from_slice(
                    format!(
                        "Content-Disposition: form-data; name=\"{name}\"; filename=\"{file}\"\r\nContent-Type: application/octet-stream\r\n\r\n"
                    )
                    .as_bytes(),
                );
                body.extend_from_slice(bytes);
                body.extend_from_slice(b"\r\n");
            }
        }
    }
    body.extend_from_slice(format!("--{boundary}--\r\n").as_bytes());
    (format!("multipart/form-data; boundary={boundary}"), body)
}

/// A keep-alive connection to one server.
pub struct Client {
    addr: SocketAddr,
    conn: Option<BufReader<TcpStream>>,
    read_timeout: Duration,
}

/// How long a client waits for a response by default: a bound on a stuck server, not a
/// timing assertion.
pub const READ_TIMEOUT: Duration = Duration::from_secs(120);

impl Client {
    /// A client for the server at `addr` (connects on first use).
    pub fn new(addr: SocketAddr) -> Self {
        Self::with_read_timeout(addr, READ_TIMEOUT)
    }

    /// A client that waits up to `read_timeout` for each response (e.g. a benchmark whose
    /// requests queue behind a thousand others).
    pub fn with_read_timeout(addr: SocketAddr, read_timeout: Duration) -> Self {
        Self {
            addr,
            conn: None,
            read_timeout,
        }
    }

    /// GET `path`.
    pub fn get(&mut self, path: &str) -> std::io::Result<Response> {
        self.request("GET", path, &[], None)
    }

    /// POST a JSON body to `path`, with a bearer token if given.
    pub fn post_json(
        &mut self,
        path: &str,
        body: &serde_json::Value,
        token: Option<&str>,
    ) -> std::io::Result<Response> {
        let auth = token.map(|t| format!("Bearer {t}"));
        let mut headers = vec![("Content-Type", "application/json")];
        if let Some(a) = &auth {
            headers.push(("Authorization", a));
        }
        self.request("POST", path, &headers, Some(body.to_string().as_bytes()))
    }

    /// POST a multipart form to `path`, with a bearer token if given.
    pub fn post_multipart(
        &mut self,
        path: &str,
        parts: &[Part],
        token: Option<&str>,
    ) -> std::io::Result<Response> {
        let (content_type, body) = multipart(parts);
        let auth = token.map(|t| format!("Bearer {t}"));
        let mut headers = vec![("Content-Type", content_type.as_str())];
        if let Some(a) = &auth {
            headers.push(("Authorization", a));
        }
        self.request("POST", path, &headers, Some(&body))
    }

    /// Sends one request and reads its response; reconnects once if a kept-alive connection
    /// was closed by the server.
    pub fn request(
        &mut self,
        method: &str,
        path: &str,
        headers: &[(&str, &str)],
        body: Option<&[u8]>,
    ) -> std::io::Result<Response> {
        let mut head = format!("{method} {path} HTTP/1.1\r\nHost: {}\r\n", self.addr);
        for (n, v) in headers {
            head.push_str(&format!("{n}: {v}\r\n"));
        }
        if let Some(b) = body {
            head.push_str(&format!("Content-Length: {}\r\n", b.len()));
        }
        head.push_str("\r\n");
        let fresh = self.conn.is_none();
        match self.try_request(head.as_bytes(), body) {
            Ok(r) => Ok(r),
            Err(_) if !fresh => {
                self.conn = None;
                self.try_request(head.as_bytes(), body)
            }
            Err(e) => Err(e),
        }
    }

    /// Sends `raw` (a whole request: line, headers, blank line, body) as it is and reads one
    /// response: for requests the other methods cannot make (another `Host`, no `Host`).
    pub fn request_raw(&mut self, raw: &[u8]) -> std::io::Result<Response> {
        let conn = self.connection()?;
        conn.get_mut().write_all(raw)?;
        conn.get_mut().flush()?;
        let response = read_response(conn);
        if response.as_ref().map_or(true, closes) {
            self.conn = None;
        }
        response
    }

    /// The open connection, made first when there is none (no Nagle delay, reads time out
    /// after the client's read timeout).
    fn connection(&mut self) -> std::io::Result<&mut BufReader<TcpStream>> {
        if self.conn.is_none() {
            let s = TcpStream::connect(self.addr)?;
            s.set_nodelay(true)?;
            s.set_read_timeout(Some(self.read_timeout))?;
            self.conn = Some(BufReader::new(s));
        }
        Ok(self.conn.as_mut().expect("connected above"))
    }

    /// Sends `head` (request line, headers, blank line) and `body` on the connection and
    /// reads one response.
    fn try_request(&mut self, head: &[u8], body: Option<&[u8]>) -> std::io::Result<Response> {
        let conn = self.connection()?;
        let stream = conn.get_mut();
        stream.write_all(head)?;
        if let Some(b) = body {
            stream.write_all(b)?;
        }
        stream.flush()?;
        let response = read_response(conn)?;
        if closes(&response) {
            self.conn = None;
        }
        Ok(response)
    }
}

/// Whether the server closes the connection after `r` (`Connection: close`).
fn closes(r: &Response) -> bool {
    r.header("connection")
        .is_some_and(|c| c.eq_ignore_ascii_case("close"))
}

fn bad(what: &str) -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::InvalidData, what.to_string())
}

/// Reads one response from a connection (status line, headers, `Content-Length` or chunked
/// body).
pub fn read_response(r: &mut BufReader<TcpStream>) -> std::io::Result<Response> {
    let mut line = String::new();
    if r.read_line(&mut line)? == 0 {
        return Err(std::io::Error::new(
            std::io::ErrorKind::UnexpectedEof,
            "connection closed",
        ));
    }
    let status: u16 = line
        .split_whitespace()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| bad("bad status line"))?;
    let mut headers = Vec::new();
    loop {
        line.clear();
        r.read_line(&mut line)?;
        let l = line.trim_end();
        if l.is_empty() {
            break;
        }
        let (n, v) = l.split_once(':').ok_or_else(|| bad("bad header"))?;
        headers.push((n.trim().to_ascii_lowercase(), v.trim().to_string()));
    }
    let find = |name: &str| {
        headers
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.clone())
    };
    let mut body = Vec::new();
    if find("transfer-encoding").is_some_and(|v| v.eq_ignore_ascii_case("chunked")) {
        loop {
            line.clear();
            r.read_line(&mut line)?;
            let size = usize::from_str_radix(line.trim().split(';').next().unwrap_or(""), 16)
                .map_err(|_| bad("bad chunk size"))?;
            if size == 0 {
                line.clear();
                r.read_line(&mut line)?;
                break;
            }
            let start = body.len();
            body.resize(start + size, 0);
            r.read_exact(&mut body[start..])?;
            line.clear();
            r.read_line(&mut line)?;
        }
    } else if let Some(n) = find("content-length") {
        let n: usize = n.parse().map_err(|_| bad("bad content-length"))?;
        body.resize(n, 0);
        r.read_exact(&mut body)?;
    } else if status != 204 && status != 304 {
        r.read_to_end(&mut body)?;
    }
    Ok(Response {
        status,
        headers,
        body,
    })
}

//! The page's HTTP server, on 127.0.0.1 only: the page itself (embedded in
//! the binary), the newest frame as a PNG, the state as JSON, and the state
//! streamed as Server-Sent Events.
//!
//! | path | answer |
//! |---|---|
//! | `/` | the page |
//! | `/events` | `text/event-stream`: a `state` event (the JSON of `/state`) at every change |
//! | `/state` | the state: frame number, pass, spp, size, error, ... |
//! | `/frame.png` | the newest frame (header `X-Luster-Frame`: its number); 404 before the first |
//! | `/editor.js` | the editor component (CodeMirror 6, bundled by `tools/editor/build.sh`) |
//! | `/shaders` | the shader files the page may edit and each script's `params{}` ([`Editor::to_json`]) |
//! | `/shader/NAME` | GET: the text of listed file `NAME` (percent-encoded); POST: saves the body as it |
//! | `/params` | POST `{"shader": ID, "name": P, "value": V}`: overrides a parameter for the session (`null`: not) |
//! | `/params/reset` | POST: drops every override |
//!
//! Every other path answers 404, and a method a path does not take 405.
//! A POST may change only the files and parameters [`Editor`] lists.
//!
//! A small HTTP/1.1 server on `std::net`, heads parsed by [`request`]
//! (httparse): a few fixed paths need caps and timeouts, not an async runtime.
//! No client can stall or exhaust it:
//!
//! | what | limit | then |
//! |---|---|---|
//! | request head | [`MAX_HEAD`] bytes, [`MAX_FIELDS`](super::request::MAX_FIELDS) fields | 431, closed |
//! | request body | [`MAX_BODY`] (`Content-Length` only) | 413 before a byte of it is read, closed |
//! | time for a head | [`HEAD_TIME`] from the connection or the previous answer | closed (408 when part of it came) |
//! | time for a body | [`BODY_TIME`] | closed |
//! | time for an answer or an event | [`WRITE_TIME`] | closed |
//! | connections | [`MAX_CONNECTIONS`], a thread each; a new one closes the one waiting longest for a request, or gets 503 when all are being answered | |
//! | event streams | [`MAX_STREAMS`] of those connections | 503 |
//! | `Host`, `Origin` | see [`request::admit`] | 421, 403 |

use super::conns::Conns;
use super::editor::{Editor, Refused};
use super::hub::Hub;
use super::request::{self, Method, Refusal, Request, MAX_BODY, MAX_HEAD};
use luster_core::uri::percent_decode;
use std::io::{ErrorKind, Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The page, plain HTML and JavaScript with nothing fetched from elsewhere.
const PAGE: &str = include_str!("page.html");

/// The editor component: CodeMirror 6 (MIT licence), minified by
/// `tools/editor/build.sh` from the versions in its package-lock.json.
const EDITOR_JS: &str = include_str!("editor.js");

pub use super::conns::{MAX_CONNECTIONS, MAX_STREAMS};

/// Longest wait for a whole request head.
pub const HEAD_TIME: Duration = Duration::from_secs(5);

/// Longest wait for a whole request body, after its head.
pub const BODY_TIME: Duration = Duration::from_secs(10);

/// Longest time to write one answer or one event.
pub const WRITE_TIME: Duration = Duration::from_secs(10);

/// Longest silence on a stream: a comment line then finds closed tabs.
const KEEPALIVE: Duration = Duration::from_secs(10);

/// How long a refused request's remaining bytes are read and dropped before
/// closing, so that closing with unread bytes (a TCP reset) does not destroy
/// the refusal before the client reads it.
const LINGER: Duration = Duration::from_secs(1);

/// The listening socket and the open connections.
pub struct Server {
    listener: TcpListener,
    addr: SocketAddr,
    conns: Arc<Conns>,
}

/// Binds 127.0.0.1:`port` (0: any free port).
pub fn bind(port: u16) -> Result<Server, String> {
    let fail = |e: std::io::Error| {
        let why = match e.kind() {
            ErrorKind::AddrInUse => "the port is in use (try --port 0)".to_string(),
            _ => luster_core::file::io_reason(&e),
        };
        format!("cannot serve the page on 127.0.0.1:{port}: {why}")
    };
    let listener = TcpListener::bind(("127.0.0.1", port)).map_err(fail)?;
    let addr = listener.local_addr().map_err(fail)?;
    Ok(Server { listener, addr, conns: Arc::new(Conns::default()) })
}

impl Server {
    /// The address it listens on.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Accepts connections until the hub closes, each on a thread of its own
    /// up to [`MAX_CONNECTIONS`].
    pub fn serve(&self, hub: Arc<Hub>, editor: Arc<Editor>) {
        for conn in self.listener.incoming() {
            if hub.is_closed() {
                break;
            }
            let Ok(socket) = conn else {
                // Out of file descriptors, say: give the open ones time to end.
                std::thread::sleep(Duration::from_millis(50));
                continue;
            };
            let Some(id) = self.conns.admit(&socket) else {
                // Every connection is being answered: refuse at once, never
                // waiting on this client from the accepting thread.
                let mut socket = socket;
                let _ = socket.set_nonblocking(true);
                let busy = Refusal { status: 503, why: "the server is busy; try again" };
                let _ = write_answer(&mut socket, &Answer::refusal(busy), false, false);
                continue;
            };
            let (conns, hub, port) = (Arc::clone(&self.conns), Arc::clone(&hub), self.addr.port());
            let editor = Arc::clone(&editor);
            let spawned = std::thread::Builder::new().name("watch-http".into()).spawn(move || {
                let editor = &editor;
                Connection { socket, id, conns: &conns, hub: &hub, editor, port, buf: Vec::new() }.run();
                conns.leave(id);
            });
            if spawned.is_err() {
                self.conns.leave(id);
            }
        }
    }

    /// Closes every connection and ends [`Server::serve`] (the hub must be
    /// closed first).
    pub fn unblock(&self) {
        self.conns.close_all();
        // Wake the accepting thread, blocked in accept().
        let _ = TcpStream::connect_timeout(&self.addr, Duration::from_secs(1));
    }
}

/// An answer's body.
enum Body {
    Static(&'static [u8]),
    Owned(Vec<u8>),
    Shared(Arc<Vec<u8>>),
}

/// An answer to one request (the event stream aside).
struct Answer {
    status: u16,
    content_type: &'static str,
    body: Body,
    /// More header fields (name, value), ASCII written here.
    fields: Vec<(&'static str, String)>,
}

impl Answer {
    fn new(status: u16, content_type: &'static str, body: Body) -> Answer {
        Answer { status, content_type, body, fields: Vec::new() }
    }

    fn text(status: u16, text: &'static str) -> Answer {
        Answer::new(status, "text/plain; charset=utf-8", Body::Static(text.as_bytes()))
    }

    fn refusal(r: Refusal) -> Answer {
        Answer::text(r.status, r.why)
    }

    fn refused(r: Refused) -> Answer {
        Answer::new(r.status, "text/plain; charset=utf-8", Body::Owned(r.why.into_bytes()))
    }

    fn json(text: String) -> Answer {
        Answer::new(200, "application/json", Body::Owned(text.into_bytes()))
    }

    fn not_allowed(allow: &'static str) -> Answer {
        let mut a = Answer::text(405, "that method is not served at this path");
        a.fields.push(("Allow", allow.into()));
        a
    }
}

fn reason(status: u16) -> &'static str {
    match status {
        100 => "Continue",
        200 => "OK",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        409 => "Conflict",
        408 => "Request Timeout",
        413 => "Content Too Large",
        417 => "Expectation Failed",
        421 => "Misdirected Request",
        431 => "Request Header Fields Too Large",
        501 => "Not Implemented",
        503 => "Service Unavailable",
        505 => "HTTP Version Not Supported",
        _ => "",
    }
}

/// Writes `a` within [`WRITE_TIME`] (the head only when `head_only`).
fn write_answer(
    socket: &mut TcpStream,
    a: &Answer,
    head_only: bool,
    keep_alive: bool,
) -> std::io::Result<()> {
    let body: &[u8] = match &a.body {
        Body::Static(b) => b,
        Body::Owned(b) => b,
        Body::Shared(b) => b,
    };
    let mut head = format!(
        "HTTP/1.1 {} {}\r\nContent-Type: {}\r\nContent-Length: {}\r\nCache-Control: no-store\r\n\
         X-Content-Type-Options: nosniff\r\nCross-Origin-Resource-Policy: same-origin\r\n",
        a.status,
        reason(a.status),
        a.content_type,
        body.len()
    );
    for (name, value) in &a.fields {
        head.push_str(&format!("{name}: {value}\r\n"));
    }
    head.push_str(if keep_alive { "\r\n" } else { "Connection: close\r\n\r\n" });
    let end = Instant::now() + WRITE_TIME;
    write_by(socket, head.as_bytes(), end)?;
    if !head_only {
        write_by(socket, body, end)?;
    }
    socket.flush()
}

/// Writes all of `data` before `end`, however slowly the client reads.
fn write_by(socket: &mut TcpStream, data: &[u8], end: Instant) -> std::io::Result<()> {
    for chunk in data.chunks(64 * 1024) {
        let left = end.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return Err(ErrorKind::TimedOut.into());
        }
        socket.set_write_timeout(Some(left))?;
        socket.write_all(chunk)?;
    }
    Ok(())
}

/// What came of waiting for a request.
enum Next {
    Request(Request),
    /// The client closed, or the connection was closed for another.
    Closed,
    /// No whole head in time; whether part of one came.
    Late(bool),
    Refused(Refusal),
}

/// One client's connection: its requests, one after another.
struct Connection<'a> {
    socket: TcpStream,
    id: u64,
    conns: &'a Conns,
    hub: &'a Hub,
    editor: &'a Editor,
    port: u16,
    /// Bytes read and not yet used (a head being read, or what followed one).
    buf: Vec<u8>,
}

impl Connection<'_> {
    fn run(mut self) {
        let _ = self.socket.set_nodelay(true);
        loop {
            if !self.conns.mark(self.id, true) {
                return;
            }
            let req = match self.head() {
                Next::Request(r) => r,
                Next::Closed => return,
                Next::Late(partial) => {
                    if partial {
                        self.refuse(Refusal { status: 408, why: "the request came too slowly" });
                    }
                    return;
                }
                Next::Refused(r) => return self.refuse(r),
            };
            if let Err(r) = request::admit(&req, self.port) {
                return self.refuse(r);
            }
            let Some(body) = self.body(&req) else { return };
            if !self.conns.mark(self.id, false) {
                return;
            }
            if !self.answer(&req, &body) || !req.keep_alive {
                return;
            }
        }
    }

    /// Reads until a whole head is buffered, within [`HEAD_TIME`].
    fn head(&mut self) -> Next {
        let end = Instant::now() + HEAD_TIME;
        let mut chunk = [0u8; 4096];
        // What is buffered (a pipelined request) is parsed before reading.
        let mut fresh = !self.buf.is_empty();
        loop {
            if fresh {
                match request::parse(&self.buf) {
                    Ok(Some(r)) => {
                        self.buf.drain(..r.head_len);
                        return Next::Request(r);
                    }
                    Ok(None) => {}
                    Err(r) => return Next::Refused(r),
                }
            }
            let late = Next::Late(!self.buf.is_empty());
            let left = end.saturating_duration_since(Instant::now());
            if left.is_zero() || self.socket.set_read_timeout(Some(left)).is_err() {
                return late;
            }
            match self.socket.read(&mut chunk) {
                Ok(0) => return Next::Closed,
                Ok(n) => {
                    self.buf.extend_from_slice(&chunk[..n]);
                    // A head ends with a line feed; until one comes (or the
                    // cap is passed) parsing again tells nothing new.
                    fresh = chunk[..n].contains(&b'\n') || self.buf.len() > MAX_HEAD;
                }
                Err(e) if e.kind() == ErrorKind::Interrupted => fresh = false,
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => return late,
                Err(_) => return Next::Closed,
            }
        }
    }

    /// Reads the body `req` announced (at most [`MAX_BODY`], checked by the
    /// parser), within [`BODY_TIME`]; `None` when it does not come whole.
    fn body(&mut self, req: &Request) -> Option<Vec<u8>> {
        let len = req.body_len.min(MAX_BODY);
        let mut body: Vec<u8> = self.buf.drain(..len.min(self.buf.len())).collect();
        if body.len() < len && req.expect_continue {
            write_by(&mut self.socket, b"HTTP/1.1 100 Continue\r\n\r\n", Instant::now() + WRITE_TIME).ok()?;
        }
        let end = Instant::now() + BODY_TIME;
        // Grown as bytes come, so a body announced and never sent costs nothing.
        let mut chunk = [0u8; 16 * 1024];
        while body.len() < len {
            let left = end.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return None;
            }
            self.socket.set_read_timeout(Some(left)).ok()?;
            let want = (len - body.len()).min(chunk.len());
            match self.socket.read(&mut chunk[..want]) {
                Ok(0) => return None,
                Ok(n) => body.extend_from_slice(&chunk[..n]),
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(_) => return None,
            }
        }
        Some(body)
    }

    /// Answers a refused request and closes the connection, reading what
    /// the client still sends for a moment so the answer reaches it.
    fn refuse(&mut self, r: Refusal) {
        if write_answer(&mut self.socket, &Answer::refusal(r), false, false).is_err() {
            return;
        }
        let _ = self.socket.shutdown(Shutdown::Write);
        let end = Instant::now() + LINGER;
        let mut sink = [0u8; 16 * 1024];
        for _ in 0..64 {
            let left = end.saturating_duration_since(Instant::now());
            if left.is_zero() || self.socket.set_read_timeout(Some(left)).is_err() {
                return;
            }
            if !matches!(self.socket.read(&mut sink), Ok(n) if n > 0) {
                return;
            }
        }
    }

    /// Answers an admitted request; `false` when the connection is done.
    fn answer(&mut self, req: &Request, body: &[u8]) -> bool {
        let head_only = req.method == Method::Head;
        let get = matches!(req.method, Method::Get | Method::Head);
        let post = req.method == Method::Post;
        let path = req.path.as_str();
        let a = if let Some(name) = path.strip_prefix("/shader/") {
            match percent_decode(name) {
                None => Answer::text(400, "the file name is not percent-encoded UTF-8"),
                Some(name) if get => match self.editor.read(&name) {
                    Ok(text) => Answer::new(200, "text/plain; charset=utf-8", Body::Owned(text.into_bytes())),
                    Err(r) => Answer::refused(r),
                },
                Some(name) if post => match self.editor.save(&name, body) {
                    Ok(()) => Answer::text(200, "saved"),
                    Err(r) => Answer::refused(r),
                },
                Some(_) => Answer::not_allowed("GET, HEAD, POST"),
            }
        } else if matches!(path, "/params" | "/params/reset") {
            if !post {
                Answer::not_allowed("POST")
            } else if path == "/params/reset" {
                self.editor.reset();
                Answer::json(self.editor.to_json())
            } else {
                match self.set_param(body) {
                    Ok(()) => Answer::json(self.editor.to_json()),
                    Err(r) => Answer::refused(r),
                }
            }
        } else if !get {
            let known = matches!(
                path,
                "/" | "/index.html" | "/state" | "/frame.png" | "/events" | "/editor.js" | "/shaders"
            );
            if known {
                Answer::not_allowed("GET, HEAD")
            } else {
                Answer::text(404, "not found")
            }
        } else {
            match path {
                "/events" => {
                    self.stream(head_only);
                    return false;
                }
                "/" | "/index.html" => {
                    Answer::new(200, "text/html; charset=utf-8", Body::Static(PAGE.as_bytes()))
                }
                "/editor.js" => {
                    Answer::new(200, "text/javascript; charset=utf-8", Body::Static(EDITOR_JS.as_bytes()))
                }
                "/shaders" => Answer::json(self.editor.to_json()),
                "/state" => Answer::json(self.hub.snapshot().to_json()),
                "/frame.png" => match self.hub.snapshot().frame {
                    Some(f) => {
                        let mut a = Answer::new(200, "image/png", Body::Shared(f.png));
                        a.fields.push(("X-Luster-Frame", f.number.to_string()));
                        a
                    }
                    None => Answer::text(404, "no frame yet"),
                },
                _ => Answer::text(404, "not found"),
            }
        };
        write_answer(&mut self.socket, &a, head_only, req.keep_alive).is_ok()
    }

    /// `POST /params`: `{"shader": ID, "name": P, "value": V}`.
    fn set_param(&self, body: &[u8]) -> Result<(), Refused> {
        let bad = |why: &str| Refused { status: 400, why: why.to_string() };
        let v: serde_json::Value = serde_json::from_slice(body).map_err(|_| bad("the body is not JSON"))?;
        let (Some(id), Some(name), Some(value)) = (v["shader"].as_str(), v["name"].as_str(), v.get("value"))
        else {
            return Err(bad("expected {\"shader\": id, \"name\": parameter, \"value\": value}"));
        };
        self.editor.set(id, name, value)
    }

    /// Streams the state as Server-Sent Events until the client leaves or
    /// the hub closes.
    fn stream(&mut self, head_only: bool) {
        if !self.conns.start_stream() {
            let busy = Answer::text(503, "too many open pages");
            let _ = write_answer(&mut self.socket, &busy, head_only, false);
            return;
        }
        self.events(head_only);
        self.conns.end_stream();
    }

    fn events(&mut self, head_only: bool) {
        let head = "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\n\
                    Connection: close\r\n\r\n";
        let send = |socket: &mut TcpStream, text: &str| {
            write_by(socket, text.as_bytes(), Instant::now() + WRITE_TIME)
                .and_then(|()| socket.flush())
                .is_ok()
        };
        if !send(&mut self.socket, head) || head_only {
            return;
        }
        let mut state = self.hub.snapshot();
        loop {
            if !send(&mut self.socket, &format!("event: state\ndata: {}\n\n", state.to_json())) {
                return;
            }
            let seq = state.seq;
            loop {
                if let Some(s) = self.hub.wait_newer(seq, KEEPALIVE) {
                    state = s;
                    break;
                }
                if self.hub.is_closed() || !send(&mut self.socket, ": keep-alive\n\n") {
                    return;
                }
            }
        }
    }
}

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

use super::hub::Hub;
use std::io::Write;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;
use tiny_http::{Header, Request, Response, Server};

/// The page, plain HTML and JavaScript with nothing fetched from elsewhere.
const PAGE: &str = include_str!("page.html");

/// Event streams open at once; more are refused (each holds a thread).
const MAX_STREAMS: usize = 32;

/// Longest silence on a stream: a comment line then finds closed tabs.
const KEEPALIVE: Duration = Duration::from_secs(10);

/// Binds 127.0.0.1:`port` (0: any free port).
pub fn bind(port: u16) -> Result<Server, String> {
    Server::http(("127.0.0.1", port)).map_err(|e| {
        let why = match e.downcast_ref::<std::io::Error>() {
            Some(io) if io.kind() == std::io::ErrorKind::AddrInUse => {
                "the port is in use (try --port 0)".to_string()
            }
            Some(io) => luster_core::file::io_reason(io),
            None => e.to_string(),
        };
        format!("cannot serve the page on 127.0.0.1:{port}: {why}")
    })
}

/// Answers requests until the hub closes.
pub fn serve(server: Arc<Server>, hub: Arc<Hub>) {
    let streams = Arc::new(AtomicUsize::new(0));
    while !hub.is_closed() {
        let req = match server.recv_timeout(Duration::from_millis(250)) {
            Ok(Some(r)) => r,
            Ok(None) => continue,
            Err(_) => break,
        };
        let path = req.url().split('?').next().unwrap_or("").to_string();
        match path.as_str() {
            "/events" => {
                if streams.fetch_add(1, Ordering::SeqCst) >= MAX_STREAMS {
                    streams.fetch_sub(1, Ordering::SeqCst);
                    let _ = req.respond(Response::from_string("too many open pages").with_status_code(503));
                    continue;
                }
                let (hub, open) = (Arc::clone(&hub), Arc::clone(&streams));
                let spawned = std::thread::Builder::new().name("watch-events".into()).spawn(move || {
                    stream(req, &hub);
                    open.fetch_sub(1, Ordering::SeqCst);
                });
                if spawned.is_err() {
                    streams.fetch_sub(1, Ordering::SeqCst);
                }
            }
            _ => answer(req, &path, &hub),
        }
    }
}

fn header(name: &str, value: &str) -> Header {
    // Both halves are ASCII constants or numbers written here.
    Header::from_bytes(name.as_bytes(), value.as_bytes()).unwrap_or_else(|()| unreachable!("ASCII header"))
}

/// Every answer but the event stream.
fn answer(req: Request, path: &str, hub: &Hub) {
    let no_store = header("Cache-Control", "no-store");
    let r = match path {
        "/" | "/index.html" => req.respond(
            Response::from_string(PAGE)
                .with_header(header("Content-Type", "text/html; charset=utf-8"))
                .with_header(no_store),
        ),
        "/state" => req.respond(
            Response::from_string(hub.snapshot().to_json())
                .with_header(header("Content-Type", "application/json"))
                .with_header(no_store),
        ),
        "/frame.png" => match hub.snapshot().frame {
            Some(f) => req.respond(
                Response::from_data(f.png.as_slice())
                    .with_header(header("Content-Type", "image/png"))
                    .with_header(header("X-Luster-Frame", &f.number.to_string()))
                    .with_header(no_store),
            ),
            None => req.respond(Response::from_string("no frame yet").with_status_code(404)),
        },
        _ => req.respond(Response::from_string("not found").with_status_code(404)),
    };
    // A client that went away mid-answer is no concern of the session.
    let _ = r;
}

/// Streams the state as Server-Sent Events until the client leaves or the
/// hub closes.
fn stream(req: Request, hub: &Hub) {
    let mut out = req.into_writer();
    let head = "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\n\
                Connection: close\r\n\r\n";
    if out.write_all(head.as_bytes()).and_then(|()| out.flush()).is_err() {
        return;
    }
    let mut state = hub.snapshot();
    loop {
        let event = format!("event: state\ndata: {}\n\n", state.to_json());
        if out.write_all(event.as_bytes()).and_then(|()| out.flush()).is_err() {
            return;
        }
        let seq = state.seq;
        loop {
            if let Some(s) = hub.wait_newer(seq, KEEPALIVE) {
                state = s;
                break;
            }
            if hub.is_closed() || out.write_all(b": keep-alive\n\n").and_then(|()| out.flush()).is_err() {
                return;
            }
        }
    }
}

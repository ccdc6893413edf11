//! The watch server's request parser: bytes in, a request head (or a refusal
//! with its status code) out, with no I/O, so unit tests and the
//! `watch_request` fuzz target drive exactly what the server runs.
//!
//! The request line and header fields are split by `httparse` (hyper's
//! parser); this module adds the limits and the meaning:
//!
//! | what | rule | refusal |
//! |---|---|---|
//! | head | at most [`MAX_HEAD`] bytes and [`MAX_FIELDS`] fields | 431 |
//! | request line | `METHOD /path HTTP/1.x` (origin form) | 400; other versions 505 |
//! | `Host` | exactly one | 400 |
//! | `Content-Length` | at most one, digits only, at most [`MAX_BODY`] | 400; too large 413 |
//! | `Transfer-Encoding` | not supported (no chunked bodies) | 501 |
//! | `Expect` | only `100-continue` | 417 |
//!
//! [`admit`] then checks who asks: the `Host` must name this server
//! (`127.0.0.1:PORT`, `localhost:PORT` or `[::1]:PORT`), or a page on any
//! name that resolves to 127.0.0.1 could read `/state` (DNS rebinding): 421.
//! A request that may change something (any method but GET and HEAD) whose
//! `Origin` is another site's is refused (a form on another site posting
//! here): 403.

/// Longest request head (request line and fields): browsers send under 2
/// KiB, but cookies set for `localhost` by other local servers come along.
pub const MAX_HEAD: usize = 32 * 1024;

/// Most header fields in a head.
pub const MAX_FIELDS: usize = 64;

/// Largest request body (room for a shader script saved from the page).
pub const MAX_BODY: usize = 4 * 1024 * 1024;

/// The request methods the server tells apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// `GET`.
    Get,
    /// `HEAD`: a GET answered without its body.
    Head,
    /// `POST`.
    Post,
    /// Any other method.
    Other,
}

/// A parsed request head.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Request {
    /// The method.
    pub method: Method,
    /// The path, without the query (starts with `/`).
    pub path: String,
    /// The `Host` field, as sent.
    pub host: String,
    /// The `Origin` field, when sent.
    pub origin: Option<String>,
    /// Bytes of the head, up to and including its empty line.
    pub head_len: usize,
    /// Bytes of the body that follows (`Content-Length`; 0 without one).
    pub body_len: usize,
    /// Whether the connection may carry another request after this one
    /// (HTTP/1.1 without `Connection: close`).
    pub keep_alive: bool,
    /// Whether the client waits for `100 Continue` before sending the body.
    pub expect_continue: bool,
}

/// Why a request is refused: the status code and a short sentence for the
/// answer's body (never a piece of the request).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Refusal {
    /// The HTTP status code.
    pub status: u16,
    /// The answer's text.
    pub why: &'static str,
}

const fn refuse(status: u16, why: &'static str) -> Refusal {
    Refusal { status, why }
}

/// Parses the request head at the start of `buf` (which may hold its body
/// and further requests after it). `Ok(None)`: the head is not complete yet
/// and more bytes may complete it.
pub fn parse(buf: &[u8]) -> Result<Option<Request>, Refusal> {
    // Parse only the first MAX_HEAD bytes: a head that does not end within
    // them is refused however much more is buffered.
    let window = &buf[..buf.len().min(MAX_HEAD)];
    let mut fields = [httparse::EMPTY_HEADER; MAX_FIELDS];
    let mut req = httparse::Request::new(&mut fields);
    let head_len = match req.parse(window) {
        Ok(httparse::Status::Complete(n)) => n,
        Ok(httparse::Status::Partial) if buf.len() > MAX_HEAD => {
            return Err(refuse(431, "the request head is too long"));
        }
        Ok(httparse::Status::Partial) => return Ok(None),
        Err(httparse::Error::TooManyHeaders) => {
            return Err(refuse(431, "the request has too many header fields"))
        }
        Err(httparse::Error::Version) => return Err(refuse(505, "only HTTP/1.0 and HTTP/1.1 are served")),
        Err(_) => return Err(refuse(400, "the request is malformed")),
    };
    let method = match req.method {
        Some("GET") => Method::Get,
        Some("HEAD") => Method::Head,
        Some("POST") => Method::Post,
        _ => Method::Other,
    };
    let target = req.path.unwrap_or_default();
    if !target.starts_with('/') {
        return Err(refuse(400, "the request target must be a path"));
    }
    let path = target.split(['?', '#']).next().unwrap_or_default().to_string();

    let mut host = None;
    let mut origin = None;
    let mut length: Option<usize> = None;
    let mut close = req.version != Some(1);
    let mut expect_continue = false;
    for f in req.headers.iter() {
        let name = f.name;
        if name.eq_ignore_ascii_case("host") {
            if host.is_some() {
                return Err(refuse(400, "the request has more than one Host"));
            }
            host = Some(visible(f.value).ok_or(refuse(400, "the Host is malformed"))?);
        } else if name.eq_ignore_ascii_case("origin") {
            if origin.is_some() {
                return Err(refuse(400, "the request has more than one Origin"));
            }
            origin = Some(visible(f.value).ok_or(refuse(400, "the Origin is malformed"))?);
        } else if name.eq_ignore_ascii_case("content-length") {
            // Two lengths, even equal ones, mean a proxy and a server may
            // split the stream differently: refuse rather than pick one.
            if length.is_some() {
                return Err(refuse(400, "the request has more than one Content-Length"));
            }
            length = Some(content_length(f.value)?);
        } else if name.eq_ignore_ascii_case("transfer-encoding") {
            return Err(refuse(501, "request bodies must come with a Content-Length"));
        } else if name.eq_ignore_ascii_case("connection") {
            close |= tokens(f.value).any(|t| t.eq_ignore_ascii_case(b"close"));
        } else if name.eq_ignore_ascii_case("expect") {
            if !trim(f.value).eq_ignore_ascii_case(b"100-continue") {
                return Err(refuse(417, "only Expect: 100-continue is understood"));
            }
            expect_continue = true;
        }
    }
    let host = host.ok_or(refuse(400, "the request has no Host"))?;
    Ok(Some(Request {
        method,
        path,
        host,
        origin,
        head_len,
        body_len: length.unwrap_or(0),
        keep_alive: !close,
        expect_continue,
    }))
}

/// Whether this server on `port` may answer `req`: its Host names it and,
/// for a request that may change something, its Origin (when sent) is the
/// page's own.
pub fn admit(req: &Request, port: u16) -> Result<(), Refusal> {
    if !local(&req.host, port) {
        return Err(refuse(421, "this server answers only to 127.0.0.1, localhost and [::1] on its port"));
    }
    let changes = !matches!(req.method, Method::Get | Method::Head);
    let foreign = req.origin.as_deref().is_some_and(|o| {
        o.get(..7).is_none_or(|scheme| !scheme.eq_ignore_ascii_case("http://")) || !local(&o[7..], port)
    });
    if changes && foreign {
        return Err(refuse(403, "requests that change something are taken only from the page itself"));
    }
    Ok(())
}

/// Whether `authority` (`name:port`) is one of this server's names with its
/// port (which a browser leaves out when it is 80).
fn local(authority: &str, port: u16) -> bool {
    let (name, given) = match authority.rsplit_once(':') {
        Some((n, p)) if !authority.ends_with(']') => (n, Some(p)),
        _ => (authority, None),
    };
    let port_ok = match given {
        Some(p) => p == port.to_string(),
        None => port == 80,
    };
    port_ok && ["127.0.0.1", "localhost", "[::1]"].iter().any(|n| name.eq_ignore_ascii_case(n))
}

/// A field value of visible ASCII (and inner spaces), trimmed.
fn visible(value: &[u8]) -> Option<String> {
    let v = trim(value);
    let ok = v.iter().all(|&b| b == b' ' || b == b'\t' || b.is_ascii_graphic());
    ok.then(|| String::from_utf8_lossy(v).into_owned())
}

/// A `Content-Length`: decimal digits only; a value over [`MAX_BODY`] is
/// refused as too large without being converted, whatever its digits.
fn content_length(value: &[u8]) -> Result<usize, Refusal> {
    let v = trim(value);
    if v.is_empty() || !v.iter().all(u8::is_ascii_digit) {
        return Err(refuse(400, "the Content-Length is not a number"));
    }
    let digits = &v[v.iter().position(|&b| b != b'0').unwrap_or(v.len())..];
    let too_large = refuse(413, "the request body is larger than 4 MiB");
    if digits.len() > 8 {
        return Err(too_large);
    }
    let n = digits.iter().fold(0usize, |n, &d| n * 10 + usize::from(d - b'0'));
    if n > MAX_BODY {
        return Err(too_large);
    }
    Ok(n)
}

fn trim(v: &[u8]) -> &[u8] {
    v.trim_ascii()
}

/// The comma-separated tokens of a field value.
fn tokens(v: &[u8]) -> impl Iterator<Item = &[u8]> {
    v.split(|&b| b == b',').map(trim).filter(|t| !t.is_empty())
}

/// The `watch_request` fuzz target's body: parses `data` as a connection
/// reads it (a head, its body, the next head, ...) and panics when the
/// parser breaks a promise the server relies on: a head within the caps, a
/// path that starts with `/`, the same head from its own bytes alone, and
/// no head from any shorter prefix (so a head split over several reads
/// parses as it would whole).
pub fn fuzz(data: &[u8]) {
    let mut rest = data;
    for _ in 0..64 {
        let req = match parse(rest) {
            Ok(Some(r)) => r,
            Ok(None) => {
                assert!(rest.len() <= MAX_HEAD, "more than MAX_HEAD bytes without a head or a refusal");
                return;
            }
            Err(r) => {
                assert!(matches!(r.status, 400 | 413 | 417 | 431 | 501 | 505), "unexpected refusal {r:?}");
                return;
            }
        };
        assert!(req.head_len > 0 && req.head_len <= rest.len().min(MAX_HEAD), "head length {}", req.head_len);
        assert!(req.body_len <= MAX_BODY && req.path.starts_with('/'), "{req:?}");
        assert_eq!(parse(&rest[..req.head_len]), Ok(Some(req.clone())), "the head alone parses alike");
        for cut in [req.head_len - 1, req.head_len / 2, 1] {
            assert_eq!(parse(&rest[..cut.min(req.head_len - 1)]), Ok(None), "a prefix of {cut} bytes");
        }
        for port in [80, 8795] {
            let _ = admit(&req, port);
        }
        rest = &rest[(req.head_len + req.body_len).min(rest.len())..];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok(text: &str) -> Request {
        parse(text.as_bytes()).unwrap_or_else(|r| panic!("{text:?}: {r:?}")).expect("a whole head")
    }

    fn status(text: &[u8]) -> u16 {
        match parse(text) {
            Err(r) => r.status,
            other => panic!("{:?} parsed: {other:?}", String::from_utf8_lossy(text)),
        }
    }

    const HOST: &str = "Host: 127.0.0.1:8795\r\n";

    #[test]
    fn a_plain_get() {
        let text = format!("GET /frame.png?n=3 HTTP/1.1\r\n{HOST}Accept: */*\r\n\r\nNEXT");
        let r = ok(&text);
        assert_eq!(
            (r.method, r.path.as_str(), r.host.as_str()),
            (Method::Get, "/frame.png", "127.0.0.1:8795")
        );
        assert_eq!((r.head_len, r.body_len, r.keep_alive), (text.len() - 4, 0, true));
        assert_eq!(admit(&r, 8795), Ok(()));
    }

    #[test]
    fn every_prefix_of_a_head_asks_for_more() {
        let text =
            format!("POST /x HTTP/1.1\r\n{HOST}Content-Length: 3\r\nOrigin: http://localhost:8795\r\n\r\n");
        for n in 0..text.len() {
            assert_eq!(parse(&text.as_bytes()[..n]), Ok(None), "{n} bytes");
        }
        let r = ok(&text);
        assert_eq!((r.body_len, r.origin.as_deref()), (3, Some("http://localhost:8795")));
    }

    #[test]
    fn the_head_and_the_field_count_are_capped() {
        let long = format!("GET / HTTP/1.1\r\n{HOST}X: {}\r\n\r\n", "a".repeat(MAX_HEAD));
        assert_eq!(status(long.as_bytes()), 431);
        // Unfinished and already past the cap: refused now, not read on.
        assert_eq!(status(&long.as_bytes()[..MAX_HEAD + 1]), 431);
        assert_eq!(parse(&long.as_bytes()[..MAX_HEAD]), Ok(None));
        let many: String = (0..MAX_FIELDS).map(|i| format!("X-{i}: 1\r\n")).collect();
        assert_eq!(status(format!("GET / HTTP/1.1\r\n{HOST}{many}\r\n").as_bytes()), 431);
        let fits: String = (0..MAX_FIELDS - 1).map(|i| format!("X-{i}: 1\r\n")).collect();
        ok(&format!("GET / HTTP/1.1\r\n{HOST}{fits}\r\n"));
    }

    #[test]
    fn content_length_is_one_number_within_the_cap() {
        let with = |fields: &str| format!("POST / HTTP/1.1\r\n{HOST}{fields}\r\n");
        assert_eq!(ok(&with("Content-Length: 4194304\r\n")).body_len, MAX_BODY);
        assert_eq!(ok(&with("Content-Length: 0000012\r\n")).body_len, 12);
        for huge in ["4194305", "99999999999999", "18446744073709551616", &"9".repeat(400)] {
            assert_eq!(status(with(&format!("Content-Length: {huge}\r\n")).as_bytes()), 413, "{huge}");
        }
        for bad in ["-1", "1e3", "0x10", "", "1 2", "+5", "5,5", "٣"] {
            assert_eq!(status(with(&format!("Content-Length: {bad}\r\n")).as_bytes()), 400, "{bad:?}");
        }
        assert_eq!(status(with("Content-Length: 5\r\nContent-Length: 5\r\n").as_bytes()), 400);
        assert_eq!(status(with("Content-Length: 5\r\ncontent-length: 6\r\n").as_bytes()), 400);
    }

    #[test]
    fn transfer_encodings_and_unknown_expectations_are_refused() {
        let with = |fields: &str| format!("POST / HTTP/1.1\r\n{HOST}{fields}\r\n");
        assert_eq!(status(with("Transfer-Encoding: chunked\r\n").as_bytes()), 501);
        assert_eq!(status(with("Content-Length: 3\r\nTransfer-Encoding: chunked\r\n").as_bytes()), 501);
        assert_eq!(status(with("Expect: something-else\r\n").as_bytes()), 417);
        assert!(ok(&with("Content-Length: 3\r\nExpect: 100-Continue\r\n")).expect_continue);
    }

    #[test]
    fn malformed_heads_are_bad_requests() {
        for text in [
            "GET / HTTP/1.1\r\nHost: a\r\nHost: b\r\n\r\n".to_string(),
            "GET / HTTP/1.1\r\n\r\n".to_string(),
            format!("GET http://127.0.0.1:8795/ HTTP/1.1\r\n{HOST}\r\n"),
            format!("OPTIONS * HTTP/1.1\r\n{HOST}\r\n"),
            format!("GET / HTTP/1.1\r\n{HOST}Bad Name: x\r\n\r\n"),
            format!("GET / HTTP/1.1\r\n{HOST}X: a\0b\r\n\r\n"),
            format!("GET / HTTP/1.1\r\n{HOST}Origin: a\r\nOrigin: b\r\n\r\n"),
            "GET / HTTP/1.1\r\nHost: \x7f\r\n\r\n".to_string(),
            "\u{1b}[2J / HTTP/1.1\r\n\r\n".to_string(),
        ] {
            assert_eq!(status(text.as_bytes()), 400, "{text:?}");
        }
        assert_eq!(status(format!("GET / HTTP/2.0\r\n{HOST}\r\n").as_bytes()), 505);
        assert_eq!(status(b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n"), 505);
    }

    #[test]
    fn connection_close_and_http_1_0_end_the_connection() {
        assert!(!ok(&format!("GET / HTTP/1.1\r\n{HOST}Connection: keep-alive, Close\r\n\r\n")).keep_alive);
        assert!(!ok(&format!("GET / HTTP/1.0\r\n{HOST}\r\n")).keep_alive);
        assert!(ok(&format!("GET / HTTP/1.1\r\n{HOST}Connection: keep-alive\r\n\r\n")).keep_alive);
    }

    #[test]
    fn only_this_servers_names_are_admitted() {
        let get = |host: &str| ok(&format!("GET /state HTTP/1.1\r\nHost: {host}\r\n\r\n"));
        for host in ["127.0.0.1:8795", "localhost:8795", "LOCALHOST:8795", "[::1]:8795"] {
            assert_eq!(admit(&get(host), 8795), Ok(()), "{host}");
        }
        for host in [
            "evil.example",
            "evil.example:8795",
            "localhost.evil.example:8795",
            "127.0.0.1:80",
            "127.0.0.1",
            "127.0.0.1:08795",
            "127.0.0.1:8795:8795",
            "[::1]",
            "[::1]:8795]",
            "::1:8795",
            ":8795",
            "127.0.0.2:8795",
        ] {
            assert_eq!(admit(&get(host), 8795).map_err(|r| r.status), Err(421), "{host}");
        }
        // Port 80 is left out of the Host by browsers.
        assert_eq!(admit(&get("localhost"), 80), Ok(()));
        assert_eq!(admit(&get("localhost:80"), 80), Ok(()));
        assert_eq!(admit(&get("[::1]"), 80), Ok(()));
    }

    #[test]
    fn a_foreign_origin_may_read_nothing_new_and_change_nothing() {
        let req = |method: &str, origin: &str| {
            ok(&format!("{method} /state HTTP/1.1\r\n{HOST}Origin: {origin}\r\nContent-Length: 0\r\n\r\n"))
        };
        for origin in ["http://127.0.0.1:8795", "http://localhost:8795", "HTTP://[::1]:8795"] {
            assert_eq!(admit(&req("POST", origin), 8795), Ok(()), "{origin}");
        }
        for origin in
            ["http://evil.example", "null", "https://127.0.0.1:8795", "http://127.0.0.1:1", "http:/"]
        {
            for method in ["POST", "PUT", "DELETE"] {
                assert_eq!(
                    admit(&req(method, origin), 8795).map_err(|r| r.status),
                    Err(403),
                    "{method} {origin}"
                );
            }
            // A GET changes nothing and the browser keeps its answer from
            // the foreign page (no CORS header); the Host check covers rebinding.
            assert_eq!(admit(&req("GET", origin), 8795), Ok(()), "GET {origin}");
        }
        let no_origin = ok(&format!("POST /state HTTP/1.1\r\n{HOST}\r\n"));
        assert_eq!(admit(&no_origin, 8795), Ok(()), "a local tool sends no Origin");
    }

    #[test]
    fn pipelined_requests_parse_one_after_another() {
        let one = format!("POST /a HTTP/1.1\r\n{HOST}Content-Length: 4\r\n\r\nbody");
        let two = format!("GET /b HTTP/1.1\r\n{HOST}\r\n");
        let all = format!("{one}{two}");
        let first = ok(&all);
        assert_eq!((first.path.as_str(), first.body_len), ("/a", 4));
        let second = ok(&all[first.head_len + first.body_len..]);
        assert_eq!(second.path, "/b");
        fuzz(all.as_bytes());
    }
}

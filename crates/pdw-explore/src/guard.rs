//! Who may use the server: every request is checked before it is routed, so a refused one
//! never reaches a handler (no file is read, no computation starts, no body is read).
//!
//! The threat is a web page the user visits (it can make the browser send requests to
//! 127.0.0.1, and, by DNS rebinding, make its own host name resolve there), and another user of
//! the machine (anyone can connect to the loopback address). The checks, in order:
//! 1. **Host** must name this server: the bound address with its port, or `localhost` with the
//!    port (a server bound to the unspecified address also takes any IP literal with the port).
//!    A rebound host name (`rebind.attacker.example:8737`) is refused: 403.
//! 2. **Origin**, when sent, must be the server's own (`http://` + the Host): a page of another
//!    site, or of another port of the same host, is refused: 403. So is `Sec-Fetch-Site:
//!    cross-site` or `same-site` on the API (a no-cors request carries no Origin but this).
//! 3. **The session token** ([`Token`], 32 random bytes in hex, printed in the URL) is required
//!    on every `/api/` request: the cookie the page receives when loaded with `?token=…`, an
//!    `Authorization: token …` header, or a `token` query parameter. Missing or wrong: 403.
//! 4. **API POSTs** must be `Content-Type: application/json` (a cross-site form or `text/plain`
//!    POST needs no preflight; JSON does): 415.
//!
//! Then a POST body is read with a deadline ([`Limits::body_timeout`]) and the size cap
//! ([`crate::MAX_BODY`]): a client that sends its body slowly is answered 408 and dropped.

use crate::error::ApiError;
use crate::MAX_BODY;
use axum::body::Body;
use axum::extract::{Request, State};
use axum::http::{header, HeaderMap, Method, StatusCode};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use std::net::{IpAddr, SocketAddr};
use std::sync::Arc;
use std::time::Duration;

/// Bytes of randomness in a session token (64 hex digits).
pub const TOKEN_BYTES: usize = 32;

/// A session token: random, made once per server.
#[derive(Clone)]
pub struct Token(String);

impl Token {
    /// 32 bytes of `/dev/urandom` in hex.
    pub fn random() -> Result<Token, String> {
        Ok(Token(hex(&random_bytes(TOKEN_BYTES)?)))
    }

    /// The token as text (64 hex digits).
    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// Whether `given` is this token, compared in time independent of where they differ.
    pub fn matches(&self, given: &str) -> bool {
        let (a, b) = (self.0.as_bytes(), given.as_bytes());
        a.len() == b.len() && a.iter().zip(b).fold(0u8, |d, (x, y)| d | (x ^ y)) == 0
    }
}

/// `n` bytes read from `/dev/urandom`.
pub fn random_bytes(n: usize) -> Result<Vec<u8>, String> {
    use std::io::Read;
    let mut buf = vec![0u8; n];
    std::fs::File::open("/dev/urandom")
        .and_then(|mut f| f.read_exact(&mut buf))
        .map_err(|e| format!("cannot read /dev/urandom for a session token: {e}"))?;
    Ok(buf)
}

/// Lower-case hex of `b`.
pub fn hex(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02x}")).collect()
}

/// Time limits of a connection.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    /// Time a connection has to send a complete request head (each request of a kept-alive
    /// connection too); then it is closed.
    pub header_timeout: Duration,
    /// Time a POST has to send its body once its head is in: then 408.
    pub body_timeout: Duration,
}

/// What the checks compare against.
pub struct Guard {
    pub token: Token,
    /// The bound address and port.
    pub addr: SocketAddr,
    /// The cookie that carries the token (named by the port: browsers share cookies between
    /// the ports of one host).
    pub cookie: String,
    pub limits: Limits,
}

impl Guard {
    pub fn new(token: Token, addr: SocketAddr, limits: Limits) -> Guard {
        Guard {
            token,
            cookie: format!("pdw_explore_{}", addr.port()),
            addr,
            limits,
        }
    }

    /// Refuses a Host that does not name this server; the Host when admitted.
    fn host<'a>(&self, h: &'a HeaderMap) -> Result<&'a str, ApiError> {
        let port = self.addr.port();
        let refuse = |v: &str| {
            ApiError::forbidden(format!(
                "Host '{v}' is not this server's: use {}:{port} or localhost:{port} \
                 (other names are refused against DNS rebinding)",
                ip_text(self.addr.ip())
            ))
        };
        let v = h
            .get(header::HOST)
            .map(|v| v.to_str().map_err(|_| refuse("(not text)")))
            .transpose()?
            .ok_or_else(|| refuse("(none)"))?;
        let (name, p) = split_host(v).ok_or_else(|| refuse(v))?;
        let p = match p {
            Some(p) => p.parse::<u16>().map_err(|_| refuse(v))?,
            None => 80,
        };
        if p != port {
            return Err(refuse(v));
        }
        let ip = self.addr.ip();
        let ok = name.eq_ignore_ascii_case("localhost")
            || match parse_ip(name) {
                Some(a) => a == ip || ip.is_unspecified(),
                None => false,
            };
        if ok {
            Ok(v)
        } else {
            Err(refuse(v))
        }
    }

    /// Whether the request carries this server's token (cookie, header or query).
    fn has_token(&self, req: &Request) -> bool {
        let h = req.headers();
        let by_header = h
            .get_all(header::AUTHORIZATION)
            .iter()
            .filter_map(|v| v.to_str().ok())
            .filter_map(|v| v.strip_prefix("token "))
            .any(|t| self.token.matches(t.trim()));
        let by_cookie = h
            .get_all(header::COOKIE)
            .iter()
            .filter_map(|v| v.to_str().ok())
            .flat_map(|v| v.split(';'))
            .filter_map(|kv| kv.trim().split_once('='))
            .any(|(k, v)| k == self.cookie && self.token.matches(v));
        by_header || by_cookie || query_token(req).is_some_and(|t| self.token.matches(t))
    }
}

/// The `token` query parameter of `req`.
fn query_token(req: &Request) -> Option<&str> {
    req.uri()
        .query()?
        .split('&')
        .find_map(|kv| kv.strip_prefix("token="))
}

/// An address as a URL writes it (`[::1]` for IPv6).
pub fn ip_text(ip: IpAddr) -> String {
    match ip {
        IpAddr::V6(a) => format!("[{a}]"),
        IpAddr::V4(a) => a.to_string(),
    }
}

/// `name` and `port` of a Host value (`[::1]:8737`, `127.0.0.1:8737`, `localhost`).
fn split_host(v: &str) -> Option<(&str, Option<&str>)> {
    if let Some(rest) = v.strip_prefix('[') {
        let (name, after) = rest.split_once(']')?;
        return match after {
            "" => Some((name, None)),
            _ => Some((name, Some(after.strip_prefix(':')?))),
        };
    }
    match v.split_once(':') {
        Some((n, p)) => Some((n, Some(p))),
        None => Some((v, None)),
    }
}

fn parse_ip(name: &str) -> Option<IpAddr> {
    name.parse().ok()
}

/// The middleware: the checks of the module's docs, then the page's cookie.
pub async fn check(State(g): State<Arc<Guard>>, req: Request, next: Next) -> Response {
    match admit(&g, req).await {
        Ok((req, set_cookie)) => {
            let mut res = next.run(req).await;
            if set_cookie {
                let c = format!(
                    "{}={}; Path=/; HttpOnly; SameSite=Strict",
                    g.cookie,
                    g.token.as_str()
                );
                if let Ok(v) = c.parse() {
                    res.headers_mut().insert(header::SET_COOKIE, v);
                }
            }
            res
        }
        Err(e) => e.into_response(),
    }
}

/// The request admitted (its body read, for a POST) and whether it loads the page with the
/// token (then the response sets the cookie); or the refusal.
async fn admit(g: &Guard, req: Request) -> Result<(Request, bool), ApiError> {
    let h = req.headers();
    let host = g.host(h)?;
    if let Some(o) = h.get(header::ORIGIN) {
        let own = format!("http://{host}");
        let o = o.to_str().unwrap_or("(not text)");
        if !o.eq_ignore_ascii_case(&own) {
            return Err(ApiError::forbidden(format!(
                "Origin '{o}' is not this server's ({own}): requests from other pages are refused"
            )));
        }
    }
    let api = req.uri().path().starts_with("/api/");
    if api {
        if let Some(s) = h.get("sec-fetch-site").and_then(|v| v.to_str().ok()) {
            if s != "same-origin" && s != "none" {
                return Err(ApiError::forbidden(format!(
                    "Sec-Fetch-Site '{s}': the API answers only this server's own page"
                )));
            }
        }
        if !g.has_token(&req) {
            return Err(ApiError::forbidden(
                "this request lacks the explorer's session token: open the URL that \
                 `pdw-sweep explore` printed (with ?token=…), or send `Authorization: token …`",
            ));
        }
    }
    if api && req.method() == Method::POST {
        let ct = req
            .headers()
            .get(header::CONTENT_TYPE)
            .and_then(|v| v.to_str().ok())
            .unwrap_or("(none)");
        let mime = ct.split(';').next().unwrap_or("").trim();
        if !mime.eq_ignore_ascii_case("application/json") {
            return Err(ApiError::new(
                StatusCode::UNSUPPORTED_MEDIA_TYPE,
                format!("Content-Type '{ct}': API requests must be application/json"),
            ));
        }
    }
    let page_with_token = !api
        && req.uri().path() == "/"
        && match query_token(&req) {
            Some(t) if g.token.matches(t) => true,
            Some(_) => {
                return Err(ApiError::forbidden(
                    "wrong session token: open the URL that `pdw-sweep explore` printed",
                ))
            }
            None => false,
        };
    let req = if req.method() == Method::POST {
        read_body(req, g.limits.body_timeout).await?
    } else {
        req
    };
    Ok((req, page_with_token))
}

/// `req` with its body read whole within `timeout` and [`MAX_BODY`] bytes.
async fn read_body(req: Request, timeout: Duration) -> Result<Request, ApiError> {
    let (parts, body) = req.into_parts();
    let read = axum::body::to_bytes(body, MAX_BODY);
    let bytes = match tokio::time::timeout(timeout, read).await {
        Err(_) => {
            return Err(ApiError::new(
                StatusCode::REQUEST_TIMEOUT,
                format!(
                    "request body: not received within {} s",
                    timeout.as_secs_f64()
                ),
            ))
        }
        Ok(Err(_)) => {
            return Err(ApiError::new(
                StatusCode::PAYLOAD_TOO_LARGE,
                format!("request body: larger than {MAX_BODY} bytes (or broken)"),
            ))
        }
        Ok(Ok(b)) => b,
    };
    Ok(Request::from_parts(parts, Body::from(bytes)))
}

//! The static file server behind `chopperscape web`: hyper's HTTP/1.1 on a tokio runtime, with limits.
//!
//! hyper parses requests (keep-alive, pipelining, `HEAD`, an over-long head answered with 431); this module
//! adds what a server that faces a network needs around it:
//! - at most [`max_connections`] connections at once: more are answered 503 and closed, and a failed
//!   `accept` (out of file descriptors, say) is logged and retried, never the end of the server;
//! - a request head of at most [`MAX_HEAD`] bytes, complete within [`HEAD_TIMEOUT`];
//! - a connection on which no byte moves for [`IDLE_TIMEOUT`] is closed (the read and write timeout), and
//!   each connection is served on its own task, so a client that stops reading holds up nobody else;
//! - only `GET` and `HEAD` (405 with `Allow` otherwise), and only regular files whose real path lies inside
//!   the served folder ([`files::resolve`]), streamed in chunks.

mod body;
mod files;
mod inactivity;
mod log;

use std::convert::Infallible;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use anyhow::{Context, Result};
use hyper::header::{ALLOW, CACHE_CONTROL, CONTENT_TYPE, HeaderValue};
use hyper::server::conn::http1;
use hyper::service::service_fn;
use hyper::{Method, Request, Response, StatusCode};
use hyper_util::rt::{TokioIo, TokioTimer};
use tokio::io::AsyncWriteExt;
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::Semaphore;

pub use body::Payload;
pub use files::{Refusal, content_type, resolve};

/// The largest request head (request line and headers) read, in bytes; a longer one is answered 431.
pub const MAX_HEAD: usize = 32 * 1024;
/// The time a client has to send a complete request head once it starts one.
pub const HEAD_TIMEOUT: Duration = Duration::from_secs(10);
/// A connection on which no byte moves either way for this long is closed.
pub const IDLE_TIMEOUT: Duration = Duration::from_secs(10);
/// The most connections served at once, whatever the file-descriptor limit allows.
pub const MAX_CONNECTIONS: usize = 256;
/// How long to wait before accepting again after `accept` failed.
const ACCEPT_BACKOFF: Duration = Duration::from_millis(100);

/// The connection cap: [`MAX_CONNECTIONS`], or fewer when the process may open fewer files (each
/// connection takes one descriptor and a second while it reads a file; 32 are kept for everything else).
pub fn max_connections() -> usize {
    let open_files = open_files_limit().unwrap_or(1024);
    (open_files.saturating_sub(32) / 2).clamp(4, MAX_CONNECTIONS as u64) as usize
}

/// The soft limit on open file descriptors (`ulimit -n`), where the platform has one.
#[cfg(unix)]
fn open_files_limit() -> Option<u64> {
    let mut limit = libc::rlimit { rlim_cur: 0, rlim_max: 0 };
    // SAFETY: getrlimit only writes the struct it is given, which lives for the call.
    let ok = unsafe { libc::getrlimit(libc::RLIMIT_NOFILE, &mut limit) } == 0;
    #[allow(clippy::unnecessary_cast, reason = "rlim_t is 32 bits wide on some targets")]
    ok.then_some(limit.rlim_cur as u64)
}

#[cfg(not(unix))]
fn open_files_limit() -> Option<u64> {
    None
}

/// Serves the files of `root` on `listener` until the process is stopped.
///
/// # Errors
/// Only if the runtime cannot start or the listener cannot be handed to it; once serving, nothing ends it.
pub fn serve(listener: std::net::TcpListener, root: &Path) -> Result<()> {
    let root = Arc::new(std::fs::canonicalize(root).with_context(|| format!("cannot open {}", root.display()))?);
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("cannot start the server's runtime")?;
    listener.set_nonblocking(true).context("cannot make the listening socket non-blocking")?;
    runtime.block_on(async move {
        let listener = TcpListener::from_std(listener).context("cannot listen")?;
        accept_forever(listener, root).await;
        Ok(())
    })
}

async fn accept_forever(listener: TcpListener, root: Arc<PathBuf>) {
    let cap = max_connections();
    let slots = Arc::new(Semaphore::new(cap));
    let mut refused = log::Throttled::new();
    let mut failed = log::Throttled::new();
    loop {
        match listener.accept().await {
            Ok((stream, peer)) => match Arc::clone(&slots).try_acquire_owned() {
                Ok(slot) => {
                    let root = Arc::clone(&root);
                    tokio::spawn(async move {
                        connection(stream, root).await;
                        drop(slot);
                    });
                }
                Err(_) => {
                    refused.note(|n| {
                        format!(
                            "web: refused {n} connection(s) (latest from {peer}): {cap} connections are open, \
                             the most served at once"
                        )
                    });
                    tokio::spawn(busy(stream));
                }
            },
            Err(e) => {
                failed.note(|n| format!("web: could not accept {n} connection(s): {e}; still serving"));
                tokio::time::sleep(ACCEPT_BACKOFF).await;
            }
        }
    }
}

/// Answers a connection over the cap with 503 and closes it (giving up at once if the client does not read).
async fn busy(mut stream: TcpStream) {
    const BUSY: &[u8] = b"HTTP/1.1 503 Service Unavailable\r\nConnection: close\r\nRetry-After: 1\r\n\
Content-Length: 0\r\n\r\n";
    let _ = tokio::time::timeout(Duration::from_secs(1), stream.write_all(BUSY)).await;
}

/// Serves one connection until the client closes it, it breaks a limit, or it idles out.
async fn connection(stream: TcpStream, root: Arc<PathBuf>) {
    let _ = stream.set_nodelay(true);
    let io = TokioIo::new(inactivity::Inactivity::new(stream, IDLE_TIMEOUT));
    let service = service_fn(move |req| respond(Arc::clone(&root), req));
    let _ = http1::Builder::new()
        .timer(TokioTimer::new())
        .header_read_timeout(HEAD_TIMEOUT)
        .max_buf_size(MAX_HEAD)
        .serve_connection(io, service)
        .await;
}

/// The response to one request.
async fn respond<B>(root: Arc<PathBuf>, req: Request<B>) -> Result<Response<Payload>, Infallible> {
    if req.method() != Method::GET && req.method() != Method::HEAD {
        let mut r = plain(StatusCode::METHOD_NOT_ALLOWED, "only GET and HEAD are served\n");
        r.headers_mut().insert(ALLOW, HeaderValue::from_static("GET, HEAD"));
        return Ok(r);
    }
    let path = req.uri().path().to_string();
    let opened = tokio::task::spawn_blocking(move || open(&root, &path)).await;
    Ok(match opened {
        Ok(Ok((file, len, real))) => {
            let mut r = Response::new(Payload::file(tokio::fs::File::from_std(file), len));
            let headers = r.headers_mut();
            headers.insert(CONTENT_TYPE, HeaderValue::from_static(content_type(&real)));
            headers.insert(CACHE_CONTROL, HeaderValue::from_static("no-cache"));
            r
        }
        Ok(Err(Refusal::BadPath(why))) => plain(StatusCode::BAD_REQUEST, &format!("bad path: {why}\n")),
        Ok(Err(Refusal::Outside)) => plain(StatusCode::FORBIDDEN, "that file lies outside the served folder\n"),
        Ok(Err(Refusal::NotFound)) => plain(StatusCode::NOT_FOUND, "not found\n"),
        Err(_) => plain(StatusCode::INTERNAL_SERVER_ERROR, "cannot read the file\n"),
    })
}

/// Opens the file `url_path` names: the open file, its length and its real path.
fn open(root: &Path, url_path: &str) -> Result<(std::fs::File, u64, PathBuf), Refusal> {
    let real = resolve(root, url_path)?;
    let file = std::fs::File::open(&real).map_err(|_| Refusal::NotFound)?;
    let len = file.metadata().map_err(|_| Refusal::NotFound)?.len();
    Ok((file, len, real))
}

fn plain(status: StatusCode, text: &str) -> Response<Payload> {
    let mut r = Response::new(Payload::text(text));
    *r.status_mut() = status;
    r.headers_mut().insert(CONTENT_TYPE, HeaderValue::from_static("text/plain; charset=utf-8"));
    r
}

/// Whether every address `host` stands for is a loopback address (only this machine can connect).
pub fn is_loopback(addrs: &[SocketAddr]) -> bool {
    !addrs.is_empty() && addrs.iter().all(|a| a.ip().is_loopback())
}

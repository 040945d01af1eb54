//! `chopperscape web`: serve the already-built browser version on this machine.

use std::path::{Component, Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::Args;
use tiny_http::{Header, Response, Server};

/// The folder the browser build writes, relative to the repository root.
pub const DIST: &str = "web/dist";

/// Serve the browser version (built by `bash scripts/build-web.sh`) over HTTP.
///
/// Builds nothing. Listens on 127.0.0.1 only, unless --host is given; prints the address to open.
/// `--port 0` picks a free port.
#[derive(Args, Debug)]
#[command(after_help = "Examples:\n  bash scripts/build-web.sh && chopperscape web\n  \
chopperscape web --port 9000\n  chopperscape web --host 0.0.0.0 --dir web/dist")]
pub struct WebArgs {
    /// Port to listen on (0: any free port)
    #[arg(long, default_value_t = 8000)]
    pub port: u16,
    /// Address to listen on; other machines can reach the page only if you give one
    #[arg(long, default_value = "127.0.0.1")]
    pub host: String,
    /// The built page's folder [default: web/dist in the current folder or the nearest parent that has one]
    #[arg(long, value_name = "DIR")]
    pub dir: Option<PathBuf>,
}

/// The content type of a file, by its extension.
pub fn content_type(path: &Path) -> &'static str {
    match path.extension().and_then(|e| e.to_str()).unwrap_or("") {
        "html" | "htm" => "text/html; charset=utf-8",
        "js" | "mjs" => "text/javascript; charset=utf-8",
        "wasm" => "application/wasm",
        "css" => "text/css; charset=utf-8",
        "png" => "image/png",
        "gif" => "image/gif",
        "svg" => "image/svg+xml",
        "ico" => "image/x-icon",
        "json" | "map" => "application/json",
        "txt" => "text/plain; charset=utf-8",
        _ => "application/octet-stream",
    }
}

/// `web/dist` in the current folder or its nearest ancestor that has one.
fn find_dist() -> Option<PathBuf> {
    let cwd = std::env::current_dir().ok()?;
    cwd.ancestors().map(|a| a.join(DIST)).find(|d| d.is_dir())
}

/// The file a request path names inside `root`, refusing anything that would leave it.
fn resolve(root: &Path, url: &str) -> Option<PathBuf> {
    let path = url.split(['?', '#']).next().unwrap_or("/");
    let mut file = root.to_path_buf();
    for comp in Path::new(path.trim_start_matches('/')).components() {
        match comp {
            Component::Normal(c) => file.push(c),
            Component::CurDir => {}
            _ => return None,
        }
    }
    if file.is_dir() {
        file.push("index.html");
    }
    file.is_file().then_some(file)
}

/// Runs `web`.
pub fn run(args: WebArgs) -> Result<ExitCode> {
    let dir = match args.dir.clone().or_else(find_dist) {
        Some(d) if d.is_dir() => d,
        Some(d) => bail!(
            "the browser page folder {} does not exist; build it first with: bash scripts/build-web.sh",
            d.display()
        ),
        None => bail!(
            "no built browser page ({DIST} was not found here or in a parent folder); build it first with: \
             bash scripts/build-web.sh"
        ),
    };
    if !dir.join("index.html").is_file() {
        bail!("{} has no index.html; build the page with: bash scripts/build-web.sh", dir.display());
    }
    let server = Server::http((args.host.as_str(), args.port))
        .map_err(|e| anyhow::anyhow!("{e}"))
        .with_context(|| format!("cannot listen on {}:{}", args.host, args.port))?;
    let addr = server.server_addr().to_ip().context("the server has an IP address")?;
    println!("serving {} at http://{addr}/ (Ctrl-C to stop)", dir.display());
    for request in server.incoming_requests() {
        let response = match resolve(&dir, request.url()) {
            Some(file) => match std::fs::read(&file) {
                Ok(bytes) => {
                    let header = Header::from_bytes("Content-Type", content_type(&file)).expect("a valid header");
                    Response::from_data(bytes).with_header(header)
                }
                Err(_) => Response::from_string("cannot read the file").with_status_code(500),
            },
            None => Response::from_string("not found").with_status_code(404),
        };
        let _ = request.respond(response);
    }
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_cannot_leave_the_served_folder() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("index.html"), "hi").unwrap();
        assert_eq!(resolve(dir.path(), "/"), Some(dir.path().join("index.html")));
        assert_eq!(resolve(dir.path(), "/index.html?v=1"), Some(dir.path().join("index.html")));
        assert_eq!(resolve(dir.path(), "/../etc/passwd"), None);
        assert_eq!(resolve(dir.path(), "/missing.js"), None);
    }

    #[test]
    fn wasm_is_served_as_application_wasm() {
        assert_eq!(content_type(Path::new("a/chopperscape_bg.wasm")), "application/wasm");
        assert!(content_type(Path::new("x.js")).starts_with("text/javascript"));
    }
}

//! `chopperscape web`: serve the already-built browser version on this machine.

use std::net::{SocketAddr, TcpListener, ToSocketAddrs};
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::Args;

use crate::server;

/// The folder the browser build writes, relative to the repository root.
pub const DIST: &str = "web/dist";

/// Serve the browser version (built by `bash scripts/build-web.sh`) over HTTP.
///
/// Builds nothing. Listens on 127.0.0.1 only, unless --host is given; prints the address to open.
/// `--port 0` picks a free port. Serves GET and HEAD of the files inside the folder (never through a
/// symbolic link that leads out of it), at most 256 connections at once (fewer under a low `ulimit -n`),
/// each closed after 10 s without traffic; request heads are limited to 32 KiB.
#[derive(Args, Debug)]
#[command(after_help = "Examples:\n  bash scripts/build-web.sh && chopperscape web\n  \
chopperscape web --port 9000\n  chopperscape web --host 0.0.0.0 --dir web/dist")]
pub struct WebArgs {
    /// Port to listen on (0: any free port)
    #[arg(long, default_value_t = 8000, allow_negative_numbers = true)]
    pub port: u16,
    /// Address to listen on; other machines can reach the page only if you give one
    #[arg(long, default_value = "127.0.0.1")]
    pub host: String,
    /// The built page's folder [default: web/dist in the current folder or the nearest parent that has one]
    #[arg(long, value_name = "DIR")]
    pub dir: Option<PathBuf>,
}

/// `web/dist` in the current folder or its nearest ancestor that has one.
fn find_dist() -> Option<PathBuf> {
    let cwd = std::env::current_dir().ok()?;
    cwd.ancestors().map(|a| a.join(DIST)).find(|d| d.is_dir())
}

/// Runs `web`.
pub fn run(args: WebArgs) -> Result<ExitCode> {
    let dir = match args.dir.clone().or_else(find_dist) {
        Some(d) if d.is_dir() => d,
        Some(d) if d.exists() => bail!(
            "{} is not a folder; give the built page's folder (web/dist, built by bash scripts/build-web.sh)",
            d.display()
        ),
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
    let addrs: Vec<SocketAddr> = (args.host.as_str(), args.port)
        .to_socket_addrs()
        .with_context(|| format!("cannot listen on {}: not an address or a known host name", args.host))?
        .collect();
    let listener =
        TcpListener::bind(&addrs[..]).with_context(|| format!("cannot listen on {}:{}", args.host, args.port))?;
    let addr = listener.local_addr().context("the server has an address")?;
    if !server::is_loopback(&[addr]) {
        crate::note!(
            "warning: listening on {}, which is not a loopback address: any machine that can reach this one can \
             load every file in {}; use --host 127.0.0.1 to keep it to this machine",
            addr.ip(),
            dir.display()
        );
    }
    crate::say!("serving {} at http://{addr}/ (Ctrl-C to stop)", dir.display())?;
    server::serve(listener, &dir)?;
    Ok(ExitCode::SUCCESS)
}

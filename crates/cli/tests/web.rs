//! `chopperscape web` under hostile clients: floods of idle connections, a client that never reads, endless
//! headers, symbolic links out of the folder, other methods, escaped `..`. Every server runs on 127.0.0.1 on a
//! free port and is killed when its test ends; every loop is bounded.

use std::io::{BufRead, BufReader, ErrorKind, Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

mod common;

/// A running `chopperscape web`, killed on drop.
struct Server {
    child: Child,
    addr: String,
}

impl Server {
    /// Serves `dir`, with at most `open_files` file descriptors when given (through the shell's `ulimit -n`).
    fn start(dir: &Path, open_files: Option<u32>) -> Server {
        let bin = common::bin();
        let mut cmd = match open_files {
            Some(n) => {
                let mut c = Command::new("sh");
                c.arg("-c").arg(format!("ulimit -n {n} && exec \"$0\" web --port 0 --dir \"$1\"")).arg(&bin).arg(dir);
                c
            }
            None => {
                let mut c = Command::new(&bin);
                c.args(["web", "--port", "0", "--dir"]).arg(dir);
                c
            }
        };
        let mut child = cmd.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
        let addr = line.split("http://").nth(1).expect(&line).trim_end().split('/').next().unwrap().to_string();
        assert!(addr.starts_with("127.0.0.1:"), "{line}");
        Server { child, addr }
    }

    fn connect(&self) -> TcpStream {
        let s = TcpStream::connect(&self.addr).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        s.set_write_timeout(Some(Duration::from_secs(5))).unwrap();
        s
    }

    /// Sends `request` on a new connection and reads the whole answer (the server closes the connection
    /// because the request says so).
    fn ask(&self, request: &str) -> String {
        let mut s = self.connect();
        s.write_all(request.as_bytes()).unwrap();
        let mut resp = Vec::new();
        let _ = s.read_to_end(&mut resp);
        String::from_utf8_lossy(&resp).into_owned()
    }

    fn get(&self, path: &str) -> String {
        self.ask(&format!("GET {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n"))
    }

    fn is_running(&mut self) -> bool {
        self.child.try_wait().unwrap().is_none()
    }

    /// Stops the server and returns what it wrote on standard error.
    fn stop(mut self) -> String {
        self.child.kill().unwrap();
        self.child.wait().unwrap();
        let mut err = String::new();
        self.child.stderr.take().unwrap().read_to_string(&mut err).unwrap();
        err
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn status(resp: &str) -> &str {
    resp.split(' ').nth(1).unwrap_or("(no answer)")
}

/// A page folder with an index, a 4 MB file, and a secret beside the folder.
fn page() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let dist = dir.path().join("dist");
    std::fs::create_dir(&dist).unwrap();
    std::fs::write(dist.join("index.html"), "<html>hi</html>").unwrap();
    std::fs::write(dist.join("big.wasm"), vec![7u8; 4 << 20]).unwrap();
    std::fs::write(dir.path().join("secret.txt"), "the secret").unwrap();
    dir
}

#[test]
fn a_flood_of_idle_connections_is_refused_and_the_server_keeps_serving() {
    let dir = page();
    // 128 file descriptors allow the server 48 connections; 150 idle ones are more than it may hold.
    let mut server = Server::start(&dir.path().join("dist"), Some(128));
    let idle: Vec<TcpStream> = (0..150).map(|_| server.connect()).collect();
    std::thread::sleep(Duration::from_millis(500));
    assert!(server.is_running(), "the server stopped under {} idle connections", idle.len());
    drop(idle);
    let deadline = Instant::now() + Duration::from_secs(10);
    let mut resp = server.get("/");
    while status(&resp) != "200" && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(100));
        resp = server.get("/");
    }
    assert_eq!(status(&resp), "200", "{resp}");
    assert!(server.is_running());
    let err = server.stop();
    assert!(err.contains("refused") && err.contains("connections are open"), "{err}");
}

#[test]
fn running_out_of_file_descriptors_is_logged_and_survived() {
    let dir = page();
    // 12 descriptors: the server's own (about 9) and a few connections; accepting more fails with EMFILE.
    let mut server = Server::start(&dir.path().join("dist"), Some(12));
    let idle: Vec<TcpStream> = (0..20).map(|_| server.connect()).collect();
    std::thread::sleep(Duration::from_millis(1500));
    assert!(server.is_running(), "the server stopped when it ran out of file descriptors");
    drop(idle);
    let deadline = Instant::now() + Duration::from_secs(10);
    let mut resp = server.get("/");
    while status(&resp) != "200" && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(100));
        resp = server.get("/");
    }
    assert_eq!(status(&resp), "200", "{resp}");
    let err = server.stop();
    assert!(err.contains("still serving") || err.contains("refused"), "{err}");
}

#[test]
fn a_client_that_never_reads_holds_up_nobody_else() {
    let dir = page();
    let server = Server::start(&dir.path().join("dist"), None);
    let mut slow = server.connect();
    let pipelined = "GET /big.wasm HTTP/1.1\r\nHost: x\r\n\r\n".repeat(50);
    slow.write_all(pipelined.as_bytes()).unwrap();
    std::thread::sleep(Duration::from_millis(300));
    for _ in 0..3 {
        let start = Instant::now();
        let resp = server.get("/");
        assert_eq!(status(&resp), "200", "{resp}");
        assert!(resp.ends_with("<html>hi</html>"), "{resp}");
        assert!(start.elapsed() < Duration::from_secs(3), "took {:?}", start.elapsed());
    }
    drop(slow);
}

#[test]
fn an_endless_request_head_is_cut_off_with_431() {
    let dir = page();
    let server = Server::start(&dir.path().join("dist"), None);
    let mut s = server.connect();
    let line = b"X-Filler: aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa\r\n".repeat(64);
    s.write_all(b"GET / HTTP/1.1\r\nHost: x\r\n").unwrap();
    let mut sent = 0;
    let stopped = loop {
        if sent >= 16 << 20 {
            break None;
        }
        match s.write_all(&line) {
            Ok(()) => sent += line.len(),
            Err(e) => break Some(e.kind()),
        }
    };
    // The server must close the connection (the write fails with a reset or a broken pipe), not just stop
    // reading (the write would time out) or read on (16 MB would go through).
    let stopped = stopped.expect("the server read 16 MB of request head");
    assert!(!matches!(stopped, ErrorKind::WouldBlock | ErrorKind::TimedOut), "{stopped:?} after {sent} bytes");
    let mut resp = Vec::new();
    if let Err(e) = s.read_to_end(&mut resp) {
        assert!(!matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut), "{e}");
    }
    let resp = String::from_utf8_lossy(&resp);
    assert!(resp.is_empty() || status(&resp) == "431", "{resp}");
    assert_eq!(status(&server.get("/")), "200");
}

#[cfg(unix)]
#[test]
fn symbolic_links_out_of_the_folder_are_not_served() {
    let dir = page();
    let dist = dir.path().join("dist");
    std::os::unix::fs::symlink(dir.path(), dist.join("up")).unwrap();
    std::os::unix::fs::symlink(dir.path().join("secret.txt"), dist.join("s.txt")).unwrap();
    let server = Server::start(&dist, None);
    for path in ["/up/secret.txt", "/s.txt"] {
        let resp = server.get(path);
        assert_eq!(status(&resp), "403", "{path}: {resp}");
        assert!(!resp.contains("the secret"), "{path}: {resp}");
    }
}

#[test]
fn only_get_and_head_are_served() {
    let dir = page();
    let server = Server::start(&dir.path().join("dist"), None);
    for method in ["POST", "PUT", "DELETE", "OPTIONS"] {
        let resp =
            server.ask(&format!("{method} / HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\nConnection: close\r\n\r\n"));
        assert_eq!(status(&resp), "405", "{method}: {resp}");
        assert!(resp.to_ascii_lowercase().contains("allow: get, head"), "{method}: {resp}");
    }
    let head = server.ask("HEAD /index.html HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
    assert_eq!(status(&head), "200", "{head}");
    assert!(head.to_ascii_lowercase().contains("content-length: 15"), "{head}");
    assert!(!head.contains("<html>"), "{head}");
}

#[test]
fn paths_are_percent_decoded_and_escaped_dot_dot_is_refused() {
    let dir = page();
    let server = Server::start(&dir.path().join("dist"), None);
    let resp = server.get("/index%2Ehtml");
    assert_eq!(status(&resp), "200", "{resp}");
    for bad in ["/%2e%2e/secret.txt", "/%2E%2E%2Fsecret.txt", "/index.html%00"] {
        let resp = server.get(bad);
        assert_eq!(status(&resp), "400", "{bad}: {resp}");
        assert!(!resp.contains("the secret"), "{bad}: {resp}");
    }
}

#[test]
fn a_host_that_is_not_loopback_is_warned_about() {
    let dir = page();
    let mut child = Command::new(common::bin())
        .args(["web", "--port", "0", "--host", "0.0.0.0", "--dir"])
        .arg(dir.path().join("dist"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
    child.kill().unwrap();
    child.wait().unwrap();
    let mut err = String::new();
    child.stderr.take().unwrap().read_to_string(&mut err).unwrap();
    assert!(line.contains("serving"), "{line}");
    assert!(err.contains("warning") && err.contains("not a loopback address"), "{err}");
}

#[test]
fn a_file_given_as_the_folder_is_named_as_not_a_folder() {
    let dir = page();
    common::cs()
        .args(["web", "--dir"])
        .arg(dir.path().join("dist/index.html"))
        .assert()
        .failure()
        .stderr(predicates::str::contains("is not a folder"));
}

//! Which file a request names: percent-decoded, never outside the served folder (symbolic links included),
//! and its content type.

use std::path::{Path, PathBuf};

/// Why a request path names no file to serve.
#[derive(Debug, PartialEq, Eq)]
pub enum Refusal {
    /// A malformed path: a bad `%` escape, bytes that are not UTF-8, a NUL, or a `..` segment (400).
    BadPath(&'static str),
    /// The path leads outside the served folder, through a symbolic link (403).
    Outside,
    /// Nothing there, or not a regular file (404).
    NotFound,
}

/// Decodes `%XX` escapes in a URL path.
///
/// # Errors
/// A `%` not followed by two hex digits, or a result that is not UTF-8.
pub fn percent_decode(path: &str) -> Result<String, Refusal> {
    let bytes = path.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = bytes.get(i + 1..i + 3).and_then(|h| std::str::from_utf8(h).ok());
            let byte = hex.and_then(|h| u8::from_str_radix(h, 16).ok()).ok_or(Refusal::BadPath("a bad % escape"))?;
            out.push(byte);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| Refusal::BadPath("the path is not UTF-8"))
}

/// The file that the URL path `url_path` (without the query) names inside `root`, which must already be
/// canonical (`std::fs::canonicalize`).
///
/// The path is percent-decoded first; a `..` segment or a NUL byte is refused; a folder means its
/// `index.html`. The file's real path (every symbolic link followed) must lie inside `root`.
///
/// # Errors
/// A [`Refusal`] saying why nothing is served.
pub fn resolve(root: &Path, url_path: &str) -> Result<PathBuf, Refusal> {
    let decoded = percent_decode(url_path)?;
    if decoded.contains('\0') {
        return Err(Refusal::BadPath("the path holds a NUL byte"));
    }
    let mut file = root.to_path_buf();
    for segment in decoded.split('/') {
        match segment {
            "" | "." => {}
            ".." => return Err(Refusal::BadPath("the path holds a `..` segment")),
            s => file.push(s),
        }
    }
    let mut real = inside(root, &file)?;
    if real.is_dir() {
        real = inside(root, &real.join("index.html"))?;
    }
    if real.is_file() { Ok(real) } else { Err(Refusal::NotFound) }
}

/// The canonical path of `file`, if it exists and lies inside `root`.
fn inside(root: &Path, file: &Path) -> Result<PathBuf, Refusal> {
    let real = std::fs::canonicalize(file).map_err(|_| Refusal::NotFound)?;
    if real.starts_with(root) { Ok(real) } else { Err(Refusal::Outside) }
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

#[cfg(test)]
mod tests {
    use super::*;

    fn served() -> (tempfile::TempDir, PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().join("dist");
        std::fs::create_dir_all(root.join("pkg")).unwrap();
        std::fs::write(root.join("index.html"), "hi").unwrap();
        std::fs::write(root.join("pkg/a b.js"), "js").unwrap();
        std::fs::write(dir.path().join("secret.txt"), "secret").unwrap();
        let root = std::fs::canonicalize(root).unwrap();
        (dir, root)
    }

    #[test]
    fn paths_are_percent_decoded_and_folders_mean_their_index() {
        let (_dir, root) = served();
        assert_eq!(resolve(&root, "/"), Ok(root.join("index.html")));
        assert_eq!(resolve(&root, "/index%2Ehtml"), Ok(root.join("index.html")));
        assert_eq!(resolve(&root, "/pkg/a%20b.js"), Ok(root.join("pkg/a b.js")));
        assert_eq!(resolve(&root, "/missing.js"), Err(Refusal::NotFound));
        assert_eq!(resolve(&root, "/pkg"), Err(Refusal::NotFound), "a folder without an index.html");
    }

    #[test]
    fn requests_cannot_leave_the_served_folder() {
        let (_dir, root) = served();
        for bad in ["/../secret.txt", "/%2e%2e/secret.txt", "/pkg/%2E%2E/%2e%2e/secret.txt", "/..%2fsecret.txt"] {
            assert!(matches!(resolve(&root, bad), Err(Refusal::BadPath(_))), "{bad}");
        }
        assert!(matches!(resolve(&root, "/index.html%00.js"), Err(Refusal::BadPath(_))));
        assert!(matches!(resolve(&root, "/%zz"), Err(Refusal::BadPath(_))));
        assert!(matches!(resolve(&root, "/%ff"), Err(Refusal::BadPath(_))));
    }

    #[cfg(unix)]
    #[test]
    fn symbolic_links_out_of_the_folder_are_not_followed() {
        let (dir, root) = served();
        std::os::unix::fs::symlink(dir.path(), root.join("up")).unwrap();
        std::os::unix::fs::symlink(dir.path().join("secret.txt"), root.join("s.txt")).unwrap();
        std::os::unix::fs::symlink(root.join("index.html"), root.join("home.html")).unwrap();
        assert_eq!(resolve(&root, "/up/secret.txt"), Err(Refusal::Outside));
        assert_eq!(resolve(&root, "/s.txt"), Err(Refusal::Outside));
        assert_eq!(resolve(&root, "/home.html"), Ok(root.join("index.html")), "a link inside the folder is fine");
    }

    #[test]
    fn wasm_is_served_as_application_wasm() {
        assert_eq!(content_type(Path::new("a/chopperscape_bg.wasm")), "application/wasm");
        assert!(content_type(Path::new("x.js")).starts_with("text/javascript"));
    }
}

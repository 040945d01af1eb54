//! Two outputs on one file: found before anything is played, by comparing where each path really leads
//! (its folder canonicalised, symbolic links followed, dangling ones included).

use std::path::{Path, PathBuf};

use anyhow::Result;

use crate::usage_bail;

/// `path` with its folder canonicalised (when the folder exists), the last component kept as given.
fn lexical(path: &Path) -> PathBuf {
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let parent = std::fs::canonicalize(&parent).unwrap_or(parent);
    match path.file_name() {
        Some(name) => parent.join(name),
        None => std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf()),
    }
}

/// Where `path` leads once every symbolic link is followed, even to something that does not exist.
fn final_target(path: &Path) -> PathBuf {
    let mut p = lexical(path);
    for _ in 0..40 {
        let Ok(target) = std::fs::read_link(&p) else { break };
        let next = match p.parent() {
            Some(folder) if target.is_relative() => folder.join(target),
            _ => target,
        };
        p = lexical(&next);
    }
    p
}

/// The places a write to `path` touches: the path itself and, for a symbolic link, what it leads to.
fn places(path: &Path) -> Vec<PathBuf> {
    let (a, b) = (lexical(path), final_target(path));
    if a == b { vec![a] } else { vec![a, b] }
}

/// Fails with a usage error when two of `paths` (flag name, path, whether it is a folder) lead to the same
/// place, or a file lies inside a folder of the list.
///
/// # Errors
/// A [`crate::UsageError`] naming both flags.
pub fn check(paths: &[(&str, &Path, bool)]) -> Result<()> {
    let resolved: Vec<Vec<PathBuf>> = paths.iter().map(|(_, p, _)| places(p)).collect();
    for (i, (flag_a, path_a, dir_a)) in paths.iter().enumerate() {
        for (j, (flag_b, path_b, _)) in paths.iter().enumerate().skip(i + 1) {
            if resolved[i].iter().any(|a| resolved[j].contains(a)) {
                usage_bail!(
                    "{flag_a} {} and {flag_b} {} are the same file; give each its own path",
                    path_a.display(),
                    path_b.display()
                );
            }
        }
        if *dir_a {
            for (j, (flag_b, path_b, _)) in paths.iter().enumerate() {
                if j != i && resolved[j].iter().any(|b| resolved[i].iter().any(|a| b.starts_with(a))) {
                    usage_bail!(
                        "{flag_b} {} lies inside the {flag_a} folder {}, which is replaced; write it elsewhere",
                        path_b.display(),
                        path_a.display()
                    );
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_same_file_by_another_spelling_or_through_links_is_found() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir(d.join("sub")).unwrap();
        let a = d.join("a.png");
        assert!(check(&[("--out", &a, false), ("--save-actions", &d.join("sub/../a.png"), false)]).is_err());
        assert!(check(&[("--out", &a, false), ("--save-actions", &d.join("b.json"), false)]).is_ok());
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(d.join("sub"), d.join("alias")).unwrap();
            std::os::unix::fs::symlink(d.join("nowhere.gif"), d.join("dangling.gif")).unwrap();
            let err = check(&[("--out", &d.join("sub/x.gif"), false), ("--frames", &d.join("alias/x.gif"), true)]);
            assert!(err.unwrap_err().to_string().contains("--out"));
            let err = check(&[("--out", &d.join("dangling.gif"), false), ("--frames", &d.join("nowhere.gif"), true)]);
            assert!(err.is_err(), "a dangling link and its target");
        }
        let err = check(&[("--frames", &d.join("sub"), true), ("--out", &d.join("sub/f.gif"), false)]).unwrap_err();
        assert!(err.to_string().contains("inside the --frames folder"), "{err}");
    }
}

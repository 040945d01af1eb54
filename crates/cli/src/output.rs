//! Writing files safely: nothing is overwritten without `--force`, and every output is written to a temporary
//! file (or folder) beside its destination and renamed into place when complete, so an interrupted run never
//! leaves a half-written file under the destination's name.
//!
//! Temporary names carry the writer's process id: `.{name}.{pid}.{random}.part` (and `.{name}.{pid}.{random}.old`
//! for a frames folder moved aside while it is replaced). A signal removes them ([`crate::interrupt`]); one left
//! by a process that was killed outright is removed by the next run that writes into the same folder
//! ([`sweep_stale`]), which also puts back a frames folder whose swap was cut in half.

use std::fs::File;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use tempfile::{NamedTempFile, TempDir};

use crate::interrupt::{self, Cleanup, Registered};

/// The folder a destination lives in (`.` for a bare file name).
fn parent_of(dest: &Path) -> Result<PathBuf> {
    let parent = match dest.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !parent.is_dir() {
        bail!("cannot write {}: the folder {} does not exist", dest.display(), parent.display());
    }
    Ok(parent)
}

/// The file name of `dest`, for temporary names.
fn name_of(dest: &Path) -> String {
    dest.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()
}

/// A temporary-file builder for `dest`: our naming, and the usual permissions (0666, or 0777 for a folder,
/// less the umask), not tempfile's private 0600, since the result is renamed into the user's files.
fn builder<'a>(prefix: &'a str, suffix: &'static str, folder: bool) -> tempfile::Builder<'a, 'static> {
    let mut b = tempfile::Builder::new();
    b.prefix(prefix).suffix(suffix).rand_bytes(RANDOM_LEN);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        b.permissions(std::fs::Permissions::from_mode(if folder { 0o777 } else { 0o666 }));
    }
    #[cfg(not(unix))]
    let _ = folder;
    b
}

/// Random characters in a temporary name.
const RANDOM_LEN: usize = 6;

/// The prefix of this process's temporary names for `dest`: `.{name}.{pid}.`.
fn temp_prefix(dest: &Path) -> String {
    format!(".{}.{}.", name_of(dest), std::process::id())
}

/// Fails unless `dest` may be written: nothing is there (not even a dangling symbolic link), or `force` is set;
/// and its folder exists. Stale temporary files of an earlier, killed run in that folder are cleaned up first.
pub fn check_free(dest: &Path, force: bool) -> Result<()> {
    let parent = parent_of(dest)?;
    sweep_stale(&parent);
    match std::fs::symlink_metadata(dest) {
        Ok(meta) if meta.file_type().is_symlink() && !dest.exists() => {
            let target = std::fs::read_link(dest).map(|t| t.display().to_string()).unwrap_or_default();
            if !force {
                bail!(
                    "{} is a symbolic link to {target}, which does not exist; pass --force to replace the link, \
                     or give another file",
                    dest.display()
                );
            }
        }
        Ok(meta) if meta.is_dir() => bail!("{} is a folder; give a file name", dest.display()),
        Ok(_) if !force => bail!("{} already exists; pass --force to overwrite it", dest.display()),
        _ => {}
    }
    Ok(())
}

/// A file being written beside its destination; [`PendingFile::commit`] renames it into place,
/// dropping it removes it.
pub struct PendingFile {
    tmp: NamedTempFile,
    dest: PathBuf,
    force: bool,
    _registered: Registered,
}

impl PendingFile {
    /// Starts writing `dest`.
    ///
    /// # Errors
    /// `dest` exists and `force` is not set, its folder does not exist, or the temporary file cannot be made.
    pub fn create(dest: &Path, force: bool) -> Result<PendingFile> {
        check_free(dest, force)?;
        let tmp = builder(&temp_prefix(dest), ".part", false)
            .tempfile_in(parent_of(dest)?)
            .with_context(|| format!("cannot create a temporary file beside {}", dest.display()))?;
        let registered = interrupt::register(Cleanup::Remove(tmp.path().to_path_buf()));
        Ok(PendingFile { tmp, dest: dest.to_path_buf(), force, _registered: registered })
    }

    /// The temporary file's path (for a program that writes it by name).
    pub fn temp_path(&self) -> &Path {
        self.tmp.path()
    }

    /// The destination.
    pub fn dest(&self) -> &Path {
        &self.dest
    }

    /// A second handle on the temporary file, to write through.
    pub fn writer(&self) -> Result<File> {
        self.tmp.reopen().context("cannot reopen the temporary file")
    }

    /// Renames the finished file into place.
    pub fn commit(self) -> Result<()> {
        let PendingFile { tmp, dest, force, _registered } = self;
        let done = {
            let _held = interrupt::hold();
            if force { tmp.persist(&dest).map(drop) } else { tmp.persist_noclobber(&dest).map(drop) }
        };
        done.map_err(|e| e.error).with_context(|| format!("cannot write {}", dest.display()))
    }
}

/// Writes `bytes` to `dest` through a temporary file.
pub fn write_atomic(dest: &Path, bytes: &[u8], force: bool) -> Result<()> {
    let pending = PendingFile::create(dest, force)?;
    std::fs::write(pending.temp_path(), bytes).with_context(|| format!("cannot write {}", dest.display()))?;
    pending.commit()
}

/// Whether `name` is one of the numbered frames this program writes (`frame_00012.png`).
pub fn is_frame_name(name: &str) -> bool {
    name.strip_prefix("frame_")
        .and_then(|r| r.strip_suffix(".png"))
        .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
}

/// A folder of frames being written beside its destination; [`PendingDir::commit`] renames it into place.
pub struct PendingDir {
    tmp: TempDir,
    dest: PathBuf,
    force: bool,
    _registered: Registered,
}

impl PendingDir {
    /// Starts writing the folder `dest`. An existing empty folder is replaced; one holding files only with `force`,
    /// and only if it holds nothing but numbered frames (so `--force` never deletes anything else).
    pub fn create(dest: &Path, force: bool) -> Result<PendingDir> {
        Self::check(dest, force)?;
        let tmp = builder(&temp_prefix(dest), ".part", true)
            .tempdir_in(parent_of(dest)?)
            .with_context(|| format!("cannot create a temporary folder beside {}", dest.display()))?;
        let registered = interrupt::register(Cleanup::Remove(tmp.path().to_path_buf()));
        Ok(PendingDir { tmp, dest: dest.to_path_buf(), force, _registered: registered })
    }

    /// Fails unless the folder `dest` may be written (see [`PendingDir::create`]).
    pub fn check(dest: &Path, force: bool) -> Result<()> {
        let parent = parent_of(dest)?;
        sweep_stale(&parent);
        let Ok(meta) = std::fs::symlink_metadata(dest) else { return Ok(()) };
        if meta.file_type().is_symlink() {
            bail!("{} is a symbolic link; give the frames folder itself", dest.display());
        }
        if !meta.is_dir() {
            bail!("{} exists and is not a folder", dest.display());
        }
        let mut names = Vec::new();
        for entry in std::fs::read_dir(dest).with_context(|| format!("cannot read {}", dest.display()))? {
            names.push(entry?.file_name().to_string_lossy().into_owned());
        }
        if names.is_empty() {
            return Ok(());
        }
        if !force {
            bail!("{} already exists and is not empty; pass --force to replace its frames", dest.display());
        }
        if let Some(other) = names.iter().find(|n| !is_frame_name(n)) {
            bail!("{} holds {other}, which is not a frame; refusing to replace that folder", dest.display());
        }
        Ok(())
    }

    /// The temporary folder to write frames into.
    pub fn path(&self) -> &Path {
        self.tmp.path()
    }

    /// The destination folder.
    pub fn dest(&self) -> &Path {
        &self.dest
    }

    /// Renames the finished folder into place, replacing an old frames folder (see [`PendingDir::create`]).
    ///
    /// The old folder is renamed aside first and removed only once the new one is in place; a signal waits for
    /// the two renames, and a run killed outright between them is repaired by the next run ([`sweep_stale`]).
    pub fn commit(self) -> Result<()> {
        Self::check(&self.dest, self.force)?;
        let PendingDir { tmp, dest, _registered, .. } = self;
        let tmp = tmp.keep();
        let had_old = std::fs::symlink_metadata(&dest).is_ok();
        let aside = had_old.then(|| {
            let name = tmp.file_name().unwrap_or_default().to_string_lossy();
            tmp.with_file_name(format!("{}.old", name.trim_end_matches(".part")))
        });
        let restore = aside.clone().map(|aside| interrupt::register(Cleanup::Restore { aside, dest: dest.clone() }));
        let swapped = {
            let _held = interrupt::hold();
            swap(&tmp, &dest, aside.as_deref())
        };
        drop(restore);
        drop(_registered);
        swapped.with_context(|| format!("cannot write {}", dest.display()))?;
        if let Some(aside) = aside {
            std::fs::remove_dir_all(&aside).with_context(|| {
                format!("wrote {} but cannot remove the old frames {}", dest.display(), aside.display())
            })?;
        }
        Ok(())
    }
}

/// Moves the old `dest` to `aside` (when there is one) and `new` to `dest`; puts the old one back if the
/// second rename fails, and removes `new` when it cannot be put in place.
fn swap(new: &Path, dest: &Path, aside: Option<&Path>) -> std::io::Result<()> {
    let moved = match aside {
        Some(aside) => std::fs::rename(dest, aside).and_then(|()| {
            std::fs::rename(new, dest).inspect_err(|_| {
                let _ = std::fs::rename(aside, dest);
            })
        }),
        None => std::fs::rename(new, dest),
    };
    if moved.is_err() {
        let _ = std::fs::remove_dir_all(new);
    }
    moved
}

/// A temporary name of ours: the destination's name, the writer's process id, and whether it is an old
/// folder moved aside (`.old`) rather than an unfinished output (`.part`).
#[derive(Debug, PartialEq, Eq)]
struct TempName<'a> {
    dest: &'a str,
    pid: u32,
    aside: bool,
}

fn parse_temp_name(name: &str) -> Option<TempName<'_>> {
    let rest = name.strip_prefix('.')?;
    let (rest, aside) = match rest.strip_suffix(".part") {
        Some(r) => (r, false),
        None => (rest.strip_suffix(".old")?, true),
    };
    let (rest, random) = rest.rsplit_once('.')?;
    let (dest, pid) = rest.rsplit_once('.')?;
    let ok = random.len() == RANDOM_LEN
        && random.bytes().all(|b| b.is_ascii_alphanumeric())
        && !pid.is_empty()
        && pid.bytes().all(|b| b.is_ascii_digit())
        && !dest.is_empty();
    ok.then(|| Some(TempName { dest, pid: pid.parse().ok()?, aside })).flatten()
}

/// Whether process `pid` still runs (true when that cannot be told, so nothing of a live run is touched).
#[cfg(unix)]
fn is_running(pid: u32) -> bool {
    let Ok(pid) = libc::pid_t::try_from(pid) else { return true };
    // SAFETY: kill with signal 0 only checks whether the process exists; it takes plain integers.
    let alive = unsafe { libc::kill(pid, 0) } == 0;
    alive || std::io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
}

#[cfg(not(unix))]
fn is_running(_pid: u32) -> bool {
    true
}

/// Cleans up after earlier runs that were killed outright in `folder`: removes their unfinished outputs, and
/// puts back a frames folder moved aside during a swap when its destination is missing (or removes it when the
/// new one made it into place). Only names of our own pattern whose process is gone are touched; each is
/// reported on standard error.
pub fn sweep_stale(folder: &Path) {
    let Ok(entries) = std::fs::read_dir(folder) else { return };
    let mut found: Vec<(PathBuf, String, bool)> = Vec::new();
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if let Some(t) = parse_temp_name(&name)
            && t.pid != std::process::id()
            && !is_running(t.pid)
        {
            found.push((entry.path(), t.dest.to_string(), t.aside));
        }
    }
    // Unfinished outputs first, then the folders moved aside.
    found.sort_by_key(|(_, _, aside)| *aside);
    for (path, dest_name, aside) in found {
        let dest = folder.join(&dest_name);
        if aside && std::fs::symlink_metadata(&dest).is_err() {
            if std::fs::rename(&path, &dest).is_ok() {
                crate::note!("put back {} (an interrupted run was replacing it)", dest.display());
            }
            continue;
        }
        let removed = if path.is_dir() { std::fs::remove_dir_all(&path) } else { std::fs::remove_file(&path) };
        if removed.is_ok() {
            crate::note!("removed {} (left by an interrupted run)", path.display());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_existing_file_is_kept_without_force() {
        let dir = tempfile::tempdir().unwrap();
        let dest = dir.path().join("a.txt");
        std::fs::write(&dest, "old").unwrap();
        let err = write_atomic(&dest, b"new", false).unwrap_err().to_string();
        assert!(err.contains("--force"), "{err}");
        assert_eq!(std::fs::read_to_string(&dest).unwrap(), "old");
        write_atomic(&dest, b"new", true).unwrap();
        assert_eq!(std::fs::read_to_string(&dest).unwrap(), "new");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1, "no temporary file is left");
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let plain = dir.path().join("plain.txt");
            std::fs::write(&plain, "x").unwrap();
            let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode();
            assert_eq!(mode(&dest), mode(&plain), "the file gets the permissions of any new file");
        }
    }

    #[test]
    fn an_abandoned_file_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let pending = PendingFile::create(&dir.path().join("b.gif"), false).unwrap();
        std::fs::write(pending.temp_path(), b"half").unwrap();
        drop(pending);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn force_never_replaces_a_folder_of_other_files() {
        let dir = tempfile::tempdir().unwrap();
        let dest = dir.path().join("frames");
        std::fs::create_dir(&dest).unwrap();
        std::fs::write(dest.join("notes.txt"), "keep").unwrap();
        assert!(PendingDir::create(&dest, true).is_err());
        assert!(PendingDir::create(&dest, false).is_err());
        std::fs::remove_file(dest.join("notes.txt")).unwrap();
        std::fs::write(dest.join("frame_00000.png"), "old").unwrap();
        let pending = PendingDir::create(&dest, true).unwrap();
        std::fs::write(pending.path().join("frame_00000.png"), "new").unwrap();
        pending.commit().unwrap();
        assert_eq!(std::fs::read_to_string(dest.join("frame_00000.png")).unwrap(), "new");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn a_failed_swap_keeps_the_old_folder_and_removes_the_new_one() {
        let dir = tempfile::tempdir().unwrap();
        let (new, dest) = (dir.path().join(".frames.1.abcdef.part"), dir.path().join("frames"));
        for (folder, text) in [(&new, "new"), (&dest, "old")] {
            std::fs::create_dir(folder).unwrap();
            std::fs::write(folder.join("frame_00000.png"), text).unwrap();
        }
        assert!(swap(&new, &dest, Some(&dir.path().join("missing/aside"))).is_err());
        assert_eq!(std::fs::read_to_string(dest.join("frame_00000.png")).unwrap(), "old");
        assert!(!new.exists());
    }

    #[test]
    fn temporary_names_carry_the_destination_and_the_process() {
        let dir = tempfile::tempdir().unwrap();
        let pending = PendingFile::create(&dir.path().join("run.v1.gif"), false).unwrap();
        let name = pending.temp_path().file_name().unwrap().to_string_lossy().into_owned();
        let parsed = parse_temp_name(&name).unwrap();
        assert_eq!(parsed, TempName { dest: "run.v1.gif", pid: std::process::id(), aside: false });
        assert_eq!(parse_temp_name(".frames.12.abc123.old"), Some(TempName { dest: "frames", pid: 12, aside: true }));
        for other in [".run.gif.abc123.part", "run.gif.1.abc123.part", ".x.1.abc.part", ".x.1.abc123.tmp"] {
            assert_eq!(parse_temp_name(other), None, "{other}");
        }
    }

    #[test]
    fn a_dangling_symbolic_link_is_refused_without_force() {
        let dir = tempfile::tempdir().unwrap();
        let link = dir.path().join("out.gif");
        #[cfg(unix)]
        std::os::unix::fs::symlink(dir.path().join("missing/x.gif"), &link).unwrap();
        #[cfg(unix)]
        {
            let err = check_free(&link, false).unwrap_err().to_string();
            assert!(err.contains("symbolic link") && err.contains("does not exist"), "{err}");
            check_free(&link, true).unwrap();
        }
    }
}

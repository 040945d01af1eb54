//! Writing files safely: nothing is overwritten without `--force`, and every output is written to a temporary
//! file (or folder) beside its destination and renamed into place when complete, so an interrupted run never
//! leaves a half-written file under the destination's name.

use std::fs::File;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use tempfile::{NamedTempFile, TempDir};

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

/// A temporary-file builder whose files get the usual permissions (0666, or 0777 for a folder, less the
/// umask), not tempfile's private 0600, since they are renamed into the user's files.
fn builder<'a>(prefix: &'a str, suffix: &'a str, folder: bool) -> tempfile::Builder<'a, 'a> {
    let mut b = tempfile::Builder::new();
    b.prefix(prefix).suffix(suffix);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        b.permissions(std::fs::Permissions::from_mode(if folder { 0o777 } else { 0o666 }));
    }
    #[cfg(not(unix))]
    let _ = folder;
    b
}

/// Fails unless `dest` may be written: it does not exist, or `force` is set.
pub fn check_free(dest: &Path, force: bool) -> Result<()> {
    if dest.exists() && !force {
        bail!("{} already exists; pass --force to overwrite it", dest.display());
    }
    parent_of(dest).map(drop)
}

/// A file being written beside its destination; [`PendingFile::commit`] renames it into place,
/// dropping it removes it.
pub struct PendingFile {
    tmp: NamedTempFile,
    dest: PathBuf,
    force: bool,
}

impl PendingFile {
    /// Starts writing `dest`.
    ///
    /// # Errors
    /// `dest` exists and `force` is not set, its folder does not exist, or the temporary file cannot be made.
    pub fn create(dest: &Path, force: bool) -> Result<PendingFile> {
        check_free(dest, force)?;
        let name = dest.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let prefix = format!(".{name}.");
        let tmp = builder(&prefix, ".part", false)
            .tempfile_in(parent_of(dest)?)
            .with_context(|| format!("cannot create a temporary file beside {}", dest.display()))?;
        Ok(PendingFile { tmp, dest: dest.to_path_buf(), force })
    }

    /// The temporary file's path (for a program that writes it by name).
    pub fn temp_path(&self) -> &Path {
        self.tmp.path()
    }

    /// A second handle on the temporary file, to write through.
    pub fn writer(&self) -> Result<File> {
        self.tmp.reopen().context("cannot reopen the temporary file")
    }

    /// Renames the finished file into place.
    pub fn commit(self) -> Result<()> {
        let dest = self.dest.clone();
        let done =
            if self.force { self.tmp.persist(&dest).map(drop) } else { self.tmp.persist_noclobber(&dest).map(drop) };
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
}

impl PendingDir {
    /// Starts writing the folder `dest`. An existing empty folder is replaced; one holding files only with `force`,
    /// and only if it holds nothing but numbered frames (so `--force` never deletes anything else).
    pub fn create(dest: &Path, force: bool) -> Result<PendingDir> {
        Self::check(dest, force)?;
        let tmp = builder(".frames.", ".part", true)
            .tempdir_in(parent_of(dest)?)
            .with_context(|| format!("cannot create a temporary folder beside {}", dest.display()))?;
        Ok(PendingDir { tmp, dest: dest.to_path_buf(), force })
    }

    fn check(dest: &Path, force: bool) -> Result<()> {
        if !dest.exists() {
            return parent_of(dest).map(drop);
        }
        if !dest.is_dir() {
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

    /// Renames the finished folder into place (replacing an old frames folder, see [`PendingDir::create`]).
    pub fn commit(self) -> Result<()> {
        Self::check(&self.dest, self.force)?;
        let tmp = self.tmp.keep();
        let aside = if self.dest.exists() {
            let aside = tmp.with_extension("old");
            std::fs::rename(&self.dest, &aside)?;
            Some(aside)
        } else {
            None
        };
        std::fs::rename(&tmp, &self.dest).with_context(|| format!("cannot write {}", self.dest.display()))?;
        if let Some(aside) = aside {
            std::fs::remove_dir_all(aside)?;
        }
        Ok(())
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
}

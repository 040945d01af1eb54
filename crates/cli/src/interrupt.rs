//! Ctrl-C, SIGTERM and SIGHUP while files are being written: every unfinished output is removed (and a
//! frames folder that was being swapped is put back) before the process exits with 128 + the signal.
//!
//! Whatever writes a temporary file, folder or child process registers it here for as long as it exists
//! ([`register`]); a handler thread started by [`install`] cleans up what is registered when a signal
//! comes. A swap that must not be cut in half holds the registry ([`hold`]) so the handler waits for it.

use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard};

/// Something to undo if the process is interrupted.
#[derive(Debug)]
pub enum Cleanup {
    /// An unfinished temporary file or folder: removed.
    Remove(PathBuf),
    /// The old frames folder moved aside during a swap: put back at `dest` if `dest` is missing, else removed.
    Restore {
        /// Where the old folder lies now.
        aside: PathBuf,
        /// Where it came from.
        dest: PathBuf,
    },
    /// A child process writing an output (ffmpeg): killed.
    Kill(u32),
}

static REGISTRY: Mutex<Vec<(u64, Cleanup)>> = Mutex::new(Vec::new());
static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// Keeps a [`Cleanup`] registered until dropped.
#[derive(Debug)]
pub struct Registered(u64);

impl Drop for Registered {
    fn drop(&mut self) {
        registry().retain(|(id, _)| *id != self.0);
    }
}

fn registry() -> MutexGuard<'static, Vec<(u64, Cleanup)>> {
    REGISTRY.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Registers `cleanup` until the returned guard is dropped.
pub fn register(cleanup: Cleanup) -> Registered {
    let id = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    registry().push((id, cleanup));
    Registered(id)
}

/// Holds off the cleanup (and so the exit) of an interrupt until the guard is dropped: for steps that must
/// complete together, such as the two renames of a folder swap. Register nothing while holding it.
pub fn hold() -> MutexGuard<'static, Vec<(u64, Cleanup)>> {
    registry()
}

/// Undoes everything registered; what is already gone is skipped. Returns the paths it removed.
fn clean_up(items: &mut Vec<(u64, Cleanup)>) -> Vec<PathBuf> {
    let mut removed = Vec::new();
    // Children first, so that nothing writes into what is removed next.
    for (_, item) in items.iter() {
        if let Cleanup::Kill(pid) = item {
            kill(*pid);
        }
    }
    for (_, item) in items.drain(..) {
        match item {
            Cleanup::Remove(path) => {
                let gone = if path.is_dir() { std::fs::remove_dir_all(&path) } else { std::fs::remove_file(&path) };
                if gone.is_ok() {
                    removed.push(path);
                }
            }
            Cleanup::Restore { aside, dest } => {
                if std::fs::symlink_metadata(&dest).is_err() {
                    let _ = std::fs::rename(&aside, &dest);
                } else if std::fs::remove_dir_all(&aside).is_ok() {
                    removed.push(aside);
                }
            }
            Cleanup::Kill(_) => {}
        }
    }
    removed
}

#[cfg(unix)]
fn kill(pid: u32) {
    if let Ok(pid) = libc::pid_t::try_from(pid) {
        // SAFETY: kill takes plain integers; the pid is one of our own children, not yet waited for.
        unsafe { libc::kill(pid, libc::SIGKILL) };
    }
}

#[cfg(not(unix))]
fn kill(_pid: u32) {}

/// Starts the thread that cleans up and exits on SIGINT, SIGTERM or SIGHUP.
///
/// # Errors
/// The signal handlers cannot be installed.
#[cfg(unix)]
pub fn install() -> anyhow::Result<()> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP])?;
    std::thread::Builder::new().name("signals".into()).spawn(move || {
        if let Some(signal) = signals.forever().next() {
            let removed = clean_up(&mut registry());
            let name = match signal {
                SIGINT => "interrupted",
                SIGTERM => "terminated",
                _ => "hung up",
            };
            let what = if removed.is_empty() {
                String::new()
            } else {
                let names: Vec<String> = removed.iter().map(|p| p.display().to_string()).collect();
                format!("; removed the unfinished {}", names.join(", "))
            };
            crate::report::error_line(&format!("{name}{what}"));
            std::process::exit(128 + signal);
        }
    })?;
    Ok(())
}

/// Without Unix signals there is nothing to install.
#[cfg(not(unix))]
pub fn install() -> anyhow::Result<()> {
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clean_up_removes_files_and_folders_and_puts_a_swapped_folder_back() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join(".a.gif.1.abcdef.part");
        let folder = dir.path().join(".frames.1.abcdef.part");
        let aside = dir.path().join(".frames.1.ghijkl.old");
        let dest = dir.path().join("frames");
        std::fs::write(&file, "half").unwrap();
        std::fs::create_dir(&folder).unwrap();
        std::fs::write(folder.join("frame_00000.png"), "new").unwrap();
        std::fs::create_dir(&aside).unwrap();
        std::fs::write(aside.join("frame_00000.png"), "old").unwrap();
        let mut items = vec![
            (0, Cleanup::Remove(file.clone())),
            (1, Cleanup::Remove(folder.clone())),
            (2, Cleanup::Restore { aside: aside.clone(), dest: dest.clone() }),
        ];
        let removed = clean_up(&mut items);
        assert_eq!(removed, [file, folder]);
        assert_eq!(std::fs::read_to_string(dest.join("frame_00000.png")).unwrap(), "old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}

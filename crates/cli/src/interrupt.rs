//! Ctrl-C, SIGTERM and SIGHUP while files are being written: every unfinished output is removed (and a
//! frames folder that was being swapped is put back) before the process exits with 128 + the signal.
//!
//! Whatever writes a temporary file, folder or child process registers it here for as long as it exists
//! ([`register`]); a handler thread started by [`install`] cleans up what is registered when a signal
//! comes. A swap that must not be cut in half holds the registry ([`hold`]) so the handler waits for it.
//! A child that cleans up after itself (`python -m chopperscape.integrations.datasets`) is [`Cleanup::Stop`]ped: it gets
//! the same signal and is waited for, so that it removes its own unfinished files before this process exits.

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
    /// A child process that removes its own unfinished output on a signal: sent the same signal and waited for
    /// (at most [`STOP_WAIT`], then killed).
    Stop(u32),
}

/// How long a [`Cleanup::Stop`] child is given to clean up and exit.
pub const STOP_WAIT: std::time::Duration = std::time::Duration::from_secs(60);

static STOPPING: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether a signal came and the process is cleaning up to exit: a caller that has just seen its child end
/// (because the handler stopped it) should leave the exit to the handler.
pub fn is_stopping() -> bool {
    STOPPING.load(std::sync::atomic::Ordering::SeqCst)
}

static DEFERRING: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
static PENDING: std::sync::atomic::AtomicI32 = std::sync::atomic::AtomicI32::new(0);
use std::sync::atomic::Ordering::SeqCst;

/// From now on the first signal does not end the process: it is kept for [`pending`], so a command that saves
/// its state between steps (`train`) can stop at a save point. A second signal ends the process as usual.
pub fn defer() {
    DEFERRING.store(true, SeqCst);
}

/// The signal that came while [`defer`] was on, if one did.
pub fn pending() -> Option<i32> {
    let signal = PENDING.load(SeqCst);
    (signal != 0).then_some(signal)
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

/// Undoes everything registered after `signal`; what is already gone is skipped. Returns the paths it removed.
fn clean_up(items: &mut Vec<(u64, Cleanup)>, signal: i32) -> Vec<PathBuf> {
    let mut removed = Vec::new();
    // Children first, so that nothing writes into what is removed next.
    for (_, item) in items.iter() {
        match item {
            Cleanup::Kill(pid) => kill(*pid),
            Cleanup::Stop(pid) => stop(*pid, signal),
            _ => {}
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
            Cleanup::Kill(_) | Cleanup::Stop(_) => {}
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

/// Sends `signal` to child `pid` and waits until it is gone (the main thread reaps it), at most [`STOP_WAIT`];
/// then kills it.
#[cfg(unix)]
fn stop(pid: u32, signal: i32) {
    let Ok(id) = libc::pid_t::try_from(pid) else { return };
    // SAFETY: kill takes plain integers; the pid is one of our own children.
    unsafe { libc::kill(id, signal) };
    let start = std::time::Instant::now();
    // SAFETY: as above; signal 0 only asks whether the process (or its zombie) is still there.
    while unsafe { libc::kill(id, 0) } == 0 {
        if start.elapsed() > STOP_WAIT {
            kill(pid);
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

#[cfg(not(unix))]
fn stop(_pid: u32, _signal: i32) {}

/// Makes a child process get SIGTERM when this process dies, however it dies (SIGKILL included), so that a
/// child such as `python -m chopperscape.integrations.datasets` never goes on writing alone. Linux only; elsewhere nothing.
pub fn die_with_parent(cmd: &mut std::process::Command) {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::process::CommandExt;
        // SAFETY: prctl is async-signal-safe and touches nothing of the parent's state.
        unsafe {
            cmd.pre_exec(|| {
                if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = cmd;
}

/// Starts the thread that cleans up and exits on SIGINT, SIGTERM or SIGHUP.
///
/// # Errors
/// The signal handlers cannot be installed.
#[cfg(unix)]
pub fn install() -> anyhow::Result<()> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP])?;
    std::thread::Builder::new().name("signals".into()).spawn(move || {
        for signal in signals.forever() {
            // A deferring command (`train`) stops at its next save point; a second signal stops at once.
            if DEFERRING.load(SeqCst) && PENDING.swap(signal, SeqCst) == 0 {
                crate::report::error_line("stopping after this update, once the run is saved (again to stop at once)");
                continue;
            }
            STOPPING.store(true, std::sync::atomic::Ordering::SeqCst);
            let mut items = registry();
            // A stopped child says itself what it removed.
            let quiet = items.iter().any(|(_, c)| matches!(c, Cleanup::Stop(_)));
            let removed = clean_up(&mut items, signal);
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
            if !quiet || !removed.is_empty() {
                crate::report::error_line(&format!("{name}{what}"));
            }
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
        let removed = clean_up(&mut items, 2);
        assert_eq!(removed, [file, folder]);
        assert_eq!(std::fs::read_to_string(dest.join("frame_00000.png")).unwrap(), "old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[cfg(unix)]
    #[test]
    fn a_stopped_child_gets_the_signal_and_is_waited_for() {
        use std::os::unix::process::ExitStatusExt;

        // The child traps SIGTERM, takes a moment to "clean up", and exits.
        let child = std::process::Command::new("sh")
            .args(["-c", "trap 'sleep 0.3; exit 7' TERM; while :; do sleep 0.05; done"])
            .spawn()
            .unwrap();
        let pid = child.id();
        std::thread::sleep(std::time::Duration::from_millis(300));
        // As the command's main thread does, something waits for (reaps) the child.
        let waiter = std::thread::spawn(move || {
            let mut child = child;
            child.wait().unwrap()
        });
        let started = std::time::Instant::now();
        clean_up(&mut vec![(0, Cleanup::Stop(pid))], libc::SIGTERM);
        let status = waiter.join().unwrap();
        assert_eq!((status.code(), status.signal()), (Some(7), None), "it got SIGTERM and cleaned up");
        assert!(started.elapsed() < std::time::Duration::from_secs(10));
    }
}

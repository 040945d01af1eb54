//! Reading an action log takes memory in proportion to the file, not fifty times it. (Its own test binary, so
//! that the peak memory of the children it waits for is that of the one replay it runs.)

mod common;

#[cfg(target_os = "linux")]
#[test]
fn a_long_action_log_is_parsed_in_little_more_memory_than_its_size() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("long.json");
    let actions = 10_000_000usize;
    let mut text = String::from(
        r#"{"format": "chopperscape-actions", "version": 1, "env": "ChopperScape-v0", "seed": 0, "options": {},
        "steps": 1, "return": 0, "cause": null, "actions": ["#,
    );
    text.push_str(&"3,".repeat(actions - 1));
    text.push_str("3]}");
    std::fs::write(&log, &text).unwrap();
    let out = std::process::Command::new(common::bin()).arg("replay").arg(&log).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&format!("`steps` is 1 but the log holds {actions} actions")), "{err}");
    let mut usage = std::mem::MaybeUninit::<libc::rusage>::zeroed();
    // SAFETY: getrusage writes the struct it is given, which lives for the call.
    assert_eq!(unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, usage.as_mut_ptr()) }, 0);
    // SAFETY: getrusage succeeded, so the struct is filled in.
    let peak_kib = unsafe { usage.assume_init() }.ru_maxrss;
    let file_kib = (text.len() / 1024) as i64;
    assert!(peak_kib < 3 * file_kib + 40 * 1024, "peak {peak_kib} KiB for a {file_kib} KiB log");
}

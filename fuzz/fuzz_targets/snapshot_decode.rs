//! Arbitrary bytes into the snapshot decoder: it must return an error or a snapshot that restores into an
//! environment which then steps without panicking, and re-encodes to the same bytes.
#![no_main]
use chopperscape::{ChopperScape, Env, Snapshot};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(snap) = Snapshot::from_bytes(data) {
        assert_eq!(snap.to_bytes(), data, "a decoded snapshot re-encodes to its bytes");
        let Ok(mut env) = ChopperScape::from_snapshot(&snap) else { return };
        for a in 0..5 {
            if env.step(a).is_err() {
                break;
            }
        }
    }
});

//! Arbitrary bytes into the snapshot decoder: it must return an error or a snapshot that restores into an
//! environment which then steps without panicking. A snapshot in the current format re-encodes to the same
//! bytes; one in an older format (still read) re-encodes into the current format, and those bytes decode and
//! re-encode to themselves.
#![no_main]
use chopperscape::{ChopperScape, Env, SNAPSHOT_VERSION, Snapshot};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(snap) = Snapshot::from_bytes(data) {
        let bytes = snap.to_bytes();
        let current = SNAPSHOT_VERSION.to_le_bytes();
        assert_eq!(bytes[4..6], current, "a snapshot is written in the current format");
        if data[4..6] == current {
            assert_eq!(bytes, data, "a decoded snapshot in the current format re-encodes to its bytes");
        } else {
            let again = Snapshot::from_bytes(&bytes).expect("an upgraded snapshot decodes");
            assert_eq!(again.to_bytes(), bytes, "an upgraded snapshot re-encodes to its bytes");
        }
        let Ok(mut env) = ChopperScape::from_snapshot(&snap) else { return };
        for a in 0..5 {
            if env.step(a).is_err() {
                break;
            }
        }
    }
});
